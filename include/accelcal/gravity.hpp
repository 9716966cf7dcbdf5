#pragma once
/// @file gravity.hpp
/// Local gravity magnitude and specific-force units.

#include <optional>
#include <string_view>

#include "accelcal/names.hpp"

namespace accelcal {

/// Standard gravity g0 [m/s²] (CGPM 1901), the default gravity magnitude.
inline constexpr double kStandardGravity_ms2 = 9.80665;
/// The Earth's rotation rate (WGS-84) [rad/s].
inline constexpr double kEarthRate_rad_s = 7.2921150e-5;

/// WGS-84 normal gravity on or above the ellipsoid [m/s²].
/// Somigliana's closed formula for the surface value, then the second-order free-air expansion in
/// height (NIMA TR8350.2, eq. 4-1 and 4-3). Latitude is geodetic, in degrees; height above the
/// ellipsoid in metres.
double NormalGravityWgs84_ms2(double latitude_deg, double height_m = 0.0);

/// Unit in which the calibrated specific force is expressed.
enum class ForceUnit {
  kMetersPerSecond2,  ///< "m/s2"
  kStandardGravity,   ///< "g": the gravity magnitude of the calibration is 1 in this unit
};

std::string_view ToString(ForceUnit unit);
/// Parses "m/s2" (also "m/s^2", "ms2") or "g".
std::optional<ForceUnit> ForceUnitFromString(std::string_view text);
template <>
struct EnumNames<ForceUnit> {
  static constexpr std::pair<ForceUnit, std::string_view> kTable[] = {
      {ForceUnit::kMetersPerSecond2, "m/s2"},
      {ForceUnit::kStandardGravity, "g"},
      {ForceUnit::kMetersPerSecond2, "m/s^2"},  // accepted spellings
      {ForceUnit::kMetersPerSecond2, "ms2"}};
};

}  // namespace accelcal
