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
#include "statistics/held_out_detail.hpp"

namespace accelcal::internal {

using held_out::Candidates;
using held_out::EllipsoidHeldOut;
using held_out::HeldOutError;
using held_out::kFootPointIterations;
using held_out::MayFailWithout;
using held_out::Objective;
using held_out::Setup;
using held_out::Structure;
using held_out::StructureOf;

namespace {

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

namespace {

// A position's term: ProfiledPosition's own (returned in place: its Hessian is not copied), or
// the modulus objectives' in its fields (u, ω 0, the foot point unused). The gradient and, with
// `hessian`, the Hessian are set where `ok`; nothing else is read of a term not `ok`.
using Term = ProfiledTerm;

Term Evaluate(const Setup& setup, const ModelParameters& params, const Vec3& reading,
              const Vec3& start, bool hessian) {
  if (setup.objective == Objective::kProfiled) {
    return ProfiledPosition(params, setup.gravity, setup.model, reading, start, hessian);
  }
  const ModulusTerm t = ModulusPosition(
      params, setup.gravity, setup.objective == Objective::kModulusSquared, reading, hessian);
  Term term;
  term.dir = Vec3::UnitZ();
  term.normal = Vec3::UnitZ();
  term.e = t.e;
  term.u.setZero();
  term.gradient = t.gradient;
  if (hessian) term.hessian = t.hessian;
  term.omega = 0;
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

}  // namespace

namespace held_out {

double HeldOutError(const ModelParameters& params, const Vec3& reading, double gravity) {
  const std::optional<Vec3> f = SpecificForce(params, reading);
  return f ? f->norm() - gravity : std::nan("");
}

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

}  // namespace held_out

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

Paired PairedImprovement(const std::vector<double>& simpler, const std::vector<double>& richer,
                         const std::vector<int>& positions) {
  const auto n = static_cast<double>(positions.size());
  std::vector<double> d;
  d.reserve(positions.size());
  for (int k : positions) {
    const auto i = static_cast<std::size_t>(k);
    d.push_back(simpler[i] * simpler[i] - richer[i] * richer[i]);
  }
  Paired p;
  for (double x : d) p.mean += x / n;
  double ss = 0;
  for (double x : d) ss += (x - p.mean) * (x - p.mean);
  p.se = std::sqrt(ss / (n - 1) / n);
  return p;
}

}  // namespace accelcal::internal
