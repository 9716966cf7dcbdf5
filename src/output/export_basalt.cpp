// Basalt's calib.json (export_estimator.hpp): the accelerometer (calib_accel_bias) and the
// gyroscope (calib_gyro_bias, with its rotation to the accelerometer's frame), and both sensors'
// noise. It drops the accelerometer's squared terms k2 and its drift and temperature terms, and
// the gyroscope's g-sensitivity G and offsets over temperature.
#include <Eigen/LU>

#include "output/export_estimator.hpp"

namespace accelcal::exports {

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

}  // namespace accelcal::exports
