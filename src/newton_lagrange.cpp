// Paper 001 (Sun & Xu 2020) §3.2: Newton iteration on the Lagrangian of the ML problem.
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

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
// 2 (f_j y_i + g r_i x_j) for K_ij and 2 y_i for b_i, y = gKx. Its transpose is as simple:
// Cᵀ Δθ = 2 (gK)ᵀ(ΔK f + Δb) + 2 g ΔKᵀ r, so the back-substitution needs no stored G.
//
// For speed, positions are processed kLanes at a time, every scalar of one position becoming an
// Eigen array of kLanes positions (SIMD on any x86-64), and nothing per position is stored: the
// first pass sums the reduced system, the second recomputes the few pieces it needs.
namespace {
constexpr int kLanes = 4;
using Lanes = Eigen::Array<double, kLanes, 1>;
using Lanes3 = std::array<Lanes, 3>;

// θ = (K00, b0, K10, K11, b1, K20, K21, K22, b2), K lower triangular; returns g K x.
struct LowerTriangular {
  explicit LowerTriangular(const Vec9& theta, double scale)
      : k00(scale * theta(0)),
        k10(scale * theta(2)),
        k11(scale * theta(3)),
        k20(scale * theta(5)),
        k21(scale * theta(6)),
        k22(scale * theta(7)) {}
  Lanes3 operator*(const Lanes3& x) const {
    return {k00 * x[0], k10 * x[0] + k11 * x[1], k20 * x[0] + k21 * x[1] + k22 * x[2]};
  }
  /// Kᵀ x
  Lanes3 TransposeTimes(const Lanes3& x) const {
    return {k00 * x[0] + k10 * x[1] + k20 * x[2], k11 * x[1] + k21 * x[2], k22 * x[2]};
  }
  double k00, k10, k11, k20, k21, k22;
};

Lanes Dot(const Lanes3& a, const Lanes3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// kLanes positions starting at `first`; lanes past the end repeat the first position and have
// weight 0 (so they never divide by zero and add nothing).
struct Block {
  Block(const Problem& problem, const std::vector<Vec3>& c, const std::vector<double>& lambda,
        int first) {
    const int m = problem.positions();
    for (int l = 0; l < kLanes; ++l) {
      const bool valid = first + l < m;
      const auto k = static_cast<std::size_t>(valid ? first + l : first);
      weight(l) = valid ? 1.0 : 0.0;
      lam(l) = lambda[k];
      for (int d = 0; d < 3; ++d) {
        dir[d](l) = c[k](d);
        reading[d](l) = problem.readings[k](d);
      }
    }
  }
  Lanes3 dir, reading;
  Lanes lam, weight;
};

// What both passes need of each position: the pieces of the elimination above.
struct Local {
  Local(const Block& in, const LowerTriangular& gK, const Vec3& bias, double g) : c(in.dir) {
    cc = Dot(c, c);
    h = cc - 1.0;
    const Lanes inv_norm = cc.sqrt().inverse();
    // Orthonormal basis of the plane ⟂ n without branches (Duff et al. 2017, "Building an
    // orthonormal basis, revisited", JCGT 6(1)); any basis gives the same step.
    const Lanes nx = c[0] * inv_norm, ny = c[1] * inv_norm, nz = c[2] * inv_norm;
    const Lanes s = (nz >= 0.0).select(Lanes::Constant(1.0), Lanes::Constant(-1.0));
    const Lanes a = -(s + nz).inverse();
    const Lanes b = nx * ny * a;
    E[0] = {1.0 + s * nx * nx * a, s * b, -s * nx};
    E[1] = {b, s + ny * ny * a, -ny};
    f = {g * c[0], g * c[1], g * c[2]};
    y = gK * c;
    for (int d = 0; d < 3; ++d) {
      r[d] = y[d] + bias(d) - in.reading[d];
      gr[d] = g * r[d];
    }
    T[0] = gK * E[0];
    T[1] = gK * E[1];
    const Lanes a00 = 2.0 * (Dot(T[0], T[0]) + in.lam);
    const Lanes a01 = 2.0 * Dot(T[0], T[1]);
    const Lanes a11 = 2.0 * (Dot(T[1], T[1]) + in.lam);
    const Lanes inv_det = (a00 * a11 - a01 * a01).inverse();
    w00 = a11 * inv_det;
    w01 = -a01 * inv_det;
    w11 = a00 * inv_det;
    const Lanes h_cc = h / cc;
    const Lanes3 q = {2.0 * r[0] - h_cc * y[0], 2.0 * r[1] - h_cc * y[1], 2.0 * r[2] - h_cc * y[2]};
    e0 = Dot(T[0], q);
    e1 = Dot(T[1], q);
  }
  Lanes3 c, E[2], f, y, r, gr, T[2];
  Lanes cc, h, w00, w01, w11, e0, e1;
};

// What the back-substitution needs of a block, kept from the first pass.
struct Kept {
  explicit Kept(const Local& p)
      : E{p.E[0], p.E[1]},
        y(p.y),
        r(p.r),
        cc(p.cc),
        h(p.h),
        w00(p.w00),
        w01(p.w01),
        w11(p.w11),
        e0(p.e0),
        e1(p.e1) {}
  Lanes3 E[2], y, r;
  Lanes cc, h, w00, w01, w11, e0, e1;
};

// The 9 entries of ½ C x for x (with y = gK x); the factor 2 is applied to the sums instead.
inline void HalfCoupling(const Local& p, const Lanes3& x, const Lanes3& gKx, Lanes* out) {
  out[0] = p.f[0] * gKx[0] + p.gr[0] * x[0];
  out[1] = gKx[0];
  out[2] = p.f[0] * gKx[1] + p.gr[1] * x[0];
  out[3] = p.f[1] * gKx[1] + p.gr[1] * x[1];
  out[4] = gKx[1];
  out[5] = p.f[0] * gKx[2] + p.gr[2] * x[0];
  out[6] = p.f[1] * gKx[2] + p.gr[2] * x[1];
  out[7] = p.f[2] * gKx[2] + p.gr[2] * x[2];
  out[8] = gKx[2];
}

// Running sums of the first pass, one lane per position slot.
struct Sums {
  Lanes S[45];      // −Σ G W Gᵀ, lower triangle by columns
  Lanes rhs[9];     // Σ (h/(2|c|²)) C c + G W e
  Lanes grad[9];    // Σ J_θᵀ r
  Lanes moment[9];  // Σ f_a f_b (a ≥ b), then Σ f_a
  Lanes count = Lanes::Zero(), cost = Lanes::Zero();
  Sums() {
    for (Lanes& x : S) x.setZero();
    for (Lanes& x : rhs) x.setZero();
    for (Lanes& x : grad) x.setZero();
    for (Lanes& x : moment) x.setZero();
  }
  // With G = 2G', u = 2u': G W Gᵀ = G' (4W) G'ᵀ, (h/(2|c|²)) u + G W e = (h/|c|²) u' + G' (4W) e/2.
  void Add(const Block& in, const Local& p) {
    Lanes G0[9], G1[9], u[9];
    HalfCoupling(p, p.E[0], p.T[0], G0);
    HalfCoupling(p, p.E[1], p.T[1], G1);
    HalfCoupling(p, p.c, p.y, u);
    const Lanes weight4 = 4.0 * in.weight;
    const Lanes w00 = weight4 * p.w00, w01 = weight4 * p.w01, w11 = weight4 * p.w11;
    const Lanes h_cc = in.weight * p.h / p.cc;
    const Lanes half_e0 = 0.5 * p.e0, half_e1 = 0.5 * p.e1;
    int n = 0;
    for (int j = 0; j < 9; ++j) {
      const Lanes z0 = G0[j] * w00 + G1[j] * w01;
      const Lanes z1 = G0[j] * w01 + G1[j] * w11;
      for (int i = j; i < 9; ++i) S[n++] -= z0 * G0[i] + z1 * G1[i];
      rhs[j] += h_cc * u[j] + z0 * half_e0 + z1 * half_e1;
    }
    const Lanes3 r = {in.weight * p.r[0], in.weight * p.r[1], in.weight * p.r[2]};
    grad[0] += r[0] * p.f[0];
    grad[1] += r[0];
    grad[2] += r[1] * p.f[0];
    grad[3] += r[1] * p.f[1];
    grad[4] += r[1];
    grad[5] += r[2] * p.f[0];
    grad[6] += r[2] * p.f[1];
    grad[7] += r[2] * p.f[2];
    grad[8] += r[2];
    const Lanes3 fw = {in.weight * p.f[0], in.weight * p.f[1], in.weight * p.f[2]};
    n = 0;
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b <= a; ++b) moment[n++] += fw[a] * p.f[b];
    }
    for (int a = 0; a < 3; ++a) moment[6 + a] += fw[a];
    count += in.weight;
    cost += Dot(r, p.r);
  }
};
}  // namespace

void ComputeNewtonLagrangeStep(const Problem& problem, const Vec9& theta,
                               const std::vector<Vec3>& c, const std::vector<double>& lambda,
                               NewtonLagrangeStep* step) {
  const double g = problem.gravity;
  const int m = problem.positions();
  const LowerTriangular gK(theta, g);
  const Vec3 bias(theta(1), theta(4), theta(8));
  Sums sums;
  std::vector<Kept> kept;
  kept.reserve(static_cast<std::size_t>((m + kLanes - 1) / kLanes));
  for (int first = 0; first < m; first += kLanes) {
    const Block in(problem, c, lambda, first);
    const Local local(in, gK, bias, g);
    sums.Add(in, local);
    kept.emplace_back(local);
  }
  step->cost = sums.cost.sum();
  // H_θθ = 2 Σ J_θᵀJ_θ: block diagonal by output axis, with regressors v_i = (f_0..f_i, 1).
  Eigen::Matrix4d moments;  // Σ (f, 1)(f, 1)ᵀ
  int n = 0;
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b <= a; ++b) moments(a, b) = moments(b, a) = sums.moment[n++].sum();
    moments(a, 3) = moments(3, a) = sums.moment[6 + a].sum();
  }
  moments(3, 3) = sums.count.sum();
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
    for (int i = j; i < 9; ++i) S(i, j) += sums.S[n++].sum();
    rhs(j) = sums.rhs[j].sum() - 2.0 * sums.grad[j].sum();
  }
  S.triangularView<Eigen::StrictlyUpper>() = S.transpose();
  const Vec9 scale = S.diagonal().cwiseAbs().cwiseSqrt().cwiseInverse();
  const Eigen::Matrix<double, 9, 9> scaled = scale.asDiagonal() * S * scale.asDiagonal();
  const Vec9 d_theta = scale.cwiseProduct(scaled.partialPivLu().solve(scale.cwiseProduct(rhs)));
  step->d_theta = d_theta;

  // Back-substitution with v = Cᵀ Δθ = 2 (gK)ᵀ(ΔK f + Δb) + 2 g ΔKᵀ r.
  const LowerTriangular dK(d_theta, 1.0);
  const Vec3 d_bias(d_theta(1), d_theta(4), d_theta(8));
  step->d_c.resize(static_cast<std::size_t>(m));
  step->d_lambda.resize(static_cast<std::size_t>(m));
  for (int first = 0; first < m; first += kLanes) {
    const Block in(problem, c, lambda, first);
    const Kept& p = kept[static_cast<std::size_t>(first / kLanes)];
    const Lanes3& dir = in.dir;
    const Lanes3 f = {g * dir[0], g * dir[1], g * dir[2]};
    Lanes3 w = dK * f;
    for (int d = 0; d < 3; ++d) w[d] += d_bias(d);
    const Lanes3 a = gK.TransposeTimes(w), b = dK.TransposeTimes(p.r);
    const Lanes3 v = {2.0 * (a[0] + g * b[0]), 2.0 * (a[1] + g * b[1]), 2.0 * (a[2] + g * b[2])};
    const Lanes t0 = Dot(p.E[0], v) + p.e0, t1 = Dot(p.E[1], v) + p.e1;
    const Lanes a0 = -(p.w00 * t0 + p.w01 * t1), a1 = -(p.w01 * t0 + p.w11 * t1);
    const Lanes half_h = p.h / (2.0 * p.cc);
    Lanes3 d_c;
    for (int d = 0; d < 3; ++d) d_c[d] = -half_h * dir[d] + p.E[0][d] * a0 + p.E[1][d] * a1;
    const Lanes normal_rhs = 2.0 * Dot(p.y, p.r) + 2.0 * in.lam * p.cc - in.lam * p.h;
    const Lanes d_lambda = -(normal_rhs + Dot(dir, v) + 2.0 * Dot(p.y, gK * d_c)) / (2.0 * p.cc);
    for (int l = 0; l < kLanes && first + l < m; ++l) {
      const auto k = static_cast<std::size_t>(first + l);
      step->d_c[k] = Vec3(d_c[0](l), d_c[1](l), d_c[2](l));
      step->d_lambda[k] = d_lambda(l);
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
