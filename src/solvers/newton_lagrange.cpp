// Paper 001 (Sun & Xu 2020) §3.2: Newton iteration on the Lagrangian of the ML problem.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "core/cpu_features.hpp"
#include "core/text_format.hpp"
#include "solvers/newton_lagrange_kernel.hpp"
#include "solvers/solver_common.hpp"

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
// 2 (f_j y_i + g r_i x_j) for K_ij and 2 y_i for b_i, y = gKx. Its transpose is as simple:
// Cᵀ Δθ = 2 (gK)ᵀ(ΔK f + Δb) + 2 g ΔKᵀ r, so the back-substitution needs no stored G.
//
// For speed, positions are processed four at a time in structure-of-arrays blocks that hold the
// iteration's state (c, λ): newton_lagrange_kernel.hpp, built for the baseline CPU and for AVX.
// Nothing per position is stored between the passes but the few pieces the back-substitution
// needs (Cᵀ Δθ is a 3-vector, so G is never stored).
namespace {
namespace nk = newton_kernel;

const nk::Kernel& KernelFor(KernelIsa isa) {
#ifdef ACCELCAL_HAVE_AVX_KERNEL
  if (isa == KernelIsa::kAvx) return nk::avx::kKernel;
#endif
  (void)isa;
  return nk::baseline::kKernel;
}

// The lanes' sum in a fixed order, whichever kernel produced them.
double SumLanes(const double (&x)[nk::kLanes]) { return (x[0] + x[2]) + (x[1] + x[3]); }

std::vector<nk::Block> ToBlocks(const Problem& problem, const std::vector<Vec3>& c,
                                const std::vector<double>& lambda) {
  const int m = problem.positions();
  std::vector<nk::Block> blocks(static_cast<std::size_t>((m + nk::kLanes - 1) / nk::kLanes));
  for (std::size_t i = 0; i < blocks.size(); ++i) {
    nk::Block& block = blocks[i];
    const int first = static_cast<int>(i) * nk::kLanes;
    for (int l = 0; l < nk::kLanes; ++l) {
      const bool valid = first + l < m;
      const auto k = static_cast<std::size_t>(valid ? first + l : first);
      block.weight[l] = valid ? 1.0 : 0.0;
      block.lambda[l] = lambda[k];
      for (int d = 0; d < 3; ++d) {
        block.dir[d][l] = c[k](d);
        block.reading[d][l] = problem.readings[k](d);
      }
    }
  }
  return blocks;
}

// Position k's entry of a block field.
template <typename Field>
double Lane(const std::vector<nk::Block>& blocks, int k, Field field) {
  const nk::Block& block = blocks[static_cast<std::size_t>(k / nk::kLanes)];
  return field(block)[k % nk::kLanes];
}

struct ThetaStep {
  Vec9 d_theta;
  double cost = 0;  // J at θ
};

// One Newton step from θ and the blocks' (c, λ): the kernel's first pass, the reduced 9x9 system
// and its solution here, then the kernel's back-substitution into the blocks' Δc, Δλ.
ThetaStep NewtonStep(const nk::Kernel& kernel, const Problem& problem, const Vec9& theta,
                     std::vector<nk::Block>* blocks) {
  const double g = problem.gravity;
  const int n_blocks = static_cast<int>(blocks->size());
  nk::LaneSums sums;
  kernel.accumulate(theta.data(), g, blocks->data(), n_blocks, &sums);
  // H_θθ = 2 Σ J_θᵀJ_θ: block diagonal by output axis, with regressors v_i = (f_0..f_i, 1).
  Eigen::Matrix4d moments;  // Σ (f, 1)(f, 1)ᵀ
  int n = 0;
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b <= a; ++b) moments(a, b) = moments(b, a) = SumLanes(sums.moment[n++]);
    moments(a, 3) = moments(3, a) = SumLanes(sums.moment[6 + a]);
  }
  moments(3, 3) = SumLanes(sums.count);
  Eigen::Matrix<double, 9, 9> S = Eigen::Matrix<double, 9, 9>::Zero();
  constexpr int kStart[3] = {0, 2, 5};
  for (int i = 0; i < 3; ++i) {
    const auto regressor = [i](int a) { return a <= i ? a : 3; };  // f_0..f_i, then the 1
    for (int a = 0; a < i + 2; ++a) {
      for (int b = 0; b < i + 2; ++b) {
        S(kStart[i] + a, kStart[i] + b) = 2.0 * moments(regressor(a), regressor(b));
      }
    }
  }
  Vec9 rhs;
  n = 0;
  for (int j = 0; j < 9; ++j) {
    for (int i = j; i < 9; ++i) S(i, j) += SumLanes(sums.S[n++]);
    rhs(j) = SumLanes(sums.rhs[j]) - 2.0 * SumLanes(sums.grad[j]);
  }
  S.triangularView<Eigen::StrictlyUpper>() = S.transpose();
  const Vec9 scale = S.diagonal().cwiseAbs().cwiseSqrt().cwiseInverse();
  const Eigen::Matrix<double, 9, 9> scaled = scale.asDiagonal() * S * scale.asDiagonal();
  ThetaStep step;
  step.d_theta = scale.cwiseProduct(scaled.partialPivLu().solve(scale.cwiseProduct(rhs)));
  step.cost = SumLanes(sums.cost);
  kernel.back_substitute(theta.data(), step.d_theta.data(), g, blocks->data(), n_blocks);
  return step;
}
}  // namespace

KernelIsa BestKernelIsa() {
#ifdef ACCELCAL_HAVE_AVX_KERNEL
  if (Cpu().avx) return KernelIsa::kAvx;
#endif
  return KernelIsa::kBaseline;
}

bool KernelAvailable(KernelIsa isa) {
  return isa == KernelIsa::kBaseline || BestKernelIsa() == KernelIsa::kAvx;
}

void ComputeNewtonLagrangeStep(const Problem& problem, const Vec9& theta,
                               const std::vector<Vec3>& c, const std::vector<double>& lambda,
                               NewtonLagrangeStep* step, KernelIsa isa) {
  const int m = problem.positions();
  std::vector<nk::Block> blocks = ToBlocks(problem, c, lambda);
  const ThetaStep newton = NewtonStep(KernelFor(isa), problem, theta, &blocks);
  step->d_theta = newton.d_theta;
  step->cost = newton.cost;
  step->d_c.resize(static_cast<std::size_t>(m));
  step->d_lambda.resize(static_cast<std::size_t>(m));
  for (int k = 0; k < m; ++k) {
    const auto i = static_cast<std::size_t>(k);
    for (int d = 0; d < 3; ++d) {
      step->d_c[i](d) = Lane(blocks, k, [d](const nk::Block& b) { return b.d_dir[d]; });
    }
    step->d_lambda[i] = Lane(blocks, k, [](const nk::Block& b) { return b.d_lambda; });
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
  std::vector<nk::Block> blocks = ToBlocks(problem, dirs, lambda);
  const nk::Kernel& kernel = KernelFor(BestKernelIsa());
  char message[256];
  out.summary.termination = TerminationType::kMaxIterations;
  internal::FormatTo(message, sizeof message, "reached max_iterations = %d", opt.max_iterations);
  out.summary.termination_message = message;
  double previous_step = std::numeric_limits<double>::infinity();
  double kappa = 0;  // largest observed δ_n / δ_{n−1}²

  for (int it = 0; it < opt.max_iterations; ++it) {
    const ThetaStep newton = NewtonStep(kernel, problem, theta, &blocks);
    if (it == 0) out.summary.initial_cost = newton.cost;
    const Vec9& d_theta = newton.d_theta;
    const double d_dir = kernel.apply(blocks.data(), static_cast<int>(blocks.size()));
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
      internal::FormatTo(message, sizeof message, "max(|dtheta|_s, max |dc|) = %.3e <= %.1e", step,
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
        internal::FormatTo(message, sizeof message,
                           "predicted next step 10 kappa |d|^2 = %.3e <= %.1e (|d| = %.3e, kappa = "
                           "%.3g: quadratic convergence)",
                           predicted, opt.parameter_tolerance, step, kappa);
        out.summary.termination_message = message;
        break;
      }
    }
    previous_step = step;
  }
  out.params = Unpack(theta, ModelKind::kLinear);
  for (int k = 0; k < m; ++k) {
    for (int d = 0; d < 3; ++d) {
      dirs[static_cast<std::size_t>(k)](d) =
          Lane(blocks, k, [d](const nk::Block& b) { return b.dir[d]; });
    }
  }
  for (Vec3& c : dirs) c.normalize();  // |c| = 1 holds to round-off at convergence
  out.dirs = std::move(dirs);
  out.summary.final_cost = Cost(problem, out.params, out.dirs);
  out.summary.time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace accelcal::internal
