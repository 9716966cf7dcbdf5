#include "statistics/student_t.hpp"

#include <cmath>
#include <initializer_list>

namespace accelcal::internal {
namespace {

// The continued fraction of DLMF 8.17.22 for I_x(a, b) · a B(a, b) / (x^a (1 − x)^b):
// 1 / (1 + d_1 / (1 + d_2 / (1 + …))) with d_{2j+1} = −(a + j)(a + b + j) x / ((a + 2j)(a + 2j +
// 1)) and d_{2j} = j (b − j) x / ((a + 2j − 1)(a + 2j)); it converges fast for x < (a + 1)/(a + b +
// 2).
double BetaContinuedFraction(double a, double b, double x) {
  constexpr double kTiny = 1e-300;
  constexpr double kEps = 1e-16;
  double c = 1.0;
  double d = 1.0 - (a + b) * x / (a + 1.0);
  if (std::abs(d) < kTiny) d = kTiny;
  d = 1.0 / d;
  double h = d;
  for (int j = 1; j <= 1000; ++j) {
    const double jd = j;
    const double even = jd * (b - jd) * x / ((a + 2 * jd - 1) * (a + 2 * jd));
    const double odd = -(a + jd) * (a + b + jd) * x / ((a + 2 * jd) * (a + 2 * jd + 1));
    for (const double coefficient : {even, odd}) {
      d = 1.0 + coefficient * d;
      if (std::abs(d) < kTiny) d = kTiny;
      c = 1.0 + coefficient / c;
      if (std::abs(c) < kTiny) c = kTiny;
      d = 1.0 / d;
      h *= d * c;
    }
    if (std::abs(d * c - 1.0) < kEps) break;
  }
  return h;
}

// The x ≥ 0 at which a decreasing tail probability `survival` falls to p, by bisection to a
// relative 1e-12.
template <typename Survival>
double UpperQuantile(const Survival& survival, double p) {
  double lo = 0.0, hi = 1.0;
  while (survival(hi) > p && hi < 1e300) hi *= 2.0;
  while (hi - lo > 1e-12 * hi) {
    const double mid = 0.5 * (lo + hi);
    (survival(mid) > p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// Q(a, x) · Γ(a) / (e^−x x^a) by its continued fraction (DLMF 8.9.2, in the even form
// 1 / (x + 1 − a − 1·(1 − a) / (x + 3 − a − 2·(2 − a) / (x + 5 − a − …)))), converging fast for
// x ≥ a + 1.
double GammaContinuedFraction(double a, double x) {
  constexpr double kTiny = 1e-300;
  constexpr double kEps = 1e-16;
  double b = x + 1.0 - a;
  double c = 1.0 / kTiny;
  double d = 1.0 / b;
  double h = d;
  for (int j = 1; j <= 1000; ++j) {
    const double coefficient = -j * (j - a);
    b += 2.0;
    d = coefficient * d + b;
    if (std::abs(d) < kTiny) d = kTiny;
    c = b + coefficient / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    h *= d * c;
    if (std::abs(d * c - 1.0) < kEps) break;
  }
  return h;
}

}  // namespace

double RegularizedLowerGamma(double a, double x) {
  if (!(x > 0)) return 0.0;
  if (std::isinf(x)) return 1.0;
  const double log_front = a * std::log(x) - x - std::lgamma(a);
  if (x < a + 1.0) {
    // Σ_n xⁿ / ((a + 1)…(a + n)), times e^−x x^a / Γ(a + 1).
    double term = 1.0 / a, sum = term;
    for (int n = 1; n <= 10000; ++n) {
      term *= x / (a + n);
      sum += term;
      if (std::abs(term) < 1e-17 * std::abs(sum)) break;
    }
    return std::exp(log_front) * sum;
  }
  return 1.0 - std::exp(log_front) * GammaContinuedFraction(a, x);
}

double ChiSquareSurvival(double x, double dof) {
  return 1.0 - RegularizedLowerGamma(0.5 * dof, 0.5 * x);
}

double ChiSquareQuantile(double p, double dof) {
  return UpperQuantile([dof](double x) { return ChiSquareSurvival(x, dof); }, p);
}

double RegularizedIncompleteBeta(double a, double b, double x) {
  if (x <= 0) return 0.0;
  if (x >= 1) return 1.0;
  const double log_front =
      std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) + a * std::log(x) + b * std::log1p(-x);
  if (x < (a + 1.0) / (a + b + 2.0)) {
    return std::exp(log_front) * BetaContinuedFraction(a, b, x) / a;
  }
  return 1.0 - std::exp(log_front) * BetaContinuedFraction(b, a, 1.0 - x) / b;
}

double StudentTTwoSidedP(double t, double dof) {
  if (std::isinf(t)) return 0.0;
  return RegularizedIncompleteBeta(0.5 * dof, 0.5, dof / (dof + t * t));
}

double StudentTTwoSidedQuantile(double p, double dof) {
  return UpperQuantile([dof](double t) { return StudentTTwoSidedP(t, dof); }, p);
}

double FisherFSurvival(double f, double d1, double d2) {
  if (std::isinf(f)) return 0.0;
  if (!(f > 0)) return 1.0;
  return RegularizedIncompleteBeta(0.5 * d2, 0.5 * d1, d2 / (d2 + d1 * f));
}

double FisherFQuantile(double p, double d1, double d2) {
  return UpperQuantile([d1, d2](double f) { return FisherFSurvival(f, d1, d2); }, p);
}

}  // namespace accelcal::internal
