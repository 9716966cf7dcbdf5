// Leave-one-position-out validation from an expansion of the full fit (held_out.hpp).
#include "statistics/held_out.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/LU>

#include "accelcal/frame.hpp"
#include "model/ellipsoid_quadric.hpp"
#include "solvers/smallest_eigenvector.hpp"

namespace accelcal::internal {

namespace {

// Cap of the foot point's Newton iteration (KktDirection); from the previous foot point it takes
// one or two steps.
constexpr int kFootPointIterations = 50;
// With fewer residual degrees of freedom than this, held out (m − 1 − P), every position is
// refitted: the likelihood may have several minima there (calibrate.cpp's MultiStart: ≤ 3), and
// the refits cost nothing.
constexpr int kMinExpansionDegreesOfFreedom = 4;
// Central differences of the summed Hessian for its derivative, in ‖·‖_s: the truncation error is
// (1e-4)² of the fourth derivative, the round-off 1e-16 / 1e-4 of the Hessian; the third-order term
// itself is a δ² correction (δ ~ 1e-5), so both are far below the tolerance.
constexpr double kDifferenceStep = 1e-4;
// The expansion's error is estimated as this times its last term squared over the step
// (IterativeHeldOut); without the factor, the largest error of the expansion alone measured 0.3 to
// 0.8 of the largest estimate on the Xsens and CTU recordings (test_crossval.cpp checks the bound).
constexpr double kEstimateSafety = 10.0;
// The observability check of each refit (calibrate.cpp, kMinInformationRcond): a held-out
// information S − u uᵀ ⪰ (1 − h) S, so a reciprocal condition of the full fit's times (1 − h) this
// far above the refits' threshold cannot fail it (the Jacobi scaling changes by less than the
// margin).
constexpr double kObservabilityMargin = 100;
// Newton's method on the expansion: iterations, a step that is round-off, and the quadratic
// regime's prediction of the next step (10 κ |d|², as the Newton-Lagrange solver).
constexpr int kMaxNewtonIterations = 50;
constexpr double kNegligibleStep = 1e-17;
constexpr double kQuadraticRegime = 1e-3;
constexpr double kQuadraticSafety = 10.0;
// The largest share of the held-out step that the third-order term may take for the expansion to
// be trusted (with exact passes after it); larger, the position is refitted.
constexpr double kMaxThirdOrderShare = 0.05;
// Newton steps (‖·‖_s) that stop shrinking below this are round-off: from 1e-9, quadratic
// convergence would reach 1e-17 in one step unless the model is determined to 1e-8 or worse.
constexpr double kRoundOff = 1e-9;
// Exact passes per held-out fit before it is refitted instead.
constexpr int kMaxExactPasses = 8;
// An exact pass uses the expansion's Hessian when that contracts the error at least this much per
// pass; else the exact Hessian (costing about this many gradient passes).
constexpr double kFastContraction = 1e-2;
constexpr long long kHessianPassCost = 4;
// A refit costs about as many passes (a few solver iterations, the checks, the information).
constexpr long long kRefitCost = 10;
// CheckData's coplanarity threshold (calibrate.cpp): singular values of the centred readings.
constexpr double kCoplanarRatio = 1e-3;

}  // namespace

ProfiledTerm ProfiledPosition(const ModelParameters& params, double gravity, ModelKind model,
                              const Vec3& reading, const Vec3& start, bool with_hessian) {
  ProfiledTerm t;
  const double g = gravity;
  const Vec3 c = KktDirection(params, g, reading, start, kFootPointIterations);
  if (!c.allFinite()) return t;
  const Vec3 f = g * c;
  Mat33 J;
  const Vec3 r = reading - PredictRaw(params, f, &J);
  const Mat32 E = TangentBasis(c);
  const Mat32 T = g * J * E;
  const Vec3 cross = T.col(0).cross(T.col(1));
  if (!(cross.norm() > 0)) return t;
  const Vec3 n = cross.normalized();
  const Vec12 mask = FreeMask(model);
  // M = ∂μ/∂θ (3 x 12) has axis i's regressors v_i = (f_x, .., f_i, 1, f_i²) in group i
  // (model.hpp), so Mᵀa has the blocks a_i v_i.
  const Regressors v(f);
  const auto M_transpose_times = [&](const Vec3& a) {
    Vec12 out;
    out << a(0) * v.x, a(1) * v.y, a(2) * v.z;
    return Vec12(out.cwiseProduct(mask));
  };
  t.dir = c;
  t.normal = n;
  t.e = n.dot(r);
  t.u = M_transpose_times(n);
  t.gradient = -2.0 * M_transpose_times(r);
  // The second fundamental form of the surface, as ExpectedSurfaceOffsets: with Σ = σ² I the
  // offset is −½ σ² tr(L G⁻¹).
  const Eigen::Matrix2d G = T.transpose() * T;
  const Eigen::Matrix2d G_inverse = G.inverse();
  const double radial = g * n.dot(J * c);
  Eigen::Matrix2d L;
  for (int a = 0; a < 2; ++a) {
    for (int b = 0; b < 2; ++b) {
      const Vec3 curvature = 2.0 * g * g * params.k2.cwiseProduct(E.col(a)).cwiseProduct(E.col(b));
      L(a, b) = n.dot(curvature) - (a == b ? radial : 0.0);
    }
  }
  t.omega = -0.5 * (L * G_inverse).trace();
  t.ok = std::isfinite(t.omega) && t.gradient.allFinite();
  if (!with_hessian) return t;
  // φ(θ, s) = ‖p − μ(θ, g c(s))‖² in tangent coordinates s of the sphere at c (c_s = E,
  // c_ss = −δ c); μ = M(f) θ is linear in θ. The profile's Hessian is φ_θθ − φ_θs φ_ss⁻¹ φ_sθ:
  //   φ_θθ = 2 MᵀM,  φ_θs = 2 MᵀT − 2 Σ_i r_i ∂M_i/∂s,
  //   φ_ss = 2 G − 2 Σ_i r_i ∂²μ_i/∂s∂s,  ∂²μ/∂s_a∂s_b = 2 g² k2 ∘ E_a ∘ E_b − δ_ab g J c,
  // with ∂v_i/∂s_a = (∂v_i/∂f) w, w = g E_a: (w_x, 0, 2 f_x w_x), (w_x, w_y, 0, 2 f_y w_y),
  // (w_x, w_y, w_z, 0, 2 f_z w_z).
  Mat12x2 C;
  for (int a = 0; a < 2; ++a) {
    const Vec3 w = g * E.col(a);
    Vec12 N;
    N << r(0) * w(0), 0.0, r(0) * 2.0 * f(0) * w(0),                           //
        r(1) * w(0), r(1) * w(1), 0.0, r(1) * 2.0 * f(1) * w(1),               //
        r(2) * w(0), r(2) * w(1), r(2) * w(2), 0.0, r(2) * 2.0 * f(2) * w(2);  //
    C.col(a) = 2.0 * (M_transpose_times(T.col(a)) - N.cwiseProduct(mask));
  }
  Eigen::Matrix2d phi_ss;
  const double radial_r = g * r.dot(J * c);
  const Vec3 rk2 = r.cwiseProduct(params.k2);
  for (int a = 0; a < 2; ++a) {
    for (int b = 0; b < 2; ++b) {
      const double second =
          2.0 * g * g * rk2.cwiseProduct(E.col(a)).dot(E.col(b)) - (a == b ? radial_r : 0.0);
      phi_ss(a, b) = 2.0 * G(a, b) - 2.0 * second;
    }
  }
  Mat12& H = t.hessian;
  H.setZero();
  H.block<3, 3>(kGroupStart[0], kGroupStart[0]).noalias() = 2.0 * v.x * v.x.transpose();
  H.block<4, 4>(kGroupStart[1], kGroupStart[1]).noalias() = 2.0 * v.y * v.y.transpose();
  H.block<5, 5>(kGroupStart[2], kGroupStart[2]).noalias() = 2.0 * v.z * v.z.transpose();
  H = (mask.asDiagonal() * H * mask.asDiagonal()).eval();
  const Mat12x2 W = C * phi_ss.inverse();
  H.noalias() -= W.lazyProduct(C.transpose());
  t.ok = t.ok && H.allFinite();
  return t;
}

ModulusTerm ModulusPosition(const ModelParameters& params, double gravity, bool squared,
                            const Vec3& reading, bool with_hessian) {
  ModulusTerm t;
  const Eigen::TriangularView<const Mat33, Eigen::Lower> K =
      params.K.triangularView<Eigen::Lower>();
  if (params.K(0, 0) == 0 || params.K(1, 1) == 0 || params.K(2, 2) == 0) return t;
  const Vec3 w = K.solve(Vec3(reading - params.bias));  // f, as ModulusResiduals
  const Mat33 Z = K.solve(Mat33::Identity());           // K⁻¹, column r = z_r
  // p = K w + b: ∂w/∂K_ij = −z_i w_j, ∂w/∂b_i = −z_i (k2 fixed at 0).
  struct Slot {
    int index, row, col;  // col −1: a bias
  };
  static constexpr Slot kSlots[9] = {{0, 0, 0}, {1, 0, -1}, {3, 1, 0}, {4, 1, 1},  {5, 1, -1},
                                     {7, 2, 0}, {8, 2, 1},  {9, 2, 2}, {10, 2, -1}};
  Mat3x12 W = Mat3x12::Zero();
  Vec12 coefficient = Vec12::Zero();  // c_s: w_j for K_ij, 1 for b_i
  for (const Slot& s : kSlots) {
    coefficient(s.index) = s.col >= 0 ? w(s.col) : 1.0;
    W.col(s.index) = -Z.col(s.row) * coefficient(s.index);
  }
  const double q = w.squaredNorm();
  const Vec12 grad_q = 2.0 * W.transpose() * w;
  Mat12 hess_q = Mat12::Zero();
  if (with_hessian) {
    // ∂²w/∂θ_s∂θ_t = [t ∈ K] z_r(t) Z(col t, r s) c_s + [s ∈ K] z_r(s) Z(col s, r t) c_t, so
    // wᵀ∂²w = [t ∈ K] y_r(t) Z(col t, r s) c_s + [s ∈ K] y_r(s) Z(col s, r t) c_t, y = Zᵀw.
    const Vec3 y = Z.transpose() * w;
    for (const Slot& s : kSlots) {
      for (const Slot& u : kSlots) {
        double value = 0;
        if (u.col >= 0) value += y(u.row) * Z(u.col, s.row) * coefficient(s.index);
        if (s.col >= 0) value += y(s.row) * Z(s.col, u.row) * coefficient(u.index);
        hess_q(s.index, u.index) = value;
      }
    }
    hess_q = 2.0 * (W.transpose() * W + hess_q);
  }
  Vec12 grad_e;
  Mat12 hess_e = Mat12::Zero();
  const double g = gravity;
  if (squared) {
    t.e = q / (g * g) - 1.0;
    grad_e = grad_q / (g * g);
    if (with_hessian) hess_e = hess_q / (g * g);
  } else {
    const double a = std::sqrt(q);
    t.e = a / g - 1.0;
    grad_e = grad_q / (2.0 * a * g);
    if (with_hessian) {
      hess_e = (hess_q / (2.0 * a) - grad_q * grad_q.transpose() / (4.0 * a * a * a)) / g;
    }
  }
  t.gradient = 2.0 * t.e * grad_e;
  if (with_hessian) t.hessian = 2.0 * (grad_e * grad_e.transpose() + t.e * hess_e);
  t.ok = t.gradient.allFinite() && (!with_hessian || t.hessian.allFinite());
  return t;
}

namespace {

enum class Objective { kProfiled, kModulusSquared, kModulusNorm };

// What the held-out fits solve, and the positions of the full fit in the x-first gauge.
struct Setup {
  Objective objective = Objective::kProfiled;
  bool bias_corrected = false;
  ModelKind model = ModelKind::kLinear;
  double gravity = 1;
  Vec12 mask;
  std::vector<Vec3> readings;  ///< the positions in the fit (x-first gauge)
  std::vector<Vec3> dirs;      ///< their foot points at the full fit (profiled objective)
  int dof_held_out = 0;        ///< m − 1 − P of a held-out fit
};

struct Term {
  double e = 0;
  double omega = 0;
  Vec3 dir = Vec3::UnitZ();
  Vec12 u = Vec12::Zero();
  Vec12 gradient = Vec12::Zero();
  Mat12 hessian = Mat12::Zero();
  bool ok = false;
};

Term Evaluate(const Setup& setup, const ModelParameters& params, const Vec3& reading,
              const Vec3& start, bool hessian) {
  Term term;
  if (setup.objective == Objective::kProfiled) {
    const ProfiledTerm t =
        ProfiledPosition(params, setup.gravity, setup.model, reading, start, hessian);
    term.e = t.e;
    term.omega = t.omega;
    term.dir = t.dir;
    term.u = t.u;
    term.gradient = t.gradient;
    if (hessian) term.hessian = t.hessian;
    term.ok = t.ok;
    return term;
  }
  const ModulusTerm t = ModulusPosition(
      params, setup.gravity, setup.objective == Objective::kModulusSquared, reading, hessian);
  term.e = t.e;
  term.gradient = t.gradient;
  if (hessian) term.hessian = t.hessian;
  term.ok = t.ok;
  return term;
}

// Sums over the positions (all, or all but `skip`) at θ: the objective's value, gradient and
// Hessian, and for the bias correction Σ ω_j u_j, Σ e_j ω_j and Σ ω_j².
struct Sums {
  double F = 0, EW = 0, W2 = 0;
  Vec12 gradient = Vec12::Zero();
  Vec12 B = Vec12::Zero();
  Mat12 hessian = Mat12::Zero();
  bool ok = true;
};

constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();

Sums SumAt(const Setup& setup, const Vec12& theta, bool hessian, std::size_t skip = kNone) {
  const ModelParameters params = FromVec12(theta);
  Sums s;
  for (std::size_t j = 0; j < setup.readings.size(); ++j) {
    if (j == skip) continue;
    const Vec3 start = setup.dirs.empty() ? Vec3::UnitZ() : setup.dirs[j];
    const Term t = Evaluate(setup, params, setup.readings[j], start, hessian);
    if (!t.ok) {
      s.ok = false;
      return s;
    }
    s.F += t.e * t.e;
    s.gradient += t.gradient;
    if (hessian) s.hessian += t.hessian;
    if (setup.bias_corrected) {
      s.B += t.omega * t.u;
      s.EW += t.e * t.omega;
      s.W2 += t.omega * t.omega;
    }
  }
  return s;
}

// The third-order expansion of the sums around the full fit θ̂ (first order for the bias
// correction's sums, which enter multiplied by σ̂²).
struct Expansion {
  Vec12 theta, scales;
  double F = 0;
  Vec12 g;
  Mat12 H;
  std::array<Mat12, kMaxParameters> T;  // T[i] = ∂H/∂θ_i
  Vec12 B;
  Mat12 dB;  // column i: ∂B/∂θ_i
  double EW = 0, W2 = 0;
  Vec12 dEW, dW2;
  bool ok = false;
};

Expansion Expand(const Setup& setup, const Vec12& theta, const Vec12& scales) {
  Expansion x;
  x.theta = theta;
  x.scales = scales;
  const Sums base = SumAt(setup, theta, true);
  if (!base.ok) return x;
  x.F = base.F;
  x.g = base.gradient;
  x.H = base.hessian;
  x.B = base.B;
  x.EW = base.EW;
  x.W2 = base.W2;
  x.dB.setZero();
  x.dEW.setZero();
  x.dW2.setZero();
  std::array<Mat12, kMaxParameters> D;
  for (int i = 0; i < kMaxParameters; ++i) {
    D[i].setZero();
    if (setup.mask(i) == 0.0) continue;
    const double h = kDifferenceStep / scales(i);
    Vec12 up = theta, down = theta;
    up(i) += h;
    down(i) -= h;
    const Sums plus = SumAt(setup, up, true);
    const Sums minus = SumAt(setup, down, true);
    if (!plus.ok || !minus.ok) return x;
    const double width = up(i) - down(i);
    D[i] = (plus.hessian - minus.hessian) / width;
    x.dB.col(i) = (plus.B - minus.B) / width;
    x.dEW(i) = (plus.EW - minus.EW) / width;
    x.dW2(i) = (plus.W2 - minus.W2) / width;
  }
  // ∂³F is symmetric in all three indices; each difference gives it with the first one fixed.
  for (int i = 0; i < kMaxParameters; ++i) {
    for (int a = 0; a < kMaxParameters; ++a) {
      for (int b = 0; b < kMaxParameters; ++b) {
        x.T[i](a, b) = (D[i](a, b) + D[a](i, b) + D[b](a, i)) / 3.0;
      }
    }
  }
  x.ok = true;
  return x;
}

// Σ_i δ_i T_i
Mat12 Contract(const Expansion& x, const Vec12& delta) {
  Mat12 out = Mat12::Zero();
  for (int i = 0; i < kMaxParameters; ++i) {
    if (delta(i) != 0.0) out += delta(i) * x.T[i];
  }
  return out;
}

// Solves J d = −R on the free parameters (Jacobi-scaled); NaN when J is singular.
Vec12 NewtonStep(Mat12 J, Vec12 R, const Vec12& mask) {
  for (int i = 0; i < kMaxParameters; ++i) {
    if (mask(i) != 0.0) continue;
    J.row(i).setZero();
    J.col(i).setZero();
    J(i, i) = 1.0;
    R(i) = 0.0;
  }
  const Vec12 scale = J.diagonal().cwiseAbs().cwiseSqrt().cwiseInverse();
  const Mat12 scaled = scale.asDiagonal() * J * scale.asDiagonal();
  const Eigen::PartialPivLU<Mat12> lu(scaled);
  Vec12 step = -scale.cwiseProduct(lu.solve(scale.cwiseProduct(R)));
  if (!step.allFinite()) step.setConstant(std::nan(""));
  return step.cwiseProduct(mask);
}

// σ̂² of a bias-corrected fit from its sums: dof σ̂² = Σ (e − σ̂² ω)² (calibrate.cpp's
// CorrectionOffsets at the fixed point), the root that tends to Σ e² / dof.
double BiasCorrectionVariance(double E2, double EW, double W2, int dof) {
  const double b = std::max(dof, 1) + 2.0 * EW;
  const double disc = b * b - 4.0 * W2 * E2;
  if (!(disc >= 0) || !(b > 0)) return std::nan("");
  return 2.0 * E2 / (b + std::sqrt(disc));
}

// A held-out fit found on the expansion.
struct HeldOutSolve {
  Vec12 delta = Vec12::Zero();
  double s2 = 0;         // σ̂² (bias correction)
  double last_step = 0;  // in ‖·‖_s: the last step, or the predicted next one
  Vec3 dir;              // position k's foot point (a start for the next one)
  bool ok = false;
};

// Whether a Newton iteration has converged, from its steps (‖·‖_s): a step of round-off, or the
// next one predicted to be (quadratic regime), or steps that stopped shrinking close to the
// solution: round-off in the sums, amplified by a poorly determined model (as converged as the
// arithmetic allows; `remaining` is then the step).
struct Convergence {
  double previous = std::numeric_limits<double>::infinity();
  double kappa = 0;  // largest step / previous² seen in the quadratic regime
  bool Check(double step, double* remaining) {
    *remaining = step;
    bool converged = step <= kNegligibleStep || (step >= 0.5 * previous && step <= kRoundOff);
    if (!converged && previous < kQuadraticRegime) {
      kappa = std::max(kappa, step / (previous * previous));
      const double next = kQuadraticSafety * kappa * step * step;
      converged = next <= kNegligibleStep;
      if (converged) *remaining = next;
    }
    previous = step;
    return converged;
  }
};

// Newton's method on the expansion of Σ_j (to third order, or with `third_order` false to second
// order) minus position k's exact term, from `start`, to round-off.
HeldOutSolve SolveOnExpansion(const Setup& setup, const Expansion& x, const Vec3& reading,
                              const Vec3& dir, bool third_order, const Vec12& start) {
  HeldOutSolve out;
  out.delta = start;
  out.dir = dir;
  Convergence convergence;
  for (int iteration = 0; iteration < kMaxNewtonIterations; ++iteration) {
    const Term k = Evaluate(setup, FromVec12(x.theta + out.delta), reading, out.dir, true);
    if (!k.ok) return out;
    out.dir = k.dir;
    const Mat12 Td = third_order ? Contract(x, out.delta) : Mat12::Zero();
    const Vec12 cubic = 0.5 * Td * out.delta;
    Vec12 R = x.g + x.H * out.delta + cubic - k.gradient;
    Mat12 J = x.H + Td - k.hessian;
    const double F = x.F + x.g.dot(out.delta) + 0.5 * out.delta.dot(x.H * out.delta) +
                     out.delta.dot(cubic) / 3.0 - k.e * k.e;  // Σ_{j≠k} e_j² on the expansion
    if (setup.bias_corrected) {
      out.s2 = BiasCorrectionVariance(F, x.EW + x.dEW.dot(out.delta) - k.e * k.omega,
                                      x.W2 + x.dW2.dot(out.delta) - k.omega * k.omega,
                                      setup.dof_held_out);
      R += 2.0 * out.s2 * (x.B + x.dB * out.delta - k.omega * k.u);
      J += 2.0 * out.s2 * x.dB;
    }
    const Vec12 step = NewtonStep(J, R, setup.mask);
    if (!step.allFinite()) return out;
    out.delta += step;
    if (convergence.Check(ScaledNorm(step, x.scales), &out.last_step)) {
      out.ok = true;
      return out;
    }
  }
  return out;
}

// One Newton step of a held-out fit with the exact sums over the other positions, and their
// exact Hessian or the expansion's; returns its size in ‖·‖_s, NaN on failure.
double ExactStep(const Setup& setup, const Expansion& x, std::size_t k, bool exact_hessian,
                 HeldOutSolve* solve) {
  const Vec12 theta = x.theta + solve->delta;
  const Sums rest = SumAt(setup, theta, exact_hessian, k);
  if (!rest.ok) return std::nan("");
  Mat12 J;
  if (exact_hessian) {
    J = rest.hessian;
  } else {
    const Term t = Evaluate(setup, FromVec12(theta), setup.readings[k], solve->dir, true);
    if (!t.ok) return std::nan("");
    solve->dir = t.dir;
    J = x.H + Contract(x, solve->delta) - t.hessian;
  }
  Vec12 R = rest.gradient;
  if (setup.bias_corrected) {
    solve->s2 = BiasCorrectionVariance(rest.F, rest.EW, rest.W2, setup.dof_held_out);
    R += 2.0 * solve->s2 * rest.B;
    J += 2.0 * solve->s2 * x.dB;
  }
  const Vec12 step = NewtonStep(J, R, setup.mask);
  if (!step.allFinite()) return std::nan("");
  solve->delta += step;
  return ScaledNorm(step, x.scales);
}

double HeldOutError(const ModelParameters& params, const Vec3& reading, double gravity) {
  const std::optional<Vec3> f = SpecificForce(params, reading);
  return f ? f->norm() - gravity : std::nan("");
}

// Whether the refit without position k might fail a check the expansion cannot see (CheckData's
// coplanarity, the observability of the model): those positions are refitted. The scatter of the
// other readings is the full scatter minus n/(n−1) (p_k − p̄)(p_k − p̄)ᵀ, whose smallest eigenvalue
// is at least the full one's minus n/(n−1) |p_k − p̄|².
struct Structure {
  Vec3 mean = Vec3::Zero();
  double lowest = 0, highest = 0;  // eigenvalues of the scatter
  double rcond = 0;                // of the full fit's information
  Mat12 S_inverse;
  Eigen::Matrix<double, Eigen::Dynamic, kMaxParameters> U;
};

Structure StructureOf(const Setup& setup, const ModelParameters& params,
                      const std::vector<Vec3>& dirs) {
  Structure s;
  const auto n = static_cast<double>(setup.readings.size());
  for (const Vec3& p : setup.readings) s.mean += p;
  s.mean /= n;
  Mat33 scatter = Mat33::Zero();
  for (const Vec3& p : setup.readings) scatter += (p - s.mean) * (p - s.mean).transpose();
  const Vec3 ev =
      Eigen::SelfAdjointEigenSolver<Mat33>(scatter, Eigen::EigenvaluesOnly).eigenvalues();
  s.lowest = ev(0);
  s.highest = ev(2);
  const Problem problem{setup.readings, setup.gravity, setup.model};
  InformationRows rows;
  const Information info = ComputeInformation(problem, params, dirs, &rows);
  s.rcond = info.rcond;
  s.S_inverse = info.Inverse();
  s.U = std::move(rows.U);
  return s;
}

bool MayFailWithout(const Setup& setup, const Structure& s, std::size_t k) {
  const auto n = static_cast<double>(setup.readings.size());
  const double lowest = s.lowest - n / (n - 1) * (setup.readings[k] - s.mean).squaredNorm();
  if (!(lowest > 0) || !(std::sqrt(lowest) > 2 * kCoplanarRatio * std::sqrt(s.highest))) {
    return true;
  }
  const Vec12 u = s.U.row(static_cast<Eigen::Index>(k)).transpose().cwiseProduct(setup.mask);
  const double leverage = u.dot(s.S_inverse * u);
  return !((1.0 - leverage) * s.rcond >= kObservabilityMargin * kMinInformationRcond);
}

// The held-out numbers of the iterative methods (fit positions' order); `refit` marks those a
// refit must give.
struct Candidates {
  std::vector<double> error;
  std::vector<bool> refit;
};

Candidates IterativeHeldOut(const Setup& setup, const ModelParameters& params,
                            const HeldOutSettings& settings, HeldOutPaths* paths) {
  const std::size_t n = setup.readings.size();
  Candidates out{std::vector<double>(n, std::nan("")), std::vector<bool>(n, true)};
  const Problem problem{setup.readings, setup.gravity, setup.model};
  const Vec12 theta = ToVec12(params).cwiseProduct(setup.mask);
  const Vec12 scales = ParameterScales(problem, params);
  const Expansion x = Expand(setup, theta, scales);
  if (!x.ok) return out;
  const Structure structure = StructureOf(
      setup, params, setup.dirs.empty() ? DirectionsFromParams(problem, params) : setup.dirs);
  const double tolerance = settings.tolerance;
  // Exact passes and refits for accuracy are paid from the budget (a refit as kRefitCost passes);
  // past it, a number keeps the expansion's accuracy.
  long long budget = settings.pass_budget_positions;
  const auto affordable = [&](long long passes) {
    return settings.correct && budget >= passes * static_cast<long long>(n);
  };
  const auto refit_for_accuracy = [&] {
    budget -= kRefitCost * static_cast<long long>(n);
    return true;
  };
  for (std::size_t k = 0; k < n; ++k) {
    if (MayFailWithout(setup, structure, k)) continue;
    const Vec3 dir = setup.dirs.empty() ? Vec3::UnitZ() : setup.dirs[k];
    const Vec3& reading = setup.readings[k];
    // Second order first (close to the one-step influence of position k), then third order from
    // it: the third-order term moved the solution by d, and the terms of the expansion fall by
    // about d / ‖δ‖_s each, so the next one is about d² / ‖δ‖_s.
    const HeldOutSolve second = SolveOnExpansion(setup, x, reading, dir, false, Vec12::Zero());
    if (!second.ok) continue;
    HeldOutSolve solve = SolveOnExpansion(setup, x, reading, second.dir, true, second.delta);
    if (!solve.ok && affordable(kRefitCost) && refit_for_accuracy()) continue;
    if (!solve.ok) solve = second;
    const double size = ScaledNorm(solve.delta, scales);
    const double d = ScaledNorm(solve.delta - second.delta, scales);
    // An expansion whose third-order term moves the solution by a sizeable part of it does not
    // describe the held-out fit: refit.
    if (!(d <= kMaxThirdOrderShare * size) && size > 0 && affordable(kRefitCost) &&
        refit_for_accuracy()) {
      continue;
    }
    double estimate = (size > 0 ? kEstimateSafety * d * d / size : 0.0) + solve.last_step;
    double rate = size > 0 ? kEstimateSafety * d / size : 0.0;
    // Exact passes over the other positions: Newton steps on F − f_k with its exact gradient, and
    // its exact Hessian unless the expansion's contracts the error fast. The error left after a
    // step is about the contraction times the step (linear convergence), or 10 κ step² with κ the
    // largest step / previous² (quadratic); steps that stop shrinking close to the solution are
    // round-off.
    const HeldOutSolve expansion = solve;
    const double expansion_estimate = estimate;
    bool corrected = false, round_off = false;
    const bool exact_hessian = rate > kFastContraction;
    double previous = std::numeric_limits<double>::infinity(), kappa = 0;
    for (int pass = 0; estimate > tolerance && pass < kMaxExactPasses &&
                       affordable(exact_hessian ? kHessianPassCost : 1);
         ++pass) {
      budget -= static_cast<long long>(n) * (exact_hessian ? kHessianPassCost : 1);
      if (paths) ++paths->exact_passes;
      corrected = true;
      const double step = ExactStep(setup, x, k, exact_hessian, &solve);
      if (step >= 0.5 * previous && step <= kRoundOff) {
        round_off = true;
        estimate = step;
        break;
      }
      if (!(step < previous)) {  // NaN, or diverging
        estimate = std::numeric_limits<double>::infinity();
        break;
      }
      if (exact_hessian) {
        if (previous < kQuadraticRegime) kappa = std::max(kappa, step / (previous * previous));
        estimate = previous < kQuadraticRegime ? kQuadraticSafety * kappa * step * step : step;
      } else {
        if (pass > 0) rate = std::max(rate, step / previous);
        estimate = kEstimateSafety * rate * step;
      }
      previous = step;
    }
    if (!round_off && !(estimate <= tolerance) && affordable(kRefitCost) && refit_for_accuracy()) {
      continue;  // not accurate, and a refit is affordable
    }
    if (!std::isfinite(estimate)) {  // diverging passes, and no refit affordable
      solve = expansion;
      estimate = expansion_estimate;
    }
    const double e = HeldOutError(FromVec12(theta + solve.delta), reading, setup.gravity);
    if (!std::isfinite(e)) continue;
    out.error[k] = e;
    out.refit[k] = false;
    if (paths) {
      ++(corrected ? paths->corrected : paths->from_expansion);
      paths->largest_estimate = std::max(paths->largest_estimate, estimate);
    }
  }
  return out;
}

// The ellipsoid method's held-out fits: its algebraic fit is the smallest eigenvector of the
// scatter D'ᵀD' of the design rows d(q) = (x², y², z², 2xy, 2xz, 2yz, 2x, 2y, 2z, 1) of the
// readings centred on their mean and divided by their largest deviation (ellipsoid_fit.cpp).
// Without position k the mean and scale change: q' = a q + t, d(q') = A d(q), so the held-out
// scatter is A (DᵀD − d_k d_kᵀ) Aᵀ, exactly.
using Vec10 = Eigen::Matrix<double, 10, 1>;
using Mat10 = Eigen::Matrix<double, 10, 10>;

Vec10 DesignRow(const Vec3& q) {
  Vec10 d;
  d << q(0) * q(0), q(1) * q(1), q(2) * q(2), 2 * q(0) * q(1), 2 * q(0) * q(2), 2 * q(1) * q(2),
      2 * q(0), 2 * q(1), 2 * q(2), 1.0;
  return d;
}

Mat10 DesignTransform(double a, const Vec3& t) {
  Mat10 A = Mat10::Zero();
  for (int i = 0; i < 3; ++i) {
    A(i, i) = a * a;  // x'² = a² x² + a t_x (2x) + t_x²
    A(i, 6 + i) = a * t(i);
    A(i, 9) = t(i) * t(i);
    A(6 + i, 6 + i) = a;  // 2x' = a (2x) + 2 t_x
    A(6 + i, 9) = 2 * t(i);
  }
  const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};  // 2xy, 2xz, 2yz
  for (int p = 0; p < 3; ++p) {
    const int i = pairs[p][0], j = pairs[p][1];
    A(3 + p, 3 + p) = a * a;  // 2x'y' = a² (2xy) + a t_y (2x) + a t_x (2y) + 2 t_x t_y
    A(3 + p, 6 + i) = a * t(j);
    A(3 + p, 6 + j) = a * t(i);
    A(3 + p, 9) = 2 * t(i) * t(j);
  }
  A(9, 9) = 1.0;
  return A;
}

// K and b of the quadric v in coordinates q = (p − mean) / scale (the algebraic fit's
// parameters, ellipsoid_fit.hpp); false when it is no real ellipsoid (the refit then tries the
// constrained fit).
bool QuadricParameters(const Vec10& v, const Vec3& mean, double scale, double gravity,
                       ModelParameters* params) {
  return !QuadricToParameters(v, mean, scale, gravity, params);
}

Candidates EllipsoidHeldOut(const Setup& setup, const ModelParameters& params,
                            HeldOutPaths* paths) {
  const std::size_t n = setup.readings.size();
  Candidates out{std::vector<double>(n, std::nan("")), std::vector<bool>(n, true)};
  Vec3 sum = Vec3::Zero();
  for (const Vec3& p : setup.readings) sum += p;
  const Vec3 mean = sum / static_cast<double>(n);
  double scale = 0;
  for (const Vec3& p : setup.readings)
    scale = std::max(scale, (p - mean).lpNorm<Eigen::Infinity>());
  Mat10 S = Mat10::Zero();
  for (const Vec3& p : setup.readings) {
    const Vec10 d = DesignRow((p - mean) / scale);
    S.selfadjointView<Eigen::Lower>().rankUpdate(d);
  }
  S.triangularView<Eigen::StrictlyUpper>() = S.transpose();
  // The two largest and smallest readings of each axis: the held-out scale's extremes.
  std::array<std::array<std::size_t, 2>, 3> high{}, low{};
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<std::size_t> order(n);
    for (std::size_t j = 0; j < n; ++j) order[j] = j;
    const auto by = [&](std::size_t a, std::size_t b) {
      return setup.readings[a](axis) > setup.readings[b](axis);
    };
    std::partial_sort(order.begin(), order.begin() + 2, order.end(), by);
    high[axis] = {order[0], order[1]};
    const auto below = [&](std::size_t a, std::size_t b) { return by(b, a); };
    std::partial_sort(order.begin(), order.begin() + 2, order.end(), below);
    low[axis] = {order[0], order[1]};
  }
  const Problem problem{setup.readings, setup.gravity, setup.model};
  const Structure structure = StructureOf(setup, params, DirectionsFromParams(problem, params));
  for (std::size_t k = 0; k < n; ++k) {
    if (MayFailWithout(setup, structure, k)) continue;
    const Vec3& p = setup.readings[k];
    const Vec3 held_mean = (sum - p) / static_cast<double>(n - 1);
    double held_scale = 0;
    for (int axis = 0; axis < 3; ++axis) {
      const double hi = setup.readings[high[axis][high[axis][0] == k ? 1 : 0]](axis);
      const double lo = setup.readings[low[axis][low[axis][0] == k ? 1 : 0]](axis);
      held_scale = std::max({held_scale, hi - held_mean(axis), held_mean(axis) - lo});
    }
    const Vec10 d = DesignRow((p - mean) / scale);
    const Mat10 A = DesignTransform(scale / held_scale, (mean - held_mean) / held_scale);
    Mat10 held = A * (S - d * d.transpose()) * A.transpose();
    held = (0.5 * (held + held.transpose())).eval();
    Vec10 v;
    if (const std::optional<Vec10> smallest = SmallestEigenvector(held)) {
      v = *smallest;
    } else {
      v = Eigen::SelfAdjointEigenSolver<Mat10>(held).eigenvectors().col(0);
    }
    ModelParameters fit;
    if (!QuadricParameters(v, held_mean, held_scale, setup.gravity, &fit)) continue;
    const double e = HeldOutError(fit, p, setup.gravity);
    if (!std::isfinite(e)) continue;
    out.error[k] = e;
    out.refit[k] = false;
    if (paths) ++paths->from_expansion;
  }
  return out;
}

}  // namespace

void HeldOutErrors(const std::vector<Vec3>& readings, const CalibrationOptions& options,
                   const HeldOutRefitFunction& refit, CalibrationResult* result,
                   HeldOutPaths* paths, const HeldOutSettings& settings) {
  const std::size_t m = readings.size();
  const bool z_first = options.frame == Frame::kZFirst;
  Setup setup;
  setup.model = options.model;
  setup.gravity = options.gravity;
  setup.mask = FreeMask(options.model);
  setup.bias_corrected = options.estimator == Estimator::kBiasCorrected;
  if (options.method == SolverMethod::kModulus) setup.objective = Objective::kModulusSquared;
  if (options.method == SolverMethod::kModulusNorm) setup.objective = Objective::kModulusNorm;
  std::vector<std::size_t> fit;  // input index of each position in the fit
  for (std::size_t k = 0; k < m; ++k) {
    if (result->excluded(k)) continue;
    fit.push_back(k);
    setup.readings.push_back(z_first ? MirrorAxes(readings[k]) : readings[k]);
  }
  const ModelParameters params = z_first ? MirrorAxes(result->params) : result->params;
  const int n = static_cast<int>(fit.size());
  setup.dof_held_out = n - 1 - NumParameters(options.model);

  std::vector<double> fast(m, std::nan(""));
  std::vector<bool> exact(m, true);
  if (setup.dof_held_out >= kMinExpansionDegreesOfFreedom) {
    Candidates c;
    if (options.method == SolverMethod::kEllipsoid) {
      c = EllipsoidHeldOut(setup, params, paths);
    } else {
      if (setup.objective == Objective::kProfiled) {
        const Problem problem{setup.readings, setup.gravity, setup.model};
        setup.dirs = DirectionsFromParams(problem, params);
        for (std::size_t j = 0; j < setup.readings.size(); ++j) {
          setup.dirs[j] = KktDirection(params, setup.gravity, setup.readings[j], setup.dirs[j],
                                       kFootPointIterations);
        }
      }
      c = IterativeHeldOut(setup, params, settings, paths);
    }
    for (std::size_t i = 0; i < fit.size(); ++i) {
      fast[fit[i]] = c.error[i];
      exact[fit[i]] = c.refit[i];
    }
  }
  std::vector<double> errors(m);
  for (std::size_t k = 0; k < m; ++k) {
    if (result->excluded(k)) {
      errors[k] = GravityNormErrors(result->params, {readings[k]}, options.gravity)[0];
      continue;
    }
    if (!exact[k]) {
      errors[k] = fast[k];
      continue;
    }
    const HeldOutRefit r = refit(k);
    if (paths) ++paths->refitted;
    if (!r.note.empty()) {
      result->crossval_note = r.note;
      return;
    }
    errors[k] = r.error;
  }
  result->crossval_rms = Rms(result->InFit(errors));
  result->crossval_errors = std::move(errors);
}

}  // namespace accelcal::internal
