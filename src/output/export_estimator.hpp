#pragma once
// Internal to the exports: the IMU model of the visual-inertial estimators' formats (Kalibr,
// OpenVINS, Basalt), in the accelerometer's x-first frame, m/s2 and rad/s (export_estimator.cpp).
#include <optional>
#include <string>

#include "accelcal/frame.hpp"
#include "output/export_common.hpp"

namespace accelcal::exports {

// The accelerometer as the forward-model estimators take it (Kalibr, OpenVINS): a_measured = M a
// + b in m/s², M lower-triangular = accelcal's K in the x-first frame, scaled to m/s² readings
// and forces. Basalt takes its inverse.
struct ForwardAccelerometer {
  FrameChange change;  ///< to the x-first frame: f_old = Q_old_new f_x
  Mat33 M;
  Vec3 bias_ms2;
};
ForwardAccelerometer XFirstAccelerometer(const LoadedCalibration& cal, double raw_ms2);

// Kalibr's gyroscope in the scale-misalignment model (export_estimator.cpp's KalibrGyroscope):
// M_g lower-triangular and C_gyro_i a rotation with M_g C_gyro_i = s K_g Q, A the g-sensitivity
// [(rad/s)/(m/s2)], the bias in rad/s.
struct KalibrGyro {
  Mat33 M, C, A;
  Vec3 bias_rad_s;
};

ExportLoss XFirstLoss(const LoadedCalibration& cal, const FrameChange& change);
std::string XFirstFrom(const LoadedCalibration& cal);
std::string YamlRows(const Mat33& A);
std::optional<KalibrGyro> XFirstGyroscope(const LoadedCalibration& cal,
                                          const ExportOptions& options, const FrameChange& change,
                                          std::string_view format, ExportResult* out,
                                          bool required = false);

// What an estimator's file (OpenVINS', Basalt's) is made of: the noise of both sensors, the
// accelerometer in the x-first frame and m/s², and the gyroscope there in rad/s when the file has
// one (required: its unit must be known).
struct EstimatorImu {
  const ImuNoise& noise;
  ForwardAccelerometer accelerometer;
  std::optional<KalibrGyro> gyroscope;
};
EstimatorImu ForEstimator(const LoadedCalibration& cal, const ExportOptions& options,
                          const char* file, const char* tool, const char* why, ExportResult* out);

}  // namespace accelcal::exports
