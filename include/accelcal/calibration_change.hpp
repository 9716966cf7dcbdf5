#pragma once
/// @file calibration_change.hpp
/// Whether a unit's new calibration agrees with an earlier one within their uncertainties: the
/// difference of the parameters against the sum of the two covariances (the sessions are
/// independent), one χ² per sensor.

#include <optional>
#include <string>
#include <vector>

#include "accelcal/calibration_file.hpp"

namespace accelcal {

/// One sensor's change between two calibrations.
struct ParameterChange {
  double chi2 = 0;  ///< Δθᵀ (C_old + C_new)⁻¹ Δθ
  int dof = 0;      ///< the parameters compared
  /// P(χ²_dof ≥ chi2); with noise_dof, P(F(dof, noise_dof) ≥ chi2 / dof).
  double p = 1;
  /// The degrees of freedom of the noise levels the covariances were scaled by, when estimated
  /// from the fits (LoadedCalibration::covariance_dof, summed): then the test is an F test.
  std::optional<double> noise_dof;
  /// Every parameter's Δ / √(C_old,ii + C_new,ii), in the file's parameter order, with its name.
  std::vector<std::pair<std::string, double>> z;
};

struct CalibrationChange {
  /// Every parameter of the accelerometer; then its scale-and-misalignment part (K, k2) and its
  /// bias apart, to say which moved.
  ParameterChange accelerometer, accelerometer_scale, accelerometer_bias;
  /// When both calibrations have a gyroscope of the same model, each with its covariance.
  std::optional<ParameterChange> gyroscope;
  /// What was not compared, and why: the gyroscopes (one has none, their models differ, no
  /// covariance), the temperature coefficients of calibrations over temperature.
  std::vector<std::string> notes;
  /// p ≥ kChangeP for every sensor compared.
  bool compatible = true;
};

/// The p below which two calibrations of one unit are said to differ (as verify fails at).
inline constexpr double kChangeP = 1e-3;

struct ChangeOptions {
  /// The accelerometer's turn-on bias repeatability [specific-force unit, 1σ per axis]: how far a
  /// MEMS part's bias moves between power-ups (its datasheet's), which no calibration's covariance
  /// holds. Each session's bias has it, so 2 q² is added to each bias difference's variance.
  /// None: the biases are compared as the covariances say.
  std::optional<Vec3> bias_repeatability;
};

/// Compares `later` with `earlier` (two calibrations of one unit, from independent sessions).
/// Throws DataError when they cannot be compared: another model, frame or unit, no covariance,
/// or parameters over temperature with reference temperatures more than 0.5 K apart (or only one
/// of them over temperature). A drifting bias is compared at its reference time.
CalibrationChange CompareCalibrations(const LoadedCalibration& earlier,
                                      const LoadedCalibration& later,
                                      const ChangeOptions& options = {});

}  // namespace accelcal
