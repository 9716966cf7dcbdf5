#pragma once
// Leave-one-position-out validation (CrossValidate, calibrate.hpp) without m refits.
//
// Every method's fit solves equations that are sums over the positions. For the maximum-likelihood
// methods the directions profile out: the fit minimises F(θ) = Σ_j f_j(θ), f_j the squared distance
// of reading j from the surface μ(θ, g S²), and the fit without position k minimises F − f_k. The
// held-out fits are all close to the full one (each moves θ by about h_k e_k / signal, h_k = P/m
// on average), so F is expanded once around the full fit θ̂, to third order (its gradient, its
// Hessian, and the derivative of the Hessian by central differences: 2P + 1 passes over the
// positions), and each fit without a position is found by Newton's method on that expansion minus
// the exact f_k (second order first, then third order from there): no pass over the positions per
// held-out fit. The bias-corrected estimator's fixed point (the readings shifted by σ̂² ω_j along
// the normals, σ̂² from the shifted cost) adds Σ ω_j u_j, Σ e_j ω_j and Σ ω_j² to the sums; the
// modulus methods expand their own sum of squares; the ellipsoid fit, closed form, downdates its
// scatter matrix (exact).
//
// The expansion's error is estimated from its last term (how far the third-order term moved the
// solution). Where it exceeds HeldOutSettings::tolerance, exact Newton passes over the other
// positions (F − f_k's exact gradient) finish the fit, and where the expansion does not describe
// the fit (its third-order term moves it by over 5 %, the iteration fails) the position is
// refitted; these are paid from a budget, past which numbers keep the expansion's accuracy.
// Positions whose refit could fail a check (too few positions, a position without which the others
// do not determine the model or lie in one plane, a reading out of the held-out fit's range) are
// refitted as before, so that the failure notes are unchanged. A refit's solver stopping at its
// iteration cap (two-step, Newton-Lagrange) is not reproduced: the expansion gives that position's
// number.

#include <functional>
#include <string>
#include <vector>

#include "accelcal/calibration_types.hpp"
#include "solvers/solver_common.hpp"

namespace accelcal::internal {

/// A refit without one position, as CrossValidate always did it (the fit of the other positions
/// started from the full fit): the held-out error |f_k| − g, or the note why there is none
/// (CalibrationResult::crossval_note).
struct HeldOutRefit {
  double error = 0;
  std::string note;
};
using HeldOutRefitFunction = std::function<HeldOutRefit(std::size_t position)>;

/// How each held-out error was obtained (tests and benchmarks).
struct HeldOutPaths {
  int from_expansion = 0;  ///< Newton on the expansion alone
  int corrected = 0;       ///< the expansion, then exact passes over the other positions
  int exact_passes = 0;    ///< exact passes over the other positions in all
  int refitted = 0;        ///< refits (HeldOutRefitFunction)
  /// Largest estimated error of an accepted number, in ‖·‖_s (TerminationType's metric); the
  /// held-out error is accurate to about g times this.
  double largest_estimate = 0;
};

/// Settings of HeldOutErrors.
struct HeldOutSettings {
  /// Accept a held-out fit when its estimated error in ‖·‖_s is below this. The refits stop at
  /// steps of 1e-14 (CalibrationOptions' parameter tolerances) and agree with each other to a few
  /// 1e-13 (round-off; see test_crossval.cpp), so the expansion is asked for the same.
  double tolerance = 1e-13;
  /// Work allowed for accuracy, in positions evaluated: exact passes over the other positions
  /// (one pass: m positions; with the exact Hessian, 4 m) and refits of positions the expansion
  /// does not describe (10 m each). Past it, a number keeps the expansion's accuracy
  /// (HeldOutPaths::largest_estimate). Refits for the checks a refit makes (held_out.cpp,
  /// MayFailWithout) are not limited: they decide the failure notes.
  long long pass_budget_positions = 4'000'000;
  /// false: every number from the expansion alone (tests measure its accuracy), except the
  /// positions a refit must decide (failures).
  bool correct = true;
};

/// Fills result->crossval_errors and crossval_rms, or crossval_note, as m refits would
/// (`refit`, called for the positions the expansion does not serve). `result` is a converged fit of
/// `readings` with `options`.
void HeldOutErrors(const std::vector<Vec3>& readings, const CalibrationOptions& options,
                   const HeldOutRefitFunction& refit, CalibrationResult* result,
                   HeldOutPaths* paths = nullptr, const HeldOutSettings& settings = {});

/// The refit without position k that CrossValidate always made (calibrate.cpp): the positions of
/// `result`'s fit but k, with `options`, started from `result`'s parameters.
HeldOutRefit RefitWithout(const std::vector<Vec3>& readings, const CalibrationOptions& options,
                          const CalibrationResult& result, std::size_t position);

/// The reference: CrossValidate by m refits, as before the expansion (calibrate.cpp).
void CrossValidateByRefits(const std::vector<Vec3>& readings, const CalibrationOptions& options,
                           CalibrationResult* result);

/// The one leave-one-position-out loop (orientation-free refits, CrossValidateByRefits, and the
/// known-orientation fit): each position's held-out error from `refit_without`, the excluded
/// positions' under the result itself (they are held out of every fit already); the first note
/// ends it as result->crossval_note, else result->crossval_rms (over the positions in the fit) and
/// crossval_errors.
void LeaveOneOut(const std::vector<Vec3>& readings, const HeldOutRefitFunction& refit_without,
                 CalibrationResult* result);

/// Position k's held-out error |f| − g under `without` (a fit of the others), or the note that
/// the reading is outside that fit's range.
HeldOutRefit HeldOutErrorUnder(const ModelParameters& without, const Vec3& reading, double gravity,
                               std::size_t k);

/// One position's term of the profiled maximum-likelihood objective at θ (x-first gauge):
/// f(θ) = min over |c| = 1 of ‖p − μ(θ, g c)‖². Exposed for the derivative tests.
struct ProfiledTerm {
  Vec3 dir;     ///< the foot point c (unit)
  Vec3 normal;  ///< unit normal of the surface at μ(θ, g c), T₁ × T₂ (ExpectedSurfaceOffsets)
  double e = 0;      ///< nᵀ(p − μ): signed distance, f = e²
  Vec12 u;           ///< Mᵀ n, M = ∂μ/∂θ (the information row, ReducedInformationRows)
  Vec12 gradient;    ///< ∇f = −2 Mᵀ(p − μ) = −2 e u
  Mat12 hessian;     ///< ∇²f (zero rows and columns for fixed parameters)
  double omega = 0;  ///< the bias correction's offset per unit noise variance: m = σ² ω
  bool ok = false;   ///< false: no foot point (a degenerate surface)
};
/// `start`: where the foot point's Newton iteration starts (the previous foot point).
ProfiledTerm ProfiledPosition(const ModelParameters& params, double gravity, ModelKind model,
                              const Vec3& reading, const Vec3& start, bool with_hessian);

/// One position's term of the modulus objectives (linear model): e = |f|²/g² − 1 (squared) or
/// |f|/g − 1, f = K⁻¹(p − b); gradient and Hessian of e² in the 12-layout.
struct ModulusTerm {
  double e = 0;
  Vec12 gradient;
  Mat12 hessian;
  bool ok = false;  ///< false: K singular
};
ModulusTerm ModulusPosition(const ModelParameters& params, double gravity, bool squared,
                            const Vec3& reading, bool with_hessian);

/// The held-out evidence of a richer fit over a simpler one (model_selection.hpp): the mean and
/// standard error of d_k = e_simpler,k² − e_richer,k² over `positions` (indices into both).
struct Paired {
  double mean = 0;
  double se = 0;
};
Paired PairedImprovement(const std::vector<double>& simpler, const std::vector<double>& richer,
                         const std::vector<int>& positions);

}  // namespace accelcal::internal
