#pragma once
/// @file gyro_calibration.hpp
/// The gyroscope calibrated from the recording that calibrates the accelerometer (issue 18):
/// still positions with turns between them. Each still position's mean rate observes the bias
/// (and the g-sensitivity, gyro_model.hpp); each turn observes the rotation that takes the
/// gravity direction of one position into the next, by integrating the calibrated rate sample by
/// sample (Tedaldi, Pretto, Menegatti, ICRA 2014, for the idea).
///
/// The accelerometer's still intervals are not the gyro's: the accelerometer cannot see a turn
/// about the vertical, hardly sees the slow ends of a turn, and a gyro stream that lags or leads
/// it turns inside them. So each position's still rate is averaged where the gyro itself is still
/// (the longest run of the interval whose 0.1 s means stay within the rate noise, found by the
/// peak of the motions beyond it), and each turn is integrated from one such span to the next:
/// what the gyro turned inside the accelerometer's interval is integrated with the turns
/// (GyroStillSpan::turned_outside_deg, the diagnosis' gyro_turned_in_still).
///
/// Two estimators, on the same data:
///   - two-stage: the accelerometer's calibration and gravity directions held, the gyroscope's
///     parameters fitted to the stills and the turns;
///   - joint: one maximum-likelihood problem over the accelerometer's parameters, the
///     gyroscope's and every still position's gravity direction, so that the turns also inform
///     the accelerometer (six axis-aligned positions leave its misalignment poorly determined;
///     the rotations determine it).
///
/// Each group of residuals (the accelerometer's position means, the gyro's still means, the
/// turns) is weighted by its own noise, multiplied by the group's scatter ratio R when R > 1, so
/// that one sensor's unmodelled error cannot pull the other: the gyro's groups under the sample
/// noise propagated to them, R = √(χ²/n); the accelerometer's under the residual σ̂ of its own
/// fit, R = √(χ²/(m − P)). The ratios are taken at the two-stage fit, then again at the joint
/// fit, which is refitted until they settle (variance components, as in geodesy's adjustment of
/// heterogeneous observations).

#include <cmath>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "accelcal/calibration_types.hpp"
#include "accelcal/gyro_model.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/names.hpp"
#include "accelcal/positions.hpp"
#include "accelcal/rotations.hpp"
#include "accelcal/thermal.hpp"

namespace accelcal {

/// The unit of the gyroscope's raw readings, for the start of the fit (never a magic seed).
enum class GyroUnit {
  kRadPerSecond,  ///< K_g starts at I
  kDegPerSecond,  ///< K_g starts at (180/π) I
  kRaw,           ///< counts: K_g's scale starts from the turned angles, in closed form
};
template <>
struct EnumNames<GyroUnit> {
  static constexpr std::pair<GyroUnit, std::string_view> kTable[] = {
      {GyroUnit::kRadPerSecond, "rad/s"},
      {GyroUnit::kDegPerSecond, "deg/s"},
      {GyroUnit::kRaw, "raw"}};
};
std::string_view ToString(GyroUnit unit);
/// The declared unit's scale, raw per rad/s (1 for rad/s, 180/π for deg/s); none for raw counts.
std::optional<double> RawPerRadPerSecond(GyroUnit unit);

/// How far a gyro's scale (a row norm of K_g) may lie from its declared unit's (1 for rad/s,
/// 180/π for deg/s) and still start the fit, and pass the diagnosis (gyro_unit_scale): MEMS
/// gyros are specified to ±3 % or better; the bundled rad/s and deg/s gyros fit within 2.7 %.
inline constexpr double kGyroUnitScaleTolerance = 0.10;

/// Which estimator (see the file comment). kImuTk is imu_tk's method (Tedaldi et al. 2014), the
/// baseline `compare` sets beside the others: the bias held at the first still position's mean
/// rate (imu_tk's initial rest; its σ that mean's), K_g fitted to the turns (its σ given the
/// bias), the accelerometer's directions held; no g-sensitivity (the linear model only). Unlike
/// imu_tk the turns are weighted by their propagated noise, and integrated with the trapezoidal
/// rule as the others.
enum class GyroEstimator { kTwoStage, kJoint, kImuTk };
template <>
struct EnumNames<GyroEstimator> {
  static constexpr std::pair<GyroEstimator, std::string_view> kTable[] = {
      {GyroEstimator::kTwoStage, "two-stage"},
      {GyroEstimator::kJoint, "joint"},
      {GyroEstimator::kImuTk, "imutk"}};
};
std::string_view ToString(GyroEstimator estimator);

/// The gyroscope's offsets over temperature (GyroThermalBias), fitted with its calibration.
struct GyroThermalOptions {
  /// The degree D of b_g(T) (0 … kMaxThermalDegree; 0: constant); std::nullopt chooses it from 0 up
  /// by the still positions' held-out mean rates, as SelectThermalDegrees chooses the
  /// accelerometer's.
  std::optional<int> degree;
  /// T_ref [°C]: the accelerometer's, so that one file has one; when it lies outside the still
  /// positions' temperatures (the gyroscope's die warmer), their mean instead, and said.
  double t_ref_c = 0;
};

struct GyroCalibrationOptions {
  /// The model; std::nullopt chooses by the leave-one-rotation-out error (g-sensitive when it
  /// lowers it, as the accelerometer's automatic model choice).
  std::optional<GyroModelKind> model;
  GyroUnit unit = GyroUnit::kRaw;
  GyroEstimator estimator = GyroEstimator::kJoint;
  RateInterpolation rule = RateInterpolation::kTrapezoidal;
  /// Leave-one-rotation-out validation (needed by the automatic model choice).
  bool validate = true;
  /// The fit without each rotation solved in full (as many fits as rotations), instead of one
  /// Gauss-Newton step from the full fit (the default; within a few percent of the full refit on
  /// the bundled recordings, measured by a test).
  bool heldout_refits = false;
  /// The site's geodetic latitude [deg]: the Earth rate's vertical part, Ω_E sin φ about each
  /// still position's up direction, is taken out of its mean rate (else the g-sensitive model's G
  /// takes it as a rate in proportion to f). Its horizontal part, Ω_E cos φ in a heading the
  /// recording does not know, stays in: a floor to the bias's accuracy
  /// (GyroCalibration::earth_rate_horizontal_rad_s).
  std::optional<double> latitude_deg;
  /// Threads the turns are integrated on (0: one per hardware thread); the result is the same
  /// bits for any count.
  int threads = 0;
  /// The offsets over temperature: each still position's mean rate at its mean temperature
  /// (the gyro log's temperature at each sample, else the accelerometer's) determines the b_d, by
  /// weighted least squares beside a constant b_g and, unless the model is linear, G; every rate
  /// sample then has b_d taken out at its temperature, and the gyroscope is calibrated from those
  /// rates as without (two-stage or imu_tk: the joint estimator refits the accelerometer's
  /// parameters as constants, which a calibration over temperature is not).
  std::optional<GyroThermalOptions> thermal;

  /// Why these options cannot calibrate, or nothing: the rules between them, stated once (the
  /// request of calibrate_unit.hpp and CalibrateGyro take them from here). Fields are named as
  /// a unit's request names its options, marked {{name}} (OptionError): `model` {{gyro_model}},
  /// `estimator` {{gyro_estimator}}, `validate` {{no_crossval}} (its opposite),
  /// `thermal->degree` {{gyro_thermal}}, `latitude_deg` {{latitude}}.
  std::optional<std::string> Validate() const;
};

/// One turn between consecutive still positions.
struct GyroRotation {
  std::size_t from = 0, to = 0;                   ///< positions (0-based, in time order)
  std::size_t first_sample = 0, last_sample = 0;  ///< the samples integrated, inclusive
  double duration_s = 0;
  double angle_deg = 0;  ///< the angle of the rotation, |Log R|, from the calibrated rates
  /// The angle turned through, |∫ ω dt| of the calibrated rates (IntegrateTurnedAngle): a turn
  /// about a fixed axis unwrapped (a full turn reads 360, where angle_deg reads about 0), and its
  /// 1σ from the parameters' covariance and the rate noise: the check against a turn of known
  /// angle (a turntable's, or a full turn against a stop).
  double turned_deg = 0, turned_std_deg = 0;
  double residual_deg = 0;  ///< angle between the predicted and the fitted direction of `to`
  /// The same with the fit that left this rotation out (validation); NaN without one.
  double heldout_deg = std::nan("");
  /// The screening of the turns (with validation): ‖r‖² of the turn's whitened residual under the
  /// fit without it (about χ² with 2 degrees of freedom), the level it must not pass (the 1 %
  /// level over all turns, Bonferroni: 2 ln(100 K) for K turns), and whether it did: a turn that
  /// disagrees with the others (a bump during it), kept in the fit and reported.
  double statistic = std::nan(""), threshold = std::nan("");
  bool flagged = false;
};

/// Where the gyroscope was still in one still position of the accelerometer: the samples its
/// still rate is averaged over, and the turns integrated from and to.
struct GyroStillSpan {
  std::size_t first_sample = 0, last_sample = 0;  ///< inclusive
  Vec3 mean_raw = Vec3::Zero();                   ///< the mean raw rate over them
  /// The angle the calibrated gyro turned through inside the accelerometer's still interval but
  /// outside this span [deg]: the slow ends of the turns the accelerometer hardly sees (small),
  /// a turn about the vertical it cannot see, or the gyro's stream lagging or leading the
  /// accelerometer's.
  double turned_outside_deg = 0;
  /// false: the gyro turned throughout this position (about the vertical, which the
  /// accelerometer cannot see) or its still part's rate is not the zero-rate offset: it gives no
  /// still rate, the turns on either side of it are integrated as one through it, and the span
  /// is the whole interval (mean_raw its mean rate, turned_outside_deg the angle turned in it).
  bool still = true;
};

/// The lag of the gyro's readings behind the accelerometer's [s] (> 0: the gyro late), from the
/// turns: the shift that best aligns the accelerometer's tilt rate with the calibrated gyro's
/// rate perpendicular to gravity (their cross-correlation's peak), ±1σ by the jackknife over the
/// turns. The still spans make the calibration hold with a lag (the file comment); an estimator
/// that fuses the two streams needs it.
struct GyroTimeOffset {
  double lag_s = 0, std_s = 0;
  double step_s = 0;  ///< the sample step the lag was searched in
  std::size_t turns = 0;
  /// The peak on the edge of the search (±0.5 s): the lag is at least that, or the streams do
  /// not correlate.
  bool at_limit = false;
};

/// The gyroscope's offsets over temperature as fitted (GyroCalibrationOptions::thermal).
struct GyroThermal {
  GyroThermalBias bias;                ///< degree 0 (no coefficients) when chosen so
  std::vector<double> temperatures_c;  ///< each still position's mean temperature [°C]
  std::pair<double, double> range_c;   ///< the still positions' lowest and highest [°C]
  /// Whose temperature the rates were taken at: "the gyroscope's log: " or "the accelerometer's
  /// log: " and the log's RawLog::temperature_source (GyroTemperatureSource).
  std::string temperature_source;
  /// Why this degree ("given", or each step's held-out and Wald evidence).
  std::string reason;
  /// The still means' scatter about the polynomial over their sample noise, √(χ²/(3(n − p)))
  /// (the covariance is multiplied by it when above 1).
  double scatter_ratio = 1;
  /// Each still position's whitened held-out mean rate under the chosen degree, ‖e‖ over its
  /// three axes (leave one position out, exact for least squares); RMS [gyro raw] at the end.
  double heldout_rms_raw = std::nan("");
};

/// The gyroscope's calibration.
struct GyroCalibration {
  GyroModelKind model = GyroModelKind::kLinear;
  std::string model_reason;  ///< why this model ("given", or the held-out errors compared)
  GyroEstimator estimator = GyroEstimator::kJoint;
  GyroUnit unit = GyroUnit::kRaw;
  GyroParameters params;
  /// Covariance of the flat parameters (GyroParameterSlots order), each group's scatter ratio
  /// applied (see the file comment); empty without degrees of freedom.
  Eigen::MatrixXd covariance;
  Vec3 noise_sigma_raw = Vec3::Zero();  ///< white noise of one rate sample, pooled over the stills
  std::vector<GyroStillSpan> still_spans;     ///< per position (FindGyroStillRuns)
  std::optional<GyroTimeOffset> time_offset;  ///< none with fewer than 3 turns
  std::vector<GyroRotation> rotations;
  double rms_deg = 0;  ///< RMS of the rotations' residual_deg
  /// RMS of the rotations' heldout_deg; NaN without validation.
  double heldout_rms_deg = std::nan("");
  /// Scatter ratios R = sqrt(χ²/n) of the stills and of the rotations under the sample noise.
  double still_scatter_ratio = 1, rotation_scatter_ratio = 1;
  /// The joint estimator's: the accelerometer's readings' scatter ratio under the σ̂ of its own
  /// fit, √(χ²/(m − P)) (1 at that fit; the turns may pull it above); 1 for the two-stage one.
  double accel_scatter_ratio = 1;
  Summary summary;
  /// With a latitude: the Earth rate's parts modelled (vertical, Ω_E sin φ) and not (horizontal,
  /// Ω_E cos φ: the floor of the bias's accuracy, whatever the noise) [rad/s].
  std::optional<double> latitude_deg;
  double earth_rate_vertical_rad_s = 0, earth_rate_horizontal_rad_s = 0;
  /// The joint estimator's accelerometer calibration (parameters, covariance and directions
  /// refitted with the rotations); unset for the two-stage one.
  std::optional<CalibrationResult> accelerometer;
  /// The offsets over temperature, when asked for (GyroCalibrationOptions::thermal): the rest of
  /// this calibration is at its T_ref, and still_spans' mean_raw have them taken out.
  std::optional<GyroThermal> thermal;
};

/// The gyroscope of a unit, as its calibration file holds it (`sensors.gyroscope`): the
/// calibration CalibrateGyro made, the name of the log its rates were read from, and the label of
/// their raw unit. A file read back gives the same fields it was written from, except those the
/// file does not hold (`accelerometer`, the solver's method and time, the time offset's step),
/// and NaN for a record an older file lacks.
struct UnitGyroscope : GyroCalibration {
  std::string source;
  std::string raw_unit = "raw";
};

/// Each rate sample's temperature [°C]: the gyro log's when it has any, else the accelerometer's
/// (the same clock, one sample each; one source, as one die may run warmer than the other); a
/// sample without one takes the line between its nearest neighbours that have one (held beyond
/// the first and the last). Throws DataError when no sample of either log has a temperature.
std::vector<double> GyroSampleTemperatures(const RawLog& gyro, const RawLog& accel);

/// Whose temperature each rate of `gyro` is taken at (the gyroscope's own where it has one, else
/// the accelerometer's at the same sample): "the gyroscope's log: …" or "the accelerometer's log:
/// …" with the log's temperature_source; empty when neither has one.
std::string GyroTemperatureSource(const RawLog& gyro, const RawLog& accel);
/// Whether two GyroTemperatureSource texts name the same sensor's temperature (the gyroscope's
/// or the accelerometer's, whatever the column).
bool SameTemperatureSensor(const std::string& a, const std::string& b);

/// Throws DataError unless `gyro` holds a rate sample at each sample of `accel` (the same count,
/// times within half the typical step): the two streams of one clock; and when its readings are
/// the accelerometer's (the same columns or file).
void CheckGyroClock(const RawLog& accel, const RawLog& gyro);

/// Calibrates the gyroscope of `gyro`, recorded beside the accelerometer of `accel` on the same
/// clock (one gyro sample at each accelerometer sample's time), from the still positions of
/// `accel` (`positions`, in time order, each with its interval) and their calibration
/// `accel_cal` (Calibrate, maximum likelihood). Throws DataError when the streams differ in
/// length or time, when a position has no interval, when there are too few rotations for the
/// model, when a rate axis is never turned about (its scale not observable, named), when a turn
/// is too fast for the sample rate, or when the fit fails (NotConvergedError, a DataError, when it
/// does not converge).
GyroCalibration CalibrateGyro(const RawLog& accel, const RawLog& gyro,
                              const std::vector<Position>& positions,
                              const CalibrationResult& accel_cal,
                              const GyroCalibrationOptions& options);

}  // namespace accelcal
