// What the exports to other tools' formats share (export_common.hpp): the numbers they write, the
// comment lines, the loss of a model a format cannot hold in full, the autopilots' diagonal model
// and the log's streams the sensors were calibrated from.
#include "output/export_common.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/LU>
#include <Eigen/SVD>

#include "accelcal/error.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/native_log.hpp"

namespace accelcal::exports {

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

// Shortest text that reads back as the same double (nlohmann's own conversion: no locale).
std::string Number(double value) { return ordered_json(Finite(value)).dump(); }

std::string Join(const std::string& a, const std::string& b) {
  if (a.empty()) return b;
  if (b.empty()) return a;
  return a + "; " + b;
}

// The first comment line (without its comment marker and line end): the log's path as one visible
// line.
std::string Header(const LoadedCalibration& cal) {
  std::string text = " accelcal calibration";
  if (!cal.source.empty()) text += " of " + internal::VisibleLine(cal.source);
  return text + " (" + std::string(ToString(cal.model)) + " model)";
}

// The raw-unit label as one visible line: the conventions go into comment lines of the files.
std::string DescribeUnits(const LoadedCalibration& cal) {
  return "raw readings in '" + internal::VisibleLine(cal.raw_unit) + "', specific force in " +
         std::string(ToString(cal.unit));
}

std::string SquaredTermsDropped(const LoadedCalibration& cal) {
  return cal.model == ModelKind::kQuadratic ? "the squared terms k2" : "";
}

// The g-sensitivity an export without it drops: the largest rate error it leaves, |K_g⁻¹ G f| at
// |f| = g over the directions (the largest singular value of K_g⁻¹ G times g), in °/h.
std::string GSensitivityDropped(const LoadedCalibration& cal) {
  const UnitGyroscope& g = *cal.gyroscope;
  if (g.model != GyroModelKind::kGSensitive || g.params.G.isZero(0)) return "";
  const Mat33 M = g.params.K.inverse() * g.params.G;
  const double largest = Eigen::JacobiSVD<Mat33>(M).singularValues()(0);
  return internal::Format("the g-sensitivity G (a rate error of up to %.3g deg/h at 1 g)",
                          largest * cal.gravity * 180.0 / 3.14159265358979323846 * 3600.0);
}

// With a drifting bias the full model takes each position's drift offset from its reading; every
// format but accelcal's own file (`holds_all`) holds one bias, its value at the drift's
// reference time (the session's mean time). With parameters that follow temperature the full
// model is θ(T_k) at each position's temperature; a format holds them at T_ref, with, where it
// compensates temperature (`thermal_offset`), an offset polynomial taken from the reading first.
ExportLoss MeasureLoss(const LoadedCalibration& cal, const Correction& exported,
                       std::string dropped, bool holds_all, const ThermalOffset& thermal_offset) {
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

namespace {

// Whether a stream can hold `sensor`'s readings: a type accelcal knows for it, or one it does
// not know at all (fields the user named). A provenance edited by hand (a gyroscope's record
// removed, leaving the accelerometer's of the same file) is not taken for another sensor's.
bool CanHold(const SourceStream& stream, std::string_view sensor) {
  std::vector<std::string_view> sensors = KnownSensors(stream.type);
  if (sensors.empty()) sensors = KnownSensors(stream.topic);  // PX4's and ArduPilot's: the topic
  return sensors.empty() || std::find(sensors.begin(), sensors.end(), sensor) != sensors.end();
}

}  // namespace

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

}  // namespace accelcal::exports
