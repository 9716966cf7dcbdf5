#pragma once
/// @file ellipsoid_fit.hpp
/// Algebraic ellipsoid fit of raw readings (paper 001 §3.3, eq. (16)-(18)).
///
/// Readings of a linear accelerometer satisfy (p − b)ᵀ K⁻ᵀ K⁻¹ (p − b) = g². The general quadric
/// pᵀ Q p + 2 Lᵀ p + c = 0 is fitted by total least squares (the unit coefficient vector v
/// minimising ‖D v‖ for the design matrix D of the centred, scaled readings); then b = −Q⁻¹ L and,
/// with s = bᵀ Q b − c, K Kᵀ = (s / g²) Q⁻¹, so K is the lower Cholesky factor: the gauge of
/// model.hpp.
///
/// Noisy or poorly spread readings can make that quadric a hyperboloid. The fit then falls back to
/// the ellipsoid-specific fit of Li & Griffiths (2004, "Least squares ellipsoid specific
/// fitting"): the same least squares under the constraint 4J − I² = 1 on the quadratic part
/// (I = tr Q, J = sum of its 2x2 principal minors), which admits ellipsoids only (all those whose
/// shortest axis is at least half the longest, which includes every accelerometer whose axis
/// gains differ by less than a factor 2).

#include <string>
#include <vector>

#include "accelcal/model.hpp"

namespace accelcal {

enum class EllipsoidFitKind {
  kAlgebraic,    ///< the unconstrained fit of paper 001 eq. (16)-(18)
  kConstrained,  ///< the algebraic quadric was no ellipsoid: Li & Griffiths' constrained fit
};

struct EllipsoidFitResult {
  ModelParameters params;  ///< K (lower-triangular, positive diagonal) and b; k2 = 0
  bool ok = false;  ///< false: no ellipsoid (too few readings, or both fits failed: `failure`)
  EllipsoidFitKind kind = EllipsoidFitKind::kAlgebraic;  ///< which fit `params` come from
  /// Why the algebraic quadric was rejected (kind == kConstrained), or why no fit is usable (!ok).
  std::string failure;
};

/// Needs at least 9 readings; gravity is the magnitude in the specific-force unit.
EllipsoidFitResult FitEllipsoid(const std::vector<Vec3>& readings, double gravity);

/// Li & Griffiths' ellipsoid-specific fit alone, whatever the algebraic quadric (kind ==
/// kConstrained, `failure` empty when ok). Exact on noise-free readings of a device whose axis
/// gains differ by less than a factor 2; biased towards a sphere beyond that.
EllipsoidFitResult FitEllipsoidConstrained(const std::vector<Vec3>& readings, double gravity);

/// "algebraic" or "constrained (Li & Griffiths 2004)".
std::string_view ToString(EllipsoidFitKind kind);

}  // namespace accelcal
