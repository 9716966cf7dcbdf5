// Calibration with parameters that follow temperature (thermal_calibration.hpp).
#include "accelcal/thermal_calibration.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include <Eigen/Cholesky>

#include "accelcal/calibrate.hpp"
#include "accelcal/error.hpp"
#include "accelcal/model_selection.hpp"
#include "accelcal/simulate.hpp"
#include "core/text_format.hpp"
#include "solvers/thermal_fit.hpp"
#include "statistics/held_out.hpp"
#include "statistics/student_t.hpp"

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
  CalibrationResult result;
  result.gravity = gravity;
  result.thermal = ThermalTerms{params, {}, temperatures_c};
  return GravityNormErrors(result, readings);
}

CalibrationResult AsCalibrationResult(const ThermalResult& thermal,
                                      const std::vector<double>& temperatures_c) {
  if (temperatures_c.size() != thermal.residuals.size()) {
    throw std::invalid_argument("AsCalibrationResult: one temperature per reading is needed");
  }
  CalibrationResult r;
  r.model = thermal.model;
  r.frame = Frame::kXFirst;
  r.gravity = thermal.gravity;
  r.params = thermal.params.At(thermal.params.t_ref_c);
  r.directions = thermal.directions;
  r.residuals = thermal.residuals;
  const auto n = static_cast<Eigen::Index>(NumParameters(thermal.model));
  if (thermal.covariance.rows() >= n) r.covariance = thermal.covariance.topLeftCorner(n, n);
  r.residual_sigma = thermal.residual_sigma;
  r.degrees_of_freedom = thermal.degrees_of_freedom;
  r.summary = thermal.summary;
  r.crossval_rms = thermal.crossval_rms;
  r.crossval_errors = thermal.crossval_errors;
  r.crossval_note = thermal.crossval_note;
  r.thermal = ThermalTerms{thermal.params, thermal.covariance, temperatures_c};
  return r;
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
  if (auto why = options.Validate()) throw OptionError(*why);
  const auto start_time = std::chrono::steady_clock::now();
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
  const ThermalParameters start =
      ConstantOverTemperature(constant_fit.params, options.base.model, options.degrees, t_ref);

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
  s.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count();
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

ThermalDegreeSelection SelectThermalDegrees(const std::vector<Vec3>& readings,
                                            ThermalOptions options, int max_degree) {
  if (max_degree < 0 || max_degree > kMaxThermalDegree) {
    throw std::invalid_argument("max_degree must be from 0 to " +
                                std::to_string(kMaxThermalDegree));
  }
  options.cross_validate = true;
  options.degrees = ThermalDegrees{};
  ThermalDegreeSelection selection;
  selection.result = CalibrateThermal(readings, options);
  if (!selection.result.crossval_rms) {
    selection.reason = "no temperature terms: the constant fit cannot be validated (" +
                       selection.result.crossval_note + ")";
    return selection;
  }
  std::vector<int> all(readings.size());
  std::iota(all.begin(), all.end(), 0);
  std::vector<std::string> passed_over;
  for (;;) {
    const ThermalDegrees current = selection.chosen;
    std::vector<ThermalDegrees> candidates;
    for (int g = 0; g < 3; ++g) {
      if (g == 2 && options.base.model != ModelKind::kQuadratic) continue;
      ThermalDegrees d = current;
      int& degree = g == 0 ? d.K : g == 1 ? d.bias : d.k2;
      if (degree >= max_degree) continue;
      ++degree;
      candidates.push_back(d);
    }
    int best = -1;
    ThermalResult best_result;
    for (const ThermalDegrees& d : candidates) {
      ThermalDegreeStep step;
      step.simpler = current;
      step.richer = d;
      step.simpler_rms = *selection.result.crossval_rms;
      ThermalOptions o = options;
      o.degrees = d;
      ThermalResult richer;
      try {
        richer = CalibrateThermal(readings, o);
        if (!richer.crossval_rms) step.error = "cannot be validated: " + richer.crossval_note;
      } catch (const DataError& e) {
        step.error = e.what();
      }
      if (step.error.empty()) {
        const internal::Paired paired = internal::PairedImprovement(
            selection.result.crossval_errors, richer.crossval_errors, all);
        const auto n = static_cast<int>(all.size());
        step.richer_rms = *richer.crossval_rms;
        step.improvement = paired.mean;
        step.improvement_se = paired.se;
        step.improvement_threshold =
            internal::StudentTTwoSidedQuantile(2 * kHeldOutImprovementAlpha, n - 1) * paired.se;
        // The coefficients the step adds: its group's slots at its new degree.
        const std::vector<ThermalSlot> slots = ThermalSlots(options.base.model, d);
        std::vector<Eigen::Index> added;
        for (std::size_t i = 0; i < slots.size(); ++i) {
          if (slots[i].degree == d.Of(slots[i].slot.group) && slots[i].degree > 0 &&
              d.Of(slots[i].slot.group) != current.Of(slots[i].slot.group)) {
            added.push_back(static_cast<Eigen::Index>(i));
          }
        }
        step.wald_dof = static_cast<int>(added.size());
        step.wald_threshold = internal::ChiSquareQuantile(kThermalAlpha, step.wald_dof);
        if (richer.covariance.rows() > 0) {
          const Eigen::VectorXd x = Pack(richer.params, options.base.model);
          Eigen::VectorXd e(step.wald_dof);
          Eigen::MatrixXd C(step.wald_dof, step.wald_dof);
          for (int i = 0; i < step.wald_dof; ++i) {
            e(i) = x(added[std::size_t(i)]);
            for (int j = 0; j < step.wald_dof; ++j) {
              C(i, j) = richer.covariance(added[std::size_t(i)], added[std::size_t(j)]);
            }
          }
          step.wald = e.dot(C.ldlt().solve(e));
        } else {
          step.wald = std::nan("");
        }
        step.accepted =
            step.improvement > step.improvement_threshold && step.wald > step.wald_threshold;
      }
      if (!step.accepted) {
        passed_over.push_back(d.ToString() +
                              (step.error.empty()
                                   ? internal::Format(" (held-out %.4g against %.4g, "
                                                      "Wald %.3g)",
                                                      step.richer_rms, step.simpler_rms, step.wald)
                                   : " (" + step.error + ")"));
      } else if (best < 0 || step.improvement > selection.steps[std::size_t(best)].improvement) {
        best = static_cast<int>(selection.steps.size());
        best_result = std::move(richer);
      }
      selection.steps.push_back(step);
    }
    if (best < 0) break;
    selection.chosen = selection.steps[std::size_t(best)].richer;
    selection.result = std::move(best_result);
  }
  selection.reason = "degrees " + selection.chosen.ToString() +
                     ": each raised while it predicted held-out positions better beyond sampling "
                     "error with significant coefficients";
  if (!passed_over.empty()) {
    selection.reason += "; passed over:";
    for (const std::string& p : passed_over) selection.reason += " " + p + ";";
    selection.reason.pop_back();
  }
  return selection;
}

}  // namespace accelcal
