#pragma once
// The part of each of the accelerometer's still intervals where the gyroscope is still too.
//
// The accelerometer sees a turn only as its direction to gravity changes: it misses a turn about
// the vertical (a full turn inside one "still" position) and the slow ends of every turn, and a
// gyro whose readings lag the accelerometer's turns inside the next position's interval. A
// gyroscope still rate averaged over such samples is wrong, and its noise inflated; the turn
// integrated without them misses part of its angle. So each interval is narrowed to the longest
// run where the gyro's rate stays at its noise level, and the turns are integrated between
// those runs.
#include <cstddef>
#include <vector>

#include "accelcal/positions.hpp"
#include "accelcal/types.hpp"

namespace accelcal::internal {

struct GyroStillRuns {
  /// Per interval: its still run (begin, end only); empty (begin == end) when the gyro did not
  /// stand still in it (it turned throughout, or its still part's rate is not the offset).
  std::vector<StaticInterval> runs;
  std::size_t window = 1;                ///< samples per window mean
  Vec3 window_sigma_raw = Vec3::Zero();  ///< robust σ of a window mean about its run's mean
  /// Per interval: the σ its windows were judged by (window_sigma_raw, or the interval's own
  /// slow wobble up to kGyroWobbleFraction of turn_peak_raw).
  std::vector<Vec3> interval_sigma_raw;
  /// Per interval: true when its run's window means scatter more than kGyroWobbleSignificance
  /// times white noise would make them (σ of successive samples' differences / √2, pooled over
  /// the runs, over √window) on some axis: the unit moved slowly as it stood (or its output is
  /// filtered).
  std::vector<char> wobbles;
  /// The zero-rate offset: per axis the median of the runs' mean rates. In the sensor frame it is
  /// the same in every orientation (but for the g-sensitivity and the Earth's rate, small).
  Vec3 offset_raw = Vec3::Zero();
  /// The turns' peak rate: the median over the gaps between intervals of the largest deviation
  /// of a window mean from the offset there (any axis); 0 without gaps.
  double turn_peak_raw = 0;
  /// Per interval: the mean rate of its run less offset_raw, and the most it may be off the
  /// offset and still be a still position's (both 0 for an interval without a run).
  std::vector<Vec3> run_offset_raw, run_tolerance_raw;
};

/// Windows of `window` samples (about 0.1 s: round(0.1 / sample_step_s), at most a quarter of
/// the shortest interval) are compared with their interval's still rate in robust σ of such
/// means (their absolute deviations' lower quartile / 0.3186 over all the windows, then their
/// median / 0.6745 over the windows inside the runs found), per axis; an interval whose own
/// windows scatter more (a unit that wobbles on a soft mount or in the hand) is judged by its own
/// σ (the median of its windows' deviations / 0.6745), up to kGyroWobbleFraction of the turns'
/// peak rate. A stretch of consecutive windows beyond kGyroStillThreshold σ on an axis is a
/// motion when one of them is beyond kGyroMotionThreshold σ (hysteresis: the motion is found by
/// its peak, its extent by its tails), and so is one at the interval's edge (a turn's slow end,
/// its peak beyond the interval); each interval keeps its longest run of samples in no motion's
/// window. Three passes: the still rate is first each interval's median, then its run's mean.
/// Then each run's mean rate is judged against the zero-rate offset, the median of all the
/// runs' means: a run off it by more than the larger of kGyroWobbleFraction of the turns' peak
/// rate, kGyroOffsetSpread robust σ of the runs' means about the offset (their spread by
/// g-sensitivity and drift) and kGyroMotionThreshold σ of its own mean, turned at a steady
/// rate (about the vertical, which the accelerometer cannot see): it is no still run.
/// `quantum_raw` floors σ at a quantised axis' rounding noise. An interval with no still run left
/// (fewer than two samples) has an empty run.
GyroStillRuns FindGyroStillRuns(const std::vector<Vec3>& rates_raw,
                                const std::vector<StaticInterval>& intervals, double sample_step_s,
                                const Vec3& quantum_raw);

/// A motion's extent: windows beyond this many robust σ, next to its peak. Low, so that the slow
/// start and end of a turn are not taken for still (a 15 s turn's first second stayed in at 5σ,
/// and K_g came out 0.5 % low); noise extends a motion by a window or two, which only shortens a
/// still run.
inline constexpr double kGyroStillThreshold = 2.0;
/// A motion's peak: a window beyond this many σ. The Xsens recording's still positions hold
/// single windows at 5-6 σ (its noise has heavier tails than Gaussian, or the hand shook the
/// table), which split a position without it; a turn peaks at hundreds of σ.
inline constexpr double kGyroMotionThreshold = 10.0;
/// A still position's slow wobble is judged as its noise up to this fraction of the turns' peak
/// rate, and a still run's mean may be off the zero-rate offset by as much: MEMS units turned by
/// hand wobble at 0.006-0.011 rad/s (σ, against 0.003 of sample noise) where their turns peak
/// at 1-3 rad/s; a turn about the vertical inside a position peaks at a tenth of a turn's rate or
/// more, ten times this, so it stays a motion (kGyroMotionThreshold σ).
inline constexpr double kGyroWobbleFraction = 0.01;
/// A run's mean may be off the offset by this many robust σ of all the runs' means about it:
/// their spread by the g-sensitivity (over directions spread on the sphere the largest is about
/// twice the median absolute deviation, 1.35 σ) and by a drifting bias.
inline constexpr double kGyroOffsetSpread = 5.0;
/// An interval's own scatter replaces the pooled σ only beyond this multiple of it: from a few
/// seconds' windows it is within about 30 % of the noise, so quiet recordings are judged as
/// before.
inline constexpr double kGyroWobbleSignificance = 1.5;

}  // namespace accelcal::internal
