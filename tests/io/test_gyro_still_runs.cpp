// The gyroscope's still run inside each of the accelerometer's still intervals
// (gyro_still_runs.hpp), on synthetic rates with known motions.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "io/gyro_still_runs.hpp"

namespace accelcal::internal {
namespace {

TEST(GyroStillRuns, TrimsTurnsEndsAndSplitsAtMotionsButNotAtANoiseSpike) {
  // Three intervals of 500 samples at 100 Hz (windows of 10), white noise of 1 count about a
  // bias of 100: the first begins with a turn's tail (a rate falling linearly from 50 counts to
  // 0 over 40 samples), the second holds one sample of 22 counts (a window mean of 2.2 = 7σ of
  // such means: beyond the extent threshold, not the peak's), the third turns in its middle
  // (samples 150-249 of it at 30 counts).
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<Vec3> rates;
  std::vector<StaticInterval> intervals;
  for (int i = 0; i < 3; ++i) {
    StaticInterval iv;
    iv.begin = rates.size() + 50;
    iv.end = iv.begin + 500;
    intervals.push_back(iv);
    for (int k = 0; k < 550; ++k) {
      const double x = noise(rng), y = noise(rng), z = noise(rng);
      rates.emplace_back(100 + x, 100 + y, 100 + z);
    }
  }
  for (std::size_t k = 0; k < 40; ++k) {
    rates[intervals[0].begin + k](1) += 50.0 * (1.0 - static_cast<double>(k) / 40.0);
  }
  rates[intervals[1].begin + 250](2) += 22.0;
  for (std::size_t k = 150; k < 250; ++k) rates[intervals[2].begin + k](0) += 30.0;
  const GyroStillRuns still =
      FindGyroStillRuns(rates, intervals, 0.01, Vec3::Constant(std::nan("")));
  ASSERT_EQ(still.window, 10u);
  ASSERT_EQ(still.runs.size(), 3u);
  // σ of a window mean, 1/√10, from about 150 independent windows per axis by their median
  // absolute deviation: a relative standard error of 9.5 %, so within 30 %.
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(still.window_sigma_raw(a), 1 / std::sqrt(10.0), 0.3 / std::sqrt(10.0));
  }
  // The tail is above 2σ of a window mean (0.63 counts) for its first 39 samples; the run starts
  // after it, and no more than a window later.
  EXPECT_GE(still.runs[0].begin, intervals[0].begin + 30);
  EXPECT_LE(still.runs[0].begin, intervals[0].begin + 50);
  EXPECT_EQ(still.runs[0].end, intervals[0].end);
  // The spike stays in (a window of noise beyond 2σ at an edge, one in eight, is trimmed).
  EXPECT_LE(still.runs[1].begin, intervals[1].begin + 20);
  EXPECT_GE(still.runs[1].end, intervals[1].end - 20);
  // The motion splits the third: its longer part, after the motion, is kept; the noise next to
  // it, beyond 2σ one window in eight, may extend the motion by a window or two.
  EXPECT_GE(still.runs[2].begin, intervals[2].begin + 250);
  EXPECT_LE(still.runs[2].begin, intervals[2].begin + 270);
  EXPECT_EQ(still.runs[2].end, intervals[2].end);
}

TEST(GyroStillRuns, AnIntervalTurningThroughoutHasNoRun) {
  std::vector<Vec3> rates;
  for (int k = 0; k < 400; ++k) {
    const double turning = k >= 200 ? 50.0 * std::sin(0.05 * k) + 60 : 0.0;
    rates.emplace_back(std::sin(1.3 * k), std::cos(0.7 * k) + turning, std::sin(2.1 * k));
  }
  std::vector<StaticInterval> intervals(2);
  intervals[0].begin = 0, intervals[0].end = 200;
  intervals[1].begin = 200, intervals[1].end = 400;
  const GyroStillRuns still =
      FindGyroStillRuns(rates, intervals, 0.01, Vec3::Constant(std::nan("")));
  EXPECT_GT(still.runs[0].end - still.runs[0].begin, 150u);
  EXPECT_LT(still.runs[1].end - still.runs[1].begin, 2u);
}

TEST(GyroStillRuns, AWobblingPositionIsStillAndOneTurningSteadilyIsNot) {
  // Issue 47: eight intervals of 400 samples at 100 Hz about a zero-rate offset of (50, −20, 60)
  // counts with 1 count of white noise, joined by turns of 100 samples peaking at 1000 counts.
  // Interval 1 wobbles slowly (σ 6 counts at 0.5 Hz: 0.6 % of the turns' peak, 19σ of a window
  // mean's white noise), as a MEMS unit held by hand; interval 4 turns throughout at a steady 30
  // counts (3 % of the turns' peak) about one axis, as a unit turned about the vertical, which the
  // accelerometer cannot see; interval 6 reads 2 counts off the offset (a g-sensitivity).
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, 1.0);
  const Vec3 offset(50, -20, 60);
  const double pi = std::acos(-1.0);
  std::vector<Vec3> rates;
  std::vector<StaticInterval> intervals;
  for (int i = 0; i < 8; ++i) {
    StaticInterval iv;
    iv.begin = rates.size();
    iv.end = iv.begin + 400;
    intervals.push_back(iv);
    for (int k = 0; k < 400; ++k) {
      const double x = noise(rng), y = noise(rng), z = noise(rng);
      Vec3 rate = offset + Vec3(x, y, z);
      const double t = 0.01 * k;
      if (i == 0) {
        rate +=
            6 * std::sqrt(2.0) * Vec3(std::sin(pi * t), std::cos(pi * t + 1), std::sin(pi * t + 2));
      }
      if (i == 3) rate(2) += 30;
      if (i == 5) rate(0) += 2;
      rates.push_back(rate);
    }
    if (i == 7) break;
    for (int k = 1; k < 100; ++k) {
      rates.push_back(offset + Vec3(1000 * std::sin(pi * k / 100.0), noise(rng), noise(rng)));
    }
  }
  const GyroStillRuns still =
      FindGyroStillRuns(rates, intervals, 0.01, Vec3::Constant(std::nan("")));
  ASSERT_EQ(still.runs.size(), 8u);
  EXPECT_NEAR(still.turn_peak_raw, 1000, 10);
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(still.offset_raw(a), offset(a), 0.5) << a;
  // The wobbling interval keeps most of itself (the wobble is judged against its own σ, which the
  // cap of 1 % of the turns' peak, 10 counts, leaves as it is).
  EXPECT_GT(still.runs[0].end - still.runs[0].begin, 300u);
  EXPECT_GT(still.interval_sigma_raw[0].maxCoeff(), 4.0);
  // The steady turn has no still run; the others keep theirs.
  EXPECT_EQ(still.runs[3].end, still.runs[3].begin);
  for (int i : {1, 2, 4, 5, 6, 7}) {
    EXPECT_GT(
        still.runs[static_cast<std::size_t>(i)].end - still.runs[static_cast<std::size_t>(i)].begin,
        300u)
        << i;
  }
}

}  // namespace
}  // namespace accelcal::internal
