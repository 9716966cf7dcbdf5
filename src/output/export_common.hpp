#pragma once
// Internal to the exports: what the targets' files (export_<target>.cpp) share, and the targets
// for export.cpp's dispatch. The numbers and comment lines they write, the loss of a model a
// format cannot hold in full, the autopilots' diagonal model and the log's streams are in
// export_common.cpp; the units the targets read and the plausibility checks in export_units.cpp;
// the noise analysis's keys and comments in export_noise.cpp; YAML's scalars in export_yaml.cpp.
#include <algorithm>
#include <array>
#include <functional>
#include <optional>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "accelcal/export.hpp"
#include "core/text_format.hpp"

namespace accelcal::exports {

using ordered_json = nlohmann::ordered_json;
using internal::Format;

// ASCII classes, whatever the C locale's LC_CTYPE (std::isalpha takes 0xE4 for a letter in
// ISO-8859-1 locales).
inline bool IsAsciiDigit(char c) { return c >= '0' && c <= '9'; }
inline bool IsAsciiLetter(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z'); }
inline bool IsIdentifierChar(char c) { return IsAsciiLetter(c) || IsAsciiDigit(c) || c == '_'; }

// The numbers an export writes (export_common.cpp; YAML's, export_yaml.cpp).
double Finite(double value);
double Float32(double value);
std::string Number(double value);
std::string YamlNumber(double value);
std::string YamlQuoted(std::string_view text);

// The comment lines (export_common.cpp).
std::string Join(const std::string& a, const std::string& b);
std::string Header(const LoadedCalibration& cal);
std::string DescribeUnits(const LoadedCalibration& cal);

// What a format drops, and what that costs on the positions calibrated (export_common.cpp).
std::string SquaredTermsDropped(const LoadedCalibration& cal);
std::string GSensitivityDropped(const LoadedCalibration& cal);
// A correction f(p) in the calibration's specific-force unit, or nullopt where it has none.
using Correction = std::function<std::optional<Vec3>(const Vec3&)>;

// A raw offset at a temperature [°C]: what a target's temperature compensation takes from a
// reading before its correction.
using ThermalOffset = std::function<Vec3(double)>;

ExportLoss MeasureLoss(const LoadedCalibration& cal, const Correction& exported,
                       std::string dropped, bool holds_all = false,
                       const ThermalOffset& thermal_offset = nullptr);

// The offsets' temperature terms of a thermal calibration: b_d [raw per K^d], d = 1 … 3 (zero
// above the bias's degree), and the raw offset b(T) − b(T_ref) they add at T, with T held to the
// fitted range as the autopilots hold it to their TMIN…TMAX.
struct OffsetPolynomial {
  double t_ref_c = 0, t_min_c = 0, t_max_c = 0;
  std::array<Vec3, 4> b;  // b[d], b[0] unused
  Vec3 At(double t_c) const {
    const double dt = std::clamp(t_c, t_min_c, t_max_c) - t_ref_c;
    return b[1] * dt + b[2] * dt * dt + b[3] * dt * dt * dt;
  }
};
OffsetPolynomial OffsetsOverTemperature(const LoadedCalibration& cal);

// Diagonal-only targets (PX4, ArduPilot): f_i = s_i (p_i − o_i) in m/s².
struct Diagonal {
  Vec3 offset_ms2, scale;
  Correction correction;  // in the calibration's unit
  std::string dropped;
};
Diagonal DiagonalPart(const LoadedCalibration& cal, double raw_ms2);
std::string DiagonalConvention(std::string_view tool, const LoadedCalibration& cal, double raw_ms2);

// The binary log's streams the sensors were calibrated from (export_common.cpp).
const SourceStream* AccelerometerStream(const LoadedCalibration& cal);
const SourceStream* GyroscopeStream(const LoadedCalibration& cal);

// The largest relative scale error a sensor's calibration may have before its readings are taken
// for another unit than their label's: MEMS sensitivities are within a few % of nominal, and the
// units readings are mistaken for are 9.8, 57 or thousands of times apart.
inline constexpr double kMostPlausibleScaleError = 0.5;

// The largest accelerometer offset a target may be given, in g. Datasheets' worst zero-g offsets
// are a few tenths of a g (ADXL345/ADXL350: ±150 mg on x and y, ±250 mg on z; consumer IMUs such
// as the MPU-6050 or ICM-20602 well below), and an offset of half a g would already take a
// quarter of a ±2 g part's full scale; ArduPilot's own accelerometer calibration refuses offsets
// beyond 1 g (AccelCalibrator::accept_result). Twice the datasheets' worst leaves room for the
// stress of soldering and mounting; beyond it the readings are another unit's, or the calibration
// is not a sensor's.
inline constexpr double kMostPlausibleOffset_g = 0.5;

// The largest gyroscope offset a target may be given, in deg/s. Consumer MEMS gyroscopes' zero-rate
// offsets reach tens of deg/s at their widest full scale (the MPU-6050's ±20 deg/s, the L3GD20's
// ±75 deg/s typical at ±2000 deg/s); twice the worst of them is more than half of a ±250 deg/s
// part's range, which no calibration that leaves the sensor usable has.
inline constexpr double kMostPlausibleRateOffset_deg_s = 150.0;

// The units the targets read, and the checks that a calibration's readings fit them
// (export_units.cpp).
double RawToMetersPerSecond2(const LoadedCalibration& cal, const ExportOptions& options,
                             std::string_view format, std::string_view why);
double ForceToMetersPerSecond2(const LoadedCalibration& cal);
std::optional<double> RawToRadPerSecond(const LoadedCalibration& cal, const ExportOptions& options,
                                        std::string_view format, std::string_view why,
                                        std::string* omitted);
void PlausibleAccelerometer(const LoadedCalibration& cal, const ExportOptions& options,
                            double raw_ms2, const char* tool);
std::string ImplausibleGyroscope(const LoadedCalibration& cal, const ExportOptions& options,
                                 double rad_s, std::string_view format);

// The noise analysis as the formats that hold it write it (export_noise.cpp).
const ImuNoise& NeedNoise(const ExportOptions& options, const char* format, bool gyroscope);
double Largest(const Vec3& v);
std::string Axes(const Vec3& v);
bool Unresolved(const ImuNoise& n);
std::string NoiseComments(const ImuNoise& n, const char* prefix);
std::string KalibrNoiseKeys(const ImuNoise& n, const std::string& rostopic,
                            const std::string& indent);

// The targets, one file each.
ExportResult ImuTk(const LoadedCalibration& cal);           // export_imutk.cpp
ExportResult ImuTkGyroscope(const LoadedCalibration& cal);  // export_imutk.cpp
ExportResult Px4(const LoadedCalibration& cal, const ExportOptions& options);
ExportResult ArduPilot(const LoadedCalibration& cal, const ExportOptions& options);
ExportResult Kalibr(const LoadedCalibration& cal, const ExportOptions& options);
ExportResult KalibrImu(const LoadedCalibration& cal, const ExportOptions& options);      // kalibr
ExportResult RosCovariance(const LoadedCalibration& cal, const ExportOptions& options);  // ros
ExportResult OpenVins(const LoadedCalibration& cal, const ExportOptions& options);
ExportResult Basalt(const LoadedCalibration& cal, const ExportOptions& options);
ExportResult CHeader(const LoadedCalibration& cal, const ExportOptions& options);

}  // namespace accelcal::exports
