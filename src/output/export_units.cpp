// The units the exports' targets read (m/s2, rad/s), and whether a calibration's readings fit
// them: the checks every target makes before it writes anything (export_common.hpp).
#include <cmath>
#include <stdexcept>

#include <Eigen/SVD>

#include "accelcal/error.hpp"
#include "accelcal/gravity.hpp"
#include "output/export_common.hpp"

namespace accelcal::exports {

// m/s² per raw unit, for the formats that apply a calibration to readings in m/s².
double RawToMetersPerSecond2(const LoadedCalibration& cal, const ExportOptions& options,
                             std::string_view format, std::string_view why) {
  const std::string label = options.raw_unit.empty() ? cal.raw_unit : options.raw_unit;
  const std::optional<ForceUnit> unit = ForceUnitFromString(label);
  const std::optional<ForceUnit> file_unit = ForceUnitFromString(cal.raw_unit);
  if (!options.raw_unit.empty() && file_unit && unit && *file_unit != *unit) {
    throw std::invalid_argument("raw_unit '" + options.raw_unit +
                                "' contradicts the calibration, whose readings were in '" +
                                cal.raw_unit + "'");
  }
  if (!unit) {
    throw DataError(
        std::string(format) + " applies its calibration to readings already in m/s2 (" +
        std::string(why) + "), but this calibration's raw unit is '" +
        internal::VisibleLine(label) +
        "': calibrate readings in m/s2 or g (raw_units), or give raw_unit (m/s2 or g) if "
        "the readings were in one of them");
  }
  return *unit == ForceUnit::kStandardGravity ? kStandardGravity_ms2 : 1.0;
}
double ForceToMetersPerSecond2(const LoadedCalibration& cal) {
  return cal.unit == ForceUnit::kStandardGravity ? kStandardGravity_ms2 : 1.0;
}

// The rad/s of one raw gyro unit, for the formats that read rates in rad/s; std::nullopt, with
// why in `omitted`, for another unit.
std::optional<double> RawToRadPerSecond(const LoadedCalibration& cal, const ExportOptions& options,
                                        std::string_view format, std::string_view why,
                                        std::string* omitted) {
  const std::string& file_label = cal.gyroscope->raw_unit;
  const std::string label = options.gyro_raw_unit.empty() ? file_label : options.gyro_raw_unit;
  if (!options.gyro_raw_unit.empty() && (file_label == "rad/s" || file_label == "deg/s") &&
      file_label != options.gyro_raw_unit) {
    throw std::invalid_argument("gyro_raw_unit '" + options.gyro_raw_unit +
                                "' contradicts the calibration, whose gyroscope's rates were in '" +
                                file_label + "'");
  }
  if (label == "rad/s") return 1.0;
  if (label == "deg/s") return 3.14159265358979323846 / 180.0;
  *omitted = std::string(format) + " reads rates in rad/s (" + std::string(why) +
             "), and this gyroscope's raw unit is '" + internal::VisibleLine(label) +
             "': calibrate rates in rad/s or deg/s, or give gyro_raw_unit (rad/s or deg/s) if "
             "the rates were in one of them";
  return std::nullopt;
}

// The accelerometer as a target that takes readings in m/s² applies it (PX4, ArduPilot, Kalibr,
// OpenVINS, Basalt), checked before anything is written: scales (K_ii⁻¹ in m/s² per m/s², what
// PX4's and ArduPilot's SCALE hold) far from 1 are readings in another unit than the one they are
// said to be in (counts labelled m/s2), and an offset beyond any sensor's is no sensor's
// calibration; the target would apply either as written. One check for every target, so that a
// file one of them refuses is refused by all. A unit given with the export is checked as the
// file's label is: vouching for a unit does not make the readings fit it.
void PlausibleAccelerometer(const LoadedCalibration& cal, const ExportOptions& options,
                            double raw_ms2, const char* tool) {
  const Vec3 scale =
      (ForceToMetersPerSecond2(cal) / raw_ms2) * cal.params.K.diagonal().cwiseInverse();
  const Vec3 offset_ms2 = raw_ms2 * cal.params.bias;
  const std::string label = internal::VisibleLine(cal.raw_unit);
  for (int i = 0; i < 3; ++i) {
    if (!(scale(i) >= 1 / (1 + kMostPlausibleScaleError) &&
          scale(i) <= 1 + kMostPlausibleScaleError)) {
      if (!options.raw_unit.empty()) {
        throw DataError(Format(
            "%s would apply scales of %.6g, %.6g, %.6g: a sensor's readings in '%s' have scales "
            "near 1, so the raw unit given (raw_unit %s) does not fit these readings (counts?); "
            "calibrate them in their unit",
            tool, scale(0), scale(1), scale(2), options.raw_unit.c_str(),
            options.raw_unit.c_str()));
      }
      throw DataError(Format(
          "%s would apply scales of %.6g, %.6g, %.6g: a sensor's readings in '%s' have scales "
          "near 1, so these readings were not in '%s' (counts?); calibrate them with their "
          "unit, or give the raw unit option if they were in it",
          tool, scale(0), scale(1), scale(2), label.c_str(), label.c_str()));
    }
  }
  const double most_ms2 = kMostPlausibleOffset_g * kStandardGravity_ms2;
  for (int i = 0; i < 3; ++i) {
    if (!(std::abs(offset_ms2(i)) <= most_ms2)) {
      throw DataError(Format(
          "%s would apply offsets of %.6g, %.6g, %.6g m/s2: an accelerometer's zero-g offset is "
          "within %.3g m/s2 (%.2g g; datasheets' worst are a few tenths of a g), so this is no "
          "sensor's calibration, or its readings were not in '%s'",
          tool, offset_ms2(0), offset_ms2(1), offset_ms2(2), most_ms2, kMostPlausibleOffset_g,
          options.raw_unit.empty() ? label.c_str() : options.raw_unit.c_str()));
    }
  }
}

// The gyroscope as a target that takes rates in rad/s applies it (`rad_s` the rad/s of one raw
// unit), the same check as the accelerometer's: its scales (the singular values of (s K_g)⁻¹, so
// that a rotation between the sensors, which Kalibr, OpenVINS and Basalt hold, is no error) near
// 1 and its offsets within any gyroscope's. Empty when plausible, else why not, for the target to
// leave the gyroscope out with that reason or, where its file states a gyroscope in any case
// (OpenVINS, Basalt), to refuse the export.
std::string ImplausibleGyroscope(const LoadedCalibration& cal, const ExportOptions& options,
                                 double rad_s, std::string_view format) {
  const UnitGyroscope& g = *cal.gyroscope;
  const std::string tool(format);
  const std::string label =
      options.gyro_raw_unit.empty() ? internal::VisibleLine(g.raw_unit) : options.gyro_raw_unit;
  const Vec3 singular = Eigen::JacobiSVD<Mat33>(Mat33(rad_s * g.params.K)).singularValues();
  const double largest_scale = 1 / singular(2), smallest_scale = 1 / singular(0);
  if (!(largest_scale <= 1 + kMostPlausibleScaleError &&
        smallest_scale >= 1 / (1 + kMostPlausibleScaleError))) {
    const std::string why =
        options.gyro_raw_unit.empty()
            ? "these rates were not in '" + label + "' (counts?); give gyro_raw_unit if they were"
            : "the unit given (gyro_raw_unit " + label + ") does not fit these rates";
    return Format(
        "%s would apply gyroscope scales from %.6g to %.6g: a gyroscope's rates in '%s' have "
        "scales near 1, so %s",
        tool.c_str(), smallest_scale, largest_scale, label.c_str(), why.c_str());
  }
  const Vec3 offset_rad_s = rad_s * g.params.bias;
  const double most_rad_s = kMostPlausibleRateOffset_deg_s * 3.14159265358979323846 / 180.0;
  for (int i = 0; i < 3; ++i) {
    if (!(std::abs(offset_rad_s(i)) <= most_rad_s)) {
      return Format(
          "%s would apply gyroscope offsets of %.6g, %.6g, %.6g rad/s: a gyroscope's zero-rate "
          "offset is within %.3g rad/s (%.3g deg/s), so this is no sensor's calibration, or its "
          "rates were not in '%s'",
          tool.c_str(), offset_rad_s(0), offset_rad_s(1), offset_rad_s(2), most_rad_s,
          kMostPlausibleRateOffset_deg_s, label.c_str());
    }
  }
  return "";
}

}  // namespace accelcal::exports
