// Static-interval detection on synthetic logs with known intervals, and on the Xsens recording.
#include <random>

#include <gtest/gtest.h>

#include "accelcal/error.hpp"
#include "accelcal/static_detection.hpp"

namespace accelcal {
namespace {

// 100 Hz log: still periods of the given lengths separated by 2-second rotations.
RawLog SyntheticLog(const std::vector<double>& still_s,
                    std::vector<std::pair<std::size_t, std::size_t>>* truth) {
  std::mt19937_64 rng(1);
  std::normal_distribution<double> noise(0.0, 2.0);
  RawLog log;
  log.source = "synthetic";
  log.rate_hz = 100.0;
  Vec3 level(33000, 33000, 37000);
  for (std::size_t k = 0; k < still_s.size(); ++k) {
    const std::size_t n = static_cast<std::size_t>(still_s[k] * 100);
    truth->push_back({log.samples.size(), log.samples.size() + n});
    for (std::size_t i = 0; i < n; ++i) {
      const double z = noise(rng), y = noise(rng), x = noise(rng);  // a fixed order (GCC's)
      log.samples.push_back(level + Vec3(x, y, z));
    }
    const Vec3 next = level + Vec3(3000.0 * std::sin(static_cast<double>(k) + 1.0),
                                   -2500.0 * std::cos(static_cast<double>(k)), 1000.0);
    for (int i = 0; i < 200; ++i) {  // smooth move with a wobble
      const double s = i / 200.0;
      log.samples.push_back(level + (next - level) * s +
                            Vec3(300 * std::sin(30 * s), 200 * std::cos(25 * s), 100));
    }
    level = next;
  }
  for (std::size_t i = 0; i < log.samples.size(); ++i)
    log.time_s.push_back(static_cast<double>(i) / 100.0);
  return log;
}

TEST(StaticDetection, FindsEveryStillPeriod) {
  std::vector<std::pair<std::size_t, std::size_t>> truth;
  const RawLog log = SyntheticLog({20, 5, 3, 8, 1.8, 4}, &truth);
  const StaticDetectionResult r = DetectStaticIntervals(log, {});
  ASSERT_EQ(r.intervals.size(), truth.size());
  for (std::size_t k = 0; k < truth.size(); ++k) {
    // Window centres: half a window (25 samples) is trimmed at each end, never more than a window.
    EXPECT_GE(r.intervals[k].begin, truth[k].first);
    EXPECT_LE(r.intervals[k].begin, truth[k].first + 51);
    EXPECT_LE(r.intervals[k].end, truth[k].second);
    EXPECT_GE(r.intervals[k].end + 51, truth[k].second);
    EXPECT_NEAR(r.intervals[k].std(0), 2.0, 0.5);
  }
}

// From a hostile test: one absurd reading early in a log (1e20 at sample 40 of a ULog, 1e200 in a
// CSV: a bit flip, a garbled record) spoiled every window after it (its square swamped the sliding
// sums, or made them inf) and the log was refused as having one position, or "cut into 1 pieces
// by gaps". It is cut out as a gap is, and named; the still periods are found as without it.
TEST(StaticDetection, ACorruptedReadingIsCutOutAndNamed) {
  std::vector<std::pair<std::size_t, std::size_t>> truth;
  const RawLog clean = SyntheticLog({20, 5, 3, 8, 1.8, 4}, &truth);
  const StaticDetectionResult expected = DetectStaticIntervals(clean, {});
  EXPECT_TRUE(expected.corrupted.empty());
  for (const double value : {1e20, 1e200, -1e12}) {
    RawLog log = clean;
    log.samples[40](1) = value;
    const StaticDetectionResult r = DetectStaticIntervals(log, {});
    EXPECT_EQ(r.corrupted, std::vector<std::size_t>{40}) << value;
    ASSERT_EQ(r.intervals.size(), expected.intervals.size()) << value;
    // The same quantile of the scores less the 51 windows that held the reading.
    EXPECT_NEAR(r.noise_reference, expected.noise_reference, 0.02 * expected.noise_reference);
    // The first still period begins after the reading (no window holds it), the rest are as they
    // were.
    EXPECT_GT(r.intervals[0].begin, 40u) << value;
    for (std::size_t k = 1; k < r.intervals.size(); ++k) {
      EXPECT_EQ(r.intervals[k].begin, expected.intervals[k].begin) << value;
      EXPECT_EQ(r.intervals[k].end, expected.intervals[k].end) << value;
    }
  }
  // A hard knock, a hundred thousand times the noise (2 counts), is a sensor's reading: kept.
  RawLog log = clean;
  log.samples[40](1) += 1e5 * 2;
  EXPECT_TRUE(DetectStaticIntervals(log, {}).corrupted.empty());
}

TEST(StaticDetection, ShortStillPeriodsAreDropped) {
  std::vector<std::pair<std::size_t, std::size_t>> truth;
  const RawLog log = SyntheticLog({10, 0.9, 5}, &truth);
  StaticDetectionOptions o;
  o.min_duration_s = 1.0;
  EXPECT_EQ(DetectStaticIntervals(log, o).intervals.size(), 2u);
}

TEST(StaticDetection, InitialRestReference) {
  std::vector<std::pair<std::size_t, std::size_t>> truth;
  const RawLog log = SyntheticLog({20, 5, 3}, &truth);
  StaticDetectionOptions o;
  o.init_rest_s = 15;
  const StaticDetectionResult r = DetectStaticIntervals(log, o);
  EXPECT_EQ(r.intervals.size(), 3u);
  EXPECT_NEAR(r.noise_reference, 3 * 4.0, 1.0);  // three axes of variance 2²
}

TEST(StaticDetection, NeedsARate) {
  RawLog log;
  log.source = "log.csv";
  log.samples.assign(1000, Vec3::Zero());
  try {
    DetectStaticIntervals(log, {});
    FAIL();
  } catch (const DataError& e) {
    EXPECT_EQ(std::string(e.what()), "the log has no time column and no sample rate was given");
  }
}

TEST(StaticDetection, RejectsInvalidOptions) {
  RawLog log;
  log.rate_hz = 100;
  StaticDetectionOptions o;
  o.window_s = 0;
  EXPECT_THROW(DetectStaticIntervals(log, o), DataError);
}

}  // namespace
}  // namespace accelcal
