// Name tables, validation and small members of the calibration vocabulary (calibration_types.hpp).
#include "accelcal/calibration_types.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/median.hpp"
#include "core/text_format.hpp"
#include "solvers/solver_common.hpp"

namespace accelcal {

std::string_view ToString(SolverMethod method) { return NameOf(method); }
std::optional<SolverMethod> SolverMethodFromString(std::string_view text) {
  return FromName<SolverMethod>(text);
}

std::string_view ToString(Estimator estimator) { return NameOf(estimator); }
std::optional<Estimator> EstimatorFromString(std::string_view text) {
  return FromName<Estimator>(text);
}

std::string_view ToString(OutlierPolicy policy) { return NameOf(policy); }
std::optional<std::string> OutlierOptions::Validate() const {
  if (!(false_alarm_probability > 0 && false_alarm_probability < 1)) {
    return "{{outlier_probability}} must be in (0, 1)";
  }
  if (max_excluded < 0) return "{{max_outliers}} must be non-negative";
  return std::nullopt;
}

std::string_view ToString(OutlierStatistic statistic) {
  return statistic == OutlierStatistic::kFisherF ? "F" : "t";
}
std::optional<OutlierPolicy> OutlierPolicyFromString(std::string_view text) {
  return FromName<OutlierPolicy>(text);
}

std::vector<Vec3> CalibrationResult::DriftOffsets(std::size_t readings) const {
  std::vector<Vec3> offsets(readings, Vec3::Zero());
  if (!drift) return offsets;
  if (drift->times_s.size() != readings) {
    throw std::invalid_argument("the drift has " + std::to_string(drift->times_s.size()) +
                                " position times for " + std::to_string(readings) + " readings");
  }
  for (std::size_t k = 0; k < readings; ++k) {
    offsets[k] = drift->Offset(drift->times_s[k]);
  }
  return offsets;
}

int CalibrationResult::positions_used() const {
  int used = static_cast<int>(directions.size());
  for (const OutlierFinding& o : outliers) used -= o.excluded ? 1 : 0;
  return used;
}

std::vector<double> CalibrationResult::InFit(const std::vector<double>& per_position) const {
  std::vector<double> kept;
  kept.reserve(per_position.size());
  for (std::size_t k = 0; k < per_position.size(); ++k) {
    if (!excluded(k)) kept.push_back(per_position[k]);
  }
  return kept;
}

std::string_view ToString(Initialization init) { return NameOf(init); }
std::optional<Initialization> InitializationFromString(std::string_view text) {
  return FromName<Initialization>(text);
}

std::string_view ToString(TerminationType type) { return NameOf(type); }

std::optional<std::string> CalibrationOptions::Validate() const {
  if (!(gravity > 0) || !std::isfinite(gravity)) return "gravity must be a positive number";
  if (two_step.max_sweeps < 1) return "two_step.max_sweeps must be at least 1";
  if (two_step.max_newton_iterations < 1) return "two_step.max_newton_iterations must be >= 1";
  if (!(two_step.parameter_tolerance >= 0) || !(two_step.function_tolerance >= 0)) {
    return "two-step tolerances must be non-negative";
  }
  if (joint.max_iterations < 1) return "joint.max_iterations must be at least 1";
  if (!(joint.parameter_tolerance >= 0) || !(joint.function_tolerance >= 0)) {
    return "joint tolerances must be non-negative";
  }
  if (!(joint.initial_damping > 0)) return "joint.initial_damping must be positive";
  if (modulus.max_iterations < 1) return "modulus.max_iterations must be at least 1";
  if (!(modulus.parameter_tolerance >= 0) || !(modulus.function_tolerance >= 0)) {
    return "modulus tolerances must be non-negative";
  }
  if (newton_lagrange.max_iterations < 1) return "newton_lagrange.max_iterations must be >= 1";
  if (!(newton_lagrange.parameter_tolerance >= 0)) {
    return "newton_lagrange.parameter_tolerance must be non-negative";
  }
  if ((initialization == Initialization::kGiven) != initial_params.has_value()) {
    return "initial_params must be given exactly when initialization is kGiven";
  }
  if (initial_params && !(initial_params->K.allFinite() && initial_params->bias.allFinite() &&
                          initial_params->k2.allFinite())) {
    return "initial_params must be finite";
  }
  if (method == SolverMethod::kKnownOrientation || frame == Frame::kPlatform) {
    return "known orientations (the platform frame) need CalibrateKnownOrientations "
           "(known_orientation.hpp)";
  }
  if (estimator == Estimator::kBiasCorrected && !IsMaximumLikelihood(method)) {
    return "the bias-corrected estimator corrects maximum likelihood: it does not apply to the " +
           std::string(ToString(method)) + " method";
  }
  if (auto why = outliers.Validate()) return why;
  if (bias_correction.max_rounds < 1) return "bias_correction.max_rounds must be at least 1";
  if (!(bias_correction.tolerance > 0)) return "bias_correction.tolerance must be positive";
  if (method == SolverMethod::kEllipsoid && initialization != Initialization::kAuto &&
      initialization != Initialization::kEllipsoidFit) {
    return "the ellipsoid method is the ellipsoid fit: it takes no other initialisation";
  }
  if ((method == SolverMethod::kModulus || method == SolverMethod::kModulusNorm ||
       method == SolverMethod::kNewtonLagrange || method == SolverMethod::kEllipsoid) &&
      model != ModelKind::kLinear) {
    return "the " + std::string(ToString(method)) + " method fits the linear model only";
  }
  if (!bias_model.constant()) {
    const std::string name = ToString(bias_model);
    if (bias_model.kind == BiasModelKind::kSpline &&
        (bias_model.knots < 2 || bias_model.knots > kMaxBiasKnots)) {
      return "a spline bias has 2 to " + std::to_string(kMaxBiasKnots) + " knots";
    }
    if (method != SolverMethod::kJoint) {
      return "a " + name + " bias is fitted by the joint method only, not " +
             std::string(ToString(method));
    }
    if (estimator != Estimator::kMaximumLikelihood) {
      return "a " + name + " bias is fitted by maximum likelihood only";
    }
  }
  if (bias_random_walk && !(bias_random_walk->allFinite() && bias_random_walk->minCoeff() > 0)) {
    return "bias_random_walk must be finite and positive";
  }
  if (bias_random_walk && bias_model.kind == BiasModelKind::kSpline && reading_sigmas.empty()) {
    return "a random walk of the bias weighs the readings by their noise: it needs reading_sigmas";
  }
  if (bias_basis && bias_basis->model != bias_model) {
    return "bias_basis is the basis of another bias model";
  }
  return std::nullopt;
}

std::string Summary::BriefReport() const {
  char buf[512];
  internal::FormatTo(
      buf, sizeof buf, "%s solver, init %s: %s after %d iterations (%s); J %.6e -> %.6e; %.1f us",
      std::string(ToString(method)).c_str(), std::string(ToString(initialization)).c_str(),
      converged() ? "converged" : "NOT CONVERGED", iterations, termination_message.c_str(),
      initial_cost, final_cost, time_s * 1e6);
  if (estimator == Estimator::kBiasCorrected) {
    return std::string(buf) + "; bias-corrected in " + std::to_string(correction_rounds) +
           " refits";
  }
  return buf;
}

std::vector<double> GravityNormErrors(const ModelParameters& params,
                                      const std::vector<Vec3>& readings, double gravity) {
  std::vector<double> errors;
  errors.reserve(readings.size());
  for (const Vec3& p : readings) {
    const std::optional<Vec3> f = SpecificForce(params, p);
    errors.push_back(f ? f->norm() - gravity : std::nan(""));
  }
  return errors;
}

std::vector<double> GravityNormErrors(const CalibrationResult& result,
                                      const std::vector<Vec3>& readings) {
  if (result.thermal) {
    const ThermalTerms& t = *result.thermal;
    if (t.temperatures_c.size() != readings.size()) {
      throw std::invalid_argument("GravityNormErrors: one temperature per reading is needed");
    }
    std::vector<double> errors;
    errors.reserve(readings.size());
    for (std::size_t k = 0; k < readings.size(); ++k) {
      errors.push_back(
          GravityNormErrors(t.params.At(t.temperatures_c[k]), {readings[k]}, result.gravity)[0]);
    }
    return errors;
  }
  if (!result.drift) return GravityNormErrors(result.params, readings, result.gravity);
  const std::vector<Vec3> offsets = result.DriftOffsets(readings.size());
  std::vector<Vec3> corrected(readings.size());
  for (std::size_t k = 0; k < readings.size(); ++k) corrected[k] = readings[k] - offsets[k];
  return GravityNormErrors(result.params, corrected, result.gravity);
}

std::optional<double> GravityNormRmsUncalibrated(const std::vector<Vec3>& readings,
                                                 double gravity) {
  if (readings.empty()) return std::nullopt;
  std::vector<double> norms;
  for (const Vec3& p : readings) norms.push_back(p.norm());
  const double median = internal::Median(norms);
  if (std::abs(median - gravity) > 0.2 * gravity) return std::nullopt;
  for (double& v : norms) v -= gravity;
  return Rms(norms);
}

double Rms(const std::vector<double>& values) {
  if (values.empty()) return std::nan("");
  double sum = 0;
  for (double v : values) sum += v * v;
  return std::sqrt(sum / static_cast<double>(values.size()));
}

}  // namespace accelcal
