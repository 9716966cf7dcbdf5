// Paper 001 (Sun & Xu 2020) §3.2: Newton iteration on the Lagrangian of the ML problem.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "solver_common.hpp"

namespace accelcal::internal {

namespace {
// Steps below this (in the metric of TerminationType) are taken to be in Newton's quadratic regime.
constexpr double kQuadraticRegime = 1e-3;
constexpr double kQuadraticSafety = 10.0;

}  // namespace

void LagrangianDerivatives(const Problem& problem, const Vec9& theta, const std::vector<Vec3>& c,
                           const std::vector<double>& lambda, LagrangianBlocks* b) {
  const ModelParameters params = Unpack(theta, ModelKind::kLinear);
  const double g = problem.gravity;
  const int m = problem.positions();
  const std::vector<ParameterSlot>& slots = ParameterSlots(ModelKind::kLinear);
  b->value = b->cost = 0;
  b->g_theta.setZero();
  b->H_theta.setZero();
  b->g_z.resize(m);
  b->H_theta_z.resize(m);
  b->H_z.resize(m);
  const Mat33 gK = g * params.K.triangularView<Eigen::Lower>().toDenseMatrix();
  const Mat33 KtK2 = 2.0 * gK.transpose() * gK;
  // J_θ (eq. (15) rows, linear model) is block-sparse: output axis i depends only on its own
  // parameters (2, 3 and 4 of them, starting at 0, 2 and 5) with coefficients v_i, so J_θᵀJ_θ is
  // block diagonal and the rows of J_θᵀ X in group i are v_i ⊗ (row i of X).
  constexpr int kStart[3] = {0, 2, 5};
  for (int k = 0; k < m; ++k) {
    const Vec3 f = g * c[k];
    const Vec3 r = PredictRaw(params, f) - problem.readings[k];  // μ − p
    const Eigen::Vector2d vx(f(0), 1.0);
    const Eigen::Vector3d vy(f(0), f(1), 1.0);
    const Eigen::Vector4d vz(f(0), f(1), f(2), 1.0);
    const double h = c[k].squaredNorm() - 1.0;
    b->cost += r.squaredNorm();
    b->value += r.squaredNorm() + lambda[k] * h;
    // Eq. (15): ∇_θ = 2 Σ J_θᵀ r, H_θθ = 2 Σ J_θᵀ J_θ (μ is linear in θ).
    b->g_theta.segment<2>(kStart[0]) += 2.0 * r(0) * vx;
    b->g_theta.segment<3>(kStart[1]) += 2.0 * r(1) * vy;
    b->g_theta.segment<4>(kStart[2]) += 2.0 * r(2) * vz;
    b->H_theta.block<2, 2>(kStart[0], kStart[0]).noalias() += 2.0 * vx * vx.transpose();
    b->H_theta.block<3, 3>(kStart[1], kStart[1]).noalias() += 2.0 * vy * vy.transpose();
    b->H_theta.block<4, 4>(kStart[2], kStart[2]).noalias() += 2.0 * vz * vz.transpose();
    // ∇_c = 2 g Kᵀ r + 2 λ c, ∇_λ = ‖c‖² − 1.
    b->g_z[k].head<3>() = 2.0 * gK.transpose() * r + 2.0 * lambda[k] * c[k];
    b->g_z[k](3) = h;
    // H_cc = 2 g² KᵀK + 2 λ I, H_cλ = 2 c, H_λλ = 0.
    b->H_z[k].topLeftCorner<3, 3>() = KtK2 + 2.0 * lambda[k] * Mat33::Identity();
    b->H_z[k].topRightCorner<3, 1>() = 2.0 * c[k];
    b->H_z[k].bottomLeftCorner<1, 3>() = 2.0 * c[k].transpose();
    b->H_z[k](3, 3) = 0.0;
    // H_θc = 2 J_θᵀ (g K) + the derivative of J_θ itself: ∂μ_i/∂K_ij = g c_j, so
    // ∂(2 r_i g c_j)/∂c_l adds 2 g r_i δ_jl. H_θλ = 0.
    Eigen::Matrix<double, 9, 4>& C = b->H_theta_z[k];
    C.col(3).setZero();
    C.block<2, 3>(kStart[0], 0).noalias() = 2.0 * vx * gK.row(0);
    C.block<3, 3>(kStart[1], 0).noalias() = 2.0 * vy * gK.row(1);
    C.block<4, 3>(kStart[2], 0).noalias() = 2.0 * vz * gK.row(2);
    for (int s = 0; s < 9; ++s) {
      if (slots[s].group == ParameterGroup::kK) C(s, slots[s].col) += 2.0 * g * r(slots[s].row);
    }
  }
}

SolverOutput SolveNewtonLagrange(const Problem& problem, const ModelParameters& init_params,
                                 std::vector<Vec3> dirs, const CalibrationOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const auto& opt = options.newton_lagrange;
  const int m = problem.positions();
  SolverOutput out;
  out.summary.method = SolverMethod::kNewtonLagrange;
  Vec9 theta = Pack(init_params, ModelKind::kLinear);
  // Multipliers from ∇_c L = 0 at the start: λ_k = −g c_kᵀ Kᵀ r_k for |c_k| = 1.
  std::vector<double> lambda(m);
  for (int k = 0; k < m; ++k) {
    const Vec3 r = PredictRaw(init_params, Vec3(problem.gravity * dirs[k])) - problem.readings[k];
    lambda[k] = -problem.gravity * dirs[k].dot(init_params.K.transpose() * r);
  }
  LagrangianBlocks b;
  LagrangianDerivatives(problem, theta, dirs, lambda, &b);
  out.summary.initial_cost = b.cost;
  char message[256];
  out.summary.termination = TerminationType::kMaxIterations;
  std::snprintf(message, sizeof message, "reached max_iterations = %d", opt.max_iterations);
  out.summary.termination_message = message;
  std::vector<Eigen::Matrix4d> M_inv(m);
  double previous_step = std::numeric_limits<double>::infinity();
  double kappa = 0;  // largest observed δ_n / δ_{n−1}²

  for (int it = 0; it < opt.max_iterations; ++it) {
    // Newton step (eq. (13)) by block elimination: S Δθ = −(g_θ − Σ C_k M_k⁻¹ g_zk).
    Eigen::Matrix<double, 9, 9> S = b.H_theta;
    Vec9 rhs = -b.g_theta;
    for (int k = 0; k < m; ++k) {
      // Eigen's 4x4 inverse is vectorised: measured faster than bordering with a 2x2 reduced
      // Hessian on a tangent basis.
      M_inv[k] = b.H_z[k].inverse();
      // The coupling's λ column is zero (H_θλ = 0): only its first three columns take part.
      const auto C = b.H_theta_z[k].leftCols<3>();
      const Eigen::Matrix<double, 9, 4> CM = C.lazyProduct(M_inv[k].topRows<3>());
      S.noalias() -= CM.leftCols<3>().lazyProduct(C.transpose());
      rhs.noalias() += CM * b.g_z[k];
    }
    const Vec9 scale = S.diagonal().cwiseAbs().cwiseSqrt().cwiseInverse();
    const Eigen::Matrix<double, 9, 9> scaled = scale.asDiagonal() * S * scale.asDiagonal();
    const Vec9 d_theta = scale.cwiseProduct(scaled.partialPivLu().solve(scale.cwiseProduct(rhs)));
    double d_dir = 0;
    for (int k = 0; k < m; ++k) {
      const Eigen::Vector4d dz = -M_inv[k] * (b.g_z[k] + b.H_theta_z[k].transpose() * d_theta);
      dirs[k] += dz.head<3>();
      lambda[k] += dz(3);
      d_dir = std::max(d_dir, dz.head<3>().lpNorm<Eigen::Infinity>());
    }
    theta += d_theta;
    ++out.summary.iterations;
    const ModelParameters current = Unpack(theta, ModelKind::kLinear);
    const double step = std::max(
        ScaledNorm(ToVec12(Unpack(d_theta, ModelKind::kLinear)), ParameterScales(problem, current)),
        d_dir);
    if (!std::isfinite(step)) {
      out.summary.termination = TerminationType::kNoProgress;
      out.summary.termination_message = "Newton diverged (non-finite step)";
      break;
    }
    if (step <= opt.parameter_tolerance) {
      out.summary.termination = TerminationType::kParameterTolerance;
      std::snprintf(message, sizeof message, "max(|dtheta|_s, max |dc|) = %.3e <= %.1e", step,
                    opt.parameter_tolerance);
      out.summary.termination_message = message;
      break;
    }
    // Quadratic convergence, δ_{n+1} ≈ κ δ_n²: once the next step predicted with the largest κ
    // observed so far (times 10) is below the tolerance, computing it would only confirm
    // round-off. A sequence that is not converging quadratically has growing ratios and does
    // not pass.
    if (previous_step < kQuadraticRegime) {
      kappa = std::max(kappa, step / (previous_step * previous_step));
      const double predicted = kQuadraticSafety * kappa * step * step;
      if (predicted <= opt.parameter_tolerance) {
        out.summary.termination = TerminationType::kParameterTolerance;
        std::snprintf(message, sizeof message,
                      "predicted next step 10 kappa |d|^2 = %.3e <= %.1e (|d| = %.3e, kappa = "
                      "%.3g: quadratic convergence)",
                      predicted, opt.parameter_tolerance, step, kappa);
        out.summary.termination_message = message;
        break;
      }
    }
    previous_step = step;
    LagrangianDerivatives(problem, theta, dirs, lambda, &b);
  }
  out.params = Unpack(theta, ModelKind::kLinear);
  for (Vec3& c : dirs) c.normalize();  // |c| = 1 holds to round-off at convergence
  out.dirs = std::move(dirs);
  out.summary.final_cost = Cost(problem, out.params, out.dirs);
  out.summary.time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace accelcal::internal
