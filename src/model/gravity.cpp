#include "accelcal/gravity.hpp"

#include <cmath>

namespace accelcal {

double NormalGravityWgs84_ms2(double latitude_deg, double height_m) {
  // WGS-84 defining and derived constants (NIMA TR8350.2, Tables 3.1-3.4).
  constexpr double kGammaEquator = 9.7803253359;     // m/s²
  constexpr double kSomiglianaK = 0.00193185265241;  // (b γ_p − a γ_e) / (a γ_e)
  constexpr double kE2 = 0.00669437999013;           // first eccentricity squared
  constexpr double kA = 6378137.0;                   // semi-major axis, m
  constexpr double kF = 1.0 / 298.257223563;         // flattening
  constexpr double kM = 0.00344978650684;            // ω² a² b / GM
  constexpr double kPi = 3.14159265358979323846;
  const double s = std::sin(latitude_deg * kPi / 180.0);
  const double s2 = s * s;
  const double gamma0 = kGammaEquator * (1.0 + kSomiglianaK * s2) / std::sqrt(1.0 - kE2 * s2);
  const double h = height_m;
  return gamma0 * (1.0 - 2.0 / kA * (1.0 + kF + kM - 2.0 * kF * s2) * h + 3.0 * h * h / (kA * kA));
}

std::string_view ToString(ForceUnit unit) { return NameOf(unit); }

std::optional<ForceUnit> ForceUnitFromString(std::string_view text) {
  return FromName<ForceUnit>(text);
}

}  // namespace accelcal
