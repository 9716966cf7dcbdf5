#include "accelcal/calibrate.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "accelcal/ellipsoid_fit.hpp"
#include "accelcal/error.hpp"
#include "accelcal/frame.hpp"
#include "core/text_format.hpp"
#include "solvers/solver_common.hpp"
#include "statistics/held_out.hpp"
#include "statistics/outliers.hpp"

namespace accelcal {

std::string_view ToString(SolverMethod method) {
  switch (method) {
    case SolverMethod::kTwoStep:
      return "two-step";
    case SolverMethod::kJoint:
      return "joint";
    case SolverMethod::kModulus:
      return "modulus";
    case SolverMethod::kModulusNorm:
      return "modulus-norm";
    case SolverMethod::kNewtonLagrange:
      return "newton-lagrange";
    case SolverMethod::kEllipsoid:
      return "ellipsoid";
    case SolverMethod::kKnownOrientation:
      break;
  }
  return "known-orientation";
}
std::optional<SolverMethod> SolverMethodFromString(std::string_view text) {
  for (SolverMethod m : {SolverMethod::kTwoStep, SolverMethod::kJoint, SolverMethod::kModulus,
                         SolverMethod::kModulusNorm, SolverMethod::kNewtonLagrange,
                         SolverMethod::kEllipsoid, SolverMethod::kKnownOrientation}) {
    if (text == ToString(m)) return m;
  }
  return std::nullopt;
}

std::string_view ToString(Estimator estimator) {
  return estimator == Estimator::kMaximumLikelihood ? "ml" : "bias-corrected";
}
std::optional<Estimator> EstimatorFromString(std::string_view text) {
  if (text == "ml") return Estimator::kMaximumLikelihood;
  if (text == "bias-corrected") return Estimator::kBiasCorrected;
  return std::nullopt;
}

std::string_view ToString(OutlierPolicy policy) {
  switch (policy) {
    case OutlierPolicy::kOff:
      return "off";
    case OutlierPolicy::kFlag:
      return "flag";
    case OutlierPolicy::kExclude:
      break;
  }
  return "exclude";
}
std::optional<std::string> OutlierOptions::Validate() const {
  if (!(false_alarm_probability > 0 && false_alarm_probability < 1)) {
    return "false_alarm_probability must be in (0, 1)";
  }
  if (max_excluded < 0) return "max_excluded must be non-negative";
  return std::nullopt;
}

std::string_view ToString(OutlierStatistic statistic) {
  return statistic == OutlierStatistic::kFisherF ? "F" : "t";
}
std::optional<OutlierPolicy> OutlierPolicyFromString(std::string_view text) {
  for (OutlierPolicy p : {OutlierPolicy::kOff, OutlierPolicy::kFlag, OutlierPolicy::kExclude}) {
    if (text == ToString(p)) return p;
  }
  return std::nullopt;
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

std::string_view ToString(Initialization init) {
  switch (init) {
    case Initialization::kAuto:
      return "auto";
    case Initialization::kEllipsoidFit:
      return "ellipsoid";
    case Initialization::kNormalizedReadings:
      return "normalized-readings";
    case Initialization::kGiven:
      break;
  }
  return "given";
}
std::optional<Initialization> InitializationFromString(std::string_view text) {
  if (text == "auto") return Initialization::kAuto;
  if (text == "ellipsoid") return Initialization::kEllipsoidFit;
  if (text == "normalized-readings") return Initialization::kNormalizedReadings;
  if (text == "given") return Initialization::kGiven;
  return std::nullopt;
}

std::string_view ToString(TerminationType type) {
  switch (type) {
    case TerminationType::kParameterTolerance:
      return "parameter_tolerance";
    case TerminationType::kFunctionTolerance:
      return "function_tolerance";
    case TerminationType::kZeroResidual:
      return "zero_residual";
    case TerminationType::kMaxIterations:
      return "max_iterations";
    case TerminationType::kClosedForm:
      return "closed_form";
    case TerminationType::kNoProgress:
      break;
  }
  return "no_progress";
}

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
           "(known_orientation.hpp; the command line's --orientations)";
  }
  if (estimator == Estimator::kBiasCorrected && !IsMaximumLikelihood(method)) {
    return "the bias-corrected estimator corrects maximum likelihood: it does not apply to the " +
           std::string(ToString(method)) + " method";
  }
  if (auto why = outliers.Validate()) return "outliers." + *why;
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

std::optional<double> GravityNormRmsUncalibrated(const std::vector<Vec3>& readings,
                                                 double gravity) {
  if (readings.empty()) return std::nullopt;
  std::vector<double> norms;
  for (const Vec3& p : readings) norms.push_back(p.norm());
  std::vector<double> sorted = norms;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2),
                   sorted.end());
  const double median = sorted[sorted.size() / 2];
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

namespace {

using internal::Problem;

void CheckData(const std::vector<Vec3>& readings, ModelKind model) {
  const int m = static_cast<int>(readings.size());
  for (int k = 0; k < m; ++k) {
    if (!readings[k].allFinite()) {
      throw DataError("position " + std::to_string(k + 1) + " has a non-finite reading");
    }
  }
  if (m < MinimumPositions(model)) {
    throw DataError("the " + std::string(ToString(model)) + " model needs at least " +
                    std::to_string(MinimumPositions(model)) + " positions, got " +
                    std::to_string(m));
  }
  // Directions on one great circle put the readings on one plane (exactly for the linear model):
  // the axis normal to it is then not observable.
  Vec3 mean = Vec3::Zero();
  for (const Vec3& p : readings) mean += p;
  mean /= m;
  Mat33 scatter = Mat33::Zero();
  for (const Vec3& p : readings) scatter += (p - mean) * (p - mean).transpose();
  // Singular values of the centred readings, ascending.
  const Vec3 sv = Eigen::SelfAdjointEigenSolver<Mat33>(scatter, Eigen::EigenvaluesOnly)
                      .eigenvalues()
                      .cwiseMax(0.0)
                      .cwiseSqrt();
  if (!(sv(0) > 1e-3 * sv(2))) {
    char buf[256];
    internal::FormatTo(buf, sizeof buf,
                       "all %d positions lie in one plane (spread ratio %.2g): the sensor must be "
                       "turned about more than one axis",
                       m, sv(2) > 0 ? sv(0) / sv(2) : 0.0);
    throw DataError(buf);
  }
}

// Name of a 12-layout slot in the frame the user asked for.
std::string SlotName(int index, Frame frame) {
  return std::string(
      ParameterSlots(ModelKind::kQuadratic, frame)[static_cast<std::size_t>(index)].name);
}

void ThrowIfUnobservable(const internal::Information& info, ModelKind model, Frame frame) {
  if (info.rcond >= internal::kMinInformationRcond) return;
  char buf[256];
  internal::FormatTo(buf, sizeof buf,
                     "the positions do not determine the %s model: parameter %s is not observable "
                     "(reciprocal condition %.2g); add positions with other orientations",
                     std::string(ToString(model)).c_str(), SlotName(info.weakest, frame).c_str(),
                     info.rcond);
  throw DataError(buf);
}

struct Start {
  ModelParameters params;
  std::vector<Vec3> dirs;
  Initialization used;
  EllipsoidFitKind fit_kind = EllipsoidFitKind::kAlgebraic;
  std::string note;
};

Start Initialise(const Problem& problem, Initialization requested,
                 const std::optional<ModelParameters>& given) {
  Start start;
  if (requested == Initialization::kGiven) {
    start.params = *given;
    if (problem.model == ModelKind::kLinear) start.params.k2.setZero();
    start.dirs = internal::DirectionsFromParams(problem, start.params);
    start.used = Initialization::kGiven;
    return start;
  }
  if (requested != Initialization::kNormalizedReadings) {
    const EllipsoidFitResult fit = FitEllipsoid(problem.readings, problem.gravity);
    if (fit.ok) {
      start.params = fit.params;
      start.dirs = internal::DirectionsFromParams(problem, fit.params);
      start.used = Initialization::kEllipsoidFit;
      start.fit_kind = fit.kind;
      if (fit.kind == EllipsoidFitKind::kConstrained) {
        start.note = "algebraic ellipsoid fit rejected (" + fit.failure +
                     "); started from the constrained fit of Li & Griffiths (2004)";
      }
      return start;
    }
    if (requested == Initialization::kEllipsoidFit) {
      throw DataError("ellipsoid-fit initialisation failed: " + fit.failure);
    }
    start.note = "ellipsoid fit failed (" + fit.failure + "); used normalised readings";
  }
  // Paper 000 eq. (26): directions are the normalised raw readings, then eq. (15) for θ.
  start.dirs.reserve(problem.readings.size());
  for (const Vec3& p : problem.readings) start.dirs.push_back(p.normalized());
  start.params = internal::SolveParametersGivenDirections(problem, start.dirs);
  start.used = Initialization::kNormalizedReadings;
  return start;
}

}  // namespace

namespace {

// The sandwich covariance with per-position noise, inflated by the scatter ratio (calibrate.hpp).
internal::Mat12 SampleNoiseCovariance(const Problem& problem, const internal::SolverOutput& out,
                                      const internal::InformationRows& rows,
                                      const internal::Mat12& S_inverse,
                                      const std::vector<Vec3>& sigmas, CalibrationResult* result) {
  const int m = problem.positions();
  Eigen::VectorXd variance(m);
  double chi2 = 0;
  for (int k = 0; k < m; ++k) {
    const auto i = static_cast<std::size_t>(k);
    const Vec3& n = rows.normals[i];
    variance(k) = n.cwiseAbs2().dot(sigmas[i].cwiseAbs2());
    const Vec3 residual =
        problem.readings[i] - PredictRaw(out.params, Vec3(problem.gravity * out.dirs[i]));
    chi2 += std::pow(n.dot(residual), 2) / variance(k);
  }
  const internal::Mat12 meat = rows.U.transpose() * variance.asDiagonal() * rows.U;
  const double ratio2 = chi2 / result->degrees_of_freedom;
  result->noise_source = "samples";
  result->scatter_ratio = std::sqrt(ratio2);
  return std::max(1.0, ratio2) * S_inverse * meat * S_inverse;
}

// The iterative methods from a start.
internal::SolverOutput SolveFrom(const Problem& problem, const ModelParameters& params,
                                 std::vector<Vec3> dirs, const CalibrationOptions& options) {
  switch (options.method) {
    case SolverMethod::kTwoStep:
      return internal::SolveTwoStep(problem, params, std::move(dirs), options);
    case SolverMethod::kModulus:
    case SolverMethod::kModulusNorm:
      return internal::SolveModulus(problem, params, options);
    case SolverMethod::kNewtonLagrange:
      return internal::SolveNewtonLagrange(problem, params, std::move(dirs), options);
    case SolverMethod::kJoint:
    case SolverMethod::kEllipsoid:
    case SolverMethod::kKnownOrientation:
      break;
  }
  return internal::SolveJoint(problem, params, std::move(dirs), options);
}

// With few more positions than parameters (m − P ≤ 3) the likelihood has several minima: the
// property test over 10,000 random devices found 5 quadratic fits of 13-14 positions whose
// default start converged to J up to 1e4 times a minimum that another start reaches. There the
// fit is repeated from the paper 000 start and from the first solution perturbed (10 % in K, 5 %
// of g in b), and the lowest converged J is kept; the summary says when the starts disagreed.
constexpr int kMultiStartDegreesOfFreedom = 3;

void MultiStart(const Problem& problem, const CalibrationOptions& options,
                internal::SolverOutput* out) {
  if (!IsMaximumLikelihood(options.method) || options.initialization == Initialization::kGiven ||
      problem.positions() - NumParameters(options.model) > kMultiStartDegreesOfFreedom) {
    return;
  }
  std::vector<internal::SolverOutput> others;
  {
    std::vector<Vec3> dirs;
    for (const Vec3& p : problem.readings) dirs.push_back(p.normalized());
    others.push_back(
        SolveFrom(problem, internal::SolveParametersGivenDirections(problem, dirs), dirs, options));
  }
  ModelParameters perturbed = out->params;
  perturbed.K *= 1.1;
  perturbed.bias.array() += 0.05 * problem.gravity;
  others.push_back(
      SolveFrom(problem, perturbed, internal::DirectionsFromParams(problem, perturbed), options));
  int distinct = 0;
  const double first_cost = out->summary.final_cost;
  for (internal::SolverOutput& other : others) {
    if (!other.summary.converged()) continue;
    const double cost = other.summary.final_cost;
    if (std::abs(cost - first_cost) > 1e-8 * std::max(cost, first_cost)) ++distinct;
    if (out->summary.converged() && !(cost < out->summary.final_cost)) continue;
    other.summary.initial_cost = out->summary.initial_cost;
    *out = std::move(other);
  }
  if (distinct > 0) {
    char buf[200];
    internal::FormatTo(
        buf, sizeof buf,
        "; with %d positions for %d parameters the starts reached different minima (J "
        "%.3e from the first), the lowest kept: add positions",
        problem.positions(), NumParameters(options.model), first_cost);
    out->summary.termination_message += buf;
  }
}

// The bias correction's offsets at the fit to `problem`, with the noise the covariance uses
// (calibrate.hpp): σ̂ from the residuals, or the readings' sigmas inflated by the scatter ratio.
// The offsets are linear in the noise covariance, so the inflation R² (which needs the normals)
// scales those of the uninflated sigmas: one pass over the positions.
internal::SurfaceOffsets CorrectionOffsets(const Problem& problem,
                                           const internal::SolverOutput& out,
                                           const CalibrationOptions& options, int dof) {
  const std::size_t m = problem.readings.size();
  if (options.reading_sigmas.empty()) {
    const Vec3 sigma = Vec3::Constant(std::sqrt(out.summary.final_cost / dof));
    return internal::ExpectedSurfaceOffsets(problem, out.params, out.dirs,
                                            std::vector<Vec3>(m, sigma));
  }
  internal::SurfaceOffsets offsets =
      internal::ExpectedSurfaceOffsets(problem, out.params, out.dirs, options.reading_sigmas);
  double chi2 = 0;
  for (std::size_t k = 0; k < m; ++k) {
    const Vec3 residual =
        problem.readings[k] - PredictRaw(out.params, Vec3(problem.gravity * out.dirs[k]));
    chi2 += std::pow(offsets.normal[k].dot(residual) / offsets.normal_sigma[k], 2);
  }
  const double inflation2 = std::max(1.0, chi2 / dof);
  for (std::size_t k = 0; k < m; ++k) {
    offsets.offset[k] *= inflation2;
    offsets.normal_sigma[k] *= std::sqrt(inflation2);
  }
  return offsets;
}

// Estimator::kBiasCorrected (calibrate.hpp): refits `out` with each reading moved inward by its
// expected offset from the fitted surface until the shifts settle; returns the readings of the
// last fit.
std::vector<Vec3> CorrectBias(const std::vector<Vec3>& readings, const CalibrationOptions& options,
                              internal::SolverOutput* out) {
  std::vector<Vec3> shifted = readings;
  Summary& summary = out->summary;
  const int dof = static_cast<int>(readings.size()) - NumParameters(options.model);
  if (dof <= 0 && options.reading_sigmas.empty()) {
    summary.termination_message +=
        "; bias correction not applied: no residual degrees of freedom to estimate the noise";
    return shifted;
  }
  const Summary ml = summary;
  int iterations = ml.iterations;
  double change = 0;
  for (int round = 0; round <= options.bias_correction.max_rounds; ++round) {
    const Problem problem{shifted, options.gravity, options.model};
    const internal::SurfaceOffsets offsets =
        CorrectionOffsets(problem, *out, options, std::max(dof, 1));
    std::vector<Vec3> next(readings.size());
    change = 0;
    for (std::size_t k = 0; k < readings.size(); ++k) {
      next[k] = readings[k] - offsets.offset[k] * offsets.normal[k];
      change = std::max(change, (next[k] - shifted[k]).norm() / offsets.normal_sigma[k]);
    }
    if (change <= options.bias_correction.tolerance) break;  // the last fit used these shifts
    if (round == options.bias_correction.max_rounds) break;
    shifted = std::move(next);
    *out = SolveFrom(Problem{shifted, options.gravity, options.model}, out->params,
                     std::move(out->dirs), options);
    iterations += summary.iterations;
    summary.correction_rounds = round + 1;
    if (!summary.converged()) break;
  }
  summary.estimator = Estimator::kBiasCorrected;
  summary.iterations = iterations;
  summary.initial_cost = ml.initial_cost;
  if (summary.converged() && change > options.bias_correction.tolerance) {
    char buf[200];
    internal::FormatTo(
        buf, sizeof buf,
        "; bias correction: a reading's shift still changed by %.2g of its noise after "
        "%d refits",
        change, summary.correction_rounds);
    summary.termination = TerminationType::kMaxIterations;
    summary.termination_message += buf;
  }
  return shifted;
}

// A fit and, when the options ask for it and the fit converged, its outlier statistics.
struct Fit {
  CalibrationResult result;
  internal::Screening screening;
};

// The fit in the x-first gauge; `frame` only names parameters in messages (the z-first fit runs
// here on mirrored readings).
Fit CalibrateXFirst(const std::vector<Vec3>& readings, const CalibrationOptions& options,
                    Frame frame) {
  const auto t0 = std::chrono::steady_clock::now();
  CheckData(readings, options.model);
  const Problem data{readings, options.gravity, options.model};

  Start start = Initialise(data, options.initialization, options.initial_params);
  internal::SolverOutput out;
  if (options.method == SolverMethod::kEllipsoid) {
    if (start.used != Initialization::kEllipsoidFit) {
      throw DataError("the ellipsoid method cannot run: " + start.note);
    }
    out.params = start.params;
    out.dirs = std::move(start.dirs);
    out.summary.method = SolverMethod::kEllipsoid;
    out.summary.termination = TerminationType::kClosedForm;
    out.summary.termination_message =
        start.fit_kind == EllipsoidFitKind::kAlgebraic
            ? "algebraic fit (paper 001 eq. (16)-(18))"
            : "ellipsoid-specific fit (Li & Griffiths 2004): the algebraic quadric of paper "
              "001 eq. (16)-(18) is no ellipsoid";
    out.summary.initial_cost = out.summary.final_cost = internal::Cost(data, out.params, out.dirs);
  } else {
    out = SolveFrom(data, start.params, std::move(start.dirs), options);
    MultiStart(data, options, &out);
  }
  // The readings the final fit was solved for (shifted by the bias correction).
  std::vector<Vec3> fit_readings;
  if (options.estimator == Estimator::kBiasCorrected && out.summary.converged()) {
    fit_readings = CorrectBias(readings, options, &out);
  }
  const Problem problem{fit_readings.empty() ? readings : fit_readings, options.gravity,
                        options.model};
  out.summary.initialization = start.used;
  out.summary.initialization_note = start.note;

  // Observability at the solution: a (near) singular reduced information matrix means some
  // parameter is not determined by these positions, whatever the solver returned.
  internal::InformationRows rows;
  const internal::Information info =
      internal::ComputeInformation(problem, out.params, out.dirs, &rows);
  ThrowIfUnobservable(info, options.model, frame);
  // A solver that did not converge on poorly conditioned data is usually wandering along a
  // valley of nearly equal fits: say which parameter the positions barely determine.
  if (!out.summary.converged() && info.rcond < internal::kPoorInformationRcond) {
    char buf[200];
    internal::FormatTo(
        buf, sizeof buf,
        "; the positions barely determine parameter %s (reciprocal condition %.2g): add "
        "positions with other orientations",
        SlotName(info.weakest, frame).c_str(), info.rcond);
    out.summary.termination_message += buf;
  }

  Fit fit;
  CalibrationResult& result = fit.result;
  result.model = options.model;
  result.gravity = options.gravity;
  result.params = out.params;
  result.directions = out.dirs;
  result.residuals.reserve(readings.size());
  for (std::size_t k = 0; k < readings.size(); ++k) {
    result.residuals.push_back(readings[k] -
                               PredictRaw(out.params, Vec3(options.gravity * out.dirs[k])));
  }
  const int P = NumParameters(options.model);
  result.degrees_of_freedom = static_cast<int>(readings.size()) - P;
  const bool screen = options.outliers.policy != OutlierPolicy::kOff && out.summary.converged();
  const bool covariance_wanted =
      result.degrees_of_freedom > 0 && IsMaximumLikelihood(options.method);
  const internal::Mat12 inverse =
      screen || covariance_wanted ? info.Inverse() : internal::Mat12::Zero();
  if (screen) {
    fit.screening =
        internal::ScreenPositions(rows, inverse, options.model, result.residuals,
                                  internal::SignalAmplitude(out.params, options.gravity),
                                  options.outliers.false_alarm_probability);
  }
  if (covariance_wanted) {
    const double sigma2 = out.summary.final_cost / result.degrees_of_freedom;
    result.residual_sigma = std::sqrt(sigma2);
    internal::Mat12 covariance = sigma2 * inverse;
    if (!options.reading_sigmas.empty()) {
      covariance =
          SampleNoiseCovariance(problem, out, rows, inverse, options.reading_sigmas, &result);
    }
    const std::vector<int>& cols = ActiveColumns(options.model);
    result.covariance.resize(P, P);
    for (int i = 0; i < P; ++i) {
      for (int j = 0; j < P; ++j) result.covariance(i, j) = covariance(cols[i], cols[j]);
    }
  }
  result.summary = out.summary;
  result.summary.time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return fit;
}

// The fit in the requested frame (frame.hpp): z-first is the x-first fit of the mirrored readings
// (the outlier statistics do not depend on the gauge).
Fit CalibrateInFrame(const std::vector<Vec3>& readings, const CalibrationOptions& options) {
  if (options.frame == Frame::kXFirst) return CalibrateXFirst(readings, options, Frame::kXFirst);
  std::vector<Vec3> mirrored;
  mirrored.reserve(readings.size());
  for (const Vec3& p : readings) mirrored.push_back(MirrorAxes(p));
  CalibrationOptions mirrored_options = options;
  if (options.initial_params) mirrored_options.initial_params = MirrorAxes(*options.initial_params);
  for (Vec3& s : mirrored_options.reading_sigmas) s = MirrorAxes(s).cwiseAbs();
  Fit fit = CalibrateXFirst(mirrored, mirrored_options, Frame::kZFirst);
  CalibrationResult& result = fit.result;
  result.frame = Frame::kZFirst;
  result.params = MirrorAxes(result.params);
  for (Vec3& c : result.directions) c = MirrorAxes(c);
  for (Vec3& r : result.residuals) r = MirrorAxes(r);
  if (result.covariance.size() > 0) {
    const Eigen::VectorXd d = MirrorSigns(options.model);
    result.covariance = d.asDiagonal() * result.covariance * d.asDiagonal();
  }
  return fit;
}

}  // namespace

void internal::CheckDistinctReadings(const std::vector<Vec3>& readings) {
  // Sorted by reading, equal readings by index: each group's first entry is the original, the
  // others repeat it. The repeat earliest in the input is named.
  std::vector<std::size_t> order(readings.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const Vec3& p = readings[a];
    const Vec3& q = readings[b];
    if (p != q) return std::lexicographical_compare(p.data(), p.data() + 3, q.data(), q.data() + 3);
    return a < b;
  });
  std::size_t repeat = readings.size(), original = 0, group_first = 0;
  for (std::size_t i = 0; i < order.size(); ++i) {
    if (i == 0 || readings[order[i]] != readings[order[i - 1]]) {
      group_first = order[i];
    } else if (order[i] < repeat) {
      repeat = order[i];
      original = group_first;
    }
  }
  if (repeat < readings.size()) {
    throw DataError("position " + std::to_string(repeat + 1) + " repeats position " +
                    std::to_string(original + 1) +
                    " exactly: repeated rows are not independent positions (they would shrink "
                    "every uncertainty); remove them");
  }
}

void internal::CheckReadingSigmas(const std::vector<Vec3>& sigmas, std::size_t readings) {
  if (sigmas.empty()) return;
  if (sigmas.size() != readings) {
    throw std::invalid_argument("reading_sigmas has " + std::to_string(sigmas.size()) +
                                " entries for " + std::to_string(readings) + " readings");
  }
  for (const Vec3& s : sigmas) {
    if (!s.allFinite() || !(s.minCoeff() > 0)) {
      throw std::invalid_argument("reading_sigmas must be finite and positive");
    }
  }
}

void internal::SpreadOverAllPositions(const std::vector<Vec3>& readings,
                                      const std::vector<int>& keep, CalibrationResult* fit) {
  std::vector<Vec3> directions(readings.size()), residuals(readings.size());
  std::vector<bool> kept(readings.size(), false);
  for (std::size_t i = 0; i < keep.size(); ++i) {
    const auto k = static_cast<std::size_t>(keep[i]);
    directions[k] = fit->directions[i];
    residuals[k] = fit->residuals[i];
    kept[k] = true;
  }
  for (std::size_t k = 0; k < readings.size(); ++k) {
    if (kept[k]) continue;
    const std::optional<Vec3> f = SpecificForce(fit->params, readings[k]);
    directions[k] = f && f->norm() > 0 ? Vec3(f->normalized()) : Vec3::UnitZ();
    residuals[k] = readings[k] - PredictRaw(fit->params, Vec3(fit->gravity * directions[k]));
  }
  fit->directions = std::move(directions);
  fit->residuals = std::move(residuals);
}

namespace {

// The options of a refit without one position: started from the full fit, the same positions.
CalibrationOptions HeldOutOptions(const CalibrationOptions& options,
                                  const CalibrationResult& result) {
  CalibrationOptions held_out = options;
  held_out.cross_validate = false;
  held_out.outliers.policy = OutlierPolicy::kOff;    // the same positions as the full fit
  held_out.reading_sigmas.clear();                   // no covariance needed from the held-out fits
  if (options.method != SolverMethod::kEllipsoid) {  // closed form: nothing to start from
    held_out.initialization = Initialization::kGiven;
    held_out.initial_params = result.params;
  }
  return held_out;
}

}  // namespace

// Position k's held-out error from a fit of the other positions in the fit, or why there is none.
internal::HeldOutRefit internal::RefitWithout(const std::vector<Vec3>& readings,
                                              const CalibrationOptions& options,
                                              const CalibrationResult& result, std::size_t k) {
  const CalibrationOptions held_out = HeldOutOptions(options, result);
  std::vector<Vec3> subset;
  subset.reserve(readings.size());
  for (std::size_t j = 0; j < readings.size(); ++j) {
    if (j != k && !result.excluded(j)) subset.push_back(readings[j]);
  }
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
  const double e = GravityNormErrors(fit.params, {readings[k]}, options.gravity)[0];
  if (!std::isfinite(e)) {
    return {0.0,
            "position " + std::to_string(k + 1) + " lies outside the range of the fit without it"};
  }
  return {e, ""};
}

// Leave-one-position-out by m refits, each started from the full fit (the held-out optimum is
// close to it, so each refit takes a few iterations). Positions the screening excluded are held
// out of every fit already: their error is that of the final fit.
void internal::CrossValidateByRefits(const std::vector<Vec3>& readings,
                                     const CalibrationOptions& options, CalibrationResult* result) {
  if (auto why = options.Validate()) throw std::invalid_argument(*why);
  std::vector<double> errors;
  for (std::size_t k = 0; k < readings.size(); ++k) {
    if (result->excluded(k)) {
      errors.push_back(GravityNormErrors(result->params, {readings[k]}, options.gravity)[0]);
      continue;
    }
    const internal::HeldOutRefit refit = internal::RefitWithout(readings, options, *result, k);
    if (!refit.note.empty()) {
      result->crossval_note = refit.note;
      return;
    }
    errors.push_back(refit.error);
  }
  result->crossval_rms = Rms(result->InFit(errors));
  result->crossval_errors = std::move(errors);
}

// The same numbers from an expansion of the full fit, refitting only the positions it cannot serve
// (held_out.hpp).
void CrossValidate(const std::vector<Vec3>& readings, const CalibrationOptions& options,
                   CalibrationResult* result) {
  if (auto why = options.Validate()) throw std::invalid_argument(*why);
  const CalibrationResult& full = *result;
  internal::HeldOutErrors(
      readings, options,
      [&](std::size_t k) { return internal::RefitWithout(readings, options, full, k); }, result);
}

namespace {

// The readings (and their sigmas) of the positions in `keep`.
CalibrationOptions SubsetOptions(const CalibrationOptions& options, const std::vector<int>& keep,
                                 const ModelParameters& start) {
  CalibrationOptions subset = options;
  subset.cross_validate = false;
  if (!options.reading_sigmas.empty()) {
    subset.reading_sigmas.clear();
    for (int k : keep) subset.reading_sigmas.push_back(options.reading_sigmas[std::size_t(k)]);
  }
  if (options.method != SolverMethod::kEllipsoid) {
    subset.initialization = Initialization::kGiven;
    subset.initial_params = start;
  }
  return subset;
}

// The fit with the screening of OutlierOptions, as Rosner's generalised ESD test (1983): the most
// discordant position is removed and the rest refitted, r = max(1, max_excluded) times, each step
// recording its t and threshold; the number of discordant positions is the last step whose |t|
// exceeds its threshold. Testing the later steps as well is what finds two discordant positions
// that inflate the scatter enough to hide each other from the first step. The refits run only when
// the first step is significant or the robust scale finds a position suspicious (Screening).
CalibrationResult CalibrateScreened(const std::vector<Vec3>& readings,
                                    const CalibrationOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  Fit first = CalibrateInFrame(readings, options);
  CalibrationResult& full = first.result;
  if (options.outliers.policy == OutlierPolicy::kOff || !full.summary.converged()) return full;
  internal::Screening screening = std::move(first.screening);
  std::string note = screening.note;
  if (!screening.significant && !screening.suspicious) {
    full.outlier_note = std::move(note);
    return full;
  }
  struct Step {
    OutlierFinding finding;
    CalibrationResult fit;  // without the positions of this and the previous steps
    std::vector<int> keep;
  };
  std::vector<Step> steps;
  const int max_steps = std::max(1, options.outliers.max_excluded);
  steps.reserve(std::min(static_cast<std::size_t>(max_steps), readings.size()));  // `current`
  // points into it: no step removes more than every position
  std::vector<int> keep(readings.size());
  for (std::size_t k = 0; k < keep.size(); ++k) keep[k] = static_cast<int>(k);
  const CalibrationResult* current = &full;
  std::optional<OutlierFinding> unremovable;  // discordant, but the rest cannot be fitted
  while (static_cast<int>(steps.size()) < max_steps && screening.most_discordant >= 0) {
    OutlierFinding finding = screening.Finding(screening.most_discordant);
    finding.position = keep[std::size_t(finding.position)];
    std::vector<int> rest;
    std::vector<Vec3> rest_readings;
    for (int k : keep) {
      if (k == finding.position) continue;
      rest.push_back(k);
      rest_readings.push_back(readings[std::size_t(k)]);
    }
    std::optional<Fit> refit;
    std::string why;
    try {
      refit = CalibrateInFrame(rest_readings, SubsetOptions(options, rest, current->params));
      if (!refit->result.summary.converged()) why = "the fit without it did not converge";
    } catch (const DataError& e) {
      why = e.what();
    }
    if (!why.empty()) {
      if (std::abs(finding.t) > finding.threshold) {
        unremovable = finding;
        note = "position " + std::to_string(finding.position + 1) +
               " disagrees but cannot be left out: without it, " + why;
      }
      break;
    }
    steps.push_back({finding, std::move(refit->result), rest});
    current = &steps.back().fit;
    keep = std::move(rest);
    screening = std::move(refit->screening);
    if (!screening.ran) break;
  }
  std::size_t discordant = 0;
  for (std::size_t i = 0; i < steps.size(); ++i) {
    if (std::abs(steps[i].finding.t) > steps[i].finding.threshold) discordant = i + 1;
  }
  if (!unremovable && discordant == steps.size() && static_cast<int>(steps.size()) == max_steps &&
      screening.significant) {
    note = "more positions may disagree: the screening tests at most " + std::to_string(max_steps);
  }
  const std::size_t excluded =
      options.outliers.policy == OutlierPolicy::kExclude
          ? std::min(discordant, static_cast<std::size_t>(options.outliers.max_excluded))
          : 0;
  CalibrationResult result = excluded > 0 ? std::move(steps[excluded - 1].fit) : std::move(full);
  if (excluded > 0) {
    internal::SpreadOverAllPositions(readings, steps[excluded - 1].keep, &result);
    // The summary tells the whole solve: where it started, every fit's iterations and time.
    Summary& summary = result.summary;
    summary.initialization = full.summary.initialization;
    summary.initialization_note = full.summary.initialization_note;
    summary.initial_cost = full.summary.initial_cost;
    for (std::size_t i = 0; i + 1 < excluded; ++i) {
      summary.iterations += steps[i].fit.summary.iterations;
    }
    summary.iterations += full.summary.iterations;
  }
  for (std::size_t i = 0; i < discordant; ++i) {
    steps[i].finding.excluded = i < excluded;
    result.outliers.push_back(steps[i].finding);
  }
  if (unremovable && discordant == steps.size()) result.outliers.push_back(*unremovable);
  result.outlier_note = std::move(note);
  result.summary.time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace

CalibrationResult Calibrate(const std::vector<Vec3>& readings, const CalibrationOptions& options) {
  if (auto why = options.Validate()) throw std::invalid_argument(*why);
  internal::CheckReadingSigmas(options.reading_sigmas, readings.size());
  internal::CheckDistinctReadings(readings);
  CalibrationResult result = CalibrateScreened(readings, options);
  if (result.summary.converged()) result.screening = options.outliers.policy;
  if (options.cross_validate && result.summary.converged()) {
    CrossValidate(readings, options, &result);
  }
  return result;
}

}  // namespace accelcal
