// SampleClockCheck: lost samples and changing rates found, a steady clock (fine, jittery or
// coarse) left alone.
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

// The check of `t` [s] (lines 1, 2, ...) as the noise command runs it: the axis of the whole log.
Checked Check(std::vector<double> t) {
  std::vector<std::uint32_t> line(t.size());
  for (std::size_t k = 0; k < t.size(); ++k) line[k] = static_cast<std::uint32_t>(k + 1);
  Checked out;
  out.axis = MakeTimeAxis(&t, TimeUnit::kSeconds, "t");
  SampleClockCheck check(out.axis);
  // In two pieces, as a streamed log comes: the result is the same.
  const std::size_t half = t.size() / 2;
  check.Add(t.data(), line.data(), half);
  check.Add(t.data() + half, line.data() + half, t.size() - half);
  out.report = check.Finish(out.axis.rate_hz);
  return out;
}

std::vector<double> Uniform(std::size_t n, double rate_hz, double jitter_s, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> e(0, jitter_s);
  std::vector<double> t(n);
  for (std::size_t k = 0; k < n; ++k) t[k] = static_cast<double>(k) / rate_hz + e(rng);
  for (std::size_t k = 1; k < n; ++k) t[k] = std::max(t[k], t[k - 1]);
  return t;
}

TEST(SampleClock, SteadyClockWithJitterPasses) {
  // 100 Hz with 0.3 ms of jitter (a host clock): every step within half a period.
  const Checked c = Check(Uniform(100000, 100, 3e-4, 1));
  EXPECT_EQ(c.report.long_steps, 0u);
  EXPECT_EQ(c.report.short_steps, 0u);
  EXPECT_EQ(c.report.lost_fraction, 0);
  EXPECT_FALSE(c.report.rate_departs());
  EXPECT_EQ(c.report.windows, 100000u / 256);
  // 2 × 0.3 ms / 2.56 s of span, times √2 or so: a few 10⁻⁴ of departure, under 1 %.
  EXPECT_LT(c.report.worst_departure, 1e-3);
}

TEST(SampleClock, LostSamplesAreCountedWithTheLineAfterTheFirst) {
  // 100 Hz, every 50th sample lost from sample 1000 on (1.96 % of what is left), one run of 3.
  std::vector<double> t;
  std::size_t lost = 0;
  for (std::size_t k = 0; k < 102000; ++k) {
    if ((k >= 1000 && k % 50 == 0) || (k >= 5000 && k < 5003)) {
      ++lost;
      continue;
    }
    t.push_back(static_cast<double>(k) / 100);
  }
  const Checked c = Check(t);
  EXPECT_EQ(c.report.lost, lost);
  EXPECT_EQ(c.report.short_steps, 0u);
  EXPECT_NEAR(c.report.lost_fraction, static_cast<double>(lost) / static_cast<double>(t.size()),
              1e-12);
  // Samples 0-999 on lines 1-1000, sample 1000 lost: sample 1001 on line 1001.
  EXPECT_EQ(c.report.first_long_line, 1001u);
  EXPECT_EQ(c.report.long_steps, lost - 2);  // the run of 3 is one step
}

TEST(SampleClock, BurstsOfAJitteryClockAreNotLoss) {
  // A host that stamps samples on arrival: now and then two arrive late, together with a third.
  std::vector<double> t = Uniform(50000, 200, 0, 2);
  for (std::size_t k = 100; k + 3 < t.size(); k += 97) t[k] = t[k + 1] = t[k + 2];
  const Checked c = Check(t);
  EXPECT_GT(c.report.long_steps, 500u);
  EXPECT_GE(c.report.short_steps, c.report.lost);
  EXPECT_EQ(c.report.lost_fraction, 0);
  EXPECT_FALSE(c.report.rate_departs());
}

TEST(SampleClock, ARateThatChangesDeparts) {
  // 100 Hz, then 120 Hz: every step within the typical one's half, so only the windows see it.
  std::vector<double> t = Uniform(30000, 100, 0, 3);
  const double t1 = t.back();
  for (std::size_t k = 1; k <= 30000; ++k) t.push_back(t1 + static_cast<double>(k) / 120);
  const Checked c = Check(t);
  EXPECT_EQ(c.report.long_steps + c.report.short_steps, 0u);
  ASSERT_TRUE(c.report.rate_departs());
  // The log's rate is 109 Hz; 120 Hz departs most.
  EXPECT_NEAR(c.report.worst_rate_hz, 120, 1e-6);
  EXPECT_GT(c.report.worst_first_line, 30000u);
}

TEST(SampleClock, CoarseTimestampsPassAndStillShowARateChange) {
  // 200 Hz printed to 10 ms (the T265's): half the steps 0, the others 10 ms.
  std::vector<double> t = Uniform(60000, 200, 0, 4);
  for (double& v : t) v = std::floor(v * 100 + 1e-9) / 100;
  Checked c = Check(t);
  EXPECT_GT(c.axis.repeated_fraction, 0.05);
  EXPECT_EQ(c.report.long_steps + c.report.short_steps, 0u);  // single steps unresolved
  EXPECT_FALSE(c.report.rate_departs());
  // Windows span 200 resolutions: 400 steps; tolerance 1 % plus 2 × 10 ms / 2 s.
  EXPECT_NEAR(c.report.tolerance, 0.02, 1e-12);
  // The last third at 210 Hz (5 %) is seen.
  std::vector<double> u = Uniform(40000, 200, 0, 5);
  const double t1 = u.back();
  for (std::size_t k = 1; k <= 20000; ++k) u.push_back(t1 + static_cast<double>(k) / 210);
  for (double& v : u) v = std::floor(v * 100 + 1e-9) / 100;
  c = Check(u);
  EXPECT_TRUE(c.report.rate_departs());
}

}  // namespace
}  // namespace accelcal
