#pragma once
/// @file model_selection.hpp
/// Which model do the data support? The quadratic model always lowers the in-sample residual (it
/// has three more parameters), so the choice is made on held-out error: both models are fitted
/// with leave-one-position-out validation (CalibrationOptions::cross_validate), and the quadratic
/// model is chosen only when it predicts the held-out positions better (lower crossval_rms). When
/// the quadratic model cannot be fitted or validated (too few positions, unobservable, not
/// converged), the linear model is kept and the reason says why.

#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "accelcal/calibrate.hpp"

namespace accelcal {

struct ModelSelection {
  ModelKind chosen = ModelKind::kLinear;
  std::string reason;  ///< why `chosen`, with the numbers that decided
  CalibrationResult linear;
  /// Absent when the quadratic model cannot be fitted; quadratic_error says why.
  std::optional<CalibrationResult> quadratic;
  std::string quadratic_error;
  /// k2_i / σ(k2_i) of the quadratic fit (t-statistics; NaN without a covariance): |t| of 2 or
  /// less means the squared coefficient is not distinguishable from zero.
  Vec3 k2_t = Vec3::Constant(std::nan(""));

  const CalibrationResult& chosen_result() const {
    return chosen == ModelKind::kQuadratic ? *quadratic : linear;
  }
};

/// Fits both models with `options` (its model and cross_validate are overridden) and chooses.
/// Throws as Calibrate() does when the linear model cannot be fitted.
ModelSelection SelectModel(const std::vector<Vec3>& readings, CalibrationOptions options);

}  // namespace accelcal
