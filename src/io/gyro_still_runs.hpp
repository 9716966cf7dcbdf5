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
  std::vector<StaticInterval> runs;      ///< per interval: its still run (begin, end only)
  std::size_t window = 1;                ///< samples per window mean
  Vec3 window_sigma_raw = Vec3::Zero();  ///< robust σ of a window mean about its run's mean
};

/// Windows of `window` samples (about 0.1 s: round(0.1 / sample_step_s), at most a quarter of
/// the shortest interval) are compared with their interval's still rate in robust σ of such
/// means (their absolute deviations' lower quartile / 0.3186 over all the windows, then their
/// median / 0.6745 over the windows inside the runs found), per axis. A
/// stretch of consecutive windows beyond kGyroStillThreshold σ on an axis is a motion when one of
/// them is beyond kGyroMotionThreshold σ (hysteresis: the motion is found by its peak, its extent
/// by its tails), and so is one at the interval's edge (a turn's slow end, its peak beyond the
/// interval); each interval keeps its longest run of samples in no motion's window. Three
/// passes: the still rate is first each interval's median, then its run's mean.
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

}  // namespace accelcal::internal
