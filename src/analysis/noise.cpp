// A still sensor's noise, axis by axis (noise.hpp).
#include "accelcal/noise.hpp"

#include <cmath>
#include <string>

#include "accelcal/error.hpp"

namespace accelcal {

NoiseAnalysis AnalyseNoise(const std::vector<Vec3>& samples, double sample_period_s,
                           const NoiseOptions& options) {
  NoiseAnalysis out;
  out.samples = samples.size();
  out.sample_period_s = sample_period_s;
  AllanOptions allan;
  allan.sample_period_s = sample_period_s;
  allan.full_overlap_up_to = options.full_overlap_up_to;
  std::size_t terms = 0;
  for (bool fitted : options.fit.terms) terms += fitted ? 1 : 0;
  std::vector<double> axis(samples.size());
  for (int a = 0; a < 3; ++a) {
    for (std::size_t k = 0; k < samples.size(); ++k) axis[k] = samples[k](a);
    AllanAccumulator accumulator(allan);
    accumulator.Add(axis.data(), axis.size());
    AxisNoise& result = out.axes[static_cast<std::size_t>(a)];
    result.points = accumulator.Points();
    if (result.points.size() < terms + 1) {
      throw DataError(
          std::to_string(samples.size()) + " samples give " + std::to_string(result.points.size()) +
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
    result.fit = FitNoiseModel(result.points, options.fit);
  }
  return out;
}

}  // namespace accelcal
