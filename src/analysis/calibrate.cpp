// Calibrate: the screened fit (statistics/outliers.hpp) and its leave-one-position-out
// validation (statistics/held_out.hpp).
#include "accelcal/calibrate.hpp"

#include <stdexcept>

#include "accelcal/error.hpp"
#include "statistics/fit.hpp"
#include "statistics/held_out.hpp"
#include "statistics/outliers.hpp"

namespace accelcal {

// The same numbers from an expansion of the full fit, refitting only the positions it cannot serve
// (held_out.hpp).
void CrossValidate(const std::vector<Vec3>& readings, const CalibrationOptions& options,
                   CalibrationResult* result) {
  if (auto why = options.Validate()) throw OptionError(*why);
  const CalibrationResult& full = *result;
  if (full.drift) {  // the expansion is the constant bias's: refits
    internal::CrossValidateByRefits(readings, options, result);
    return;
  }
  internal::HeldOutErrors(
      readings, options,
      [&](std::size_t k) { return internal::RefitWithout(readings, options, full, k); }, result);
}

CalibrationResult Calibrate(const std::vector<Vec3>& readings, const CalibrationOptions& options) {
  if (auto why = options.Validate()) throw OptionError(*why);
  internal::CheckReadingSigmas(options.reading_sigmas, readings.size());
  internal::CheckDistinctReadings(readings);
  CalibrationResult result = internal::CalibrateScreened(readings, options);
  if (result.summary.converged()) result.screening = options.outliers.policy;
  if (options.cross_validate && result.summary.converged()) {
    CrossValidate(readings, options, &result);
  }
  return result;
}

}  // namespace accelcal
