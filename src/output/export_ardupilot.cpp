// ArduPilot's parameter file (export_common.hpp): the accelerometer as INS_ACC<n> offsets and
// scales, composed with the calibration in force where the log's records were already corrected,
// with its offsets' temperature terms (INS_TCAL<n>_ACC); of the gyroscope, whose offsets ArduPilot
// learns at boot, only the offsets' change with temperature (INS_TCAL<n>_GYR). ArduPilot holds a
// diagonal model: it drops the accelerometer's misalignments and squared terms k2, the scale and
// misalignment temperature terms and the bias drift, and the gyroscope's offsets, scale,
// misalignment and g-sensitivity.
#include <array>
#include <cmath>
#include <map>
#include <optional>
#include <stdexcept>

#include "accelcal/error.hpp"
#include "accelcal/native_log.hpp"
#include "output/export_common.hpp"

namespace accelcal::exports {

namespace {

constexpr char kAxes[3] = {'X', 'Y', 'Z'};

// The parameters in force when the log was recorded: those given (current_params), else the
// log's PARM records; `from` says which, for messages.
const std::map<std::string, double>& InForce(const SourceStream& stream,
                                             const ExportOptions& options, const char** from) {
  *from = options.current_params ? "the parameters given" : "the log's PARM records";
  return options.current_params ? *options.current_params : stream.calibration_in_force;
}

// A calibration of the IMU and ACC records, which the calibration in force (`prefix`'s OFFS and
// SCAL) had already corrected, composed with it into `d`: the parameters for the sensor's own
// readings. Returns the scale in force, and in `composed` the comment line that says so.
Vec3 ComposeWithInForce(const SourceStream& stream, const ExportOptions& options, int instance,
                        const std::string& prefix, Diagonal* d, std::string* composed,
                        std::string* convention) {
  // The IMU and ACC records are a = (p - o_old) .* s_old, rotated by AHRS_ORIENTATION; the
  // calibration of them, f = (a - o) .* s, is then f = (p - (o_old + o ./ s_old)) .* (s_old .*
  // s): the parameters for the sensor's own readings (AHRS_ORIENTATION 0: no rotation between).
  const char* from = nullptr;
  const std::map<std::string, double>& in_force = InForce(stream, options, &from);
  const auto value = [&](const std::string& name) {
    const auto it = in_force.find(name);
    if (it == in_force.end()) {
      throw DataError("this calibration is of ArduPilot's " + internal::VisibleLine(stream.topic) +
                      " records, already corrected by the calibration in force, and " + from +
                      " do not hold " + name +
                      ": give the parameters in force when the log was recorded "
                      "(current_params)");
    }
    return it->second;
  };
  if (const auto it = in_force.find("AHRS_ORIENTATION"); it != in_force.end() && it->second != 0) {
    throw DataError(
        Format("AHRS_ORIENTATION is %g in %s: the logged records are rotated to the "
               "vehicle after the correction, and accelcal composes a calibration "
               "with the one in force only without that rotation (0)",
               it->second, from));
  }
  if (stream.instance != instance) {
    throw DataError(
        Format("the calibration is of instance %d's records and the export is for "
               "instance %d: the calibration in force is another sensor's",
               stream.instance, instance));
  }
  Vec3 o_old, s_old;
  for (int i = 0; i < 3; ++i) {
    o_old(i) = value(prefix + "OFFS_" + kAxes[i]);
    s_old(i) = value(prefix + "SCAL_" + kAxes[i]);
    if (!(s_old(i) > 0) || !std::isfinite(o_old(i))) {
      throw DataError(
          Format("%sSCAL_%c is %g in %s: not a scale", prefix.c_str(), kAxes[i], s_old(i), from));
    }
  }
  d->offset_ms2 = o_old + d->offset_ms2.cwiseQuotient(s_old);
  d->scale = s_old.cwiseProduct(d->scale);
  for (int i = 0; i < 3; ++i) Finite(d->offset_ms2(i)), Finite(d->scale(i));
  *composed = Format(
      "# composed with the calibration in force when %s was logged (%s: %sOFFS = %.9g, %.9g, "
      "%.9g; %sSCAL = %.9g, %.9g, %.9g), so that these apply to the sensor's own readings",
      internal::VisibleLine(stream.topic).c_str(), from, prefix.c_str(), o_old(0), o_old(1),
      o_old(2), prefix.c_str(), s_old(0), s_old(1), s_old(2));
  *convention += "; composed with the calibration in force (" + std::string(from) + ")";
  return s_old;
}

// ArduPilot learns its gyroscope's offsets at each boot and holds no gyroscope scale: of a
// calibrated gyroscope it takes only the offsets' change with temperature, in rad/s. The rad/s of
// one raw unit when that is written, else std::nullopt; why not in `out->gyroscope_omitted`.
std::optional<double> GyroscopeTemperatureTerms(const LoadedCalibration& cal,
                                                const ExportOptions& options, int instance,
                                                ExportResult* out) {
  std::optional<double> gyro_rad_s;
  if (!cal.gyroscope) return gyro_rad_s;
  out->gyroscope_omitted =
      "ArduPilot learns its gyroscope's offsets at each boot and holds no gyroscope scale";
  if (cal.gyroscope->thermal && cal.gyroscope->thermal->bias.degree() > 0) {
    std::string why;
    const std::optional<double> rad_s =
        RawToRadPerSecond(cal, options, "ArduPilot", "its drivers scale the rates", &why);
    // Terms in rad/s of rates that are not in the unit said would be applied as written.
    if (rad_s) why = ImplausibleGyroscope(cal, options, *rad_s, "ArduPilot");
    if (why.empty()) gyro_rad_s = rad_s;
    out->gyroscope_omitted +=
        gyro_rad_s ? Format(
                         ": only the offsets' change with temperature is written "
                         "(INS_TCAL%d_GYR)",
                         instance + 1)
                   : "; the offsets' change with temperature is not written either: " + why;
  }
  return gyro_rad_s;
}

// sum_d b_d (T - T_ref)^d in powers of u = T - 35 (its constant cancels against CALTEMP's).
constexpr double kReference_C = 35.0, kScale = 1e6;
std::array<Vec3, 3> About35(const std::array<Vec3, 4>& b, double t_ref_c) {
  const double delta = t_ref_c - kReference_C;
  return std::array<Vec3, 3>{b[1] - 2 * delta * b[2] + 3 * delta * delta * b[3],
                             b[2] - 3 * delta * b[3], b[3]};
}

}  // namespace

ExportResult ArduPilot(const LoadedCalibration& cal, const ExportOptions& options) {
  const int instance = options.instance.value_or(0);
  const double raw_ms2 =
      RawToMetersPerSecond2(cal, options, "ArduPilot", "its drivers scale the counts");
  Diagonal d = DiagonalPart(cal, raw_ms2);
  for (int i = 0; i < 3; ++i) Float32(d.offset_ms2(i)), Float32(d.scale(i));
  PlausibleAccelerometer(cal, options, raw_ms2, "ArduPilot");
  ExportResult out;
  out.convention = DiagonalConvention("ArduPilot (AP_InertialSensor)", cal, raw_ms2);
  const std::string prefix = instance == 0 ? "INS_ACC" : "INS_ACC" + std::to_string(instance + 1);
  std::string composed;
  Vec3 s_in_force = Vec3::Ones();  // the scale of the calibration in force, composed with
  const SourceStream* stream = AccelerometerStream(cal);
  if (stream != nullptr && stream->corrected) {
    s_in_force =
        ComposeWithInForce(*stream, options, instance, prefix, &d, &composed, &out.convention);
  }
  out.text = "#" + Header(cal) + "\n# " + out.convention + "\n";
  if (!composed.empty()) out.text += composed + "\n";
  for (int i = 0; i < 3; ++i) {
    out.text += Format("%sOFFS_%c,%.9g\n", prefix.c_str(), kAxes[i], d.offset_ms2(i));
  }
  for (int i = 0; i < 3; ++i) {
    out.text += Format("%sSCAL_%c,%.9g\n", prefix.c_str(), kAxes[i], d.scale(i));
  }
  // Temperature: INS_TCAL<n>, v <- v - P(T - 35) + P(CALTEMP - 35) before the offsets
  // (AP_InertialSensor_tempcal.cpp: correct_accel, correct_gyro), P(u) = 1e-6 (c1 u + c2 u^2 +
  // c3 u^3), T held to TMIN..TMAX. The accelerometer's CALTEMP is T_ref, so that the offsets and
  // scales above are those at T_ref; the gyroscope's (INS_GYR<n>_CALTEMP) is the temperature
  // ArduPilot learnt its offsets at, at boot: only their change with temperature is written.
  const bool accel_terms = cal.thermal && cal.thermal->params.degrees.bias > 0;
  const std::optional<double> gyro_rad_s = GyroscopeTemperatureTerms(cal, options, instance, &out);
  if (!accel_terms && !gyro_rad_s) {  // nothing for INS_TCAL to hold
    // The loss is the diagonal model's against the full one, on the data calibrated.
    out.loss = MeasureLoss(cal, d.correction, d.dropped);
    return out;
  }
  if (stream != nullptr && stream->corrected) {
    const char* from = nullptr;
    const std::map<std::string, double>& in_force = InForce(*stream, options, &from);
    const auto enabled = in_force.find(Format("INS_TCAL%d_ENABLE", instance + 1));
    if (enabled != in_force.end() && enabled->second == 1) {
      throw DataError(Format(
          "this calibration is of records a temperature calibration in force (INS_TCAL%d_ENABLE "
          "1) had already corrected, and accelcal does not compose one with it: record with "
          "INS_TCAL%d_ENABLE 0 and calibrate that",
          instance + 1, instance + 1));
    }
  }
  const int n = instance + 1;
  // The accelerometer's offset polynomial, taken once.
  const std::optional<OffsetPolynomial> poly =
      accel_terms ? std::optional(OffsetsOverTemperature(cal)) : std::nullopt;
  const std::pair<double, double> range =
      poly ? std::pair(poly->t_min_c, poly->t_max_c) : cal.gyroscope->thermal->range_c;
  out.text += Format("INS_TCAL%d_ENABLE,1\nINS_TCAL%d_TMIN,%.9g\nINS_TCAL%d_TMAX,%.9g\n", n, n,
                     Float32(range.first), n, Float32(range.second));
  if (poly) {
    const std::array<Vec3, 3> c = About35(poly->b, poly->t_ref_c);
    for (int k = 0; k < 3; ++k) {
      for (int i = 0; i < 3; ++i) {
        out.text +=
            Format("INS_TCAL%d_ACC%d_%c,%.9g\n", n, k + 1, kAxes[i],
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
    const GyroThermalBias& t = cal.gyroscope->thermal->bias;
    std::array<Vec3, 4> b{Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
    for (int k = 1; k <= t.degree(); ++k) {
      b[static_cast<std::size_t>(k)] =
          *gyro_rad_s * t.coefficients[static_cast<std::size_t>(k - 1)];
    }
    const std::array<Vec3, 3> c = About35(b, t.t_ref_c);
    for (int k = 0; k < 3; ++k) {
      for (int i = 0; i < 3; ++i) {
        out.text += Format("INS_TCAL%d_GYR%d_%c,%.9g\n", n, k + 1, kAxes[i],
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

}  // namespace accelcal::exports
