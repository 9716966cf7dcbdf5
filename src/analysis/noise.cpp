// A still sensor's noise, axis by axis (noise.hpp).
#include "accelcal/noise.hpp"

#include <cmath>
#include <string>

#include "accelcal/error.hpp"

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
  for (int a = 0; a < 3; ++a) axes_.emplace_back(AllanOf(sample_period_s, options));
}

void NoiseAccumulator::Add(const Vec3* samples, std::size_t count) {
  buffer_.resize(count);
  for (int a = 0; a < 3; ++a) {
    for (std::size_t k = 0; k < count; ++k) buffer_[k] = samples[k](a);
    axes_[static_cast<std::size_t>(a)].Add(buffer_.data(), count);
  }
  samples_ += count;
}

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
    bool constant = true;
    for (const AllanPoint& p : result.points) constant = constant && p.avar == 0;
    if (constant) {
      throw DataError("the " + std::string(1, "xyz"[a]) +
                      " axis reads the same value throughout: it has no noise to characterise "
                      "(a constant or missing column?)");
    }
    result.fit = FitNoiseModel(result.points, options_.fit);
  }
  return out;
}

NoiseAnalysis AnalyseNoise(const std::vector<Vec3>& samples, double sample_period_s,
                           const NoiseOptions& options) {
  NoiseAccumulator accumulator(sample_period_s, options);
  accumulator.Add(samples.data(), samples.size());
  return accumulator.Finish();
}

}  // namespace accelcal
