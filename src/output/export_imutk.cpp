// imu_tk's CalibratedTriad (export_common.hpp): one sensor a file, the accelerometer or the
// gyroscope (ExportOptions::sensor), its linear model in accelcal's body frame. It drops the
// accelerometer's squared terms k2 and its drift and temperature terms, and the gyroscope's
// g-sensitivity G and offsets over temperature.
#include <Eigen/LU>

#include "accelcal/error.hpp"
#include "output/export_common.hpp"

namespace accelcal::exports {

namespace {

// imu_tk's CalibratedTriad of a sensor read as raw = K x + b: x = T S (raw − B), T unit-diagonal,
// S diagonal, T S = K⁻¹, B = b; `text` as its load() reads it (T, S, then B).
struct Triad {
  Mat33 T;
  Vec3 s;
  std::string text;
};
Triad CalibratedTriad(const Mat33& K, const Vec3& bias) {
  const Mat33 M = K.inverse();
  Triad out;
  out.s = M.diagonal();
  out.T = M.array().rowwise() / out.s.transpose().array();  // x / x = 1 exactly
  const auto matrix = [](const Mat33& A) {
    std::string text;
    for (int i = 0; i < 3; ++i) {
      text += Number(A(i, 0)) + " " + Number(A(i, 1)) + " " + Number(A(i, 2)) + "\n";
    }
    return text;
  };
  out.text = matrix(out.T) + "\n" + matrix(Mat33(out.s.asDiagonal())) + "\n" + Number(bias(0)) +
             "\n" + Number(bias(1)) + "\n" + Number(bias(2)) + "\n\n";
  return out;
}

}  // namespace

// imu_tk: f = T S (p − B), T unit-diagonal, S diagonal: T S = K⁻¹ (any frame, linear part).
ExportResult ImuTk(const LoadedCalibration& cal) {
  const Triad triad = CalibratedTriad(cal.params.K, cal.params.bias);
  ExportResult out;
  out.text = triad.text;
  out.convention =
      "imu_tk CalibratedTriad (load() reads misalignment T, scale S, bias B): f = T S (p - B), T "
      "with unit diagonal, S diagonal; T S = K^-1, B = b (" +
      DescribeUnits(cal) + ", accelcal's " + std::string(ToString(cal.frame)) + " body frame)";
  const Mat33 TS = triad.T * triad.s.asDiagonal();
  out.loss = MeasureLoss(
      cal, [&](const Vec3& p) -> std::optional<Vec3> { return Vec3(TS * (p - cal.params.bias)); },
      SquaredTermsDropped(cal));
  return out;
}

// imu_tk's gyroscope triad: w = T S (raw − B), T unit-diagonal, S diagonal: T S = K_g⁻¹, B = b.
ExportResult ImuTkGyroscope(const LoadedCalibration& cal) {
  if (!cal.gyroscope) {
    throw DataError("imutk gyroscope: the calibration file holds no gyroscope calibration");
  }
  const UnitGyroscope& g = *cal.gyroscope;
  ExportResult out;
  out.text = CalibratedTriad(g.params.K, g.params.bias).text;
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

}  // namespace accelcal::exports
