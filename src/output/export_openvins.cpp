// OpenVINS' kalibr_imu_chain.yaml (export_estimator.hpp): the accelerometer (Ta) and the
// gyroscope (Tw, its rotation and g-sensitivity Tg), and both sensors' noise. It drops the
// accelerometer's squared terms k2 and its drift and temperature terms, and the gyroscope's
// offsets over temperature; the constant biases are comments (OpenVINS estimates its own).
#include "output/export_estimator.hpp"

namespace accelcal::exports {

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

}  // namespace accelcal::exports
