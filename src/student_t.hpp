#pragma once
// Student's t distribution, for the outlier test of calibrate.hpp (OutlierOptions).

namespace accelcal::internal {

/// Regularised incomplete beta function I_x(a, b) for a, b > 0 and 0 ≤ x ≤ 1, by its continued
/// fraction (DLMF 8.17.22), evaluated with the modified Lentz method; the symmetry
/// I_x(a, b) = 1 − I_{1−x}(b, a) keeps x in the fraction's fast-converging range.
double RegularizedIncompleteBeta(double a, double b, double x);

/// P(|T| ≥ |t|) for T with `dof` degrees of freedom: I_{ν/(ν+t²)}(ν/2, 1/2).
double StudentTTwoSidedP(double t, double dof);

/// The |t| whose two-sided probability is `p` (0 < p < 1), by bisection on StudentTTwoSidedP to
/// a relative 1e-12.
double StudentTTwoSidedQuantile(double p, double dof);

}  // namespace accelcal::internal
