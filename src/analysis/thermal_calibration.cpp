// Calibration with parameters that follow temperature (thermal_calibration.hpp).
#include "accelcal/thermal_calibration.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "accelcal/calibrate.hpp"
#include "accelcal/error.hpp"
#include "accelcal/simulate.hpp"
#include "core/text_format.hpp"
#include "solvers/thermal_fit.hpp"
#include "statistics/held_out.hpp"

namespace accelcal {

std::optional<std::string> ThermalOptions::Validate() const {
  if (auto why = base.Validate()) return why;
  if (base.method != SolverMethod::kJoint)
    return "a thermal calibration is fitted by the joint method";
  if (base.frame != Frame::kXFirst) return "a thermal calibration is fitted in the x-first frame";
  if (base.estimator != Estimator::kMaximumLikelihood) {
    return "a thermal calibration is fitted by maximum likelihood";
  }
  if (!base.bias_model.constant()) {
    return "a thermal calibration takes the bias as a function of temperature, not of time";
  }
  try {
    (void)ThermalSlots(base.model, degrees);
  } catch (const std::invalid_argument& e) {
    return std::string(e.what());
  }
  for (double t : temperatures_c) {
    if (!std::isfinite(t) || t < -273.15) return "temperatures must be finite and above 0 K";
  }
  if (t_ref_c && !(std::isfinite(*t_ref_c) && *t_ref_c >= -273.15)) {
    return "t_ref_c must be finite and above 0 K";
  }
  return std::nullopt;
}

std::vector<double> ThermalGravityNormErrors(const ThermalParameters& params,
                                             const std::vector<Vec3>& readings,
                                             const std::vector<double>& temperatures_c,
                                             double gravity) {
  std::vector<double> errors;
  errors.reserve(readings.size());
  for (std::size_t k = 0; k < readings.size(); ++k) {
    errors.push_back(GravityNormErrors(params.At(temperatures_c.at(k)), {readings[k]}, gravity)[0]);
  }
  return errors;
}

std::vector<Vec3> SimulateThermalPositions(const ThermalParameters& truth, double gravity,
                                           const std::vector<Vec3>& directions,
                                           const std::vector<double>& temperatures_c,
                                           const Vec3& sigma_raw, std::uint64_t seed) {
  if (temperatures_c.size() != directions.size()) {
    throw std::invalid_argument("one temperature per direction is needed");
  }
  // μ is linear in θ: the readings at T_ref plus the change of μ from T_ref to T_k.
  const ModelParameters at_ref = truth.At(truth.t_ref_c);
  std::vector<Vec3> readings = SimulatePositions(at_ref, gravity, directions, sigma_raw, seed);
  for (std::size_t k = 0; k < readings.size(); ++k) {
    const Vec3 f = gravity * directions[k].normalized();
    readings[k] += PredictRaw(truth.At(temperatures_c[k]), f) - PredictRaw(at_ref, f);
  }
  return readings;
}

namespace {

// The fit of `readings` from `start` and its directions.
internal::ThermalFit Fit(const std::vector<Vec3>& readings, const ThermalOptions& options,
                         const std::vector<double>& temperatures_c, const ThermalParameters& start,
                         const std::vector<Vec3>& dirs) {
  const internal::Problem problem{readings, options.base.gravity, options.base.model};
  internal::ThermalFit fit =
      internal::SolveThermal(problem, temperatures_c, start, dirs, options.base.joint);
  if (fit.summary.rank_deficient) {
    throw DataError(internal::Format(
        "the positions' temperatures and orientations do not determine a thermal model of degrees "
        "%s (reciprocal condition %.2g): record the orientations at %d temperatures or more, or "
        "lower the degrees",
        options.degrees.ToString().c_str(), std::max(0.0, fit.summary.reciprocal_condition),
        options.degrees.Max() + 1));
  }
  return fit;
}

}  // namespace

ThermalResult CalibrateThermal(const std::vector<Vec3>& readings, const ThermalOptions& options) {
  if (auto why = options.Validate()) throw std::invalid_argument(*why);
  if (options.temperatures_c.size() != readings.size()) {
    throw std::invalid_argument("temperatures_c has " +
                                std::to_string(options.temperatures_c.size()) + " for " +
                                std::to_string(readings.size()) + " readings");
  }
  const std::vector<double>& temps = options.temperatures_c;
  const double t_ref =
      options.t_ref_c.value_or(readings.empty() ? 0.0
                                                : std::accumulate(temps.begin(), temps.end(), 0.0) /
                                                      static_cast<double>(temps.size()));
  // The start: one calibration of every position, as if temperature did not matter.
  CalibrationOptions constant = options.base;
  constant.cross_validate = false;
  constant.outliers.policy = OutlierPolicy::kOff;
  constant.reading_sigmas.clear();
  const CalibrationResult constant_fit = Calibrate(readings, constant);
  ThermalParameters start = UnpackThermal(
      Eigen::VectorXd::Zero(
          static_cast<Eigen::Index>(ThermalSlots(options.base.model, options.degrees).size())),
      options.base.model, options.degrees, t_ref);
  start.coefficients[0] = constant_fit.params;

  const internal::ThermalFit fit = Fit(readings, options, temps, start, constant_fit.directions);
  ThermalResult result;
  result.model = options.base.model;
  result.gravity = options.base.gravity;
  result.params = fit.params;
  result.directions = fit.dirs;
  result.residuals = fit.residuals;
  const int n = static_cast<int>(fit.U.cols()), m = static_cast<int>(readings.size());
  result.degrees_of_freedom = m - n;
  Summary& s = result.summary;
  s.method = SolverMethod::kJoint;
  s.iterations = constant_fit.summary.iterations + fit.summary.iterations;
  s.termination = fit.summary.termination;
  s.termination_message =
      "thermal " + options.degrees.ToString() + ": " + fit.summary.termination_message;
  s.initial_cost = fit.summary.initial_cost;
  s.final_cost = fit.summary.final_cost;
  if (result.degrees_of_freedom > 0 && fit.S_inverse.rows() == n) {
    const double sigma2 = fit.summary.final_cost / result.degrees_of_freedom;
    result.residual_sigma = std::sqrt(sigma2);
    result.covariance = sigma2 * fit.S_inverse;
  }
  if (!options.cross_validate || !s.converged()) return result;

  // Leave one position out: each refit starts from the full fit.
  CalibrationResult shim;  // the one leave-one-out loop reads its exclusions and fills its rms
  shim.model = result.model;
  shim.gravity = result.gravity;
  shim.params = result.params.At(t_ref);
  internal::LeaveOneOut(
      readings,
      [&](std::size_t k) -> internal::HeldOutRefit {
        std::vector<Vec3> subset, dirs;
        std::vector<double> subset_temps;
        for (std::size_t j = 0; j < readings.size(); ++j) {
          if (j == k) continue;
          subset.push_back(readings[j]);
          dirs.push_back(result.directions[j]);
          subset_temps.push_back(temps[j]);
        }
        const std::string without = "without position " + std::to_string(k + 1) + ": ";
        internal::ThermalFit refit;
        try {
          refit = Fit(subset, options, subset_temps, result.params, dirs);
        } catch (const DataError& e) {
          return {0.0, without + e.what()};
        }
        if (!refit.summary.converged()) {
          return {0.0, without + "did not converge: " + refit.summary.termination_message};
        }
        return internal::HeldOutErrorUnder(refit.params.At(temps[k]), readings[k],
                                           options.base.gravity, k);
      },
      &shim);
  result.crossval_errors = shim.crossval_errors;
  result.crossval_rms = shim.crossval_rms;
  result.crossval_note = shim.crossval_note;
  return result;
}

}  // namespace accelcal
