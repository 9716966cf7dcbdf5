#pragma once
/// @file static_detection.hpp
/// Automatic detection of static intervals in a raw log.
///
/// For every sample i the variance of each axis over a centred window of w samples is computed;
/// the score s_i is the sum of the three variances [raw²]. The noise reference s_ref is either the
/// same sum over an initial rest period (imu_tk's approach, `init_rest_s` > 0) or, by default, a
/// low quantile of all window scores (quiet windows exist in any usable recording). A sample is
/// static when s_i ≤ threshold_factor · s_ref and its window looks like white noise around a
/// constant: s_i ≤ max_noise_ratio · d_i / 2, with d_i the same sum for the successive differences
/// (for white noise s ≈ d/2; slow motion makes s far larger, so a log with no still period yields
/// no interval even though its quietest windows set the reference). Runs of static window centres
/// at least `min_duration_s` long become intervals. Using the window centres trims half a window at
/// each end of a still period, so the samples kept are those whose whole neighbourhood was still.

#include <optional>
#include <string>
#include <vector>

#include "accelcal/log_reader.hpp"
#include "accelcal/positions.hpp"

namespace accelcal {

struct StaticDetectionOptions {
  double window_s = 0.5;           ///< variance window length [s]
  double min_duration_s = 1.0;     ///< shortest interval kept [s]
  double threshold_factor = 10.0;  ///< threshold = factor × noise reference
  /// > 0: the noise reference is the variance of the first init_rest_s seconds (the sensor must be
  /// still then). 0: the reference is the `reference_quantile` quantile of the window scores.
  double init_rest_s = 0.0;
  double reference_quantile = 0.05;
  /// Largest accepted ratio of window variance to half the variance of successive differences.
  /// Measured on real still periods: 1.0-2.4 (Xsens MTi, 100 Hz), 2.7-10 (T265, 200 Hz, whose
  /// samples repeat); smooth motion gives hundreds.
  double max_noise_ratio = 20.0;
  /// An error message when an option is out of range, else std::nullopt.
  std::optional<std::string> Validate() const;
};

/// A still run that did not become an interval, and why (the report shows them).
struct RejectedInterval {
  enum class Cause {
    kTooShort,  ///< shorter than min_duration_s (but at least a quarter of it)
    /// Some axis sits at the log's largest or smallest value in at least 1 % of the run's
    /// samples (and at least 3) while another axis varies: the sensor saturated, so the mean is
    /// wrong. In a real log the extremes belong to the motion between positions, so a still run
    /// reaching them repeatedly is at the sensor's limit.
    kClipped,
    /// Every window is quiet but the mean moves steadily across the run (a slow turn): the
    /// slope of the means of 8 batches is beyond |t| = 12 on some axis and turns the mean
    /// faster than 0.5°/s (relative to a 1 g reading).
    kMoving,
  };
  std::size_t begin = 0, end = 0;     ///< sample indices, end one past the last
  double t_begin_s = 0, t_end_s = 0;  ///< [s]
  Cause cause = Cause::kTooShort;
  std::string reason;
};

struct StaticDetectionResult {
  std::vector<StaticInterval> intervals;
  /// Still runs shorter than min_duration_s but at least a quarter of it (shorter blips are
  /// noise, not attempted positions), and clipped runs (RejectedInterval::Cause).
  std::vector<RejectedInterval> rejected;
  double rate_hz = 0;              ///< rate used
  std::size_t window_samples = 0;  ///< window length used
  double noise_reference = 0;      ///< s_ref [raw²]
  double threshold = 0;            ///< [raw²]
  /// Per axis, the smallest nonzero change between successive samples [raw]: the quantisation
  /// step of a quantised sensor or log; q²/12 floors the noise levels.
  Vec3 quantisation_step = Vec3::Zero();
  std::size_t segments = 1;  ///< pieces of the log between time gaps (RawLog::time)
  /// Readings left out as corrupted (CorruptedReadings), by index: no window holds one, so one
  /// absurd value (a bit flip, a garbled record) spoils neither the windows after it nor the
  /// noise reference; a still interval around one ends at it.
  std::vector<std::size_t> corrupted;
  /// Still periods split by a short disturbance that were joined: two intervals at most a window
  /// apart whose means agree within 5 standard errors per axis (plus a quantisation step).
  std::size_t joined = 0;
};

/// Why `detection` found no interval, for a message: "no static interval found" and, when quiet
/// periods were rejected as turning, how many ("a log in continuous motion has no static
/// positions"), else the threshold used.
std::string NoStaticIntervalReason(const StaticDetectionResult& detection);

/// How far from the log's median, in multiples of its spread, a reading is corrupted: the spread
/// (per axis, the median absolute deviation of the readings, or their smallest step when that is
/// larger) is at least a sensor's noise, and no sensor's range is a million times its noise
/// around where it reads most; below this, a reading's square cannot swamp the window sums
/// (1e12 times the noise's variance, against a double's 1e-16).
inline constexpr double kCorruptedReadingFactor = 1e6;

/// The readings (indices) more than kCorruptedReadingFactor times the spread from the median on an
/// axis, or not numbers. `step`: each axis's smallest nonzero change (StaticDetectionResult).
std::vector<std::size_t> CorruptedReadings(const std::vector<Vec3>& samples, const Vec3& step);

/// Throws DataError when the log is too short, has no rate (no time column and no rate given) or
/// the options are invalid. Returns an empty interval list when nothing is still.
StaticDetectionResult DetectStaticIntervals(const RawLog& log,
                                            const StaticDetectionOptions& options);

}  // namespace accelcal
