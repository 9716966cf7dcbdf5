// Whether a log's samples come one per period with none missing (sample_clock.hpp).
#include "accelcal/sample_clock.hpp"

#include <algorithm>
#include <cmath>

namespace accelcal {

namespace {

constexpr std::size_t kMinWindowSteps = 256;
constexpr double kWindowResolutions = 200;  // a window spans at least this many resolutions
constexpr double kRateTolerance = 0.01;     // beyond what the timestamps explain
constexpr std::size_t kBlockSteps = 16;
// Blocks for timestamps rounded coarser than the period, or to a step that is no whole number
// of periods: 512 steps, over which the rounding (a resolution) is small.
constexpr std::size_t kCoarseBlockSteps = 512;
// The histogram of block mean steps: [0.5, 1.5] typical steps in bins of 10⁻⁵ of it, so that
// the period's error, times the 35 M steps of a day at 400 Hz, stays under a sample.
constexpr std::size_t kBins = 100000;
constexpr double kLow = 0.5, kHigh = 1.5;
// Single steps: [0, 4] typical steps in bins of 10⁻⁴ of it (the last takes longer ones).
constexpr std::size_t kStepBins = 40000;
constexpr double kStepHigh = 4;

// The value below which `fraction` of the histogram's counts lie, interpolated in its bin, in
// units of the histogram's range [kLow, kHigh].
double Quantile(const std::vector<std::uint32_t>& histogram, double fraction) {
  double total = 0;
  for (std::uint32_t c : histogram) total += c;
  const double want = fraction * total;
  double below = 0;
  const double bins = static_cast<double>(histogram.size() - 2);
  for (std::size_t i = 0; i < histogram.size(); ++i) {
    const double c = histogram[i];
    if (below + c >= want && c > 0) {
      if (i == 0) return kLow;
      if (i == histogram.size() - 1) return kHigh;
      const double within = (want - below) / c;
      return kLow + (kHigh - kLow) * (static_cast<double>(i - 1) + within) / bins;
    }
    below += c;
  }
  return kHigh;
}

}  // namespace

SampleClockCheck::SampleClockCheck(const TimeAxis& axis)
    : typical_s_(axis.typical_step_s), resolution_s_(axis.resolution_s) {
  // Coarse timestamps (a resolution of steps or more) need long windows: 200 resolutions.
  window_steps_ = std::max(
      kMinWindowSteps,
      static_cast<std::size_t>(std::ceil(kWindowResolutions * resolution_s_ / typical_s_)));
  // Bins 1 … kBins; 0 and kBins + 1 take what falls below and above the range.
  for (std::size_t steps : {kBlockSteps, kCoarseBlockSteps}) {
    blocks_.push_back({steps, std::vector<std::uint32_t>(kBins + 2, 0), 0.0, 0});
  }
  step_histogram_.assign(kStepBins + 1, 0);
  step_sums_.assign(kStepBins + 1, 0.0);
}

void SampleClockCheck::Add(const double* t_s, const std::uint32_t* line, std::size_t count) {
  for (std::size_t k = 0; k < count; ++k) {
    const double t = t_s[k];
    if (samples_++ == 0) {
      first_t_ = previous_t_ = t;
      for (Blocks& b : blocks_) b.t0 = t;
      continue;
    }
    if (first_long_line_ == 0 && t - previous_t_ >= 1.5 * typical_s_) first_long_line_ = line[k];
    window_steps_seen_.push_back(t - previous_t_);
    const double step = (t - previous_t_) / typical_s_ / kStepHigh * kStepBins;
    const std::size_t step_bin = static_cast<std::size_t>(std::clamp(step, 0.0, double(kStepBins)));
    ++step_histogram_[step_bin];
    step_sums_[step_bin] += t - previous_t_;
    previous_t_ = t;
    for (Blocks& b : blocks_) {
      if (++b.count < b.steps) continue;
      const double mean_step = (t - b.t0) / static_cast<double>(b.steps) / typical_s_;
      const double position = (mean_step - kLow) / (kHigh - kLow) * kBins;
      const std::size_t bin =
          position < 0
              ? 0
              : static_cast<std::size_t>(std::min(std::floor(position), double(kBins))) + 1;
      ++b.histogram[bin];
      b.t0 = t;
      b.count = 0;
    }
    // Each window's place on the clock: the median of its timestamps' offsets from a grid of
    // the typical step (a burst or a late timestamp moves a few of them, not the median).
    if (window_offsets_.empty()) window_line0_ = line[k];
    window_offsets_.push_back(t - static_cast<double>(samples_ - 1) * typical_s_);
    if (window_offsets_.size() == window_steps_) {
      const auto middle = window_offsets_.begin() + static_cast<std::ptrdiff_t>(window_steps_ / 2);
      std::nth_element(window_offsets_.begin(), middle, window_offsets_.end());
      // The steps' scatter (their median absolute deviation): of the timestamps about the
      // grid, √2 times; a drifting grid moves every step alike and leaves it alone.
      std::vector<double>& d = window_steps_seen_;
      const auto mid = d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2);
      std::nth_element(d.begin(), mid, d.end());
      const double median_step = *mid;
      for (double& v : d) v = std::abs(v - median_step);
      std::nth_element(d.begin(), mid, d.end());
      windows_.push_back({*middle, window_line0_, *mid});
      window_offsets_.clear();
      window_steps_seen_.clear();
    }
  }
}

SampleClockReport SampleClockCheck::Finish() const {
  SampleClockReport out;
  out.samples = samples_;
  out.span_s = previous_t_ - first_t_;
  if (samples_ < 2 || !(out.span_s > 0)) return out;
  out.rate_hz = static_cast<double>(samples_ - 1) / out.span_s;
  out.first_long_line = first_long_line_;
  // Steps of the step histogram: the mean step in a bin (0 in the first).
  const auto step_of = [&](std::size_t i) {
    return i == 0 || step_histogram_[i] == 0 ? 0.0 : step_sums_[i] / step_histogram_[i];
  };
  // The fraction of the steps that are a whole number of `m` (to 5 % of it).
  const auto multiples_of = [&](double m) {
    double total = 0, multiples = 0;
    for (std::size_t i = 0; i < step_histogram_.size(); ++i) {
      if (step_histogram_[i] == 0) continue;
      total += step_histogram_[i];
      const double r = step_of(i) / m;
      if (std::abs(r - std::round(r)) < 0.05) multiples += step_histogram_[i];
    }
    return total > 0 ? multiples / total : 0.0;
  };
  {  // the median single step: the mean of the steps in its bin
    double total = 0, below = 0;
    for (std::uint32_t c : step_histogram_) total += c;
    for (std::size_t i = 0; i < step_histogram_.size(); ++i) {
      below += step_histogram_[i];
      if (below >= total / 2) {
        out.median_step_s = step_of(i);
        break;
      }
    }
  }
  // The timestamps' quantum: the shortest step, when nearly every step is a whole number of it.
  // Coarse: a quantum beyond 1.5 typical steps, or one the median step is no whole number of.
  for (std::size_t i = 1; i < step_histogram_.size(); ++i) {
    if (step_histogram_[i] == 0) continue;
    if (multiples_of(step_of(i)) >= 0.95) out.quantum_s = step_of(i);
    break;
  }
  if (out.quantum_s > 0) {
    const double ratio = out.median_step_s / out.quantum_s;
    out.coarse = out.quantum_s > 1.5 * typical_s_ || std::abs(ratio - std::round(ratio)) > 0.05;
  }
  // Lost samples can explain the span only when the steps are whole numbers of the median one.
  out.steps_are_multiples = out.median_step_s > 0 && multiples_of(out.median_step_s) >= 0.95;
  // The sampling period: the mean of the blocks' mean steps within 3 % of their median. A block
  // of 16 that lost a sample steps 6 % longer and is left out; jitter scatters both ways and
  // averages out. Coarse timestamps: blocks of 512, over which the rounding is small.
  const std::vector<std::uint32_t>& histogram = blocks_[out.coarse ? 1 : 0].histogram;
  const double median = Quantile(histogram, 0.5);
  double sum = 0, count = 0;
  const double bins = static_cast<double>(kBins);
  for (std::size_t i = 1; i <= kBins; ++i) {
    const double value = kLow + (kHigh - kLow) * (static_cast<double>(i) - 0.5) / bins;
    if (histogram[i] > 0 && std::abs(value / median - 1) <= 0.03) {
      sum += value * histogram[i];
      count += histogram[i];
    }
  }
  if (count > 0) {
    out.period_s = typical_s_ * sum / count;
    out.lost = out.span_s / out.period_s - static_cast<double>(samples_ - 1);
    out.lost_fraction = out.lost / static_cast<double>(samples_);
  }
  // A window's rate from the offsets of it and the next: (their difference over a window of
  // steps) plus the typical step. Each median is off by some 2σ of the timestamps' scatter at
  // most (half a resolution of a coarse clock; far less for jitter, over 256 of them).
  std::vector<double> scatter;
  for (const Window& w : windows_) scatter.push_back(w.step_mad_s);
  double step_mad = 0;
  if (!scatter.empty()) {
    const auto mid = scatter.begin() + static_cast<std::ptrdiff_t>(scatter.size() / 2);
    std::nth_element(scatter.begin(), mid, scatter.end());
    step_mad = *mid;
  }
  out.jitter_s = 1.4826 * step_mad / std::sqrt(2.0);
  const double span_s = static_cast<double>(window_steps_) * typical_s_;
  out.tolerance = kRateTolerance + 2 * (2 * out.jitter_s + 0.5 * resolution_s_) / span_s;
  out.windows = windows_.size();
  if (windows_.size() < 2) return out;
  std::vector<double> rates;
  for (std::size_t j = 0; j + 1 < windows_.size(); ++j) {
    const double step =
        typical_s_ + (windows_[j + 1].offset_s - windows_[j].offset_s) / double(window_steps_);
    rates.push_back(step > 0 ? 1 / step : INFINITY);
  }
  // The reference: the median of the first five windows' rates, the rate the log starts at.
  std::vector<double> first(rates.begin(),
                            rates.begin() + std::min<std::ptrdiff_t>(5, rates.size()));
  const auto middle = first.begin() + static_cast<std::ptrdiff_t>(first.size() / 2);
  std::nth_element(first.begin(), middle, first.end());
  out.reference_rate_hz = *middle;
  for (std::size_t j = 0; j < rates.size(); ++j) {
    const double departure = std::abs(rates[j] / out.reference_rate_hz - 1);
    if (!(departure <= out.worst_departure)) out.worst_departure = departure;  // ∞ departs most
    if (out.first_departing_line == 0 && !(departure <= out.tolerance)) {
      out.first_departing_line = windows_[j + 1].first_line;
      out.first_departing_rate_hz = rates[j];
    }
  }
  return out;
}

}  // namespace accelcal
