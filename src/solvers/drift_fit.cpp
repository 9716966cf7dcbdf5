// The joint fit with a drifting bias (drift_fit.hpp).
#include "solvers/drift_fit.hpp"

#include <cmath>
#include <stdexcept>

namespace accelcal::internal {

DriftProblem::DriftProblem(const Problem& problem, const BiasTimeBasis& basis,
                           const std::vector<double>& times_s,
                           const std::optional<RandomWalkPrior>& prior)
    : problem_(problem),
      slots_(ParameterSlots(problem.model)),
      P_(static_cast<int>(slots_.size())),
      J_(basis.size()) {
  phi_.reserve(times_s.size());
  for (double t : times_s) phi_.push_back(basis.Evaluate(t));
  if (!prior) return;
  if (basis.model.kind != BiasModelKind::kSpline) {
    throw std::invalid_argument("a random-walk prior is on a spline bias's knots");
  }
  if (prior->reading_sigmas.size() != times_s.size()) {
    throw std::invalid_argument("a random-walk prior needs one reading sigma per position");
  }
  const std::vector<double>& knots = basis.knots_s;
  for (std::size_t k = 0; k < times_s.size(); ++k) {
    const double t = std::clamp(times_s[k], knots.front(), knots.back());
    std::size_t j = 0;
    while (j + 2 < knots.size() && t > knots[j + 1]) ++j;
    const double bridge = (t - knots[j]) * (knots[j + 1] - t) / (knots[j + 1] - knots[j]);
    const Vec3 variance = prior->reading_sigmas[k].cwiseAbs2() +
                          prior->q_raw_per_sqrt_s.cwiseAbs2() * std::max(0.0, bridge);
    weights_.push_back(variance.cwiseSqrt().cwiseInverse());
  }
  // Axis i's increments β_{j+1} − β_j = d_{j+1} − d_j with d_0 = 0 (D's column j − 1 is d_j).
  prior_rows_ = Eigen::MatrixXd::Zero(3 * J_, 3 * J_);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < J_; ++j) {
      const double dt = knots[std::size_t(j + 1)] - knots[std::size_t(j)];
      const double w = 1.0 / (prior->q_raw_per_sqrt_s(i) * std::sqrt(dt));
      prior_rows_(i * J_ + j, i * J_ + j) = w;
      if (j > 0) prior_rows_(i * J_ + j, i * J_ + j - 1) = -w;
    }
  }
}

Eigen::VectorXd DriftProblem::PlusLocal(int /*block*/, const Eigen::VectorXd& y,
                                        const Eigen::VectorXd& delta) const {
  const Vec3 c = y;
  return Retract(c, TangentBasis(c), Eigen::Vector2d(delta));
}

bool DriftProblem::Evaluate(int block, const Eigen::VectorXd& x, const Eigen::VectorXd& y,
                            Eigen::VectorXd* residual, Eigen::MatrixXd* J_x,
                            Eigen::MatrixXd* J_y) const {
  if (block == problem_.positions()) {  // the prior
    *residual = prior_rows_ * x.tail(3 * J_);
    if (J_x != nullptr) {
      J_x->setZero(3 * J_, GlobalSize());
      J_x->rightCols(3 * J_) = prior_rows_;
    }
    return residual->allFinite();
  }
  const auto k = static_cast<std::size_t>(block);
  const ModelParameters params = Params(x);
  const Vec3 c = y;
  const Vec3 f = problem_.gravity * c;
  const Eigen::VectorXd& phi = phi_[k];
  Mat33 J_f;
  Vec3 offset = Vec3::Zero();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < J_; ++j) offset(i) += x(P_ + i * J_ + j) * phi(j);
  }
  *residual = problem_.readings[k] - PredictRaw(params, f, &J_f) - offset;
  const Vec3 w = Weight(block);
  residual->array() *= w.array();
  if (J_x != nullptr) {
    J_x->setZero(3, GlobalSize());
    for (int s = 0; s < P_; ++s) {
      const ParameterSlot& slot = slots_[static_cast<std::size_t>(s)];
      (*J_x)(slot.row, s) = -SlotRegressor(slot, f);
    }
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < J_; ++j) (*J_x)(i, P_ + i * J_ + j) = -phi(j);
    }
    for (int i = 0; i < 3; ++i) J_x->row(i) *= w(i);
  }
  if (J_y != nullptr) *J_y = -(w.asDiagonal() * J_f * problem_.gravity) * TangentBasis(c);
  return residual->allFinite();
}

ModelParameters DriftProblem::Params(const Eigen::VectorXd& x) const {
  return Unpack(Eigen::VectorXd(x.head(P_)), slots_);
}

Eigen::Matrix<double, 3, Eigen::Dynamic> DriftProblem::Drift(const Eigen::VectorXd& x) const {
  Eigen::Matrix<double, 3, Eigen::Dynamic> D(3, J_);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < J_; ++j) D(i, j) = x(P_ + i * J_ + j);
  }
  return D;
}

DriftFit SolveDrift(const Problem& problem, const BiasTimeBasis& basis,
                    const std::vector<double>& times_s, const ModelParameters& start,
                    const std::vector<Vec3>& dirs, const CalibrationOptions::Joint& joint,
                    const std::optional<RandomWalkPrior>& prior) {
  const bool with_prior = prior.has_value();
  const DriftProblem lsq(problem, basis, times_s, prior);
  const int P = NumParameters(problem.model), m = problem.positions();
  LeastSquaresState state;
  state.x = Eigen::VectorXd::Zero(lsq.GlobalSize());
  state.x.head(P) = Pack(start, problem.model);
  for (const Vec3& c : dirs) state.y.emplace_back(c.normalized());
  if (with_prior) state.y.emplace_back();  // the prior's block has no parameters of its own

  LeastSquaresOptions options;
  options.max_iterations = joint.max_iterations;
  options.initial_damping = joint.initial_damping;
  options.function_tolerance = joint.function_tolerance;
  // Whitened residuals (the prior) are in units of their noise: the signal is that many of them.
  double whitening = 1.0;
  if (with_prior) {
    for (const Vec3& s : prior->reading_sigmas) whitening = std::max(whitening, 1.0 / s.minCoeff());
  }
  options.step_tolerance =
      joint.parameter_tolerance * SignalAmplitude(start, problem.gravity) * whitening;
  options.zero_residual_cost = with_prior ? -1.0 : ZeroResidualCost(problem, start);
  options.compute_covariance = true;

  DriftFit fit;
  fit.summary = SolveLeastSquares(lsq, options, &state);
  fit.params = lsq.Params(state.x);
  fit.D = lsq.Drift(state.x);
  for (int k = 0; k < m; ++k) fit.dirs.emplace_back(state.y[std::size_t(k)]);
  fit.S_inverse = fit.summary.information_inverse;

  // The rows of the reduced information: u_k = J_xᵀ n_k, n_k ⟂ the columns of J_y; and the
  // residuals, unweighted (the problem's, with a prior, are divided by Weight).
  fit.U.resize(m, lsq.GlobalSize());
  fit.normals.resize(static_cast<std::size_t>(m));
  for (int k = 0; k < m; ++k) {
    const auto i = static_cast<std::size_t>(k);
    Vec3 weighted;
    fit.U.row(k) =
        InformationRow(lsq, state.x, k, state.y[i], &fit.normals[i], &weighted).transpose();
    fit.residuals.push_back(weighted.cwiseQuotient(lsq.Weight(k)));
  }
  return fit;
}

}  // namespace accelcal::internal
