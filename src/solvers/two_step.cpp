// Paper 000 §3.1: the two-step iterative maximum-likelihood estimation.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

#include <Eigen/LU>

#include "core/text_format.hpp"
#include "solvers/solver_common.hpp"

namespace accelcal::internal {

void DirectionCostDerivatives(const ModelParameters& params, double gravity, const Vec3& p,
                              const Vec3& c, Vec3* gradient, Mat33* hessian) {
  // f(c) = ‖r‖², r = μ(g c) − p, J = ∂r/∂c = g (K + 2 diag(k2 ∘ g c)).
  // ∇f = 2 Jᵀ r (eq. (24) without the multiplier term);
  // ∇²f = 2 JᵀJ + 2 Σ_i r_i ∇²μ_i = 2 JᵀJ + 4 g² diag(k2 ∘ r): this is eq. (25) with the index
  // typos of the printed version corrected (docs/errata.md#000-eq25).
  Mat33 J_p_f;
  const Vec3 r = PredictRaw(params, Vec3(gravity * c), &J_p_f) - p;
  const Mat33 J = gravity * J_p_f;
  *gradient = 2.0 * J.transpose() * r;
  *hessian = 2.0 * J.transpose() * J;
  hessian->diagonal() += 4.0 * gravity * gravity * params.k2.cwiseProduct(r);
}

namespace {

constexpr double kKktConvergedStep = 1e-9;

// Eq. (22): [∇²L ∇h; ∇hᵀ 0] (δc, δu) = −(∇L, h) with ∇²L = ∇²f + 2u I, ∇h = 2c (eq. (23)),
// ∇L = ∇f + 2u c (eq. (24)). Solved by bordering: with H a = −∇L and H w = 2c,
// δu = (2cᵀa + h) / (2cᵀw) and δc = a − δu w; a 3x3 inverse instead of a pivoted 4x4 LU, which
// is most of a two-step sweep. The LU remains for the rare singular H (the bordered matrix can be
// regular when H is not).
Eigen::Vector4d KktStep(const Mat33& hess_f, const Vec3& grad_f, const Vec3& c, double u) {
  const Mat33 H = hess_f + 2.0 * u * Mat33::Identity();
  const Vec3 grad_L = grad_f + 2.0 * u * c;
  const double h = c.squaredNorm() - 1.0;
  Mat33 H_inv;
  bool invertible = false;
  H.computeInverseWithCheck(H_inv, invertible, 1e-12 * H.cwiseAbs().maxCoeff());
  Eigen::Vector4d step;
  if (invertible) {
    const Vec3 a = -(H_inv * grad_L);
    const Vec3 w = 2.0 * (H_inv * c);
    const double denominator = 2.0 * c.dot(w);
    if (std::abs(denominator) > 1e-12 * std::abs(2.0 * c.dot(a) + h) && denominator != 0.0) {
      step(3) = (2.0 * c.dot(a) + h) / denominator;
      step.head<3>() = a - step(3) * w;
      return step;
    }
  }
  Eigen::Matrix4d kkt;
  kkt.topLeftCorner<3, 3>() = H;
  kkt.topRightCorner<3, 1>() = 2.0 * c;
  kkt.bottomLeftCorner<1, 3>() = 2.0 * c.transpose();
  kkt(3, 3) = 0.0;
  Eigen::Vector4d rhs;
  rhs.head<3>() = -grad_L;
  rhs(3) = -h;
  return kkt.partialPivLu().solve(rhs);
}

}  // namespace

Vec3 KktDirection(const ModelParameters& params, double gravity, const Vec3& p, const Vec3& c0,
                  int max_iterations) {
  Vec3 c = c0.normalized();
  Vec3 grad;
  Mat33 hess;
  DirectionCostDerivatives(params, gravity, p, c, &grad, &hess);
  // The paper starts the multiplier at a large constant (u = 1000); the least-squares multiplier
  // of ∇f + 2 u c = 0 at the starting point is scale-free and already close.
  double u = -c.dot(grad) / 2.0;
  for (int it = 0; it < max_iterations; ++it) {
    const Eigen::Vector4d step = KktStep(hess, grad, c, u);
    if (!step.allFinite()) break;
    c += step.head<3>();
    u += step(3);
    // Newton converges quadratically: after a step δ the error is about κδ², κ ≈ 2 here (the
    // KKT system is quadratic in (c, u) with the cross term 2uc, and u scales with the Hessian),
    // so below δ = 1e-9 the next step would be round-off. Measured on the paper 000 and 001
    // test problems and the Xsens, T265 and CTU-49 recordings: the step after it never exceeded
    // 2.1e-15, the round-off of a unit vector, whatever the size of δ below 1e-9.
    if (step.head<3>().lpNorm<Eigen::Infinity>() <= kKktConvergedStep) break;
    DirectionCostDerivatives(params, gravity, p, c, &grad, &hess);
  }
  return c.normalized();
}

SolverOutput SolveTwoStep(const Problem& problem, const ModelParameters& init_params,
                          std::vector<Vec3> dirs, const CalibrationOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const auto& opt = options.two_step;
  SolverOutput out;
  out.summary.method = SolverMethod::kTwoStep;
  out.summary.initial_cost = Cost(problem, init_params, dirs);

  ModelParameters params = init_params;
  double cost = out.summary.initial_cost;
  double previous_step = std::numeric_limits<double>::infinity();
  std::array<double, 5> rho_history;
  rho_history.fill(std::numeric_limits<double>::infinity());
  const double zero_cost = ZeroResidualCost(problem, init_params);
  out.summary.termination = TerminationType::kMaxIterations;
  char message[256];
  internal::FormatTo(message, sizeof message, "reached max_sweeps = %d", opt.max_sweeps);
  out.summary.termination_message = message;

  for (int sweep = 1; sweep <= opt.max_sweeps; ++sweep) {
    const ModelParameters next = SolveParametersGivenDirections(problem, dirs);  // step 1
    for (int k = 0; k < problem.positions(); ++k) {                              // step 2
      dirs[k] = KktDirection(next, problem.gravity, problem.readings[k], dirs[k],
                             opt.max_newton_iterations);
    }
    const double next_cost = Cost(problem, next, dirs);
    const double step = ScaledNorm(ToVec12(next) - ToVec12(params), ParameterScales(problem, next));
    // The contraction factor is estimated conservatively, as the largest of the last few step
    // ratios: a single ratio fluctuates (measured: 0.90 where the true rate was near 0.99).
    rho_history[static_cast<std::size_t>(sweep) % rho_history.size()] = step / previous_step;
    const double rho = *std::max_element(rho_history.begin(), rho_history.end());
    params = next;
    const double cost_change = std::abs(cost - next_cost);
    cost = next_cost;
    out.summary.iterations = sweep;
    previous_step = step;

    if (cost <= zero_cost) {
      out.summary.termination = TerminationType::kZeroResidual;
      internal::FormatTo(message, sizeof message, "J = %.3e <= zero-residual level %.3e", cost,
                         zero_cost);
      out.summary.termination_message = message;
      break;
    }
    // Linear convergence: the remaining error is about step·ρ/(1−ρ)
    // (docs/errata.md#000-convergence: ρ ≈ 0.92 on the Table-3 problem, so the last step alone
    // underestimates the error tenfold).
    if (sweep > static_cast<int>(rho_history.size()) && rho < 1.0) {
      const double remaining = step * rho / (1.0 - rho);
      if (remaining <= opt.parameter_tolerance) {
        out.summary.termination = TerminationType::kParameterTolerance;
        internal::FormatTo(message, sizeof message,
                           "|dtheta|_s * rho/(1-rho) = %.3e <= %.1e (rho = %.4f)", remaining,
                           opt.parameter_tolerance, rho);
        out.summary.termination_message = message;
        break;
      }
    }
    // Steps below the tolerance that no longer shrink are round-off: nothing left to gain.
    if (sweep > static_cast<int>(rho_history.size()) && rho >= 1.0 &&
        step <= opt.parameter_tolerance) {
      out.summary.termination = TerminationType::kParameterTolerance;
      internal::FormatTo(message, sizeof message,
                         "|dtheta|_s = %.3e <= %.1e and no longer shrinking (round-off)", step,
                         opt.parameter_tolerance);
      out.summary.termination_message = message;
      break;
    }
    if (sweep >= 3 && opt.function_tolerance > 0 && cost_change <= opt.function_tolerance * cost) {
      out.summary.termination = TerminationType::kFunctionTolerance;
      internal::FormatTo(message, sizeof message, "|dJ| / J = %.3e <= %.1e", cost_change / cost,
                         opt.function_tolerance);
      out.summary.termination_message = message;
      break;
    }
  }
  out.params = params;
  out.dirs = std::move(dirs);
  out.summary.final_cost = cost;
  out.summary.time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace accelcal::internal
