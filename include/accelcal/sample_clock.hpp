#pragma once
/// @file sample_clock.hpp
/// Whether a log's samples come one per period with none missing: what an Allan variance, which
/// takes sample k to be at k·T, assumes (issue 19). A log joined from two rates, or one that lost
/// samples, gives a wrong white noise (the period is then the mean step, not the sampling one)
/// without looking wrong. A clock whose timestamps jitter, or that delivers samples in bursts
/// (a host stamping them on arrival), or whose timestamps are rounded coarser than the period,
/// loses none: its samples catch up. Two checks, fed the times piece by piece (a streamed log):
///   - samples lost: the span of the log over the sampling period, less the steps counted. The
///     sampling period is the mean of the blocks of 16 steps' mean steps within 3 % of their
///     median: a block that lost a sample steps 6 % longer and is left out, while jitter scatters
///     both ways and averages out (blocks of 512 for coarse timestamps, below);
///   - a rate that changes: windows of at least 256 steps and 200 timestamp resolutions, each
///     placed on the clock by the median offset of its timestamps from a grid of the typical step
///     (a burst moves a few of them, not the median); the rate between one window and the next
///     against the rate the log starts at (the median of the first five). One further from it
///     than 1 % plus what the timestamps
///     explain (2σ of their scatter and half a resolution, twice, over a window's span) samples
///     at another rate, or lost samples there.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "accelcal/time_axis.hpp"

namespace accelcal {

struct SampleClockReport {
  std::size_t samples = 0;
  double span_s = 0;    ///< first to last timestamp
  double rate_hz = 0;   ///< (samples − 1) / span: the log's rate, gaps and all
  double period_s = 0;  ///< the sampling period (see above)
  /// The timestamps' quantum (the shortest step, when nearly every step is a whole number of
  /// it; 0: none), and whether it is coarse: beyond 1.5 typical steps, or one the typical step is
  /// no whole number of. Coarse timestamps take blocks of 512 steps for the period, which then
  /// finds only losses of more than 3 % of a block.
  double quantum_s = 0;
  bool coarse = false;
  /// The median single step. Well below the period (by 3 % or more), with the steps whole
  /// numbers of it, the log reads two ways:
  /// a stream at 1 / median_step that lost samples in most blocks of 16, or timestamps rounded
  /// to about a median step from a stream at 1 / period (800 Hz printed in whole ms: steps of
  /// 1, 1, 1, 2 ms). Only the sensor's rate tells them apart.
  double median_step_s = 0;
  bool steps_are_multiples = false;  ///< 95 % of the steps a whole number of median steps
  bool two_readings() const { return steps_are_multiples && period_s > 1.03 * median_step_s; }
  /// Samples lost: span / period − (samples − 1); negative when there are more samples than the
  /// span holds (rows written twice).
  double lost = 0;
  double lost_fraction = 0;           ///< lost / samples
  std::uint32_t first_long_line = 0;  ///< the line after the first step of 1.5 periods or more
  double jitter_s = 0;  ///< the timestamps' scatter about the grid (from the steps' MAD)
  /// The windows: how many, the rate the log starts at (the median of the first five windows'),
  /// the first beyond the tolerance from it (0: none), and how far the furthest is.
  std::size_t windows = 0;
  double reference_rate_hz = 0;
  std::uint32_t first_departing_line = 0;
  double first_departing_rate_hz = 0;
  double worst_departure = 0;  ///< |rate / median − 1| of the furthest window
  double tolerance = 0;
  bool rate_departs() const { return worst_departure > tolerance; }
};

/// Fed the times of one log in order (seconds from its first sample, with their lines).
class SampleClockCheck {
 public:
  /// `axis`: the log's typical step and resolution (MakeTimeAxis, or the head's in StreamRawLog).
  explicit SampleClockCheck(const TimeAxis& axis);
  void Add(const double* t_s, const std::uint32_t* line, std::size_t count);
  SampleClockReport Finish() const;

 private:
  struct Window {
    double offset_s;  // the median offset of its timestamps from the grid of typical steps
    std::uint32_t first_line;
    double step_mad_s;  // the median absolute deviation of its steps
  };
  double typical_s_;
  double resolution_s_;
  std::size_t window_steps_;
  struct Blocks {  // the mean steps of blocks of `steps`, over [0.5, 1.5] typical steps
    std::size_t steps;
    std::vector<std::uint32_t> histogram;
    double t0;
    std::size_t count;
  };
  std::vector<Blocks> blocks_;                 // of 16 steps, and of 512 for coarse timestamps
  std::vector<std::uint32_t> step_histogram_;  // single steps, over [0, 4] typical
  std::vector<double> step_sums_;              // the sum of the steps in each of its bins
  std::vector<Window> windows_;
  std::size_t samples_ = 0;
  double first_t_ = 0, previous_t_ = 0;
  std::uint32_t first_long_line_ = 0;
  std::vector<double> window_offsets_;     // of the open window's samples
  std::vector<double> window_steps_seen_;  // of the open window's steps
  std::uint32_t window_line0_ = 0;
};

}  // namespace accelcal
