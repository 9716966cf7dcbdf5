// PX4's parameter file (QGroundControl's .params) (export_common.hpp): the accelerometer as
// CAL_ACC<n> offsets and scales, and the gyroscope, where its rates are PX4's driver output, as
// CAL_GYRO<n> offsets, each with its offsets' temperature terms (TC_A<n>, TC_G<n>). PX4 holds
// diagonal models: it drops the accelerometer's misalignments and squared terms k2, the scale and
// misalignment temperature terms and the bias drift, and the gyroscope's scale and misalignment
// K_g and g-sensitivity G.
#include <array>
#include <cstdint>

#include <Eigen/SVD>

#include "accelcal/error.hpp"
#include "accelcal/native_log.hpp"
#include "output/export_common.hpp"

namespace accelcal::exports {

namespace {

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
  const UnitGyroscope& g = *cal.gyroscope;
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
  if (g.thermal && g.thermal->bias.degree() > 0) {
    // TC_G<n>: the offsets' polynomial in T - TREF taken from the rate before CAL_GYRO's offset
    // (TemperatureCompensation.cpp, sensor_calibration/Gyroscope.hpp), as TC_A: X0 = 0 and TREF
    // = T_ref, so that CAL_GYRO holds the offset at T_ref; T held to TMIN..TMAX.
    std::array<Vec3, 3> per_K{Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
    for (int k = 1; k <= g.thermal->bias.degree(); ++k) {
      per_K[static_cast<std::size_t>(k - 1)] =
          *rad_s * g.thermal->bias.coefficients[static_cast<std::size_t>(k - 1)];
    }
    const Px4TemperatureTerms tc =
        Px4Temperature('G', instance, id, g.thermal->bias.t_ref_c, g.thermal->range_c, per_K,
                       "rad/s", "the rate before CAL_GYRO%d's offset", "CAL_GYRO");
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

}  // namespace

ExportResult Px4(const LoadedCalibration& cal, const ExportOptions& options) {
  const SourceStream* stream = AccelerometerStream(cal);
  if (stream != nullptr && stream->corrected) {
    // sensor_combined: the output of the calibration in force, whose slot is not in the log.
    throw DataError("this calibration is of " + internal::VisibleLine(stream->topic) +
                    ", which the calibration in force had already corrected; PX4's CAL_ACC "
                    "parameters correct the driver's output: calibrate sensor_accel (logged at "
                    "the sensor's rate) and export that");
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

}  // namespace accelcal::exports
