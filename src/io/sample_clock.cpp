// Whether a log's samples come one per period with none missing (sample_clock.hpp).
#include "accelcal/sample_clock.hpp"

#include <algorithm>
#include <cmath>

namespace accelcal {

namespace {

constexpr std::size_t kMinWindowSteps = 256;
constexpr double kWindowResolutions = 200;  // a window spans at least this many resolutions
constexpr double kRateTolerance = 0.01;     // beyond what the resolution explains

}  // namespace

SampleClockCheck::SampleClockCheck(const TimeAxis& axis)
    : typical_s_(axis.typical_step_s),
      resolution_s_(axis.resolution_s),
      steps_resolved_(axis.repeated_fraction <= 0.05) {
  // The timestamps' own error: their resolution, or a step of jitter, whichever is larger.
  const double error_s = std::max(resolution_s_, typical_s_);
  window_steps_ =
      std::max(kMinWindowSteps,
               static_cast<std::size_t>(std::ceil(kWindowResolutions * error_s / typical_s_)));
  report_.tolerance =
      kRateTolerance + 2 * error_s / (static_cast<double>(window_steps_) * typical_s_);
}

void SampleClockCheck::Add(const double* t_s, const std::uint32_t* line, std::size_t count) {
  const double gap = kGapFactor * typical_s_;
  for (std::size_t k = 0; k < count; ++k) {
    const double t = t_s[k];
    ++report_.samples;
    if (!started_ || t - previous_t_ > gap) {  // the first sample, or the first after a gap
      started_ = true;
      previous_t_ = window_t0_ = t;
      window_line0_ = line[k];
      window_count_ = 0;
      continue;
    }
    const double d = t - previous_t_;
    previous_t_ = t;
    if (steps_resolved_) {
      if (d >= 1.5 * typical_s_) {
        ++report_.long_steps;
        report_.lost += static_cast<std::size_t>(std::lround(d / typical_s_)) - 1;
        if (report_.first_long_line == 0) report_.first_long_line = line[k];
      } else if (d < 0.5 * typical_s_) {
        ++report_.short_steps;
        if (report_.first_short_line == 0) report_.first_short_line = line[k];
      }
    }
    if (++window_count_ == window_steps_) {
      const double span = t - window_t0_;
      windows_.push_back({span > 0 ? static_cast<double>(window_count_) / span : INFINITY,
                          window_line0_, line[k]});
      window_t0_ = t;
      window_line0_ = line[k];
      window_count_ = 0;
    }
  }
}

SampleClockReport SampleClockCheck::Finish(double rate_hz) const {
  SampleClockReport out = report_;
  if (steps_resolved_ && out.samples > 0 && out.lost > out.short_steps) {
    out.lost_fraction =
        static_cast<double>(out.lost - out.short_steps) / static_cast<double>(out.samples);
  }
  out.windows = windows_.size();
  for (const Window& w : windows_) {
    const double departure = std::abs(w.rate_hz / rate_hz - 1);
    if (!(departure <= out.worst_departure)) {  // an infinite rate (no span) departs most
      out.worst_departure = departure;
      out.worst_first_line = w.first_line;
      out.worst_last_line = w.last_line;
      out.worst_rate_hz = w.rate_hz;
    }
  }
  return out;
}

}  // namespace accelcal
