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
#include "accelcal/gyro_model.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/model.hpp"
#include "accelcal/positions.hpp"
#include "accelcal/thermal.hpp"

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
  /// Parameters that follow temperature (thermal.hpp, the x-first frame): each position is judged
  /// at θ(T_k), its mean temperature held to `thermal_range_c`, and `covariance` is then that of
  /// the thermal flat vector (ThermalSlots order), whose Jacobian at T_k is the model's times
  /// ΔT_k^d per slot; `params` is θ(T_ref).
  std::optional<ThermalParameters> thermal;
  std::pair<double, double> thermal_range_c{kTemperatureRange_C[0], kTemperatureRange_C[1]};
};

struct VerifyOptions {
  /// The test fails at a p-value below this (1 in 1000 correct calibrations fails by chance).
  double significance = 0.001;
  /// |z| of one position beyond which it is named as off (a note; the test is the χ²).
  double position_z = 3;
  /// A parameter whose smallest error the log would notice is beyond this many of the
  /// calibration's own σ is untested by it (Verification::untested).
  double untested_sigmas = 10;
  // (CheckOptions: position_z and untested_sigmas positive, significance in (0, 1).)
};

/// How well the new recording tests one parameter of the calibration.
struct VerifiedParameter {
  std::string name;  ///< ParameterSlot::name
  /// The error of this parameter alone the test notices in 9 logs of 10 (the noncentral χ² it
  /// makes reaches the threshold χ²_{1−α}(N) 1.28 of its standard deviations below its mean);
  /// infinite when no position excites it.
  double detectable = 0;
  double sigma = 0;  ///< the calibration's own 1σ of it (0 without a covariance)
};

struct VerifiedPosition {
  Vec3 mean_raw = Vec3::Zero();
  std::size_t samples = 0;
  double t_begin_s = 0, t_end_s = 0;
  /// The temperature it was judged at [°C] (a calibration that follows temperature; NaN else).
  double temperature_c = std::nan("");
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
  /// In ParameterSlots(model, frame) order; ThermalSlots' for a calibration over temperature.
  std::vector<VerifiedParameter> parameters;
  /// The parameters the log cannot test (VerifyOptions::untested_sigmas): a pass says nothing of
  /// them (positions that excite them are missing).
  std::vector<std::string> untested;
};

/// The accelerometer's predicted RMS of |f| − g, as a fraction of g, beyond which its
/// verification fails whatever its χ²: a covariance or noise that loose verifies nothing.
inline constexpr double kMaxPredictedNormError = 0.05;
/// Bounds beyond which a gyroscope's verification fails whatever its χ² (VerifyGyroscope).
inline constexpr double kMaxPredictedTurnDeg = 2;
inline constexpr double kMaxTurnErrorDeg = 10;
inline constexpr double kMaxBiasChangeDegS = 10;

/// The gyroscope under test (gyro_model.hpp), as its file holds it.
struct VerifiedGyroscope {
  GyroModelKind model = GyroModelKind::kLinear;
  GyroParameters params;
  /// In GyroParameterSlots(model) order; empty: the parameters are taken as exact.
  Eigen::MatrixXd covariance;
  /// Its calibration's turns, and its still positions' mean rates, scattered by these times
  /// their rate noise (≥ 1 is used).
  double rotation_scatter_ratio = 1, still_scatter_ratio = 1;
};

/// (Each turn's predicted error also carries the accelerometer's parameters' uncertainty, through
/// the gravity directions of its two positions: over temperature the directions are each at its
/// own θ(T_k), whose uncertainty the turns' noise does not cover. On 300 simulated ramps the
/// turns' χ²/dof fell from 1.058 ± 0.011 to 1.036 ± 0.011 with it; at constant temperature,
/// 1.001.)
/// One turn of the new recording: the calibrated rates integrated from one still position to the
/// next must turn the first's gravity direction into the second's.
struct VerifiedTurn {
  std::size_t from = 0, to = 0;  ///< positions, 0-based
  double duration_s = 0;
  double error_deg = 0;      ///< angle between the predicted and the measured direction of `to`
  double predicted_deg = 0;  ///< its predicted RMS (rate noise × scatter ratio, parameters)
  double z = 0;              ///< √(rᵀ C⁻¹ r) of its two components (about 1.2 when it holds)
};

/// The gyroscope's verification. Its bias is the session's: a MEMS gyro's turn-on bias changes
/// from one power-up to the next and every estimator estimates it, so the new recording's still
/// positions give it (their mean rates less G f, weighted by their noise); the pattern of those
/// rates over the orientations tests G, and the turns test K_g and G.
struct GyroVerification {
  Vec3 session_bias_raw = Vec3::Zero();
  Vec3 bias_change_raw = Vec3::Zero();  ///< session's − the calibration's
  std::vector<VerifiedTurn> turns;
  /// The still positions' mean rates about b + G f with the session's b (the weighted mean):
  /// they test G. Their χ² has 3 (positions − 1) degrees of freedom.
  double stills_chi2 = 0;
  int stills_dof = 0;
  double turns_chi2 = 0;
  int turns_dof = 0;  ///< 2 per turn
  /// Both together: the test.
  double chi2 = 0;
  int dof = 0;
  double p_value = 1;
  double rms_error_deg = 0, rms_predicted_deg = 0;
  bool passed = false;
  std::string reason;                  ///< why it failed; "" when it passed
  std::vector<std::size_t> off_turns;  ///< beyond VerifyOptions::position_z (0-based)
  /// How well the turns test each of K_g and G (GyroParameterSlots order, the bias left out: it
  /// is the session's), and those they cannot test (VerifyOptions::untested_sigmas).
  std::vector<VerifiedParameter> parameters;
  std::vector<std::string> untested;
};

/// The turns between `positions` of `accel_log` (its still intervals), integrated from
/// `gyro_log` (the same clock), against the rotations of the gravity directions the accelerometer
/// calibration measures. Each turn's residual (2 components, whitened by its rate noise: the
/// gyro fit's) has the covariance s² I (s the calibration's rotation scatter ratio, at least 1)
/// plus its parameters' J Σ Jᵀ (the bias's part the session bias' noise), correlated across
/// turns through Σ; χ² over all has 2 × turns degrees of freedom. The directions' own noise
/// (0.002° on the Xsens recording) is left out. It also fails, whatever χ², when the
/// calibration predicts turn errors beyond kMaxPredictedTurnDeg RMS (a covariance or scatter
/// ratio that loose verifies nothing: another sensor's calibration had passed at 88°), when a
/// turn is off by more than kMaxTurnErrorDeg, or when the session's bias is kMaxBiasChangeDegS
/// or more from the calibration's (no MEMS gyro's turn-on bias moves that far: another sensor, or
/// another unit). Throws DataError for a log the turns cannot be integrated from (as the
/// calibration), std::invalid_argument for bad options.
GyroVerification VerifyGyroscope(const VerifiedCalibration& accel, const VerifiedGyroscope& gyro,
                                 const RawLog& accel_log, const RawLog& gyro_log,
                                 const std::vector<Position>& positions,
                                 const VerifyOptions& options = {});

/// `log` and `positions` (its still intervals, PositionsFromIntervals) are the new recording.
/// Throws std::invalid_argument for options out of range, an empty position list, a position
/// without its interval, or a covariance that is not P × P.
Verification VerifyCalibration(const VerifiedCalibration& calibration, const RawLog& log,
                               const std::vector<Position>& positions,
                               const VerifyOptions& options = {});

}  // namespace accelcal
