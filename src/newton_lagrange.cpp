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

// The Newton system of the Lagrangian, per position (H_cc = 2(g²KᵀK + λI), H_cλ = 2c, C = H_θc):
//   H_θθ Δθ + Σ C Δc = −∇_θ,   Cᵀ Δθ + H_cc Δc + 2c Δλ = −∇_c,   2cᵀ Δc = −h  (h = |c|² − 1).
// Write Δc = Δc_p + E a with Δc_p = −h c / (2|c|²) (meets the last row) and E (3x2) an orthonormal
// basis of the plane ⟂ c. The middle rows times Eᵀ (which removes Δλ) give
//   a = −W (Gᵀ Δθ + e),  W = (Eᵀ H_cc E)⁻¹ = (2(TᵀT + λI))⁻¹,  G = C E,  e = Eᵀ(∇_c + H_cc Δc_p),
// with T = gKE; Eᵀ∇_c = 2Tᵀr and EᵀH_ccΔc_p = −(h/|c|²) Tᵀ gKc, so e = Tᵀ(2r − (h/|c|²) gKc).
// Substituting into the first row: (H_θθ − Σ G W Gᵀ) Δθ = −∇_θ + Σ (h/(2|c|²)) C c + Σ G W e.
// The middle rows times cᵀ give Δλ = −(cᵀ∇_c + (Cc)ᵀΔθ + cᵀH_ccΔc) / (2|c|²), with cᵀ∇_c =
// 2 gKc·r + 2λ|c|² and cᵀH_ccΔc = 2 gKc·(gK Δc) − λh.
// C never appears as a matrix: J_θ's rows are the regressors v_i = (f_0..f_i, 1) of output axis i,
// and ∂(2 r_i f_j)/∂c = 2 g (gK)_i· c_j + 2 g r_i e_j, so for any x ∈ R³ the entries of C x are
// 2 (f_j y_i + g r_i x_j) for K_ij and 2 y_i for b_i, y = gKx.
void ComputeNewtonLagrangeStep(const Problem& problem, const Vec9& theta,
                               const std::vector<Vec3>& c, const std::vector<double>& lambda,
                               NewtonLagrangeStep* step) {
  const double g = problem.gravity;
  const int m = problem.positions();
  const Mat33 gK = g * Unpack(theta, ModelKind::kLinear).K;
  const Vec3 bias(theta(1), theta(4), theta(8));
  step->positions.resize(static_cast<std::size_t>(m));
  step->d_c.resize(static_cast<std::size_t>(m));
  step->d_lambda.resize(static_cast<std::size_t>(m));
  step->cost = 0;
  Eigen::Matrix<double, 9, 9> S = Eigen::Matrix<double, 9, 9>::Zero();
  Vec9 rhs = Vec9::Zero();
  for (int k = 0; k < m; ++k) {
    NewtonLagrangeStep::Position& pos = step->positions[static_cast<std::size_t>(k)];
    const Vec3& ck = c[static_cast<std::size_t>(k)];
    const double lam = lambda[static_cast<std::size_t>(k)];
    const double cc = ck.squaredNorm();
    const double h = cc - 1.0;
    const Vec3 f = g * ck;
    pos.gKc = gK * ck;
    const Vec3 r = pos.gKc + bias - problem.readings[static_cast<std::size_t>(k)];
    step->cost += r.squaredNorm();
    // ∇_θ and H_θθ = 2 Σ J_θᵀJ_θ (block diagonal by output axis).
    const Eigen::Vector2d vx(f(0), 1.0);
    const Eigen::Vector3d vy(f(0), f(1), 1.0);
    const Eigen::Vector4d vz(f(0), f(1), f(2), 1.0);
    rhs.segment<2>(0) -= 2.0 * r(0) * vx;
    rhs.segment<3>(2) -= 2.0 * r(1) * vy;
    rhs.segment<4>(5) -= 2.0 * r(2) * vz;
    S.block<2, 2>(0, 0).noalias() += 2.0 * vx * vx.transpose();
    S.block<3, 3>(2, 2).noalias() += 2.0 * vy * vy.transpose();
    S.block<4, 4>(5, 5).noalias() += 2.0 * vz * vz.transpose();
    pos.E = TangentBasis(ck / std::sqrt(cc));
    const Mat32 T = gK * pos.E;
    // C x for x = E₀, E₁ and c.
    const auto coupling = [&](const Vec3& x, const Vec3& y, auto out) {
      out(0) = 2.0 * (f(0) * y(0) + g * r(0) * x(0));
      out(1) = 2.0 * y(0);
      out(2) = 2.0 * (f(0) * y(1) + g * r(1) * x(0));
      out(3) = 2.0 * (f(1) * y(1) + g * r(1) * x(1));
      out(4) = 2.0 * y(1);
      out(5) = 2.0 * (f(0) * y(2) + g * r(2) * x(0));
      out(6) = 2.0 * (f(1) * y(2) + g * r(2) * x(1));
      out(7) = 2.0 * (f(2) * y(2) + g * r(2) * x(2));
      out(8) = 2.0 * y(2);
    };
    coupling(pos.E.col(0), T.col(0), pos.G.col(0));
    coupling(pos.E.col(1), T.col(1), pos.G.col(1));
    coupling(ck, pos.gKc, pos.u.col(0));
    Eigen::Matrix2d reduced = 2.0 * T.transpose() * T;
    reduced.diagonal().array() += 2.0 * lam;
    pos.W = reduced.inverse();
    pos.e = T.transpose() * (2.0 * r - (h / cc) * pos.gKc);
    pos.normal_rhs = 2.0 * pos.gKc.dot(r) + 2.0 * lam * cc - lam * h;
    const Eigen::Matrix<double, 9, 2> Z = pos.G * pos.W;
    // Coefficient-based: the default product of a 9x2 by a 2x9 takes the general (GEMM) path,
    // measured 2x slower here.
    S.noalias() -= Z.lazyProduct(pos.G.transpose());
    rhs.noalias() += (h / (2.0 * cc)) * pos.u + Z * pos.e;
  }
  const Vec9 scale = S.diagonal().cwiseAbs().cwiseSqrt().cwiseInverse();
  const Eigen::Matrix<double, 9, 9> scaled = scale.asDiagonal() * S * scale.asDiagonal();
  step->d_theta = scale.cwiseProduct(scaled.partialPivLu().solve(scale.cwiseProduct(rhs)));
  for (int k = 0; k < m; ++k) {
    const auto i = static_cast<std::size_t>(k);
    const NewtonLagrangeStep::Position& pos = step->positions[i];
    const double cc = c[i].squaredNorm();
    const Eigen::Vector2d a = -pos.W * (pos.G.transpose() * step->d_theta + pos.e);
    step->d_c[i] = -((cc - 1.0) / (2.0 * cc)) * c[i] + pos.E * a;
    const Vec3 gK_dc = gK * step->d_c[i];
    step->d_lambda[i] =
        -(pos.normal_rhs + pos.u.dot(step->d_theta) + 2.0 * pos.gKc.dot(gK_dc)) / (2.0 * cc);
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
  NewtonLagrangeStep newton;
  ComputeNewtonLagrangeStep(problem, theta, dirs, lambda, &newton);
  out.summary.initial_cost = newton.cost;
  char message[256];
  out.summary.termination = TerminationType::kMaxIterations;
  std::snprintf(message, sizeof message, "reached max_iterations = %d", opt.max_iterations);
  out.summary.termination_message = message;
  double previous_step = std::numeric_limits<double>::infinity();
  double kappa = 0;  // largest observed δ_n / δ_{n−1}²

  for (int it = 0; it < opt.max_iterations; ++it) {
    const Vec9& d_theta = newton.d_theta;
    double d_dir = 0;
    for (int k = 0; k < m; ++k) {
      const auto i = static_cast<std::size_t>(k);
      dirs[i] += newton.d_c[i];
      lambda[i] += newton.d_lambda[i];
      d_dir = std::max(d_dir, newton.d_c[i].lpNorm<Eigen::Infinity>());
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
    ComputeNewtonLagrangeStep(problem, theta, dirs, lambda, &newton);
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
