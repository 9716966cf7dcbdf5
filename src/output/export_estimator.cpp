// The IMU model of the visual-inertial estimators' formats (Kalibr, OpenVINS, Basalt;
// export_estimator.hpp): the accelerometer's K in the x-first frame as their lower-triangular
// forward model in m/s2, the gyroscope in that frame and rad/s, and what their linear model loses.
#include <Eigen/LU>
#include <Eigen/QR>

#include "accelcal/error.hpp"
#include "output/export_estimator.hpp"

namespace accelcal::exports {

namespace {

// Kalibr's gyroscope in the scale-misalignment model (IccScaledMisalignedImu, reference IMU):
//     w_measured = M_g C_gyro_i w + A C_gyro_i a + b_g,
// M_g lower-triangular, C_gyro_i a rotation, A full [(rad/s)/(m/s²)], w and a in the IMU frame,
// which is the accelerometer's (the x-first frame of its M). With f_old = Q f_x (ChangeFrame) and s
// the rad/s of a raw unit, w_measured = s K_g Q w + s G Q a / u + s b_g (u the m/s² of the
// calibration's force unit): M_g C_gyro_i = s K_g Q (an LQ factorisation: from the QR of its
// transpose), A = (s/u) G Q C_gyro_iᵀ. Exact: nothing is dropped.
KalibrGyro KalibrGyroscope(const LoadedCalibration& cal, const Mat33& Q, double rad_s_per_raw) {
  const UnitGyroscope& g = *cal.gyroscope;
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

}  // namespace

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
                                          bool required) {
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

EstimatorImu ForEstimator(const LoadedCalibration& cal, const ExportOptions& options,
                          const char* file, const char* tool, const char* why, ExportResult* out) {
  const ImuNoise& noise = NeedNoise(options, file, true);
  const double raw_ms2 = RawToMetersPerSecond2(cal, options, tool, why);
  PlausibleAccelerometer(cal, options, raw_ms2, tool);
  const ForwardAccelerometer a = XFirstAccelerometer(cal, raw_ms2);
  std::optional<KalibrGyro> g = XFirstGyroscope(cal, options, a.change, tool, out, true);
  return {noise, a, std::move(g)};
}

}  // namespace accelcal::exports
