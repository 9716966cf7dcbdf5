// Kalibr's files (export_estimator.hpp): the IMU configuration of kalibr_calibrate_imu_camera's
// scale-misalignment model, with the accelerometer and the gyroscope (scale, misalignment,
// rotation to the accelerometer and g-sensitivity, exact), and its input imu.yaml, the noise
// alone. It drops the accelerometer's squared terms k2 and its drift and temperature terms, and
// the gyroscope's offsets over temperature; the constant biases are comments (Kalibr estimates
// its own).
#include "output/export_estimator.hpp"

namespace accelcal::exports {

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

}  // namespace accelcal::exports
