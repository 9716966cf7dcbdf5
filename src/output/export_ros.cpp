// sensor_msgs/Imu's covariances (export_common.hpp): the noise of the accelerometer and the
// gyroscope as each field's covariance and REP 145's standard deviations. It holds no
// calibration: the model is dropped whole.
#include <cmath>

#include "output/export_common.hpp"

namespace accelcal::exports {

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

}  // namespace accelcal::exports
