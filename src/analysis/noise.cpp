// A still sensor's noise, axis by axis (noise.hpp).
#include "accelcal/noise.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "accelcal/error.hpp"
#include "core/text_format.hpp"

namespace accelcal {

namespace {

AllanOptions AllanOf(double sample_period_s, const NoiseOptions& options) {
  AllanOptions allan;
  allan.sample_period_s = sample_period_s;
  allan.full_overlap_up_to = options.full_overlap_up_to;
  return allan;
}

}  // namespace

NoiseAccumulator::NoiseAccumulator(double sample_period_s, const NoiseOptions& options)
    : sample_period_s_(sample_period_s), options_(options) {
  // The fit's options checked here, so that what the fit refuses in Finish is the data's.
  const NoiseFitOptions& fit = options.fit;
  if (!(fit.confidence > 0 && fit.confidence < 1) || fit.max_iterations < 1 ||
      std::none_of(fit.terms.begin(), fit.terms.end(), [](bool t) { return t; })) {
    throw std::invalid_argument(
        "NoiseAccumulator: the fit's confidence must lie in (0, 1), its iterations be at least 1 "
        "and one term at least be fitted");
  }
  for (int a = 0; a < 3; ++a) axes_.emplace_back(AllanOf(sample_period_s, options));
}

void NoiseAccumulator::Add(const Vec3* samples, std::size_t count) {
  buffer_.resize(count);
  for (int a = 0; a < 3; ++a) {
    for (std::size_t k = 0; k < count; ++k) buffer_[k] = samples[k](a);
    axes_[static_cast<std::size_t>(a)].Add(buffer_.data(), count);  // refuses a sample not finite
  }
  for (std::size_t k = 0; k < count; ++k) {
    const Vec3& x = samples[k];
    if (samples_ == 0) {
      first_ = low_ = high_ = x;
      quantum_.setConstant(INFINITY);
    } else {
      const Vec3 change = (x - (k > 0 ? samples[k - 1] : previous_)).cwiseAbs();
      for (int a = 0; a < 3; ++a) {
        if (change(a) > 0) {
          quantum_(a) = std::min(quantum_(a), change(a));
          ++changes_[static_cast<std::size_t>(a)];
        }
        if (change(a) > largest_step_(a)) {
          largest_step_(a) = change(a);
          largest_step_at_[static_cast<std::size_t>(a)] = samples_;
        }
      }
      block_abs_steps_ += change;
      low_ = low_.cwiseMin(x);
      high_ = high_.cwiseMax(x);
    }
    sum_ += x - first_;
    block_sum_ += x - first_;
    ++samples_;
    if (samples_ % kStillBlockSamples == 0) {
      block_means_.push_back(block_sum_ / static_cast<double>(kStillBlockSamples));
      block_sum_.setZero();
      block_mean_abs_steps_.push_back(block_abs_steps_ / static_cast<double>(kStillBlockSamples));
      block_abs_steps_.setZero();
    }
  }
  if (count > 0) previous_ = samples[count - 1];
}

namespace {

// The largest change of consecutive block means against the typical one, axis by axis.
Stillness StillnessOf(const std::vector<Vec3>& means, const std::vector<Vec3>& mean_abs_steps,
                      const Vec3& quantum) {
  Stillness out;
  if (means.size() < kStillMinBlocks) return out;
  out.checked = true;
  double worst_ratio = -1;
  std::vector<double> changes(means.size() - 1);
  for (int a = 0; a < 3; ++a) {
    for (std::size_t j = 0; j + 1 < means.size(); ++j) {
      changes[j] = std::abs(means[j + 1](a) - means[j](a));
    }
    std::vector<double> sorted = changes;
    const auto middle = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2);
    std::nth_element(sorted.begin(), middle, sorted.end());
    // A sensor quieter than its quantum reads the same value for whole blocks: a change of one
    // quantum in a block's mean is then its noise.
    const double floor = std::isfinite(quantum(a)) ? quantum(a) / kStillBlockSamples : 0;
    const double typical = std::max(*middle, floor);
    const auto largest = std::max_element(changes.begin(), changes.end());
    const double ratio = typical > 0 ? *largest / typical : (*largest > 0 ? INFINITY : 0);
    if (ratio > worst_ratio) {
      worst_ratio = ratio;
      out.axis = a;
      out.largest_change = *largest;
      out.typical_change = typical;
      out.at_sample = static_cast<std::size_t>(largest - changes.begin() + 1) * kStillBlockSamples;
    }
  }
  out.still = worst_ratio <= kStillChangeRatio;
  if (!out.still) return out;
  // Against the typical step between neighbouring samples (Stillness).
  std::vector<double> steps(mean_abs_steps.size());
  for (int a = 0; a < 3 && !steps.empty(); ++a) {
    // The quietest block's: a turn in most blocks (short positions) does not raise it.
    for (std::size_t j = 0; j < steps.size(); ++j) steps[j] = mean_abs_steps[j](a);
    const double quietest = *std::min_element(steps.begin(), steps.end());
    const double step = std::max(quietest, std::isfinite(quantum(a)) ? quantum(a) : 0.0);
    double largest = 0;
    std::size_t at = 0;
    for (std::size_t j = 0; j + 1 < means.size(); ++j) {
      const double change = std::abs(means[j + 1](a) - means[j](a));
      if (change > largest) largest = change, at = j + 1;
    }
    if (step > 0 && largest > kStillStepRatio * step) {
      out.still = false;
      out.beyond_steps = true;
      out.axis = a;
      out.largest_change = largest;
      out.typical_change = step;
      out.at_sample = at * kStillBlockSamples;
      return out;
    }
  }
  return out;
}

// The largest step between neighbouring samples against the typical one, axis by axis.
Spikes SpikesOf(const std::vector<Vec3>& block_mean_abs_steps, const Vec3& largest,
                const std::array<std::size_t, 3>& at, const Vec3& quantum) {
  Spikes out;
  if (block_mean_abs_steps.size() < kStillMinBlocks) return out;
  out.checked = true;
  double worst_ratio = -1;
  std::vector<double> typical(block_mean_abs_steps.size());
  for (int a = 0; a < 3; ++a) {
    for (std::size_t j = 0; j < typical.size(); ++j) typical[j] = block_mean_abs_steps[j](a);
    const auto middle = typical.begin() + static_cast<std::ptrdiff_t>(typical.size() / 2);
    std::nth_element(typical.begin(), middle, typical.end());
    // A reading quieter than its quantum: a step of one quantum is its noise.
    const double step = std::max(*middle, std::isfinite(quantum(a)) ? quantum(a) : 0.0);
    const double ratio = step > 0 ? largest(a) / step : (largest(a) > 0 ? INFINITY : 0);
    if (ratio > worst_ratio) {
      worst_ratio = ratio;
      out.axis = a;
      out.largest_step = largest(a);
      out.typical_step = step;
      out.at_sample = at[static_cast<std::size_t>(a)];
    }
  }
  out.clean = worst_ratio <= kSpikeRatio;
  return out;
}

}  // namespace

NoiseAnalysis NoiseAccumulator::Finish(double sample_period_s) const {
  NoiseAnalysis out;
  out.samples = samples_;
  out.sample_period_s = sample_period_s;
  std::size_t terms = 0;
  for (bool fitted : options_.fit.terms) terms += fitted ? 1 : 0;
  for (int a = 0; a < 3; ++a) {
    AxisNoise& result = out.axes[static_cast<std::size_t>(a)];
    result.points = axes_[static_cast<std::size_t>(a)].Points(sample_period_s);
    if (result.points.size() < terms + 1) {
      throw DataError(
          std::to_string(samples_) + " samples give " + std::to_string(result.points.size()) +
          " octaves of averaging time (m with 4 m within the samples); the " +
          std::to_string(terms) + " noise terms need at least " + std::to_string(terms + 1) + ": " +
          std::to_string(std::size_t{1} << (terms + 2)) + " samples or more");
    }
    const std::string axis = "the " + std::string(1, "xyz"[a]) + " axis";
    if (low_(a) == high_(a)) {
      throw DataError(axis +
                      " reads the same value throughout: it has no noise to characterise "
                      "(a constant or missing column?)");
    }
    const std::size_t steps = samples_ - 1;
    if (static_cast<double>(changes_[static_cast<std::size_t>(a)]) <
        kMinChangingSteps * static_cast<double>(steps)) {
      throw DataError(internal::Format(
          "%s changes in %zu of its %zu steps: it reads one value nearly throughout (a stuck "
          "column, or readings quantised far coarser than their noise); what its Allan variance "
          "shows is those changes, not noise",
          axis.c_str(), changes_[static_cast<std::size_t>(a)], steps));
    }
    const double magnitude = std::max(std::abs(low_(a)), std::abs(high_(a)));
    if (magnitude > kMaxNoiseMagnitude || high_(a) - low_(a) < kMinNoiseSpread) {
      throw DataError(internal::Format(
          "%s reads values up to %.3g, varying by %.3g: beyond the %g to %g the noise analysis "
          "holds in double precision (the Allan variance sums their squares): give them in another "
          "unit",
          axis.c_str(), magnitude, high_(a) - low_(a), kMinNoiseSpread, kMaxNoiseMagnitude));
    }
    try {
      result.fit = FitNoiseModel(result.points, options_.fit);
    } catch (const std::invalid_argument& e) {
      // Points that do not tell the terms apart: an axis whose Allan variance is 0 beyond its
      // first averaging time (a reading that alternates between two values, or repeats a
      // pattern of a few samples) has no noise the terms describe.
      std::string why = e.what();
      const std::string prefix = "FitNoiseModel: ";
      if (why.compare(0, prefix.size(), prefix) == 0) why.erase(0, prefix.size());
      throw DataError(axis + "'s Allan variance cannot be fitted: " + why +
                      " (a reading that repeats a pattern of a few samples has no noise the terms "
                      "describe)");
    }
  }
  out.mean = first_ + sum_ / static_cast<double>(samples_);
  out.stillness = StillnessOf(block_means_, block_mean_abs_steps_, quantum_);
  out.spikes = SpikesOf(block_mean_abs_steps_, largest_step_, largest_step_at_, quantum_);
  return out;
}

NoiseAnalysis AnalyseNoise(const std::vector<Vec3>& samples, double sample_period_s,
                           const NoiseOptions& options) {
  NoiseAccumulator accumulator(sample_period_s, options);
  accumulator.Add(samples.data(), samples.size());
  return accumulator.Finish();
}

}  // namespace accelcal
