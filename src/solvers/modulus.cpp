// Paper 001's least-squares baseline: fit the corrected magnitudes to g directly.
#include <chrono>
#include <cmath>
#include <cstdio>

#include <Eigen/Cholesky>

#include "core/text_format.hpp"
#include "solvers/solver_common.hpp"

namespace accelcal::internal {

Eigen::VectorXd ModulusResiduals(const Problem& problem, const Eigen::VectorXd& theta, bool squared,
                                 Eigen::MatrixXd* jacobian) {
  const ModelParameters params = Unpack(theta, ModelKind::kLinear);
  const std::vector<ParameterSlot>& slots = ParameterSlots(ModelKind::kLinear);
  const Eigen::TriangularView<const Mat33, Eigen::Lower> K =
      params.K.triangularView<Eigen::Lower>();
  const int m = problem.positions();
  const double g = problem.gravity;
  Eigen::VectorXd e(m);
  if (jacobian != nullptr) jacobian->resize(m, static_cast<Eigen::Index>(slots.size()));
  for (int k = 0; k < m; ++k) {
    const Vec3 f = K.solve(Vec3(problem.readings[k] - params.bias));
    const double norm = f.norm();
    e(k) = squared ? f.squaredNorm() / (g * g) - 1.0 : norm / g - 1.0;
    if (jacobian == nullptr) continue;
    // ∂f/∂K_ij = −K⁻¹ e_i f_j and ∂f/∂b = −K⁻¹, so fᵀ ∂f/∂K_ij = −w_i f_j and fᵀ ∂f/∂b_i = −w_i
    // with w = K⁻ᵀ f; then ∂|f|²/∂θ = 2 fᵀ ∂f/∂θ and ∂|f|/∂θ = fᵀ ∂f/∂θ / |f|.
    const Vec3 w = K.transpose().solve(f);
    const double scale = squared ? 2.0 / (g * g) : 1.0 / (g * norm);
    for (std::size_t s = 0; s < slots.size(); ++s) {
      const double d = slots[s].group == ParameterGroup::kK ? w(slots[s].row) * f(slots[s].col)
                                                            : w(slots[s].row);
      (*jacobian)(k, static_cast<Eigen::Index>(s)) = -scale * d;
    }
  }
  return e;
}

SolverOutput SolveModulus(const Problem& problem, const ModelParameters& init_params,
                          const CalibrationOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const auto& opt = options.modulus;
  const bool squared = options.method == SolverMethod::kModulus;
  SolverOutput out;
  out.summary.method = options.method;
  Eigen::VectorXd theta = Pack(init_params, ModelKind::kLinear);
  Eigen::MatrixXd J;
  Eigen::VectorXd e = ModulusResiduals(problem, theta, squared, &J);
  double cost = e.squaredNorm();
  out.summary.initial_cost = cost;
  Damping damping(1e-9);
  char message[256];
  out.summary.termination = TerminationType::kMaxIterations;
  internal::FormatTo(message, sizeof message, "reached max_iterations = %d", opt.max_iterations);
  out.summary.termination_message = message;

  while (out.summary.iterations < opt.max_iterations) {
    const Eigen::MatrixXd A = J.transpose() * J;
    const Eigen::VectorXd gradient = J.transpose() * e;
    Eigen::MatrixXd damped = A;
    damped.diagonal() += damping.lambda() * A.diagonal();
    const Eigen::VectorXd s = A.diagonal().cwiseSqrt().cwiseInverse();
    const Eigen::MatrixXd scaled = s.asDiagonal() * damped * s.asDiagonal();
    const Eigen::VectorXd step = -s.cwiseProduct(scaled.ldlt().solve(s.cwiseProduct(gradient)));
    const ModelParameters current = Unpack(theta, ModelKind::kLinear);
    const double step_size =
        ScaledNorm(ToVec12(Unpack(step, ModelKind::kLinear)), ParameterScales(problem, current));
    if (step_size <= opt.parameter_tolerance) {
      out.summary.termination = TerminationType::kParameterTolerance;
      internal::FormatTo(message, sizeof message, "|dtheta|_s = %.3e <= %.1e", step_size,
                         opt.parameter_tolerance);
      out.summary.termination_message = message;
      break;
    }
    const Eigen::VectorXd trial = theta + step;
    Eigen::MatrixXd trial_J;
    const Eigen::VectorXd trial_e = ModulusResiduals(problem, trial, squared, &trial_J);
    const double trial_cost = trial_e.squaredNorm();
    const double actual = cost - trial_cost;
    if (std::isfinite(trial_cost) && std::abs(actual) <= opt.function_tolerance * cost) {
      if (actual > 0) {
        theta = trial, e = trial_e, J = trial_J, cost = trial_cost;
        ++out.summary.iterations;
      }
      out.summary.termination = TerminationType::kFunctionTolerance;
      internal::FormatTo(message, sizeof message, "|dJ| / J = %.3e <= %.1e",
                         std::abs(actual) / cost, opt.function_tolerance);
      out.summary.termination_message = message;
      break;
    }
    if (std::isfinite(trial_cost) && actual > 0) {
      const double predicted = -(2.0 * gradient.dot(step) + step.dot(A * step));
      damping.Accept(predicted > 0 ? actual / predicted : 1.0);
      theta = trial, e = trial_e, J = trial_J, cost = trial_cost;
      ++out.summary.iterations;
    } else {
      if (!damping.Reject()) {
        out.summary.termination = TerminationType::kNoProgress;
        internal::FormatTo(message, sizeof message,
                           "no step reduced the cost %.6e with damping up to 1e16", cost);
        out.summary.termination_message = message;
        break;
      }
    }
  }
  out.params = Unpack(theta, ModelKind::kLinear);
  out.dirs = DirectionsFromParams(problem, out.params);
  out.summary.final_cost = cost;
  out.summary.time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace accelcal::internal
