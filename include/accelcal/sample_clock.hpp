#pragma once
/// @file sample_clock.hpp
/// Whether a log's samples come one per period with none missing: what an Allan variance, which
/// takes sample k to be at k·T, assumes (issue 19). A log joined from two rates, or one that lost
/// samples, gives a wrong white noise (the period is then the mean step, not the sampling one)
/// without looking wrong. Two checks, fed the times piece by piece (a streamed log):
///   - each step, when the timestamps resolve single steps (TimeAxis::repeated_fraction ≤ 5 %):
///     a step of 1.5 to kGapFactor typical steps lost round(step/typical) − 1 samples; a step
///     under half the typical one brought one too many (a jittery clock brings the samples a long
///     step held back; so the samples lost are counted net of them);
///   - the rate over windows of at least 256 steps and 200 timestamp resolutions, against the
///     whole log's: a window away from it by more than 1 % plus what the resolution explains
///     (2 resolutions over its span) samples at another rate or lost samples there.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "accelcal/time_axis.hpp"

namespace accelcal {

struct SampleClockReport {
  std::size_t samples = 0;
  std::size_t long_steps = 0;          ///< steps of 1.5 to kGapFactor typical steps
  std::size_t lost = 0;                ///< Σ round(step / typical) − 1 over them
  std::size_t short_steps = 0;         ///< steps under half the typical one
  std::uint32_t first_long_line = 0;   ///< the line after the first long step (0: none)
  std::uint32_t first_short_line = 0;  ///< the line after the first short step (0: none)
  /// The samples lost net of the extra ones, as a fraction of the samples (0 when the
  /// timestamps do not resolve single steps).
  double lost_fraction = 0;
  /// The window whose rate departs most from the log's: its first and last lines, its rate, and
  /// |rate / log's − 1| against the tolerance (1 % plus 2 resolutions over its span).
  std::size_t windows = 0;
  std::uint32_t worst_first_line = 0, worst_last_line = 0;
  double worst_rate_hz = 0;
  double worst_departure = 0;
  double tolerance = 0;
  bool rate_departs() const { return worst_departure > tolerance; }
};

/// Fed the times of one log in order (seconds from its first sample, with their lines).
class SampleClockCheck {
 public:
  /// `axis`: the log's typical step, resolution and repeated fraction (MakeTimeAxis, or the
  /// head's in StreamRawLog).
  explicit SampleClockCheck(const TimeAxis& axis);
  void Add(const double* t_s, const std::uint32_t* line, std::size_t count);
  /// The checks against the whole log's rate [Hz] (TimeAxis::rate_hz).
  SampleClockReport Finish(double rate_hz) const;
  /// The steps in one window.
  std::size_t window_steps() const { return window_steps_; }

 private:
  struct Window {
    double rate_hz;
    std::uint32_t first_line, last_line;
  };
  double typical_s_;
  double resolution_s_;
  bool steps_resolved_;
  std::size_t window_steps_;
  SampleClockReport report_;
  std::vector<Window> windows_;
  bool started_ = false;
  double previous_t_ = 0;
  double window_t0_ = 0;
  std::uint32_t window_line0_ = 0;
  std::size_t window_count_ = 0;  // steps so far in the open window
};

}  // namespace accelcal
