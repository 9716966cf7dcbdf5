// Leave-one-position-out by refits: the reference of held_out.hpp's expansion, and the refit it
// falls back to for a position it cannot serve.
#include <cmath>
#include <stdexcept>
#include <string>

#include "accelcal/error.hpp"
#include "statistics/fit.hpp"
#include "statistics/held_out.hpp"

namespace accelcal::internal {

namespace {

// The options of a refit without one position: started from the full fit, the same positions.
CalibrationOptions HeldOutOptions(const CalibrationOptions& options,
                                  const CalibrationResult& result) {
  CalibrationOptions held_out = options;
  held_out.cross_validate = false;
  held_out.outliers.policy = OutlierPolicy::kOff;  // the same positions as the full fit
  // No covariance is needed from the held-out fits, but a random-walk prior weighs the readings
  // by their noise.
  if (!options.bias_random_walk) held_out.reading_sigmas.clear();
  if (options.method != SolverMethod::kEllipsoid) {  // closed form: nothing to start from
    held_out.initialization = Initialization::kGiven;
    held_out.initial_params = result.params;
  }
  if (result.drift) held_out.bias_basis = result.drift->basis;  // the same knots and t_ref
  return held_out;
}

}  // namespace

// Position k's held-out error from a fit of the other positions in the fit, or why there is none.
HeldOutRefit RefitWithout(const std::vector<Vec3>& readings, const CalibrationOptions& options,
                          const CalibrationResult& result, std::size_t k) {
  std::vector<int> keep;
  std::vector<Vec3> subset;
  for (std::size_t j = 0; j < readings.size(); ++j) {
    if (j != k && !result.excluded(j)) {
      keep.push_back(static_cast<int>(j));
      subset.push_back(readings[j]);
    }
  }
  const CalibrationOptions held_out = OptionsForPositions(HeldOutOptions(options, result), keep);
  const std::string without = "without position " + std::to_string(k + 1) + ": ";
  CalibrationResult fit;
  try {
    fit = CalibrateInFrame(subset, held_out).result;
  } catch (const DataError& e) {
    return {0.0, without + e.what()};
  }
  if (!fit.summary.converged()) {
    return {0.0, without + "did not converge: " + fit.summary.termination_message};
  }
  const Vec3 offset = fit.drift ? fit.drift->Offset(options.position_times_s[k]) : Vec3::Zero();
  return HeldOutErrorUnder(fit.params, readings[k] - offset, options.gravity, k);
}

HeldOutRefit HeldOutErrorUnder(const ModelParameters& without, const Vec3& reading, double gravity,
                               std::size_t k) {
  const double e = GravityNormErrors(without, {reading}, gravity)[0];
  if (!std::isfinite(e)) {
    return {0.0,
            "position " + std::to_string(k + 1) + " lies outside the range of the fit without it"};
  }
  return {e, ""};
}

// Leave-one-position-out by m refits, each started from the full fit (the held-out optimum is
// close to it, so each refit takes a few iterations). Positions the screening excluded are held
// out of every fit already: their error is that of the final fit.
void CrossValidateByRefits(const std::vector<Vec3>& readings, const CalibrationOptions& options,
                           CalibrationResult* result) {
  if (auto why = options.Validate()) throw OptionError(*why);
  LeaveOneOut(
      readings, [&](std::size_t k) { return RefitWithout(readings, options, *result, k); }, result);
}

void LeaveOneOut(const std::vector<Vec3>& readings, const HeldOutRefitFunction& refit_without,
                 CalibrationResult* result) {
  const std::vector<double> under_result = GravityNormErrors(*result, readings);
  std::vector<double> errors;
  for (std::size_t k = 0; k < readings.size(); ++k) {
    if (result->excluded(k)) {
      errors.push_back(under_result[k]);
      continue;
    }
    const HeldOutRefit refit = refit_without(k);
    if (!refit.note.empty()) {
      result->crossval_note = refit.note;
      return;
    }
    errors.push_back(refit.error);
  }
  result->crossval_rms = Rms(result->InFit(errors));
  result->crossval_errors = std::move(errors);
}

}  // namespace accelcal::internal
