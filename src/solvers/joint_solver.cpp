// Joint Levenberg-Marquardt over the parameters and all gravity directions, with the per-position
// 2x2 tangent blocks eliminated by the Schur complement.
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "core/text_format.hpp"
#include "solvers/solver_common.hpp"

namespace accelcal::internal {

namespace {

// The damping below which a step is close enough to the Gauss-Newton step to judge convergence.
constexpr double kMaxConvergedDamping = 1e-6;
// Relative cost changes below this are not resolved by evaluating J (sums of many squares).
constexpr double kCostResolution = 1e-13;

struct Step {
  Vec12 theta;
  std::vector<Eigen::Vector2d> dirs;
  double predicted_reduction = 0;  ///< J − ‖r + J δ‖² of the Gauss-Newton model
};

// Solves the damped normal equations (A_λ B; Bᵀ D_λ)(δθ; δc) = −(g_θ; g_c) by eliminating δc.
Step SolveDamped(const NormalEquations& ne, double lambda, const Vec12& mask) {
  const std::size_t m = ne.f.size();
  const Mat12 S = ReducedMatrix(ne, lambda, mask);
  Vec12 rhs = -ne.g_theta;
  std::vector<Eigen::Matrix2d> D_inv(m);
  for (std::size_t k = 0; k < m; ++k) {
    Eigen::Matrix2d D = ne.D[k];
    D.diagonal() += lambda * ne.D[k].diagonal();
    D_inv[k] = D.inverse();
    rhs += BTimes(ne, k, D_inv[k] * ne.g_c[k]);
  }
  rhs = rhs.cwiseProduct(mask);
  // Jacobi scaling before the factorisation: the parameters differ by orders of magnitude.
  const Vec12 scale = S.diagonal().cwiseAbs().cwiseSqrt().cwiseInverse();
  const Mat12 S_scaled = scale.asDiagonal() * S * scale.asDiagonal();
  Step step;
  step.theta = scale.cwiseProduct(S_scaled.ldlt().solve(scale.cwiseProduct(rhs)));
  step.theta = step.theta.cwiseProduct(mask);
  step.dirs.resize(m);
  double quadratic = step.theta.dot(ne.A * step.theta);
  double linear = ne.g_theta.dot(step.theta);
  for (std::size_t k = 0; k < m; ++k) {
    const Eigen::Vector2d Bt_theta = BTransposeTimes(ne, k, step.theta);
    step.dirs[k] = -D_inv[k] * (ne.g_c[k] + Bt_theta);
    quadratic += 2.0 * Bt_theta.dot(step.dirs[k]) + step.dirs[k].dot(ne.D[k] * step.dirs[k]);
    linear += ne.g_c[k].dot(step.dirs[k]);
  }
  step.predicted_reduction = -(2.0 * linear + quadratic);
  return step;
}

}  // namespace

SolverOutput SolveJoint(const Problem& problem, const ModelParameters& init_params,
                        std::vector<Vec3> dirs, const CalibrationOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const auto& opt = options.joint;
  const Vec12 mask = FreeMask(problem.model);
  SolverOutput out;
  out.summary.method = SolverMethod::kJoint;

  Vec12 theta = ToVec12(init_params).cwiseProduct(mask);
  NormalEquations ne;
  BuildNormalEquations(problem, FromVec12(theta), dirs, &ne);
  out.summary.initial_cost = ne.cost;
  const double zero_cost = ZeroResidualCost(problem, init_params);

  Damping damping(opt.initial_damping);
  char message[256];
  out.summary.termination = TerminationType::kMaxIterations;
  internal::FormatTo(message, sizeof message, "reached max_iterations = %d", opt.max_iterations);
  out.summary.termination_message = message;
  std::vector<Vec3> trial_dirs(dirs.size());
  int evaluations = 0;
  int reset_at = -1;        // the iteration at which the damping was last reset (small step)
  int trust_reset_at = -1;  // likewise, for a step below the cost's resolution

  std::int64_t passes =
      0;  // loop passes, accepted or not: a backstop against cycling without progress
  while (out.summary.iterations < opt.max_iterations) {
    // In 64 bits: 100 times an iteration cap near INT_MAX overflowed an int (issue 16).
    if (++passes > 100 * static_cast<std::int64_t>(opt.max_iterations)) {
      out.summary.termination = TerminationType::kNoProgress;
      out.summary.termination_message =
          "no progress after " + std::to_string(passes - 1) + " trial steps (damping cycled)";
      break;
    }
    if (ne.cost <= zero_cost) {
      out.summary.termination = TerminationType::kZeroResidual;
      internal::FormatTo(message, sizeof message, "J = %.3e <= zero-residual level %.3e", ne.cost,
                         zero_cost);
      out.summary.termination_message = message;
      break;
    }
    const Step step = SolveDamped(ne, damping.lambda(), mask);
    const ModelParameters current = FromVec12(theta);
    const double theta_step = ScaledNorm(step.theta, ParameterScales(problem, current));
    double dir_step = 0;
    for (const auto& d : step.dirs) dir_step = std::max(dir_step, d.lpNorm<Eigen::Infinity>());
    // A small step under heavy damping says only that λ is large: retry closer to Gauss-Newton.
    // (Measured on the paper 001 problem, σ = 0.1 g: steps of 3e-19 with λ grown by rejections,
    // while the gradient was still 7e-9.)
    // Once per accepted iteration: if even the near-Gauss-Newton step is rejected, the damping
    // grows again and the solve ends below as no progress.
    if (theta_step <= opt.parameter_tolerance && dir_step <= opt.parameter_tolerance &&
        damping.lambda() > kMaxConvergedDamping && reset_at != out.summary.iterations) {
      reset_at = out.summary.iterations;
      damping.Set(std::min(opt.initial_damping, kMaxConvergedDamping));
      continue;
    }
    // A (nearly) Gauss-Newton step this small changes nothing that matters: the current point
    // is the solution.
    if (theta_step <= opt.parameter_tolerance && dir_step <= opt.parameter_tolerance) {
      out.summary.termination = TerminationType::kParameterTolerance;
      internal::FormatTo(message, sizeof message, "|dtheta|_s = %.3e and max |dc| = %.3e <= %.1e",
                         theta_step, dir_step, opt.parameter_tolerance);
      out.summary.termination_message = message;
      break;
    }
    const Vec12 trial_theta = theta + step.theta;
    for (std::size_t k = 0; k < dirs.size(); ++k) {
      trial_dirs[k] = Retract(dirs[k], ne.tangent[k], step.dirs[k]);
    }
    const ModelParameters trial = FromVec12(trial_theta);
    // When the model predicts a change the cost cannot resolve (J carries 16 digits; near the
    // optimum of a large-residual problem a 1e-9 step changes it in the 18th), comparing costs
    // only measures round-off. A nearly Gauss-Newton step is then taken on trust: Gauss-Newton
    // contracts towards the optimum and the parameter criterion ends the solve.
    if (step.predicted_reduction <= kCostResolution * ne.cost) {
      if (damping.lambda() > kMaxConvergedDamping) {
        if (trust_reset_at == out.summary.iterations) {
          // The nearly Gauss-Newton step was already tried from here and measurably raised J;
          // the damped steps change it by less than it can show: J is minimal to its resolution.
          out.summary.termination = TerminationType::kFunctionTolerance;
          internal::FormatTo(message, sizeof message,
                             "predicted |dJ| = %.3e below the resolution %.0e J of the cost",
                             step.predicted_reduction, kCostResolution);
          out.summary.termination_message = message;
          break;
        }
        trust_reset_at = out.summary.iterations;
        damping.Set(kMaxConvergedDamping);
        continue;
      }
      theta = trial_theta;
      dirs.swap(trial_dirs);
      ++out.summary.iterations;
      BuildNormalEquations(problem, FromVec12(theta), dirs, &ne);
      continue;
    }
    const double actual = -CostChange(problem, current, dirs, trial, trial_dirs);
    const double trial_cost = ne.cost - actual;
    ++evaluations;
    if (opt.function_tolerance > 0 && std::abs(actual) <= opt.function_tolerance * ne.cost) {
      if (actual > 0) {
        theta = trial_theta;
        dirs.swap(trial_dirs);
        ++out.summary.iterations;
        BuildNormalEquations(problem, FromVec12(theta), dirs, &ne);
      }
      out.summary.termination = TerminationType::kFunctionTolerance;
      internal::FormatTo(message, sizeof message, "|dJ| / J = %.3e <= %.1e",
                         std::abs(actual) / ne.cost, opt.function_tolerance);
      out.summary.termination_message = message;
      break;
    }
    if (actual > 0 && std::isfinite(trial_cost)) {
      damping.Accept(step.predicted_reduction > 0 ? actual / step.predicted_reduction : 1.0);
      theta = trial_theta;
      dirs.swap(trial_dirs);
      ++out.summary.iterations;
      BuildNormalEquations(problem, FromVec12(theta), dirs, &ne);
    } else {
      if (!damping.Reject()) {
        out.summary.termination = TerminationType::kNoProgress;
        internal::FormatTo(message, sizeof message,
                           "no step reduced J = %.6e with damping up to 1e16 (%d evaluations)",
                           ne.cost, evaluations);
        out.summary.termination_message = message;
        break;
      }
    }
  }
  out.params = FromVec12(theta);
  out.dirs = std::move(dirs);
  out.summary.final_cost = ne.cost;
  out.summary.time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace accelcal::internal
