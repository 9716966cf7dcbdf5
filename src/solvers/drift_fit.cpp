// The joint fit with a drifting bias (drift_fit.hpp).
#include "solvers/drift_fit.hpp"

#include <cmath>

#include <Eigen/Geometry>  // cross

namespace accelcal::internal {

Eigen::VectorXd DriftInformationRow(const DriftProblem& problem, const Eigen::VectorXd& x, int k,
                                    const Vec3& c, Vec3* normal) {
  Eigen::VectorXd r;
  Eigen::MatrixXd J_x, J_y;
  problem.Evaluate(k, x, c, &r, &J_x, &J_y);
  *normal = Vec3(J_y.col(0)).cross(Vec3(J_y.col(1))).normalized();
  return J_x.transpose() * *normal;
}

std::vector<Vec3> DriftResiduals(const Problem& problem, const BiasTimeBasis& basis,
                                 const std::vector<double>& times_s, const ModelParameters& params,
                                 const Eigen::Matrix<double, 3, Eigen::Dynamic>& D,
                                 const std::vector<Vec3>& dirs) {
  std::vector<Vec3> residuals;
  residuals.reserve(dirs.size());
  for (std::size_t k = 0; k < dirs.size(); ++k) {
    const Vec3 offset = D.cols() > 0 ? Vec3(D * basis.Evaluate(times_s[k])) : Vec3::Zero();
    residuals.push_back(problem.readings[k] - PredictRaw(params, Vec3(problem.gravity * dirs[k])) -
                        offset);
  }
  return residuals;
}

DriftFit SolveDrift(const Problem& problem, const BiasTimeBasis& basis,
                    const std::vector<double>& times_s, const ModelParameters& start,
                    const std::vector<Vec3>& dirs, const CalibrationOptions::Joint& joint) {
  const DriftProblem lsq(problem, basis, times_s);
  const int P = NumParameters(problem.model), n = lsq.GlobalSize();
  LeastSquaresState state;
  state.x = Eigen::VectorXd::Zero(n);
  state.x.head(P) = Pack(start, problem.model);
  for (const Vec3& c : dirs) state.y.emplace_back(c.normalized());
  LeastSquaresOptions options;
  options.max_iterations = joint.max_iterations;
  options.initial_damping = joint.initial_damping;
  options.function_tolerance = joint.function_tolerance;
  options.step_tolerance = joint.parameter_tolerance * SignalAmplitude(start, problem.gravity);
  options.zero_residual_cost = ZeroResidualCost(problem, start);
  options.compute_covariance = true;

  DriftFit fit;
  fit.summary = SolveLeastSquares(lsq, options, &state);
  fit.params = lsq.Params(state.x);
  fit.D = lsq.Drift(state.x);
  for (const Eigen::VectorXd& c : state.y) fit.dirs.emplace_back(c);
  fit.S_inverse = fit.summary.information_inverse;

  // The rows of the reduced information: u_k = J_xᵀ n_k, n_k ⟂ the columns of J_y.
  const int m = problem.positions();
  fit.U.resize(m, n);
  fit.normals.resize(static_cast<std::size_t>(m));
  for (int k = 0; k < m; ++k) {
    const auto i = static_cast<std::size_t>(k);
    fit.U.row(k) = DriftInformationRow(lsq, state.x, k, state.y[i], &fit.normals[i]).transpose();
  }
  return fit;
}

}  // namespace accelcal::internal
