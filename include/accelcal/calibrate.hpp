#pragma once
/// @file calibrate.hpp
/// Orientation-free calibration from static positions: maximum likelihood for the model of
/// model.hpp with unknown unit gravity directions (paper 000 eq. (13)):
///
///     min over θ, c_1..c_m with |c_k| = 1 of  J = Σ_k ‖p_k − μ(θ, g c_k)‖²
///
/// Two solvers reach the same optimum:
///   - kTwoStep: paper 000 §3.1, alternating the linear least squares for θ given the directions
///     (eq. (15)) with a constrained Newton/KKT step per position (eq. (18)-(24), Hessian of eq.
///     (25) corrected per docs/errata.md#000-eq25). Converges linearly.
///   - kJoint: Levenberg-Marquardt over θ and all directions at once, each direction updated in its
///     2-D tangent plane, the per-position 2x2 blocks eliminated by the Schur complement.
/// Every method starts from an ellipsoid fit (paper 001 §3.3; when the algebraic quadric is no
/// ellipsoid, the constrained fit of Li & Griffiths 2004, see ellipsoid_fit.hpp) or, where both
/// fail, from the normalised readings (paper 000 eq. (26)).

#include <vector>

#include "accelcal/calibration_types.hpp"

namespace accelcal {

/// Calibrates from averaged raw readings (one per position). Throws DataError when the data cannot
/// determine the model (too few positions, coplanar or otherwise unobservable geometry, non-finite
/// readings) and std::invalid_argument for invalid options. Non-convergence is reported in
/// result.summary (converged() == false), never as a usable result.
CalibrationResult Calibrate(const std::vector<Vec3>& readings, const CalibrationOptions& options);

/// Leave-one-position-out validation of `result`, a converged Calibrate(readings, options):
/// fills its crossval_rms and crossval_errors, or crossval_note (CalibrationOptions::
/// cross_validate does this inside Calibrate): the fit without each position k minimises the
/// full objective's expansion about result->params minus k's exact term, finished by exact
/// passes or a refit where the expansion's error estimate is too large (held_out.hpp); equal to
/// refits converged to the solvers' tolerance (tests/statistics/test_crossval.cpp).
void CrossValidate(const std::vector<Vec3>& readings, const CalibrationOptions& options,
                   CalibrationResult* result);

}  // namespace accelcal
