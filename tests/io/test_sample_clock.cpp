// SampleClockCheck: lost samples and changing rates found; a steady clock left alone, be it
// jittery, bursty or coarse (the cases a hostile test of accelcal noise brought).
#include "accelcal/sample_clock.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

namespace accelcal {
namespace {

struct Checked {
  TimeAxis axis;
  SampleClockReport report;
};

// The check of `t` [s] (lines 1, 2, ...) as the noise command runs it, in two pieces as a
// streamed log comes (the result is the same).
Checked Check(std::vector<double> t) {
  std::vector<std::uint32_t> line(t.size());
  for (std::size_t k = 0; k < t.size(); ++k) line[k] = static_cast<std::uint32_t>(k + 1);
  Checked out;
  out.axis = MakeTimeAxis(&t, TimeUnit::kSeconds, "t");
  SampleClockCheck check(out.axis);
  const std::size_t half = t.size() / 2;
  check.Add(t.data(), line.data(), half);
  check.Add(t.data() + half, line.data() + half, t.size() - half);
  out.report = check.Finish();
  return out;
}

// `n` samples at `rate_hz`, each timestamp off the grid by Gaussian jitter (kept in order).
std::vector<double> Clock(std::size_t n, double rate_hz, double jitter_s, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> e(0, jitter_s);
  std::vector<double> t(n);
  for (std::size_t k = 0; k < n; ++k) t[k] = static_cast<double>(k) / rate_hz + e(rng);
  for (std::size_t k = 1; k < n; ++k) t[k] = std::max(t[k], t[k - 1]);
  return t;
}

void ExpectSteady(const Checked& c, double rate_hz, const char* what) {
  EXPECT_LT(std::abs(c.report.lost_fraction), 1e-3) << what << ": " << c.report.lost;
  EXPECT_FALSE(c.report.rate_departs())
      << what << ": " << c.report.worst_departure << " > " << c.report.tolerance;
  EXPECT_NEAR(c.report.rate_hz, rate_hz, 1e-3 * rate_hz) << what;
}

TEST(SampleClock, JitteryBurstyAndCoarseClocksLoseNothing) {
  // A host clock: 200 Hz with 0.3 and 1.5 ms of jitter (a step then often under half a period
  // or over one and a half: counting long steps against short ones drifted to "1559 lost").
  ExpectSteady(Check(Clock(100000, 200, 3e-4, 1)), 200, "0.3 ms jitter");
  ExpectSteady(Check(Clock(100000, 200, 1.5e-3, 2)), 200, "1.5 ms jitter");
  // Samples held back and delivered together: 5, then 12 (a "gap" of 12 steps) every 1000.
  for (std::size_t burst : {5, 12}) {
    std::vector<double> t = Clock(100000, 200, 0, 3);
    for (std::size_t k = 500; k + burst < t.size(); k += 1000) {
      for (std::size_t j = 0; j < burst; ++j) t[k + j] = t[k + burst];
    }
    ExpectSteady(Check(t), 200, burst == 5 ? "bursts of 5" : "bursts of 12");
  }
  // Timestamps coarser than the period: 200 Hz to 10 ms (the T265's), 800 Hz to whole ms
  // (steps of 1, 1, 1, 2 ms: "9999 samples missing" when each step was taken for one).
  for (const auto& [rate, quantum] : {std::pair{200.0, 0.01}, std::pair{800.0, 0.001}}) {
    std::vector<double> t = Clock(100000, rate, 0, 4);
    for (double& v : t) v = std::floor(v / quantum + 1e-9) * quantum;
    const Checked c = Check(t);
    ExpectSteady(c, rate, "coarse");
    // Whole ms at 800 Hz read two ways (a 1 kHz stream losing a sample in four); 10 ms at
    // 200 Hz does not (half the steps are 0).
    EXPECT_EQ(c.report.two_readings(), rate == 800.0) << c.report.median_step_s;
  }
}

TEST(SampleClock, LostSamplesAreCounted) {
  // 100 Hz with 0.5 ms of jitter, every 200th sample lost from sample 1000 on, and a run of 3.
  std::vector<double> full = Clock(200000, 100, 5e-4, 5), t;
  std::vector<std::uint32_t> kept;
  std::size_t lost = 0;
  for (std::size_t k = 0; k < full.size(); ++k) {
    if ((k >= 1000 && k % 200 == 0) || (k >= 5000 && k < 5003)) {
      ++lost;
      continue;
    }
    t.push_back(full[k]);
  }
  const Checked c = Check(t);
  // The blocks that lost a sample are left out of the period, and with them their ends' jitter
  // (0.05 periods, over 16 steps) from the sum that telescopes: √1000 of them, some 1.6 samples;
  // 5 is 3σ. The refusal is at 0.1 %: 200 samples here.
  EXPECT_NEAR(c.report.lost, static_cast<double>(lost), 5);
  EXPECT_NEAR(c.report.period_s, 0.01, 1e-7);
  // Samples 0-999 on lines 1-1000, sample 1000 lost: sample 1001 on line 1001 (unless the
  // jitter made an earlier step long: none does at 0.05 periods).
  EXPECT_EQ(c.report.first_long_line, 1001u);
  // Rows written twice: negative.
  std::vector<double> twice = Clock(20000, 100, 0, 6);
  twice.insert(twice.begin() + 5000, twice.begin() + 4000, twice.begin() + 4100);
  std::sort(twice.begin(), twice.end());
  EXPECT_NEAR(Check(twice).report.lost, -100, 0.5);
}

TEST(SampleClock, ARateThatChangesDepartsWhereItChanges) {
  // 100 Hz, then 3 % faster; 200 Hz then 1.5 % faster in ns timestamps; and a rate drifting by
  // 3 % over the log. Against the mean rate, each stayed within 1.8 %.
  const auto changed = [](double rate, double factor, std::size_t n) {
    std::vector<double> t = Clock(n, rate, 0, 7);
    for (std::size_t k = n / 2; k < n; ++k) {
      t[k] = t[n / 2 - 1] + static_cast<double>(k - n / 2 + 1) / (rate * factor);
    }
    return t;
  };
  for (const auto& [rate, factor] : {std::pair{100.0, 1.03}, std::pair{200.0, 1.015}}) {
    const std::size_t n = 40000;
    const Checked c = Check(changed(rate, factor, n));
    ASSERT_TRUE(c.report.rate_departs()) << factor;
    EXPECT_NEAR(c.report.first_departing_rate_hz, rate * factor, 1e-6 * rate) << factor;
    // The first window past the change: within two windows (512 steps) of line 20001.
    EXPECT_GE(c.report.first_departing_line, n / 2 - 512) << factor;
    EXPECT_LE(c.report.first_departing_line, n / 2 + 512) << factor;
  }
  std::vector<double> chirp(60000);
  for (std::size_t k = 1; k < chirp.size(); ++k) {
    const double f = 100 * (1 + 0.03 * static_cast<double>(k) / static_cast<double>(chirp.size()));
    chirp[k] = chirp[k - 1] + 1 / f;
  }
  EXPECT_TRUE(Check(chirp).report.rate_departs());
}

}  // namespace
}  // namespace accelcal

namespace accelcal {
namespace {

// A time in ms, µs or ns becomes the double nearest the same time written in seconds: 64180000 us
// is 64.18 s, as "64.18" reads (times 1e-6 gave 64.17999999999999, so a log's intervals differed
// from the same log's in seconds in the last digit).
TEST(TimeAxis, AUnitIsDividedOutExactly) {
  for (const auto& [unit, per_second] : {std::pair<TimeUnit, double>{TimeUnit::kMilliseconds, 1e3},
                                         {TimeUnit::kMicroseconds, 1e6},
                                         {TimeUnit::kNanoseconds, 1e9}}) {
    EXPECT_EQ(UnitsPerSecond(unit), per_second);
    std::vector<double> t;
    for (int k = 0; k <= 6418; ++k) t.push_back(k * 10 * per_second / 1e3);  // 10 ms steps
    const TimeAxis axis = MakeTimeAxis(&t, unit, "t");
    for (int k = 0; k <= 6418; ++k) {
      ASSERT_EQ(t[static_cast<std::size_t>(k)], std::stod(std::to_string(k * 10) + "e-3")) << k;
    }
    EXPECT_EQ(axis.typical_step_s, 0.01);
  }
}

}  // namespace
}  // namespace accelcal
