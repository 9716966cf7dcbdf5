#pragma once
// Student's t, Fisher's F and χ² distributions, for the outlier tests of calibrate.hpp
// (OutlierOptions) and known_orientation.hpp, and the Allan deviation's intervals (allan.hpp).

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

/// P(F ≥ f) for F with (d1, d2) degrees of freedom: I_{d2/(d2+d1 f)}(d2/2, d1/2).
double FisherFSurvival(double f, double d1, double d2);

/// The f whose upper-tail probability is `p` (0 < p < 1), by bisection on FisherFSurvival to a
/// relative 1e-12.
double FisherFQuantile(double p, double d1, double d2);

/// Regularised lower incomplete gamma function P(a, x) for a > 0, x ≥ 0: its series (DLMF 8.11.4)
/// for x < a + 1, else 1 − Q(a, x) by Q's continued fraction (DLMF 8.9.2) with the modified Lentz
/// method.
double RegularizedLowerGamma(double a, double x);

/// P(X ≥ x) for X ~ χ² with `dof` > 0 degrees of freedom (not necessarily whole): 1 − P(ν/2, x/2).
double ChiSquareSurvival(double x, double dof);

/// The x whose upper-tail probability P(X ≥ x) is `p` (0 < p < 1), by bisection on
/// ChiSquareSurvival to a relative 1e-12.
double ChiSquareQuantile(double p, double dof);

}  // namespace accelcal::internal
