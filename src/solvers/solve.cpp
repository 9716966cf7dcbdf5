#include "solvers/solve.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>

#include "accelcal/error.hpp"
#include "core/text_format.hpp"

namespace accelcal::internal {

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

}  // namespace accelcal::internal
