// Exports of a calibration to the formats of other tools (export.hpp, docs/conventions.md).
#include "accelcal/export.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <stdexcept>

#include <Eigen/LU>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <nlohmann/json.hpp>

#include "accelcal/error.hpp"
#include "accelcal/frame.hpp"
#include "accelcal/gravity.hpp"
#include "accelcal/native_log.hpp"
#include "core/text_format.hpp"

namespace accelcal {

namespace {

using ordered_json = nlohmann::ordered_json;
using internal::Format;

// ASCII classes, whatever the C locale's LC_CTYPE (std::isalpha takes 0xE4 for a letter in
// ISO-8859-1 locales).
bool IsAsciiDigit(char c) { return c >= '0' && c <= '9'; }
bool IsAsciiLetter(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z'); }
bool IsIdentifierChar(char c) { return IsAsciiLetter(c) || IsAsciiDigit(c) || c == '_'; }

// A ROS name as ROS 2 (rcl's topic validation) and ROS 1 take it: an optional '/' or "~/", then
// tokens joined by single '/', each starting with a letter or '_', then letters, digits and '_'
// (no empty token: no "//", no trailing '/').
bool IsRosName(std::string_view name) {
  if (name.substr(0, 2) == "~/") {
    name.remove_prefix(2);
  } else if (!name.empty() && name[0] == '/') {
    name.remove_prefix(1);
  }
  if (name.empty()) return false;
  std::size_t start = 0;
  while (true) {
    const std::size_t end = std::min(name.find('/', start), name.size());
    const std::string_view token = name.substr(start, end - start);
    if (token.empty() || IsAsciiDigit(token[0]) ||
        !std::all_of(token.begin(), token.end(), IsIdentifierChar)) {
      return false;
    }
    if (end == name.size()) return true;
    start = end + 1;
  }
}

// Every number an export writes is finite: a calibration whose conversion overflows (a K of
// 1e160 squared, or inverted at 1e-200) cannot be written in any format ("null", "inf").
double Finite(double value) {
  if (!std::isfinite(value)) {
    throw DataError(
        "the converted calibration has a number that is not finite: its parameters lie outside "
        "what the format's arithmetic can hold");
  }
  return value;
}

// Shortest text that reads back as the same double (nlohmann's own conversion: no locale).
// A value for a float32 parameter (PX4's and ArduPilot's): finite and within float32's range.
double Float32(double value) {
  if (!(std::abs(Finite(value)) <= std::numeric_limits<float>::max())) {
    throw DataError(
        Format("the converted calibration has %.6g, beyond a float32 parameter's "
               "range: its parameters are not a sensor's",
               value));
  }
  return value;
}

std::string Number(double value) { return ordered_json(Finite(value)).dump(); }

std::string YamlFlow(const ordered_json& j);  // below, with the YAML writer

// A number for a YAML file: as Number, with a '.' in every float's mantissa, so that YAML 1.1
// readers (PyYAML, Kalibr's) read 5e-05 as a number, not a string.
std::string YamlNumber(double value) { return YamlFlow(ordered_json(Finite(value))); }

// Text inside a C block comment: one visible line (VisibleLine) in which no "*/" ends the comment,
// no "/*" opens a nested one (-Wcomment) and no "??/" trigraph makes a backslash; a space is put
// inside each of them ("* /", "/ *", "?? /").
std::string CCommentText(std::string_view text) {
  const std::string line = internal::VisibleLine(text);
  std::string out;
  out.reserve(line.size());
  for (std::size_t i = 0; i < line.size(); ++i) {
    out += line[i];
    const char next = i + 1 < line.size() ? line[i + 1] : '\0';
    if ((line[i] == '*' && next == '/') || (line[i] == '/' && next == '*') ||
        (line[i] == '?' && i > 0 && line[i - 1] == '?' && next == '/')) {
      out += ' ';
    }
  }
  return out;
}

// A correction f(p) in the calibration's specific-force unit, or nullopt where it has none.
using Correction = std::function<std::optional<Vec3>(const Vec3&)>;

std::string Join(const std::string& a, const std::string& b);

// A raw offset at a temperature [°C]: what a target's temperature compensation takes from a
// reading before its correction.
using ThermalOffset = std::function<Vec3(double)>;

// With a drifting bias the full model takes each position's drift offset from its reading; every
// format but accelcal's own file (`holds_all`) holds one bias, its value at the drift's
// reference time (the session's mean time). With parameters that follow temperature the full
// model is θ(T_k) at each position's temperature; a format holds them at T_ref, with, where it
// compensates temperature (`thermal_offset`), an offset polynomial taken from the reading first.
ExportLoss MeasureLoss(const LoadedCalibration& cal, const Correction& exported,
                       std::string dropped, bool holds_all = false,
                       const ThermalOffset& thermal_offset = nullptr) {
  ExportLoss loss;
  if (cal.thermal && !holds_all) {
    const ThermalDegrees& d = cal.thermal->params.degrees;
    const std::string range = cal.thermal_range_c
                                  ? Format(" over %.4g to %.4g degC", cal.thermal_range_c->first,
                                           cal.thermal_range_c->second)
                                  : std::string();
    if (!thermal_offset) {
      dropped =
          Join(dropped, Format("the temperature terms (degrees %s%s; the parameters "
                               "exported are at T_ref = %.6g degC)",
                               d.ToString().c_str(), range.c_str(), cal.thermal->params.t_ref_c));
    } else if (d.K > 0 || d.k2 > 0) {
      // What that alone costs: θ(T_k) against the parameters (θ(T_ref)) with the offset b(T_k).
      double most = 0, sum2 = 0;
      int n = 0;
      for (std::size_t k = 0; k < cal.position_means.size(); ++k) {
        if (k >= cal.thermal->temperatures_c.size()) break;
        const ModelParameters at_k = cal.thermal->params.At(cal.thermal->temperatures_c[k]);
        ModelParameters offsets_only = cal.params;
        offsets_only.bias = at_k.bias;
        const std::optional<Vec3> full = SpecificForce(at_k, cal.position_means[k]);
        const std::optional<Vec3> approx = SpecificForce(offsets_only, cal.position_means[k]);
        if (!full || !approx) continue;
        const double e = (*full - *approx).norm();
        most = std::max(most, e);
        sum2 += e * e;
        ++n;
      }
      dropped = Join(
          dropped,
          Format("the scale and misalignment temperature terms (degrees %s%s: only the "
                 "offsets follow temperature there), which alone cost %.3g %s max, "
                 "%.3g %s RMS on the positions",
                 d.ToString().c_str(), range.c_str(), most, std::string(ToString(cal.unit)).c_str(),
                 n > 0 ? std::sqrt(sum2 / n) : 0.0, std::string(ToString(cal.unit)).c_str()));
    }
  }
  if (cal.drift && !holds_all) {
    dropped =
        Join(dropped, Format("the bias drift within the session (%s; the bias exported is "
                             "its value at t = %.6g s, the positions' mean time)",
                             ToString(cal.drift->basis.model).c_str(), cal.drift->basis.t_ref_s));
  }
  loss.dropped = std::move(dropped);
  double sum_error2 = 0, sum_full2 = 0, sum_export2 = 0;
  for (std::size_t k = 0; k < cal.position_means.size(); ++k) {
    const Vec3& p = cal.position_means[k];
    const Vec3 offset = cal.drift && k < cal.drift->times_s.size()
                            ? cal.drift->Offset(cal.drift->times_s[k])
                            : Vec3::Zero();
    const bool thermal = cal.thermal && k < cal.thermal->temperatures_c.size();
    const double t_c = thermal ? cal.thermal->temperatures_c[k] : 0.0;
    const std::optional<Vec3> full =
        SpecificForce(thermal ? cal.thermal->params.At(t_c) : cal.params, Vec3(p - offset));
    const std::optional<Vec3> approx = holds_all ? full
                                       : thermal && thermal_offset
                                           ? exported(Vec3(p - thermal_offset(t_c)))
                                           : exported(p);
    if (!full || !approx) continue;
    const double error = (*approx - *full).norm();
    loss.max_error = std::max(loss.max_error, error);
    sum_error2 += error * error;
    sum_full2 += std::pow(full->norm() - cal.gravity, 2);
    sum_export2 += std::pow(approx->norm() - cal.gravity, 2);
    ++loss.positions;
  }
  if (loss.positions > 0) {
    loss.rms_error = std::sqrt(sum_error2 / loss.positions);
    loss.norm_rms_full = std::sqrt(sum_full2 / loss.positions);
    loss.norm_rms_export = std::sqrt(sum_export2 / loss.positions);
  }
  return loss;
}

std::string SquaredTermsDropped(const LoadedCalibration& cal) {
  return cal.model == ModelKind::kQuadratic ? "the squared terms k2" : "";
}

std::string Join(const std::string& a, const std::string& b) {
  if (a.empty()) return b;
  if (b.empty()) return a;
  return a + "; " + b;
}

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

// The raw-unit label as one visible line: the conventions go into comment lines of the files.
std::string DescribeUnits(const LoadedCalibration& cal) {
  return "raw readings in '" + internal::VisibleLine(cal.raw_unit) + "', specific force in " +
         std::string(ToString(cal.unit));
}

// imu_tk: f = T S (p − B), T unit-diagonal, S diagonal: T S = K⁻¹ (any frame, linear part).
ExportResult ImuTk(const LoadedCalibration& cal) {
  const Mat33 M = cal.params.K.inverse();
  const Vec3 s = M.diagonal();
  const Mat33 T = M.array().rowwise() / s.transpose().array();  // x / x = 1 exactly
  ExportResult out;
  const auto matrix = [](const Mat33& A) {
    std::string text;
    for (int i = 0; i < 3; ++i) {
      text += Number(A(i, 0)) + " " + Number(A(i, 1)) + " " + Number(A(i, 2)) + "\n";
    }
    return text;
  };
  out.text = matrix(T) + "\n" + matrix(Mat33(s.asDiagonal())) + "\n" + Number(cal.params.bias(0)) +
             "\n" + Number(cal.params.bias(1)) + "\n" + Number(cal.params.bias(2)) + "\n\n";
  out.convention =
      "imu_tk CalibratedTriad (load() reads misalignment T, scale S, bias B): f = T S (p - B), T "
      "with unit diagonal, S diagonal; T S = K^-1, B = b (" +
      DescribeUnits(cal) + ", accelcal's " + std::string(ToString(cal.frame)) + " body frame)";
  const Mat33 TS = T * s.asDiagonal();
  out.loss = MeasureLoss(
      cal, [&](const Vec3& p) -> std::optional<Vec3> { return Vec3(TS * (p - cal.params.bias)); },
      SquaredTermsDropped(cal));
  return out;
}

// The g-sensitivity an export without it drops: the largest rate error it leaves, |K_g⁻¹ G f| at
// |f| = g over the directions (the largest singular value of K_g⁻¹ G times g), in °/h.
std::string GSensitivityDropped(const LoadedCalibration& cal) {
  const LoadedCalibration::Gyroscope& g = *cal.gyroscope;
  if (g.model != GyroModelKind::kGSensitive || g.params.G.isZero(0)) return "";
  const Mat33 M = g.params.K.inverse() * g.params.G;
  const double largest = Eigen::JacobiSVD<Mat33>(M).singularValues()(0);
  return internal::Format("the g-sensitivity G (a rate error of up to %.3g deg/h at 1 g)",
                          largest * cal.gravity * 180.0 / 3.14159265358979323846 * 3600.0);
}

// imu_tk's gyroscope triad: w = T S (raw − B), T unit-diagonal, S diagonal: T S = K_g⁻¹, B = b.
ExportResult ImuTkGyroscope(const LoadedCalibration& cal) {
  if (!cal.gyroscope) {
    throw DataError("imutk gyroscope: the calibration file holds no gyroscope calibration");
  }
  const LoadedCalibration::Gyroscope& g = *cal.gyroscope;
  const Mat33 M = g.params.K.inverse();
  const Vec3 s = M.diagonal();
  const Mat33 T = M.array().rowwise() / s.transpose().array();  // x / x = 1 exactly
  ExportResult out;
  const auto matrix = [](const Mat33& A) {
    std::string text;
    for (int i = 0; i < 3; ++i) {
      text += Number(A(i, 0)) + " " + Number(A(i, 1)) + " " + Number(A(i, 2)) + "\n";
    }
    return text;
  };
  out.text = matrix(T) + "\n" + matrix(Mat33(s.asDiagonal())) + "\n" + Number(g.params.bias(0)) +
             "\n" + Number(g.params.bias(1)) + "\n" + Number(g.params.bias(2)) + "\n\n";
  out.convention =
      "imu_tk CalibratedTriad of the gyroscope (load() reads misalignment T, scale S, bias B): w "
      "= T S (raw - B) in rad/s, T with unit diagonal, S diagonal; T S = K^-1, B = b (raw "
      "readings in '" +
      internal::VisibleLine(g.raw_unit) + "', accelcal's " + std::string(ToString(cal.frame)) +
      " body frame of the accelerometer)";
  out.gyroscope_included = true;
  out.gyroscope_dropped = GSensitivityDropped(cal);
  return out;
}

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
OffsetPolynomial OffsetsOverTemperature(const LoadedCalibration& cal) {
  const ThermalParameters& p = cal.thermal->params;
  OffsetPolynomial out;
  out.t_ref_c = p.t_ref_c;
  out.t_min_c = cal.thermal_range_c ? cal.thermal_range_c->first : kTemperatureRange_C[0];
  out.t_max_c = cal.thermal_range_c ? cal.thermal_range_c->second : kTemperatureRange_C[1];
  for (int d = 1; d <= 3; ++d) {
    out.b[static_cast<std::size_t>(d)] = d < static_cast<int>(p.coefficients.size())
                                             ? p.coefficients[static_cast<std::size_t>(d)].bias
                                             : Vec3::Zero();
  }
  return out;
}

// Diagonal-only targets (PX4, ArduPilot): f_i = s_i (p_i − o_i) in m/s².
struct Diagonal {
  Vec3 offset_ms2, scale;
  Correction correction;  // in the calibration's unit
  std::string dropped;
};
Diagonal DiagonalPart(const LoadedCalibration& cal, double raw_ms2) {
  Diagonal d;
  const double force_ms2 = ForceToMetersPerSecond2(cal);
  const Vec3 K_diagonal = cal.params.K.diagonal();
  d.offset_ms2 = raw_ms2 * cal.params.bias;
  d.scale = (force_ms2 / raw_ms2) * K_diagonal.cwiseInverse();
  d.correction = [&cal, K_diagonal](const Vec3& p) -> std::optional<Vec3> {
    return Vec3((p - cal.params.bias).cwiseQuotient(K_diagonal));
  };
  Mat33 off_diagonal = cal.params.K;
  off_diagonal.diagonal().setZero();
  d.dropped = Join(off_diagonal.isZero(0) ? "" : "the misalignments (K's off-diagonal terms)",
                   SquaredTermsDropped(cal));
  return d;
}

std::string DiagonalConvention(std::string_view tool, const LoadedCalibration& cal,
                               double raw_ms2) {
  return Format(
      "%s: f = (p - offset) .* scale in m/s2, sensor frame, before the board rotation; offset = b "
      "* %.6g, scale_i = %.6g / K_ii (raw '%s' x %.6g = m/s2, accelcal's specific force in %s)",
      std::string(tool).c_str(), raw_ms2, ForceToMetersPerSecond2(cal) / raw_ms2,
      internal::VisibleLine(cal.raw_unit).c_str(), raw_ms2,
      std::string(ToString(cal.unit)).c_str());
}

// The first comment line (without its comment marker and line end): the log's path as one visible
// line.
std::string Header(const LoadedCalibration& cal) {
  std::string text = " accelcal calibration";
  if (!cal.source.empty()) text += " of " + internal::VisibleLine(cal.source);
  return text + " (" + std::string(ToString(cal.model)) + " model)";
}

// Whether a stream can hold `sensor`'s readings: a type accelcal knows for it, or one it does
// not know at all (fields the user named). A provenance edited by hand (a gyroscope's record
// removed, leaving the accelerometer's of the same file) is not taken for another sensor's.
bool CanHold(const SourceStream& stream, std::string_view sensor) {
  std::vector<std::string_view> sensors = KnownSensors(stream.type);
  if (sensors.empty()) sensors = KnownSensors(stream.topic);  // PX4's and ArduPilot's: the topic
  return sensors.empty() || std::find(sensors.begin(), sensors.end(), sensor) != sensors.end();
}

// The binary log's stream the accelerometer was calibrated from, as the provenance records it.
const SourceStream* AccelerometerStream(const LoadedCalibration& cal) {
  for (const InputRecord& input : cal.provenance.inputs) {
    if (input.stream && (cal.source.empty() || input.name == cal.source) &&
        CanHold(*input.stream, "accelerometer")) {
      return &*input.stream;
    }
  }
  return nullptr;
}

// The binary log's stream the gyroscope was calibrated from: the last input of its name with a
// stream (the gyroscope's input follows the accelerometer's, even from the same log).
const SourceStream* GyroscopeStream(const LoadedCalibration& cal) {
  const SourceStream* found = nullptr;
  for (const InputRecord& input : cal.provenance.inputs) {
    if (input.stream && input.name == cal.gyroscope->source &&
        CanHold(*input.stream, "gyroscope")) {
      found = &*input.stream;
    }
  }
  return found;
}

// The largest relative scale error a sensor's calibration may have before its readings are taken
// for another unit than their label's: MEMS sensitivities are within a few % of nominal, and the
// units readings are mistaken for are 9.8, 57 or thousands of times apart.
constexpr double kMostPlausibleScaleError = 0.5;

// The largest accelerometer offset a target may be given, in g. Datasheets' worst zero-g offsets
// are a few tenths of a g (ADXL345/ADXL350: ±150 mg on x and y, ±250 mg on z; consumer IMUs such
// as the MPU-6050 or ICM-20602 well below), and an offset of half a g would already take a
// quarter of a ±2 g part's full scale; ArduPilot's own accelerometer calibration refuses offsets
// beyond 1 g (AccelCalibrator::accept_result). Twice the datasheets' worst leaves room for the
// stress of soldering and mounting; beyond it the readings are another unit's, or the calibration
// is not a sensor's.
constexpr double kMostPlausibleOffset_g = 0.5;

// The largest gyroscope offset a target may be given, in deg/s. Consumer MEMS gyroscopes' zero-rate
// offsets reach tens of deg/s at their widest full scale (the MPU-6050's ±20 deg/s, the L3GD20's
// ±75 deg/s typical at ±2000 deg/s); twice the worst of them is more than half of a ±250 deg/s
// part's range, which no calibration that leaves the sensor usable has.
constexpr double kMostPlausibleRateOffset_deg_s = 150.0;

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
  const LoadedCalibration::Gyroscope& g = *cal.gyroscope;
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

// A PX4 device id: 32-bit.
std::optional<std::uint64_t> Px4DeviceId(std::optional<std::uint64_t> given,
                                         const SourceStream* stream) {
  if (given && *given == 0) {
    // (No bare "sensor" in an options error: the command line names its option so.)
    throw std::invalid_argument(
        "device id 0 is none: PX4 gives every one of its sensors a nonzero id");
  }
  std::optional<std::uint64_t> id = given;
  if (!id && stream != nullptr && stream->device_id != std::optional<std::uint64_t>(0)) {
    id = stream->device_id;  // 0: a log that does not say
  }
  if (id && *id > 0xFFFFFFFFu) {
    throw std::invalid_argument(
        Format("device id %llu: PX4's are 32-bit", static_cast<unsigned long long>(*id)));
  }
  return id;
}

// A PX4 calibration slot's comment (which sensor it is for) and its ID and PRIO lines.
struct Px4Slot {
  std::string comment, lines, convention;
};
// PX4's calibration slot for a sensor (`base` CAL_ACC or CAL_GYRO): PX4 applies slot n to the
// sensor whose device id is <base><n>_ID, so the slot is the one the log's parameters give the
// sensor's id (a primary IMU's slot written for another sensor would replace its calibration and
// leave it slotless). A `given` slot that contradicts the log's is refused; without a match the
// first slot the log leaves free (no id, or 0) is taken, and `why` says so.
int Px4SlotIndex(const char* base, const SourceStream* stream, std::optional<std::uint64_t> id,
                 std::optional<int> given, std::string* why) {
  if (given && (*given < 0 || *given > 3)) {
    throw std::invalid_argument(
        Format("PX4 has calibration slots 0 to 3 (%s0 to %s3)", base, base));
  }
  std::optional<double> ids[4];
  bool any = false;
  std::string listed;  // "CAL_ACC0_ID 2, CAL_ACC1_ID 1", for messages
  for (int n = 0; n < 4 && stream != nullptr; ++n) {
    const auto it = stream->calibration_in_force.find(Format("%s%d_ID", base, n));
    if (it == stream->calibration_in_force.end()) continue;
    ids[n] = it->second;
    any = true;
    listed += Format("%s%s%d_ID %.10g", listed.empty() ? "" : ", ", base, n, it->second);
  }
  // The log holds an id as PX4's int32 parameter.
  const std::optional<double> wanted =
      id ? std::optional<double>(static_cast<std::int32_t>(static_cast<std::uint32_t>(*id)))
         : std::nullopt;
  for (int n = 0; n < 4 && wanted; ++n) {
    if (ids[n] != wanted) continue;
    if (given && *given != n) {
      throw std::invalid_argument(Format(
          "instance %d contradicts the log: its %s%d_ID is the %s's device id %llu, so PX4 "
          "applies %s%d to it (the log's: %s); %s%d would be another slot's",
          *given, base, n, std::string_view(base) == "CAL_GYRO" ? "gyroscope" : "accelerometer",
          static_cast<unsigned long long>(*id), base, n, listed.c_str(), base, *given));
    }
    *why = Format("the log's %s%d_ID is its device id", base, n);
    return n;
  }
  if (given) {
    if (ids[*given] && *ids[*given] != 0) {
      *why = Format(
          "the instance given; the log's %s%d_ID is %.10g, another sensor's, whose "
          "calibration this replaces",
          base, *given, *ids[*given]);
    }
    return *given;
  }
  if (stream == nullptr) return 0;
  const std::string unmatched =
      !any ? Format("the log holds no %sn_ID", base)
      : id ? Format("no %sn_ID of the log is its device id (the log's: %s)", base, listed.c_str())
           : Format("its device id is unknown (the log's: %s)", listed.c_str());
  for (int n = 0; n < 4; ++n) {
    if (!ids[n] || *ids[n] == 0) {
      *why = Format("%s: %s%d is the first slot it leaves free (give the instance for another)",
                    unmatched.c_str(), base, n);
      return n;
    }
  }
  throw DataError(
      Format("%s, and every %s slot holds another sensor's calibration: give the "
             "instance of the one to replace",
             unmatched.c_str(), base));
}

Px4Slot Px4SlotFor(const std::string& prefix, const SourceStream* stream,
                   std::optional<std::uint64_t> id, const char* listener, const std::string& why) {
  Px4Slot out;
  out.comment = "# " + prefix.substr(0, prefix.size() - 1) + ": ";
  if (stream != nullptr) {
    out.comment += Format("%s instance %d of the log", internal::VisibleLine(stream->topic).c_str(),
                          stream->instance);
  } else {
    out.comment += "the calibrated sensor";
  }
  if (id) {
    out.comment += Format(", device id %llu", static_cast<unsigned long long>(*id));
    // PX4 reads a parameter's value by its MAVLink type: 6 int32, 9 float.
    out.lines = Format("1\t1\t%sID\t%d\t6\n", prefix.c_str(),
                       static_cast<std::int32_t>(static_cast<std::uint32_t>(*id)));
    out.lines += Format("1\t1\t%sPRIO\t50\t6\n", prefix.c_str());  // PX4's default priority
  } else {
    out.comment += "; its device id is unknown: " + prefix +
                   "ID is not written, and PX4 applies a calibration only to the sensor of its "
                   "ID (give the device id: PX4's `listener " +
                   listener + "` shows it)";
    out.convention = "; " + prefix + "ID not written (no device id known)";
  }
  if (!why.empty())
    out.comment += "; slot " + std::to_string(prefix[prefix.size() - 2] - '0') + ": " +
                   internal::VisibleLine(why);
  out.comment += "\n";
  return out;
}

std::optional<double> RawToRadPerSecond(const LoadedCalibration& cal, const ExportOptions& options,
                                        std::string_view format, std::string_view why,
                                        std::string* omitted);  // below, with the estimators'

// PX4's temperature compensation of one sensor, TC_A<n> or TC_G<n> (TemperatureCompensation.cpp
// with sensor_calibration/Accelerometer.hpp and Gyroscope.hpp): the offsets' polynomial in
// T - TREF, T held to TMIN..TMAX, taken from the reading before the calibration's offset. X0 = 0
// and TREF = T_ref, so that the calibration (CAL_ACC, CAL_GYRO) holds the offset at T_ref;
// X1..X3 = `per_K` in `unit`; PX4 matches the terms to the sensor by TC_<s><n>_ID.
struct Px4TemperatureTerms {
  std::string lines, convention, comment;
};
Px4TemperatureTerms Px4Temperature(char sensor, int instance, std::optional<std::uint64_t> id,
                                   double t_ref_c, std::pair<double, double> range_c,
                                   const std::array<Vec3, 3>& per_K, const char* unit,
                                   const char* taken_from, const char* calibration) {
  Px4TemperatureTerms out;
  const std::string tc = Format("TC_%c%d_", sensor, instance);
  out.lines = Format("1\t1\tTC_%c_ENABLE\t1\t6\n", sensor);
  if (id) {
    out.lines += Format("1\t1\t%sID\t%d\t6\n", tc.c_str(),
                        static_cast<std::int32_t>(static_cast<std::uint32_t>(*id)));
  }
  out.lines += Format("1\t1\t%sTREF\t%.9g\t9\n1\t1\t%sTMIN\t%.9g\t9\n1\t1\t%sTMAX\t%.9g\t9\n",
                      tc.c_str(), Float32(t_ref_c), tc.c_str(), Float32(range_c.first), tc.c_str(),
                      Float32(range_c.second));
  for (int k = 0; k <= 3; ++k) {
    for (int i = 0; i < 3; ++i) {
      const double x = k == 0 ? 0.0 : per_K[static_cast<std::size_t>(k - 1)](i);
      out.lines += Format("1\t1\t%sX%d_%d\t%.9g\t9\n", tc.c_str(), k, i, Float32(x));
    }
  }
  out.convention = Format(
                       "; TC_%c%d: offset(T) = sum_k X_k (T - TREF)^k in %s, T held to "
                       "TMIN..TMAX, taken from ",
                       sensor, instance, unit) +
                   Format(taken_from, instance) +
                   Format("; X0 = 0 and TREF = T_ref, so that %s%d holds the calibration at T_ref",
                          calibration, instance);
  if (!id) {
    out.comment = Format(
        "# TC_%c%d: TC_%c%d_ID is not written (no device id known): PX4 applies these "
        "temperature terms to no sensor until it is set\n",
        sensor, instance, sensor, instance);
    out.convention += Format("; TC_%c%d_ID not written (no device id known): PX4 does not apply it",
                             sensor, instance);
  }
  return out;
}

// PX4's gyroscope calibration (src/lib/sensor_calibration/Gyroscope): w = raw - offset in rad/s,
// after its driver's scaling; no scale. offset = b (the still rate), so the scale and
// misalignment K_g and the g-sensitivity are dropped, and said.
std::optional<Px4Slot> Px4Gyroscope(const LoadedCalibration& cal, const ExportOptions& options,
                                    ExportResult* out) {
  if (!cal.gyroscope) return std::nullopt;
  const LoadedCalibration::Gyroscope& g = *cal.gyroscope;
  const SourceStream* stream = GyroscopeStream(cal);
  if (stream != nullptr && stream->corrected) {
    out->gyroscope_omitted = "its rates are " + internal::VisibleLine(stream->topic) +
                             "'s, which the calibration in force had already corrected, and "
                             "PX4's CAL_GYRO offsets correct the driver's output: calibrate "
                             "sensor_gyro for them";
    return std::nullopt;
  }
  const std::optional<double> rad_s = RawToRadPerSecond(
      cal, options, "PX4", "its drivers scale the rates", &out->gyroscope_omitted);
  if (!rad_s) return std::nullopt;
  const Vec3 offset_rad_s = *rad_s * g.params.bias;
  for (int i = 0; i < 3; ++i) Float32(offset_rad_s(i));
  const std::optional<std::uint64_t> id = Px4DeviceId(options.gyro_device_id, stream);
  std::string why;
  const int instance = Px4SlotIndex("CAL_GYRO", stream, id, options.instance, &why);
  const std::string prefix = "CAL_GYRO" + std::to_string(instance) + "_";
  Px4Slot slot = Px4SlotFor(prefix, stream, id, "sensor_gyro", why);
  const char axes[3] = {'X', 'Y', 'Z'};
  for (int i = 0; i < 3; ++i) {
    slot.lines += Format("1\t1\t%s%cOFF\t%.9g\t9\n", prefix.c_str(), axes[i], offset_rad_s(i));
  }
  // PX4's rate (raw - b) against the calibrated one K_g^-1 (raw - b): (s K_g - I) w, at most the
  // largest singular value of s K_g - I times |w|.
  const double largest =
      Eigen::JacobiSVD<Mat33>(Mat33(*rad_s * g.params.K - Mat33::Identity())).singularValues()(0);
  if (!(largest <= kMostPlausibleScaleError)) {
    // Rates that are not in the unit they are said to be in (counts labelled rad/s, or a
    // gyro_raw_unit given for them): PX4 would apply the offsets to rates of another scale.
    out->gyroscope_omitted =
        options.gyro_raw_unit.empty()
            ? Format(
                  "PX4 holds a gyroscope's offsets only, and these rates, labelled '%s', "
                  "differ from the calibrated ones by up to %.3g %% (a gyroscope's scale is "
                  "near 1): they are not in '%s'; give gyro_raw_unit if they were",
                  internal::VisibleLine(g.raw_unit).c_str(), 100 * largest,
                  internal::VisibleLine(g.raw_unit).c_str())
            : Format(
                  "PX4 holds a gyroscope's offsets only, and these rates, in '%s' as "
                  "gyro_raw_unit %s says, differ from the calibrated ones by up to %.3g %% (a "
                  "gyroscope's scale is near 1): the unit given does not fit these rates",
                  options.gyro_raw_unit.c_str(), options.gyro_raw_unit.c_str(), 100 * largest);
    return std::nullopt;
  }
  // Scales PX4 could hold within the bound above can still be no gyroscope's (offsets beyond
  // any): the check every target makes.
  out->gyroscope_omitted = ImplausibleGyroscope(cal, options, *rad_s, "PX4");
  if (!out->gyroscope_omitted.empty()) return std::nullopt;
  if (g.thermal && g.thermal->degree() > 0) {
    // TC_G<n>: the offsets' polynomial in T - TREF taken from the rate before CAL_GYRO's offset
    // (TemperatureCompensation.cpp, sensor_calibration/Gyroscope.hpp), as TC_A: X0 = 0 and TREF
    // = T_ref, so that CAL_GYRO holds the offset at T_ref; T held to TMIN..TMAX.
    std::array<Vec3, 3> per_K{Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
    for (int k = 1; k <= g.thermal->degree(); ++k) {
      per_K[static_cast<std::size_t>(k - 1)] =
          *rad_s * g.thermal->coefficients[static_cast<std::size_t>(k - 1)];
    }
    const Px4TemperatureTerms tc =
        Px4Temperature('G', instance, id, g.thermal->t_ref_c, g.thermal_range_c, per_K, "rad/s",
                       "the rate before CAL_GYRO%d's offset", "CAL_GYRO");
    slot.lines += tc.lines;
    slot.convention += tc.convention;
    slot.comment += tc.comment;
  }
  out->gyroscope_included = true;
  out->gyroscope_dropped =
      Join(Format("the scale and misalignment K_g, which PX4 does not hold (a rate error of up to "
                  "%.3g %% of the rate)",
                  100 * largest),
           GSensitivityDropped(cal));
  slot.convention += "; gyroscope: w = raw - offset in rad/s, offset = b_g * " +
                     Format("%.6g", *rad_s) + " (PX4 holds no gyroscope scale)";
  return slot;
}

ExportResult Px4(const LoadedCalibration& cal, const ExportOptions& options) {
  const SourceStream* stream = AccelerometerStream(cal);
  if (stream != nullptr && stream->corrected) {
    // sensor_combined: the output of the calibration in force, whose slot is not in the log.
    throw DataError("this calibration is of " + internal::VisibleLine(stream->topic) +
                    ", which the calibration in force had already corrected; PX4's CAL_ACC "
                    "parameters correct the driver's output: calibrate sensor_accel (logged at "
                    "the sensor's rate) and export that");
  }
  if (options.instance && (*options.instance < 0 || *options.instance > 3)) {
    throw std::invalid_argument("PX4 has calibration slots 0 to 3 (CAL_ACC0 to CAL_ACC3)");
  }
  if (options.gyro_device_id && !cal.gyroscope) {
    throw std::invalid_argument(
        "a gyroscope's device id for a calibration without a gyroscope (nothing to apply it to)");
  }
  const double raw_ms2 = RawToMetersPerSecond2(cal, options, "PX4", "its drivers scale the counts");
  const Diagonal d = DiagonalPart(cal, raw_ms2);
  for (int i = 0; i < 3; ++i) Float32(d.offset_ms2(i)), Float32(d.scale(i));
  PlausibleAccelerometer(cal, options, raw_ms2, "PX4");
  ExportResult out;
  out.convention = DiagonalConvention("PX4 (src/lib/sensor_calibration)", cal, raw_ms2);
  const std::optional<std::uint64_t> id = Px4DeviceId(options.device_id, stream);
  std::string why;
  const int instance = Px4SlotIndex("CAL_ACC", stream, id, options.instance, &why);
  const std::string prefix = "CAL_ACC" + std::to_string(instance) + "_";
  const Px4Slot slot = Px4SlotFor(prefix, stream, id, "sensor_accel", why);
  const std::optional<Px4Slot> gyro = Px4Gyroscope(cal, options, &out);
  out.convention += slot.convention + (gyro ? gyro->convention : "");
  out.text = "# Onboard parameters for Vehicle 1\n#\n#" + Header(cal) + "\n# " + out.convention +
             "\n" + slot.comment + (gyro ? gyro->comment : "") +
             "#\n# Vehicle-Id Component-Id Name Value Type\n" + slot.lines;
  const char axes[3] = {'X', 'Y', 'Z'};
  for (int i = 0; i < 3; ++i) {
    out.text += Format("1\t1\t%s%cOFF\t%.9g\t9\n", prefix.c_str(), axes[i], d.offset_ms2(i));
  }
  for (int i = 0; i < 3; ++i) {
    out.text += Format("1\t1\t%s%cSCALE\t%.9g\t9\n", prefix.c_str(), axes[i], d.scale(i));
  }
  if (gyro) out.text += gyro->lines;
  // Without a bias that follows temperature there is nothing for TC_A to hold: enabling it empty
  // would replace a thermal calibration already on the board with none.
  if (!cal.thermal || cal.thermal->params.degrees.bias == 0) {
    out.loss = MeasureLoss(cal, d.correction, d.dropped);
    return out;
  }
  // Temperature: TC_A<n>, the offsets' polynomial in T - TREF taken from the reading before
  // CAL_ACC's offset (TemperatureCompensation.cpp, sensor_calibration/Accelerometer.hpp), zero at
  // TREF so that CAL_ACC holds the offset at T_ref; PX4 matches it to the sensor by TC_A<n>_ID.
  const OffsetPolynomial poly = OffsetsOverTemperature(cal);
  const Px4TemperatureTerms tc =
      Px4Temperature('A', instance, id, poly.t_ref_c, {poly.t_min_c, poly.t_max_c},
                     {raw_ms2 * poly.b[1], raw_ms2 * poly.b[2], raw_ms2 * poly.b[3]}, "m/s2",
                     "the reading before CAL_ACC%d's offset and scale", "CAL_ACC");
  out.text += tc.lines;
  out.convention += tc.convention;
  if (!tc.comment.empty()) out.text.insert(out.text.find("#\n# Vehicle-Id"), tc.comment);
  out.loss =
      MeasureLoss(cal, d.correction, d.dropped, false, [poly](double t_c) { return poly.At(t_c); });
  return out;
}

ExportResult ArduPilot(const LoadedCalibration& cal, const ExportOptions& options) {
  const int instance = options.instance.value_or(0);
  if (instance > 2) throw std::invalid_argument("ArduPilot has accelerometers 0, 1 and 2");
  const double raw_ms2 =
      RawToMetersPerSecond2(cal, options, "ArduPilot", "its drivers scale the counts");
  Diagonal d = DiagonalPart(cal, raw_ms2);
  for (int i = 0; i < 3; ++i) Float32(d.offset_ms2(i)), Float32(d.scale(i));
  PlausibleAccelerometer(cal, options, raw_ms2, "ArduPilot");
  ExportResult out;
  out.convention = DiagonalConvention("ArduPilot (AP_InertialSensor)", cal, raw_ms2);
  const std::string prefix = instance == 0 ? "INS_ACC" : "INS_ACC" + std::to_string(instance + 1);
  const char axes[3] = {'X', 'Y', 'Z'};
  std::string composed;
  Vec3 s_in_force = Vec3::Ones();  // the scale of the calibration in force, composed with
  const SourceStream* stream = AccelerometerStream(cal);
  if (stream != nullptr && stream->corrected) {
    // The IMU and ACC records are a = (p - o_old) .* s_old, rotated by AHRS_ORIENTATION; the
    // calibration of them, f = (a - o) .* s, is then f = (p - (o_old + o ./ s_old)) .* (s_old .*
    // s): the parameters for the sensor's own readings (AHRS_ORIENTATION 0: no rotation between).
    const std::map<std::string, double>& in_force =
        options.current_params ? *options.current_params : stream->calibration_in_force;
    const char* from = options.current_params ? "the parameters given" : "the log's PARM records";
    const auto value = [&](const std::string& name) {
      const auto it = in_force.find(name);
      if (it == in_force.end()) {
        throw DataError("this calibration is of ArduPilot's " +
                        internal::VisibleLine(stream->topic) +
                        " records, already corrected by the calibration in force, and " + from +
                        " do not hold " + name +
                        ": give the parameters in force when the log was recorded "
                        "(current_params)");
      }
      return it->second;
    };
    if (const auto it = in_force.find("AHRS_ORIENTATION");
        it != in_force.end() && it->second != 0) {
      throw DataError(
          Format("AHRS_ORIENTATION is %g in %s: the logged records are rotated to the "
                 "vehicle after the correction, and accelcal composes a calibration "
                 "with the one in force only without that rotation (0)",
                 it->second, from));
    }
    if (stream->instance != instance) {
      throw DataError(
          Format("the calibration is of instance %d's records and the export is for "
                 "instance %d: the calibration in force is another sensor's",
                 stream->instance, instance));
    }
    Vec3 o_old, s_old;
    for (int i = 0; i < 3; ++i) {
      o_old(i) = value(prefix + "OFFS_" + axes[i]);
      s_old(i) = value(prefix + "SCAL_" + axes[i]);
      if (!(s_old(i) > 0) || !std::isfinite(o_old(i))) {
        throw DataError(
            Format("%sSCAL_%c is %g in %s: not a scale", prefix.c_str(), axes[i], s_old(i), from));
      }
    }
    s_in_force = s_old;
    d.offset_ms2 = o_old + d.offset_ms2.cwiseQuotient(s_old);
    d.scale = s_old.cwiseProduct(d.scale);
    for (int i = 0; i < 3; ++i) Finite(d.offset_ms2(i)), Finite(d.scale(i));
    composed = Format(
        "# composed with the calibration in force when %s was logged (%s: %sOFFS = %.9g, %.9g, "
        "%.9g; %sSCAL = %.9g, %.9g, %.9g), so that these apply to the sensor's own readings",
        internal::VisibleLine(stream->topic).c_str(), from, prefix.c_str(), o_old(0), o_old(1),
        o_old(2), prefix.c_str(), s_old(0), s_old(1), s_old(2));
    out.convention += "; composed with the calibration in force (" + std::string(from) + ")";
  }
  out.text = "#" + Header(cal) + "\n# " + out.convention + "\n";
  if (!composed.empty()) out.text += composed + "\n";
  for (int i = 0; i < 3; ++i) {
    out.text += Format("%sOFFS_%c,%.9g\n", prefix.c_str(), axes[i], d.offset_ms2(i));
  }
  for (int i = 0; i < 3; ++i) {
    out.text += Format("%sSCAL_%c,%.9g\n", prefix.c_str(), axes[i], d.scale(i));
  }
  // Temperature: INS_TCAL<n>, v <- v - P(T - 35) + P(CALTEMP - 35) before the offsets
  // (AP_InertialSensor_tempcal.cpp: correct_accel, correct_gyro), P(u) = 1e-6 (c1 u + c2 u^2 +
  // c3 u^3), T held to TMIN..TMAX. The accelerometer's CALTEMP is T_ref, so that the offsets and
  // scales above are those at T_ref; the gyroscope's (INS_GYR<n>_CALTEMP) is the temperature
  // ArduPilot learnt its offsets at, at boot: only their change with temperature is written.
  const bool accel_terms = cal.thermal && cal.thermal->params.degrees.bias > 0;
  std::optional<double> gyro_rad_s;
  if (cal.gyroscope) {
    out.gyroscope_omitted =
        "ArduPilot learns its gyroscope's offsets at each boot and holds no gyroscope scale";
    if (cal.gyroscope->thermal && cal.gyroscope->thermal->degree() > 0) {
      std::string why;
      const std::optional<double> rad_s =
          RawToRadPerSecond(cal, options, "ArduPilot", "its drivers scale the rates", &why);
      // Terms in rad/s of rates that are not in the unit said would be applied as written.
      if (rad_s) why = ImplausibleGyroscope(cal, options, *rad_s, "ArduPilot");
      if (why.empty()) gyro_rad_s = rad_s;
      out.gyroscope_omitted +=
          gyro_rad_s ? Format(
                           ": only the offsets' change with temperature is written "
                           "(INS_TCAL%d_GYR)",
                           instance + 1)
                     : "; the offsets' change with temperature is not written either: " + why;
    }
  }
  if (!accel_terms && !gyro_rad_s) {  // nothing for INS_TCAL to hold
    // The loss is the diagonal model's against the full one, on the data calibrated.
    out.loss = MeasureLoss(cal, d.correction, d.dropped);
    return out;
  }
  if (stream != nullptr && stream->corrected) {
    const std::map<std::string, double>& in_force =
        options.current_params ? *options.current_params : stream->calibration_in_force;
    const auto enabled = in_force.find(Format("INS_TCAL%d_ENABLE", instance + 1));
    if (enabled != in_force.end() && enabled->second == 1) {
      throw DataError(Format(
          "this calibration is of records a temperature calibration in force (INS_TCAL%d_ENABLE "
          "1) had already corrected, and accelcal does not compose one with it: record with "
          "INS_TCAL%d_ENABLE 0 and calibrate that",
          instance + 1, instance + 1));
    }
  }
  // sum_d b_d (T - T_ref)^d in powers of u = T - 35 (its constant cancels against CALTEMP's).
  constexpr double kReference_C = 35.0, kScale = 1e6;
  const auto about_35 = [](const std::array<Vec3, 4>& b, double t_ref_c) {
    const double delta = t_ref_c - kReference_C;
    return std::array<Vec3, 3>{b[1] - 2 * delta * b[2] + 3 * delta * delta * b[3],
                               b[2] - 3 * delta * b[3], b[3]};
  };
  const int n = instance + 1;
  // The accelerometer's offset polynomial, taken once.
  const std::optional<OffsetPolynomial> poly =
      accel_terms ? std::optional(OffsetsOverTemperature(cal)) : std::nullopt;
  const std::pair<double, double> range =
      poly ? std::pair(poly->t_min_c, poly->t_max_c) : cal.gyroscope->thermal_range_c;
  out.text += Format("INS_TCAL%d_ENABLE,1\nINS_TCAL%d_TMIN,%.9g\nINS_TCAL%d_TMAX,%.9g\n", n, n,
                     Float32(range.first), n, Float32(range.second));
  if (poly) {
    const std::array<Vec3, 3> c = about_35(poly->b, poly->t_ref_c);
    for (int k = 0; k < 3; ++k) {
      for (int i = 0; i < 3; ++i) {
        out.text +=
            Format("INS_TCAL%d_ACC%d_%c,%.9g\n", n, k + 1, axes[i],
                   // Composed with the scale in force, as the offsets are.
                   Float32(kScale * raw_ms2 * c[static_cast<std::size_t>(k)](i) / s_in_force(i)));
      }
    }
    out.text += Format("INS_ACC%d_CALTEMP,%.9g\n", n, Float32(poly->t_ref_c));
    out.convention += Format(
        "; INS_TCAL%d: a <- a - P(T - 35) + P(INS_ACC%d_CALTEMP - 35) before the offset and "
        "scale, P(u) = 1e-6 (ACC1 u + ACC2 u^2 + ACC3 u^3) in m/s2, T held to TMIN..TMAX, "
        "CALTEMP = T_ref so that the offsets and scales above are those at T_ref",
        n, n);
  }
  if (gyro_rad_s) {
    const GyroThermalBias& t = *cal.gyroscope->thermal;
    std::array<Vec3, 4> b{Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
    for (int k = 1; k <= t.degree(); ++k) {
      b[static_cast<std::size_t>(k)] =
          *gyro_rad_s * t.coefficients[static_cast<std::size_t>(k - 1)];
    }
    const std::array<Vec3, 3> c = about_35(b, t.t_ref_c);
    for (int k = 0; k < 3; ++k) {
      for (int i = 0; i < 3; ++i) {
        out.text += Format("INS_TCAL%d_GYR%d_%c,%.9g\n", n, k + 1, axes[i],
                           Float32(kScale * c[static_cast<std::size_t>(k)](i)));
      }
    }
    out.convention += Format(
        "; INS_TCAL%d gyroscope: w <- w - P(T - 35) + P(INS_GYR%d_CALTEMP - 35), P(u) = 1e-6 "
        "(GYR1 u + GYR2 u^2 + GYR3 u^3) in rad/s, CALTEMP the temperature of the offsets "
        "ArduPilot learns at boot",
        n, n);
    if (!accel_terms) {
      out.convention += Format("; TMIN..TMAX the gyroscope's still positions' (%.4g to %.4g degC)",
                               range.first, range.second);
    }
  }
  if (poly) {
    out.loss = MeasureLoss(cal, d.correction, d.dropped, false,
                           [p = *poly](double t_c) { return p.At(t_c); });
  } else {
    out.loss = MeasureLoss(cal, d.correction, d.dropped);
  }
  return out;
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

// Kalibr's gyroscope in the scale-misalignment model (IccScaledMisalignedImu, reference IMU):
//     w_measured = M_g C_gyro_i w + A C_gyro_i a + b_g,
// M_g lower-triangular, C_gyro_i a rotation, A full [(rad/s)/(m/s²)], w and a in the IMU frame,
// which is the accelerometer's (the x-first frame of its M). With f_old = Q f_x (ChangeFrame) and s
// the rad/s of a raw unit, w_measured = s K_g Q w + s G Q a / u + s b_g (u the m/s² of the
// calibration's force unit): M_g C_gyro_i = s K_g Q (an LQ factorisation: from the QR of its
// transpose), A = (s/u) G Q C_gyro_iᵀ. Exact: nothing is dropped.
struct KalibrGyro {
  Mat33 M, C, A;
  Vec3 bias_rad_s;
};
KalibrGyro KalibrGyroscope(const LoadedCalibration& cal, const Mat33& Q, double rad_s_per_raw) {
  const LoadedCalibration::Gyroscope& g = *cal.gyroscope;
  const Mat33 X = rad_s_per_raw * g.params.K * Q;
  const Eigen::HouseholderQR<Mat33> qr(Mat33(X.transpose()));
  const Mat33 R = qr.matrixQR().triangularView<Eigen::Upper>();
  Mat33 L = R.transpose();
  Mat33 C = Mat33(qr.householderQ()).transpose();
  // Signs: L's diagonal positive, C a proper rotation (a mirrored gyro keeps a negative z scale).
  for (int i = 0; i < 3; ++i) {
    if (L(i, i) < 0) {
      L.col(i) *= -1;
      C.row(i) *= -1;
    }
  }
  if (C.determinant() < 0) {
    L.col(2) *= -1;
    C.row(2) *= -1;
  }
  L.triangularView<Eigen::StrictlyUpper>().setZero();  // exact zeros (no −0 from the signs)
  KalibrGyro out;
  out.M = L;
  out.C = C;
  out.A = (rad_s_per_raw / ForceToMetersPerSecond2(cal)) * g.params.G * Q * C.transpose();
  out.bias_rad_s = rad_s_per_raw * g.params.bias;
  return out;
}

std::string YamlQuoted(std::string_view text);  // below, with the YAML writer

// The noise an export needs, or DataError naming what is missing.
const ImuNoise& NeedNoise(const ExportOptions& options, const char* format, bool gyroscope) {
  if (!options.noise) {
    throw DataError(std::string(format) +
                    " holds the sensor's noise: give the output of accelcal noise --json");
  }
  if (gyroscope && !options.noise->gyroscope) {
    throw DataError(std::string(format) + " holds the gyroscope's noise too, and " +
                    internal::VisibleLine(options.noise->source) +
                    " has none: analyse the log with the gyroscope (accelcal noise --gyro)");
  }
  return *options.noise;
}

// One value for a tool that takes one per sensor: the largest axis' (an estimator that assumes
// less noise than an axis has trusts that axis too much).
double Largest(const Vec3& v) { return v.maxCoeff(); }

// "x, y, z" of a vector, for comments.
std::string Axes(const Vec3& v) { return Number(v(0)) + ", " + Number(v(1)) + ", " + Number(v(2)); }

// Some axis' random walk is an upper bound, not resolved in the log.
bool Unresolved(const ImuNoise& n) {
  bool any = false;
  for (bool resolved : n.accelerometer.random_walk_resolved) any = any || !resolved;
  if (n.gyroscope) {
    for (bool resolved : n.gyroscope->random_walk_resolved) any = any || !resolved;
  }
  return any;
}

// Comment lines stating where the noise comes from and what each written value is.
std::string NoiseComments(const ImuNoise& n, const char* prefix) {
  std::string t = std::string(prefix) + " noise from " + internal::VisibleLine(n.source) + " (" +
                  internal::VisibleLine(n.log) + ", " + Number(n.rate_hz) + " Hz, " +
                  Format("%.0f", n.accelerometer.duration_s) +
                  " s): continuous-time densities, the largest axis' written\n";
  const auto sensor = [&](const char* name, const SensorNoiseDensities& s, const char* unit) {
    t += std::string(prefix) + " " + name + " white noise per axis [" + unit +
         "/sqrt(Hz)]: " + Axes(s.white) + "\n";
    bool bound = false;
    for (bool resolved : s.random_walk_resolved) bound = bound || !resolved;
    t += std::string(prefix) + " " + name + " random walk per axis [" + unit +
         "/s/sqrt(Hz)]: " + Axes(s.random_walk) +
         (bound ? " (where not resolved in this log: its 95 % upper bound)" : "") + "\n";
  };
  sensor("accelerometer", n.accelerometer, "m/s2");
  if (n.gyroscope) sensor("gyroscope", *n.gyroscope, "rad/s");
  return t;
}

// Kalibr's noise keys (ConfigReader.ImuParameters), at `indent`.
std::string KalibrNoiseKeys(const ImuNoise& n, const std::string& rostopic,
                            const std::string& indent) {
  std::string t;
  t += indent + "accelerometer_noise_density: " + YamlNumber(Largest(n.accelerometer.white)) + "\n";
  t += indent + "accelerometer_random_walk: " + YamlNumber(Largest(n.accelerometer.random_walk)) +
       "\n";
  if (n.gyroscope) {
    t += indent + "gyroscope_noise_density: " + YamlNumber(Largest(n.gyroscope->white)) + "\n";
    t += indent + "gyroscope_random_walk: " + YamlNumber(Largest(n.gyroscope->random_walk)) + "\n";
  }
  t += indent + "update_rate: " + YamlNumber(n.rate_hz) + "\n";
  t += indent + "rostopic: " + YamlQuoted(rostopic) + "\n";
  return t;
}

// Kalibr's input imu.yaml: a flat mapping of the six keys its ImuParameters reads.
ExportResult KalibrImu(const LoadedCalibration& cal, const ExportOptions& options) {
  const ImuNoise& n = NeedNoise(options, "Kalibr's imu.yaml", true);
  ExportResult out;
  out.convention =
      "Kalibr imu.yaml (kalibr_calibrate_imu_camera --imu): continuous-time noise densities "
      "[m/s2/sqrt(Hz), rad/s/sqrt(Hz)] and bias random walks [m/s3/sqrt(Hz), rad/s2/sqrt(Hz)], "
      "the largest axis' of each; Kalibr discretises the white noise as density x sqrt(rate)";
  out.text = "#" + Header(cal) + "\n# " + out.convention + "\n" + NoiseComments(n, "#") +
             KalibrNoiseKeys(n, options.rostopic, "");
  return out;  // the noise alone: no model, no loss
}

// sensor_msgs/Imu: each field's covariance, row-major 3x3, the variance of one sample.
ExportResult RosCovariance(const LoadedCalibration& cal, const ExportOptions& options) {
  const ImuNoise& n = NeedNoise(options, "sensor_msgs/Imu covariances", false);
  ExportResult out;
  out.convention =
      "sensor_msgs/Imu covariances, row-major 3x3: each axis' variance of one sample, white noise "
      "density^2 x rate (as Kalibr, OpenVINS and Basalt discretise the density) [(m/s2)^2, "
      "(rad/s)^2]; orientation_covariance[0] = -1: no orientation; a gyroscope without a noise "
      "analysis: all 0, unknown (REP 145)";
  const auto covariance = [&](const Vec3& density) {
    std::string t = "[";
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        t += (i || j ? ", " : "") + YamlNumber(i == j ? density(i) * density(i) * n.rate_hz : 0.0);
      }
    }
    return t + "]";
  };
  out.text = "#" + Header(cal) + "\n# " + out.convention + "\n" + NoiseComments(n, "#");
  out.text += "linear_acceleration_covariance: " + covariance(n.accelerometer.white) + "\n";
  out.text += "angular_velocity_covariance: " +
              (n.gyroscope ? covariance(n.gyroscope->white)
                           : std::string("[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]")) +
              "\n";
  out.text += "orientation_covariance: [-1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]\n";
  // REP 145's driver parameters: the square roots of the diagonals, one per field.
  out.text += "linear_acceleration_stddev: " +
              YamlNumber(Largest(n.accelerometer.white) * std::sqrt(n.rate_hz)) + "\n";
  if (n.gyroscope) {
    out.text += "angular_velocity_stddev: " +
                YamlNumber(Largest(n.gyroscope->white) * std::sqrt(n.rate_hz)) + "\n";
  }
  return out;  // the noise alone: no model, no loss
}

// The accelerometer as the forward-model estimators take it (Kalibr, OpenVINS): a_measured = M a
// + b in m/s², M lower-triangular = accelcal's K in the x-first frame, scaled to m/s² readings
// and forces. Basalt takes its inverse.
struct ForwardAccelerometer {
  FrameChange change;  ///< to the x-first frame: f_old = Q_old_new f_x
  Mat33 M;
  Vec3 bias_ms2;
};
ForwardAccelerometer XFirstAccelerometer(const LoadedCalibration& cal, double raw_ms2) {
  ForwardAccelerometer a;
  a.change = ChangeFrame(cal.params.K, Frame::kXFirst);
  a.M = (raw_ms2 / ForceToMetersPerSecond2(cal)) * a.change.K;
  a.bias_ms2 = raw_ms2 * cal.params.bias;
  return a;
}

// What a linear correction in the x-first frame loses: the squared terms. Magnitudes are
// frame-independent, so the loss compares the forces turned back: the rotation Q is not a loss.
ExportLoss XFirstLoss(const LoadedCalibration& cal, const FrameChange& change) {
  const Mat33 K_x = change.K;
  return MeasureLoss(
      cal,
      [&](const Vec3& p) -> std::optional<Vec3> {
        return Vec3(change.Q_old_new * (K_x.inverse() * (p - cal.params.bias)));
      },
      SquaredTermsDropped(cal));
}

// "the x-first frame" sentence of a convention: how the frame was reached.
std::string XFirstFrom(const LoadedCalibration& cal) {
  return cal.frame == Frame::kXFirst
             ? ""
             : " (converted exactly from the " + std::string(ToString(cal.frame)) +
                   " frame: the body frame turns, corrected magnitudes are unchanged)";
}

// A 3x3 matrix as Kalibr's and OpenVINS' YAML list it under its key: one row per line.
std::string YamlRows(const Mat33& A) {
  std::string text;
  for (int i = 0; i < 3; ++i) {
    text += "    - [" + YamlNumber(A(i, 0)) + ", " + YamlNumber(A(i, 1)) + ", " +
            YamlNumber(A(i, 2)) + "]\n";
  }
  return text;
}

// The gyroscope in the x-first frame and rad/s, when the file has one in a unit the format reads;
// else std::nullopt and, for a unit it cannot read, why in `out->gyroscope_omitted`.
// A format whose file states the gyroscope's model whether or not it was calibrated (OpenVINS'
// Tw, Basalt's calib_gyro_bias) is `required` to hold it: the identity in place of a calibrated
// gyroscope would be a claim, so the unit must be known (DataError).
std::optional<KalibrGyro> XFirstGyroscope(const LoadedCalibration& cal,
                                          const ExportOptions& options, const FrameChange& change,
                                          std::string_view format, ExportResult* out,
                                          bool required = false) {
  if (!cal.gyroscope) return std::nullopt;
  const std::optional<double> rad_s = RawToRadPerSecond(
      cal, options, format, "sensor_msgs/Imu angular_velocity", &out->gyroscope_omitted);
  if (rad_s) {
    out->gyroscope_omitted = ImplausibleGyroscope(cal, options, *rad_s, format);
  }
  if (!rad_s || !out->gyroscope_omitted.empty()) {
    if (required) throw DataError(out->gyroscope_omitted);
    return std::nullopt;
  }
  out->gyroscope_included = true;
  // The accelerometer's squared terms, dropped, reach the rate through the g-sensitivity.
  if (cal.model == ModelKind::kQuadratic && !cal.gyroscope->params.G.isZero(0)) {
    out->gyroscope_dropped =
        "the accelerometer's squared terms k2, which reach the rate through the g-sensitivity G";
  }
  return KalibrGyroscope(cal, change.Q_old_new, *rad_s);
}

// What an estimator's file (OpenVINS', Basalt's) is made of: the noise of both sensors, the
// accelerometer in the x-first frame and m/s², and the gyroscope there in rad/s when the file has
// one (required: its unit must be known).
struct EstimatorImu {
  const ImuNoise& noise;
  ForwardAccelerometer accelerometer;
  std::optional<KalibrGyro> gyroscope;
};
EstimatorImu ForEstimator(const LoadedCalibration& cal, const ExportOptions& options,
                          const char* file, const char* tool, const char* why, ExportResult* out) {
  const ImuNoise& noise = NeedNoise(options, file, true);
  const double raw_ms2 = RawToMetersPerSecond2(cal, options, tool, why);
  PlausibleAccelerometer(cal, options, raw_ms2, tool);
  const ForwardAccelerometer a = XFirstAccelerometer(cal, raw_ms2);
  std::optional<KalibrGyro> g = XFirstGyroscope(cal, options, a.change, tool, out, true);
  return {noise, a, std::move(g)};
}

// Kalibr's scale-misalignment model: a_measured = M a + b, M lower-triangular, m/s².
ExportResult Kalibr(const LoadedCalibration& cal, const ExportOptions& options) {
  const double raw_ms2 =
      RawToMetersPerSecond2(cal, options, "Kalibr", "sensor_msgs/Imu linear_acceleration");
  PlausibleAccelerometer(cal, options, raw_ms2, "Kalibr");
  const ForwardAccelerometer a = XFirstAccelerometer(cal, raw_ms2);
  ExportResult out;
  out.convention =
      "Kalibr scale-misalignment IMU (IccScaledMisalignedImu): a_measured = M a + b in m/s2, M "
      "lower-triangular = accelcal's K in the x-first frame" +
      XFirstFrom(cal) +
      "; Kalibr estimates its own time-varying bias b, so accelcal's constant bias is a comment";
  out.text =
      "#" + Header(cal) + "\n# " + out.convention + "\n" +
      (options.noise ? NoiseComments(*options.noise, "#") : std::string()) + "imu0:\n" +
      (options.noise ? KalibrNoiseKeys(*options.noise, options.rostopic, "  ") : std::string()) +
      "  model: scale-misalignment\n" + "  accelerometers:\n    M:\n" + YamlRows(a.M);
  out.text += "  # accelcal constant bias [m/s2]: [" + Axes(a.bias_ms2) + "]\n";
  if (const std::optional<KalibrGyro> g = XFirstGyroscope(cal, options, a.change, "Kalibr", &out)) {
    out.convention +=
        "; gyroscope: w_measured = M C_gyro_i w + A C_gyro_i a + b in rad/s, M lower-triangular "
        "and C_gyro_i a rotation with M C_gyro_i = accelcal's K_g in the accelerometer's x-first "
        "frame, A its g-sensitivity G [(rad/s)/(m/s2)] (exact; accelcal's constant bias a "
        "comment)";
    out.text += "  gyroscopes:\n    M:\n" + YamlRows(g->M) + "    A:\n" + YamlRows(g->A) +
                "    C_gyro_i:\n" + YamlRows(g->C);
    out.text += "  # accelcal constant gyro bias [rad/s]: [" + Axes(g->bias_rad_s) + "]\n";
  }
  out.loss = XFirstLoss(cal, a.change);
  return out;
}

// OpenVINS' kalibr_imu_chain.yaml (ov_msckf VioManagerOptions, model "kalibr"): the forward model
//     a_m = Ta R_IMUtoACC a + b_a,   w_m = Tw R_IMUtoGYRO w + Tg a + b_g   (m/s², rad/s),
// applied as a = R_ACCtoIMU Ta⁻¹ (a_m − b_a), w = R_GYROtoIMU Tw⁻¹ (w_m − b_g − Tg a)
// (Propagator::predict_and_compute), keeping the lower triangles of Ta⁻¹ and Tw⁻¹. Kalibr's
// model in OpenVINS' names: Ta = M_a, R_IMUtoACC = I, Tw = M_g, R_IMUtoGYRO = C_gyro_i and
// Tg = A C_gyro_i (A acts on the force in the gyro frame, Tg on the IMU frame's).
ExportResult OpenVins(const LoadedCalibration& cal, const ExportOptions& options) {
  ExportResult out;
  const EstimatorImu imu = ForEstimator(cal, options, "OpenVINS' kalibr_imu_chain.yaml", "OpenVINS",
                                        "sensor_msgs/Imu linear_acceleration", &out);
  const ImuNoise& n = imu.noise;
  const ForwardAccelerometer& a = imu.accelerometer;
  const std::optional<KalibrGyro>& g = imu.gyroscope;
  out.convention =
      "OpenVINS kalibr_imu_chain.yaml (ov_msckf, model kalibr): a_m = Ta R_IMUtoACC a + b_a, w_m "
      "= Tw R_IMUtoGYRO w + Tg a + b_g in m/s2 and rad/s, the IMU frame the accelerometer's "
      "x-first frame" +
      XFirstFrom(cal) + "; Ta lower-triangular = accelcal's K, R_IMUtoACC = I; " +
      (g ? "Tw lower-triangular and R_IMUtoGYRO a rotation with Tw R_IMUtoGYRO = accelcal's K_g, "
           "Tg = its g-sensitivity G on the IMU-frame force [(rad/s)/(m/s2)]"
         : "no gyroscope in the calibration: Tw = R_IMUtoGYRO = I, Tg = 0 (OpenVINS' "
           "defaults)") +
      "; OpenVINS estimates its own biases, so accelcal's constant biases are comments; noise: "
      "continuous-time densities, the largest axis' of each";
  const Mat33 I = Mat33::Identity();
  out.text = "%YAML:1.0\n#" + Header(cal) + "\n# " + out.convention + "\n" + NoiseComments(n, "#") +
             "imu0:\n" + KalibrNoiseKeys(n, options.rostopic, "  ") +
             "  time_offset: 0.0\n  model: \"kalibr\"\n";
  out.text += "  Tw:\n" + YamlRows(g ? g->M : I) + "  R_IMUtoGYRO:\n" + YamlRows(g ? g->C : I) +
              "  Ta:\n" + YamlRows(a.M) + "  R_IMUtoACC:\n" + YamlRows(I) + "  Tg:\n" +
              YamlRows(g ? Mat33(g->A * g->C) : Mat33::Zero());
  out.text += "  # accelcal constant bias [m/s2]: [" + Axes(a.bias_ms2) + "]\n";
  if (g) out.text += "  # accelcal constant gyro bias [rad/s]: [" + Axes(g->bias_rad_s) + "]\n";
  out.loss = XFirstLoss(cal, a.change);
  return out;
}

// Basalt's calib.json (cereal, basalt/calibration/calib_bias.hpp): the inverse model
//     a = (I + S_a) a_raw − b_a,   w = (I + S_g) w_raw − b_g   (m/s², rad/s),
// S_a lower-triangular (its 6 entries column by column), S_g full (9, column-major), the biases
// in calibrated units; no g-sensitivity. From Kalibr's forward model: I + S_a = M_a⁻¹, b_a =
// M_a⁻¹ bias, I + S_g = (M_g C_gyro_i)⁻¹, b_g = (M_g C_gyro_i)⁻¹ bias_g.
ExportResult Basalt(const LoadedCalibration& cal, const ExportOptions& options) {
  ExportResult out;
  const EstimatorImu imu = ForEstimator(cal, options, "Basalt's calib.json", "Basalt",
                                        "its IMU readings are in m/s2", &out);
  const ImuNoise& n = imu.noise;
  const ForwardAccelerometer& a = imu.accelerometer;
  const std::optional<KalibrGyro>& g = imu.gyroscope;
  Mat33 Sa = a.M.triangularView<Eigen::Lower>().solve(Mat33::Identity());
  Sa.triangularView<Eigen::StrictlyUpper>().setZero();
  const Vec3 ba = Sa * a.bias_ms2;
  Sa -= Mat33::Identity();
  ordered_json accel = ordered_json::array({ba(0), ba(1), ba(2)});
  for (int c = 0; c < 3; ++c) {
    for (int r = c; r < 3; ++r) accel.push_back(Sa(r, c));
  }
  ordered_json gyro = ordered_json::array({0.0, 0.0, 0.0});
  for (int i = 0; i < 9; ++i) gyro.push_back(0.0);
  if (g) {
    const Mat33 MC = g->M * g->C;
    Mat33 Sg = MC.inverse();
    const Vec3 bg = Sg * g->bias_rad_s;
    Sg -= Mat33::Identity();
    gyro = ordered_json::array({bg(0), bg(1), bg(2)});
    for (int c = 0; c < 3; ++c) {
      for (int r = 0; r < 3; ++r) gyro.push_back(Sg(r, c));
    }
    out.gyroscope_dropped = GSensitivityDropped(cal);  // G gone: k2 no longer reaches the rate
  }
  const auto axes = [](const Vec3& v) { return ordered_json::array({v(0), v(1), v(2)}); };
  ordered_json value;
  value["T_imu_cam"] = ordered_json::array();
  value["intrinsics"] = ordered_json::array();
  value["resolution"] = ordered_json::array();
  value["calib_accel_bias"] = accel;
  value["calib_gyro_bias"] = gyro;
  value["imu_update_rate"] = n.rate_hz;
  value["accel_noise_std"] = axes(n.accelerometer.white);
  value["gyro_noise_std"] = axes(n.gyroscope->white);
  value["accel_bias_std"] = axes(n.accelerometer.random_walk);
  value["gyro_bias_std"] = axes(n.gyroscope->random_walk);
  value["cam_time_offset_ns"] = 0;
  value["vignette"] = ordered_json::array();
  for (const auto& [key, field] : value.items()) {  // every number finite (Finite)
    if (field.is_number()) Finite(field.get<double>());
    for (const auto& x : field) {
      if (x.is_number()) Finite(x.get<double>());
    }
  }
  out.text = ordered_json{{"value0", value}}.dump(4) + "\n";
  out.convention =
      "Basalt calib.json (calib_bias.hpp): a = (I + S_a) a_raw - b_a, w = (I + S_g) w_raw - b_g "
      "in m/s2 and rad/s, the biases in calibrated units, the IMU frame the accelerometer's "
      "x-first frame" +
      XFirstFrom(cal) +
      "; calib_accel_bias = [b_a, S_a's lower triangle column by column], I + S_a = K^-1; " +
      (g ? "calib_gyro_bias = [b_g, S_g column-major], I + S_g = K_g^-1 (its rotation to the "
           "accelerometer's frame included)"
         : "no gyroscope in the calibration: calib_gyro_bias all 0") +
      "; noise per axis, continuous-time (accel_noise_std, gyro_noise_std white noise; "
      "accel_bias_std, gyro_bias_std random walk" +
      (Unresolved(n) ? ", where the log does not resolve it its 95 % upper bound" : "") +
      "); the camera fields empty: merge the IMU fields into the calib.json of a camera "
      "calibration";
  out.loss = XFirstLoss(cal, a.change);
  return out;
}

std::string CIdentifier(const std::string& prefix) {
  if (prefix.empty() || IsAsciiDigit(prefix[0])) {
    throw std::invalid_argument("c_prefix must start with a letter or '_'");
  }
  for (const char c : prefix) {
    if (!IsIdentifierChar(c)) {
      throw std::invalid_argument("c_prefix may hold only letters, digits and '_'");
    }
  }
  return prefix;
}

// Firmware: the model's exact inverse, as SpecificForce computes it.
ExportResult CHeader(const LoadedCalibration& cal, const ExportOptions& options) {
  const std::string p = CIdentifier(options.c_prefix);
  std::string guard;
  for (const char c : p) guard += c >= 'a' && c <= 'z' ? static_cast<char>(c - 'a' + 'A') : c;
  guard += "_CALIBRATION_H";
  const bool full = cal.frame == Frame::kPlatform;
  if (full && cal.model == ModelKind::kQuadratic) {
    throw DataError(
        "c-header: a full K with squared terms (platform frame) needs an iterative "
        "solve that the header does not provide; export the linear fit");
  }
  ExportResult out;
  out.convention =
      "C99 header: " + p + "_correct(raw, f) solves p = K f + b + k2 .* f^2 for f exactly (" +
      DescribeUnits(cal) + ", accelcal's " + std::string(ToString(cal.frame)) + " body frame)";
  const auto vec = [](const Vec3& v) {
    return "{" + Number(v(0)) + ", " + Number(v(1)) + ", " + Number(v(2)) + "}";
  };
  const auto mat = [&](const Mat33& A) {
    return "{" + vec(A.row(0).transpose()) + ", " + vec(A.row(1).transpose()) + ", " +
           vec(A.row(2).transpose()) + "}";
  };
  std::string& t = out.text;
  t = "/*" + CCommentText(Header(cal)) + "\n * " + CCommentText(out.convention) +
      "\n * Generated by accelcal export; the numbers read back as the same doubles. */\n";
  t += "#ifndef " + guard + "\n#define " + guard + "\n\n#include <math.h>\n\n";
  t += "static const double " + p + "_K[3][3] = " + mat(cal.params.K) + ";\n";
  t += "static const double " + p + "_bias[3] = " + vec(cal.params.bias) + ";\n";
  t += "static const double " + p + "_k2[3] = " + vec(cal.params.k2) + ";\n";
  if (full)
    t += "static const double " + p + "_K_inv[3][3] = " + mat(cal.params.K.inverse()) + ";\n";
  t += "\n/* Returns 0, or -1 when the reading has no real solution (quadratic model only). */\n";
  t += "static inline int " + p + "_correct(const double raw[3], double f[3]) {\n";
  if (full) {
    t += "  int i;\n  for (i = 0; i < 3; ++i) {\n"
         "    f[i] = " +
         p + "_K_inv[i][0] * (raw[0] - " + p + "_bias[0]) + " + p + "_K_inv[i][1] * (raw[1] - " +
         p + "_bias[1]) +\n           " + p + "_K_inv[i][2] * (raw[2] - " + p +
         "_bias[2]);\n  }\n  return 0;\n}\n";
  } else {
    const bool lower = cal.frame == Frame::kXFirst;
    t += std::string("  /* along K's triangle: ") + (lower ? "x, y, z" : "z, y, x") + " */\n";
    t +=
        std::string("  static const int order[3] = ") + (lower ? "{0, 1, 2}" : "{2, 1, 0}") + ";\n";
    t += "  int n, j;\n  for (n = 0; n < 3; ++n) f[n] = 0.0;\n"
         "  for (n = 0; n < 3; ++n) {\n    const int i = order[n];\n"
         "    double r = raw[i] - " +
         p +
         "_bias[i];\n    double a, disc, root;\n"
         "    for (j = 0; j < 3; ++j) {\n      if (j != i) r -= " +
         p +
         "_K[i][j] * f[j];\n    }\n"
         "    a = " +
         p +
         "_K[i][i];\n"
         "    if (" +
         p +
         "_k2[i] == 0.0) {\n      f[i] = r / a;\n      continue;\n    }\n"
         "    disc = a * a + 4.0 * " +
         p +
         "_k2[i] * r;\n    if (!(disc >= 0.0)) return -1;\n"
         "    root = sqrt(disc);\n    f[i] = 2.0 * r / (a >= 0.0 ? a + root : a - root);\n"
         "  }\n  return 0;\n}\n";
  }
  if (cal.gyroscope) {
    // The gyroscope: w = K_g^-1 (raw - b_g - G f), f the corrected specific force at the sample.
    const LoadedCalibration::Gyroscope& g = *cal.gyroscope;
    out.convention += "; " + p +
                      "_correct_gyro(raw, f, w) gives the body rate w = K_g^-1 (raw - b_g - G f) "
                      "in rad/s from a raw rate (in '" +
                      internal::VisibleLine(g.raw_unit) +
                      "') and the corrected specific force f of the same instant";
    t += "\nstatic const double " + p + "_gyro_K_inv[3][3] = " + mat(g.params.K.inverse()) + ";\n";
    t += "static const double " + p + "_gyro_bias[3] = " + vec(g.params.bias) + ";\n";
    t += "static const double " + p + "_gyro_G[3][3] = " + mat(g.params.G) + ";\n";
    t += "\nstatic inline void " + p +
         "_correct_gyro(const double raw[3], const double f[3], double w[3]) {\n"
         "  double r[3];\n  int i;\n  for (i = 0; i < 3; ++i) {\n"
         "    r[i] = raw[i] - " +
         p + "_gyro_bias[i] - " + p + "_gyro_G[i][0] * f[0] - " + p + "_gyro_G[i][1] * f[1] - " +
         p + "_gyro_G[i][2] * f[2];\n  }\n  for (i = 0; i < 3; ++i) {\n    w[i] = " + p +
         "_gyro_K_inv[i][0] * r[0] + " + p + "_gyro_K_inv[i][1] * r[1] + " + p +
         "_gyro_K_inv[i][2] * r[2];\n  }\n}\n";
    out.gyroscope_included = true;
  }
  t += "\n#endif /* " + guard + " */\n";
  out.loss = MeasureLoss(
      cal, [&](const Vec3& r) { return SpecificForce(cal.params, r); }, "");
  return out;
}

// YAML emission of a JSON value at an indentation.
bool IsScalar(const ordered_json& j) { return !j.is_object() && !j.is_array(); }
bool IsFlowArray(const ordered_json& j) {
  if (!j.is_array()) return false;
  for (const auto& e : j) {
    if (!(IsScalar(e) || (e.is_array() && std::all_of(e.begin(), e.end(), IsScalar)))) {
      return false;
    }
  }
  return true;
}
// A YAML double-quoted scalar holding exactly `text` (UTF-8) in YAML 1.1 and 1.2 readers: '"' and
// '\\' escaped, tab, line feed and carriage return as \t, \n, \r, the other characters of
// internal::IsInvisible (which readers refuse, or read as line breaks and fold) as \xHH or \uHHHH;
// printable Unicode as it is. A byte that is no UTF-8 (a JSON document holds none) is U+FFFD.
std::string YamlQuoted(std::string_view text) {
  return "\"" + internal::EscapeText(text, internal::Escaping::kYamlDoubleQuoted) + "\"";
}
// A key plain when it is an identifier that no YAML 1.1 reader takes for a boolean or null.
std::string YamlKey(const std::string& key) {
  bool plain = !key.empty() && (IsAsciiLetter(key[0]) || key[0] == '_');
  for (const char c : key) plain = plain && IsIdentifierChar(c);
  std::string lower;
  for (const char c : key) lower += internal::AsciiLower(c);
  for (const char* word : {"null", "true", "false", "yes", "no", "on", "off", "y", "n"}) {
    plain = plain && lower != word;
  }
  return plain ? key : YamlQuoted(key);
}
// JSON's spelling of a scalar, except that a float always has a '.' in its mantissa: YAML 1.1
// readers (PyYAML) take 1e-05 for a string, 1.0e-05 for a number.
std::string YamlFlow(const ordered_json& j) {
  if (j.is_array()) {
    std::string text = "[";
    for (std::size_t i = 0; i < j.size(); ++i) text += (i ? ", " : "") + YamlFlow(j[i]);
    return text + "]";
  }
  if (j.is_string()) return YamlQuoted(j.get_ref<const std::string&>());
  std::string text = j.dump();
  if (j.is_number_float() && text.find('.') == std::string::npos) {
    const std::size_t e = text.find_first_of("eE");
    text.insert(e == std::string::npos ? text.size() : e, ".0");
  }
  return text;
}
void EmitYaml(const ordered_json& j, int indent, std::string* out);
void EmitYamlValue(const ordered_json& j, int indent, std::string* out) {
  if (IsScalar(j) || IsFlowArray(j) || j.empty()) {
    *out += " " + YamlFlow(j) + "\n";  // JSON scalars and flow arrays are valid YAML
  } else {
    *out += "\n";
    EmitYaml(j, indent + 2, out);
  }
}
void EmitYaml(const ordered_json& j, int indent, std::string* out) {
  const std::string pad(static_cast<std::size_t>(indent), ' ');
  if (j.is_object()) {
    for (const auto& [key, value] : j.items()) {
      *out += pad + YamlKey(key) + ":";
      EmitYamlValue(value, indent, out);
    }
  } else {
    for (const auto& value : j) {
      if (value.is_object() && !value.empty()) {
        std::string item;
        EmitYaml(value, indent + 2, &item);
        *out += pad + "- " + item.substr(static_cast<std::size_t>(indent) + 2);
      } else {
        *out += pad + "-";
        EmitYamlValue(value, indent, out);
      }
    }
  }
}

}  // namespace

std::string_view ToString(ExportFormat format) { return NameOf(format); }

std::optional<ExportFormat> ExportFormatFromString(std::string_view text) {
  return FromName<ExportFormat>(text);
}

const std::vector<ExportFormat>& AllExportFormats() {
  static const std::vector<ExportFormat> all = [] {
    std::vector<ExportFormat> v;
    for (const auto& [format, name] : EnumNames<ExportFormat>::kTable) v.push_back(format);
    return v;
  }();
  return all;
}

std::string VisibleLine(std::string_view text) { return internal::VisibleLine(text); }

std::string JsonToYaml(const std::string& json_text) {
  const ordered_json doc = ordered_json::parse(json_text);
  std::string out = "%YAML 1.2\n---\n";
  EmitYaml(doc, 0, &out);
  return out;
}

namespace {
ExportResult ExportFormatted(const LoadedCalibration& cal, const std::string& native_json,
                             ExportFormat format, const ExportOptions& options);
}  // namespace

ExportResult ExportCalibration(const LoadedCalibration& cal, const std::string& native_json,
                               ExportFormat format, const ExportOptions& options) {
  ExportResult out = ExportFormatted(cal, native_json, format, options);
  // The gyroscope's offsets over temperature: only accelcal's own file and PX4's TC_G hold them.
  const bool holds = format == ExportFormat::kJson || format == ExportFormat::kYaml ||
                     format == ExportFormat::kPx4;
  if (out.gyroscope_included && !holds && cal.gyroscope->thermal &&
      cal.gyroscope->thermal->degree() > 0) {
    out.gyroscope_dropped =
        Join(out.gyroscope_dropped,
             Format("the offsets' change with temperature (degree %d about T_ref = %.4g degC): the "
                    "offsets are those at T_ref",
                    cal.gyroscope->thermal->degree(), cal.gyroscope->thermal->t_ref_c));
  }
  return out;
}

namespace {
ExportResult ExportFormatted(const LoadedCalibration& cal, const std::string& native_json,
                             ExportFormat format, const ExportOptions& options) {
  if (options.instance && *options.instance < 0) {
    throw std::invalid_argument("instance must be >= 0");
  }
  if (options.sensor != "accelerometer" && options.sensor != "gyroscope") {
    throw std::invalid_argument("sensor must be \"accelerometer\" or \"gyroscope\"");
  }
  if (!options.gyro_raw_unit.empty() && options.gyro_raw_unit != "rad/s" &&
      options.gyro_raw_unit != "deg/s") {
    throw std::invalid_argument("gyro_raw_unit must be rad/s or deg/s");
  }
  if (!IsRosName(options.rostopic)) {
    throw std::invalid_argument(
        "rostopic must be a ROS name: '/' or '~/' (or nothing) first, then tokens joined by '/', "
        "each a letter or '_' followed by letters, digits and '_'");
  }
  if (options.sensor == "gyroscope" && format != ExportFormat::kImuTk) {
    throw std::invalid_argument(
        "sensor \"gyroscope\" is for the imutk format (the c-header holds both sensors; json "
        "and yaml the whole file)");
  }
  ExportResult out;
  switch (format) {
    case ExportFormat::kJson:
    case ExportFormat::kYaml:
      out.text = format == ExportFormat::kJson ? native_json : JsonToYaml(native_json);
      out.convention =
          "accelcal's calibration file (docs/calibration-file.md): p = K f + b + k2 "
          ".* f^2, " +
          DescribeUnits(cal) + ", " + std::string(ToString(cal.frame)) + " body frame";
      out.loss = MeasureLoss(
          cal, [&](const Vec3& p) { return SpecificForce(cal.params, p); }, "", true);
      out.gyroscope_included = cal.has_gyroscope();
      return out;
    case ExportFormat::kKalibr:
      return Kalibr(cal, options);
    case ExportFormat::kPx4:
      return Px4(cal, options);
    case ExportFormat::kArduPilot:
      return ArduPilot(cal, options);
    case ExportFormat::kCHeader:
      return CHeader(cal, options);
    case ExportFormat::kImuTk:
      return options.sensor == "gyroscope" ? ImuTkGyroscope(cal) : ImuTk(cal);
    case ExportFormat::kKalibrImu:
      return KalibrImu(cal, options);
    case ExportFormat::kRos:
      return RosCovariance(cal, options);
    case ExportFormat::kOpenVins:
      return OpenVins(cal, options);
    case ExportFormat::kBasalt:
      return Basalt(cal, options);
  }
  throw std::invalid_argument("unknown export format");
}
}  // namespace

}  // namespace accelcal
