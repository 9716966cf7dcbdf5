#pragma once
/// @file verify.hpp
/// A calibration checked on a new recording of the same unit (issue 19, `accelcal verify`): each
/// still position's |f| − g against the error the calibration itself predicts, and one test of
/// them all.
///
/// The prediction for position k, e_k = |f(p_k)| − g with p_k its mean reading, has three parts:
///   - the parameters' uncertainty: ∂e_k/∂θ Σ_θ ∂e_k/∂θᵀ, shared by every position (so the
///     positions' errors are correlated through it): ∂e/∂θ = −u ᵀ J⁻¹ ∂μ/∂θ, with u = f/|f|, J =
///     ∂μ/∂f = K + 2 diag(k2 ∘ f) and ∂μ/∂θ the model's Jacobian (model.hpp) in the slots of the
///     calibration's frame;
///   - the new position's own noise: the covariance of its mean reading, from the means of 16
///     batches of its samples (correlated samples, as a sensor that filters its output gives,
///     make the mean noisier than σ/√n), through g_k = u ᵀ J⁻¹;
///   - what the calibration's own positions scattered by beyond their noise (model error, drift):
///     σ_m² = max(0, σ̂² − the mean noise of its position means), σ̂ its residual level, isotropic
///     in raw units, through g_k.
/// With C their sum over all positions (N × N), χ² = eᵀ C⁻¹ e has N degrees of freedom when the
/// calibration holds; the test fails at p < `significance`.

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "accelcal/frame.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/model.hpp"
#include "accelcal/positions.hpp"

namespace accelcal {

/// The calibration under test, as its file holds it.
struct VerifiedCalibration {
  ModelKind model = ModelKind::kLinear;
  Frame frame = Frame::kXFirst;
  ModelParameters params;
  /// In ParameterSlots(model, frame) order; empty: the parameters are taken as exact.
  Eigen::MatrixXd covariance;
  double gravity = 0;  ///< the magnitude its specific force should have here [its unit]
  /// The scatter of its own position means beyond their noise [raw, 1σ per axis] (see the file
  /// comment); 0 when none.
  double misfit_sigma_raw = 0;
};

struct VerifyOptions {
  /// The test fails at a p-value below this (1 in 1000 correct calibrations fails by chance).
  double significance = 0.001;
  /// |z| of one position beyond which it is named as off (a note; the test is the χ²).
  double position_z = 3;
};

struct VerifiedPosition {
  Vec3 mean_raw = Vec3::Zero();
  std::size_t samples = 0;
  double t_begin_s = 0, t_end_s = 0;
  /// |f| − g [the calibration's unit]; NaN where the model cannot invert the reading.
  double error = 0;
  /// The predicted 1σ of `error` and its parts: the parameters', the mean's noise, the misfit.
  double sigma = 0, sigma_parameters = 0, sigma_noise = 0, sigma_misfit = 0;
  double z = 0;  ///< error / sigma
};

struct Verification {
  std::vector<VerifiedPosition> positions;
  double chi2 = 0;
  int dof = 0;
  double p_value = 1;
  double rms_error = 0;      ///< RMS of the errors
  double rms_predicted = 0;  ///< RMS of the predicted σ
  bool passed = false;
  /// Why it failed ("" when it passed): the statistic and the positions furthest off.
  std::string reason;
  /// Positions (0-based) beyond VerifyOptions::position_z.
  std::vector<std::size_t> off_positions;
};

/// `log` and `positions` (its still intervals, PositionsFromIntervals) are the new recording.
/// Throws std::invalid_argument for options out of range, an empty position list, a position
/// without its interval, or a covariance that is not P × P.
Verification VerifyCalibration(const VerifiedCalibration& calibration, const RawLog& log,
                               const std::vector<Position>& positions,
                               const VerifyOptions& options = {});

}  // namespace accelcal
