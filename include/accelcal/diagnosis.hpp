#pragma once
/// @file diagnosis.hpp
/// One judgement of a calibration and its input: named findings, each a note, a warning or a
/// failure, with the numbers behind it. Every command that calibrates prints the warnings and
/// failures, the calibration file carries all of them (`diagnostics`, `verdict`), the report
/// lists them; a failure makes the result "calibrated, but failed its checks" (the command line's
/// exit status 6), never a success.
///
/// The checks and their thresholds, each with why (docs/diagnostics.md lists the codes):
///   - `not_converged` (failure): the solver stopped before any convergence criterion.
///   - `misfit` (failure): the RMS of |f_k| − g over the fitted positions beyond kMisfitFailure
///     (2 %) of g. The bundled real recordings reach 0.01-0.27 % (Xsens 0.010 %, T265 0.052 %,
///     a phone's LIS3DH 0.27 %); two sensors interleaved in one file give 3.6 %, positions taken
///     while turning or an orientation file in the wrong order far more. For known orientations
///     the measure is the residual vector p_k − μ_k taken to specific force (K⁻¹), whose
///     direction the known orientation fixes too (imucal's hand-placed Ferraris holds: 0.6 %).
///     Not a failure when the samples' own noise explains the scatter (scatter ratio at most
///     kScatterWarning): very noisy readings (paper 001's σ = 0.1 g) miss g by that much too.
///   - `interleaved` (failure): the median lag-1 autocorrelation of the still samples below
///     kInterleavedCorrelation (−0.5): rows that alternate between two sensors (−1 when
///     interleaved evenly; white noise 0, the T265's repeated samples +0.5). Their average is a
///     consistent device, so no misfit shows it.
///   - `scatter_ratio` (note beyond 3, warning beyond kScatterWarning = 30): the positions
///     scatter R times more than the noise of their samples explains; the covariance is already
///     inflated by R, so the uncertainties stay honest, but beyond 30 something other than noise
///     (drift, a model that does not fit, moving positions) dominates. Xsens 4.6, T265 9.9, the
///     CK set 4.7, the phone 7.3, imucal's Ferraris holds 62.
///   - `loose_random_walk` (warning): with a random-walk prior on the bias (bias_drift.hpp), the
///     positions scatter so much less than q and the samples' noise predict (χ² lower tail below
///     kPriorContradictionProbability) that q is larger than the bias wanders: the posterior's
///     uncertainties are then the prior's, too wide.
///   - `exactly_determined` (warning): as many positions fitted as parameters (no degrees of
///     freedom): nothing checks the fit.
///   - `exact_fit` (warning): residual degrees of freedom but residuals at round-off (below
///     1e-9 of the signal): the positions are not independent noisy readings.
///   - `held_out_outlier` (warning): a position whose held-out |f| − g is beyond 5 times the
///     typical (1.4826 × median), where the screening did not test every position (turned off,
///     or too few degrees of freedom): where it did, its own test decides.
///   - `outlier` (warning): a position the screening found discordant; `outlier_limit` (warning)
///     when as many positions were excluded as allowed (more may disagree).
///   - `coverage_gap` (warning): a direction more than 60° from every position (the fit is
///     extrapolated there; six axis-aligned positions leave at most 54.7°).
///   - `poorly_determined` (warning): a parameter's 1σ beyond what a calibration worth applying
///     has: 1 % of a scale factor, 0.5° of a misalignment angle, 10 mg of a bias, 0.01 g/g² of a
///     squared coefficient.
///   - `gravity_value` (warning): gravity more than 1 % from 9.80665 m/s² (Earth's surface spans
///     9.78-9.83).
///   - `units` (warning): the uncalibrated readings' median |p| within 20 % of 1 while gravity is
///     given as about 9.8, or the reverse: the readings are probably in the other unit.
///   - `model_choice` (warning): a quadratic result where the model selection's evidence rule
///     (model_selection.hpp) keeps the linear model.
///   - `crossval_unavailable` (note): why held-out validation has no number.
///   - `positions_like_samples` (warning): positions read from a headerless file by its row count
///     whose consecutive rows barely move (median step below kRepeatedStepFraction = 5 % of the
///     readings' RMS spread about their mean; a positions file turns to a new orientation at
///     almost every row: every bundled one has median steps of 40 % or more): a short raw log
///     read as positions, one sample each.
///   - `drifting_rest` (warning): the longest still interval (kDriftMinRest_s or more, less a
///     detection window at each end) has an Allan deviation that rises with averaging time: a
///     steady drift (the slope of kDriftBatches batch means, t beyond the two-sided kDriftP level
///     over the axes) or bias instability, random walk or rate ramp resolved at kDriftZ σ or more
///     (noise_model.hpp) on some axis. The bias drifts, and the positions' means carry it.
///   - `rejected_period` (warning when clipped, note otherwise): a still period not used;
///     `joined_periods` (note): still periods split by a short disturbance that were joined.
///   - `time_unit`, `time_gaps`, `coarse_timestamps` (notes), `irregular_sampling` (note beyond
///     1 % of the steps, warning beyond 10 %): what the time column was found to be.
///   - `corrupted_reading` (warning): readings more than kCorruptedReadingFactor times the log's
///     spread from its median (static_detection.hpp), left out of every window.
///
/// The unit's, from its calibration as a whole (CalibrateUnit, calibrate_unit.hpp):
///   - `drift_across_gap` (warning): a bias that drifts was fitted across a pause between two
///     positions of more than a minute and five times the median pause, which nothing checks.
///   - `temperature_span` (note): the positions span kTemperatureSpanNote_K or more, and the
///     parameters were fitted as constants over temperature.
///
/// The gyroscope's, when it was calibrated too (GyroFindings; gyro_calibration.hpp):
///   - `gyro_misfit` (failure): the rotations miss the fitted gravity directions by more than
///     kGyroMisfitFailure_deg (2°) RMS while their scatter ratio is beyond kScatterWarning (the
///     rate noise does not explain it). The bundled recordings reach 0.07-0.45° (Xsens 0.12°,
///     T265 joint 0.07°, imucal's Ferraris session 0.45°); the T265's two-stage fit, held to an
///     accelerometer misalignment the rotations contradict, 2.7° at a ratio of 101; a gyro whose
///     axes are mapped otherwise than the accelerometer's, 120-130°; a saturated axis or a model
///     without this gyro's g-sensitivity, 3-11°. 2° over turns of about 90° is a 2 % error, no
///     better than an uncalibrated MEMS gyro.
///   - `gyro_scatter_ratio` (note beyond 3, warning beyond kScatterWarning): the still rates or
///     the rotations scatter R times more than the rate noise explains (the covariance is
///     inflated by R).
///   - `gyro_poorly_determined` (warning): a scale factor of K_g known to worse than 1 % (1σ), or
///     a misalignment to worse than 0.5°, each entry's σ over its row's length (the scale the
///     row's largest entry, the diagonal of an aligned gyro; the others misalignments), as the
///     accelerometer's `poorly_determined`: turns about one axis mostly leave the others' free. A
///     failure at ten times that (10 % of a scale, 5° of a misalignment): no calibration at all.
///   - `gyro_turn_outlier` (warning): a turn the screening flagged (its held-out χ² beyond the 1 %
///     level over all turns): a bump during it, kept in the fit.
///   - `gyro_not_validated` (note): no held-out rotation error (validation turned off).
///   - `gyro_unit_scale` (warning): a scale of K_g more than kGyroUnitScaleTolerance (10 %) from
///     the declared unit's: the readings were converted with another range (full-scale) setting
///     than the sensor's, or are in another unit. The calibration maps the readings as they are.
///   - `gyro_time_offset` (note): the gyro's readings lag or lead the accelerometer's by more than
///     3σ and half a sample step (GyroCalibration::time_offset): the still spans keep the
///     calibration right; a filter fusing the two streams needs the lag. A warning when the best
///     alignment is at the edge of the ±0.5 s searched: the lag may exceed what the still spans
///     absorb, or the streams do not correlate; a failure when the rotations also miss by more
///     than kGyroMisfitFailure_deg RMS.
///   - `gyro_turned_in_still` (note): the gyro turned by more than kGyroTurnedInStillNote_deg
///     inside a still position of the accelerometer, outside its own still span (a turn about the
///     vertical, which the accelerometer cannot see, or the gyro's stream lagging or leading the
///     accelerometer's): those samples were integrated with the neighbouring turns.
///   - `gyro_mirrored` (warning): det K_g < 0, the gyro's axes mirrored against the
///     accelerometer's (an axis inverted or two swapped): mapped as they are, but likely a
///     driver's axis setting gone wrong.
///   - `gyro_position_turning` (warning): the gyro did not stand still in a still position of the
///     accelerometer (GyroStillSpan::still false: it turned throughout, about the vertical, or
///     its still part's rate is off the zero-rate offset the other positions agree on): the
///     position gives no still rate, and the turns on either side of it were integrated as one.

#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "accelcal/calibrate.hpp"
#include "accelcal/gravity.hpp"
#include "accelcal/gyro_calibration.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/model_selection.hpp"
#include "accelcal/names.hpp"
#include "accelcal/positions.hpp"
#include "accelcal/static_detection.hpp"

namespace accelcal {

enum class Severity {
  kNote,     ///< "note": worth knowing, nothing wrong
  kWarning,  ///< "warning": the result stands, but look at this
  kFailure,  ///< "failure": the result failed its checks and must not be used as it is
};
std::string_view ToString(Severity severity);
template <>
struct EnumNames<Severity> {
  static constexpr std::pair<Severity, std::string_view> kTable[] = {
      {Severity::kNote, "note"}, {Severity::kWarning, "warning"}, {Severity::kFailure, "failure"}};
};

/// One finding of the diagnosis.
struct Finding {
  std::string code;  ///< stable identifier (see the file comment), e.g. "misfit"
  Severity severity = Severity::kNote;
  std::string message;  ///< one sentence for a person, with the numbers
  /// The numbers behind it, by name (e.g. {"rms_fraction_of_g", 0.036}).
  std::vector<std::pair<std::string, double>> numbers;
};

/// The overall verdict: the worst severity found.
enum class Verdict {
  kOk,        ///< "ok": notes at most
  kWarnings,  ///< "warnings": at least one warning, no failure
  kFailed,    ///< "failed": at least one failure
};
std::string_view ToString(Verdict verdict);
template <>
struct EnumNames<Verdict> {
  static constexpr std::pair<Verdict, std::string_view> kTable[] = {
      {Verdict::kOk, "ok"}, {Verdict::kWarnings, "warnings"}, {Verdict::kFailed, "failed"}};
};

struct Diagnosis {
  std::vector<Finding> findings;
  Verdict verdict() const;
};

inline constexpr double kMisfitFailure = 0.02;  ///< RMS misfit as a fraction of g
inline constexpr double kScatterNote = 3.0;
inline constexpr double kScatterWarning = 30.0;
/// `loose_random_walk`: the whitened sum of a fit with a random-walk prior below its χ² quantile
/// of this lower-tail probability.
inline constexpr double kPriorContradictionProbability = 1e-3;
inline constexpr double kInterleavedCorrelation = -0.5;
/// `drifting_rest`: the rest analysed is at least this long, and a drift term counts from this
/// many standard errors above 0 (by chance in 0.13 % of rests per term).
inline constexpr double kDriftMinRest_s = 20;
inline constexpr double kDriftZ = 3;
/// `drifting_rest`'s test of a steady drift: the slope of this many batch means, two-sided at
/// this level over the three axes.
inline constexpr std::size_t kDriftBatches = 16;
inline constexpr double kDriftP = 1e-3;
inline constexpr double kRepeatedStepFraction = 0.05;
inline constexpr double kGyroMisfitFailure_deg = 2.0;  ///< RMS of the rotations' residuals
inline constexpr double kGyroScaleSigmaLimit = 0.01;   ///< 1σ of a scale, relative
inline constexpr double kGyroMisalignmentSigmaLimit = 0.5 * 3.14159265358979323846 / 180;
/// The angle a gyro may turn inside an accelerometer's still interval, outside its own still
/// span, before it is noted: the bundled recordings reach 0.22° (the hand settling after a turn).
inline constexpr double kGyroTurnedInStillNote_deg = 2.0;

/// A raw log that gave positions, for the findings about it (LogFindings).
struct DiagnosedLog {
  std::string name;  ///< prefixes its findings' messages when there are several logs
  const RawLog* log = nullptr;
  const StaticDetectionResult* detection = nullptr;
};

/// What the diagnosis looks at. `result` and `positions` are required (same order); the rest is
/// used when given.
struct DiagnosisInput {
  const CalibrationResult* result = nullptr;
  const std::vector<Position>* positions = nullptr;
  /// The most positions the screening could exclude (OutlierOptions::max_excluded).
  int max_excluded = OutlierOptions{}.max_excluded;
  const ModelSelection* selection = nullptr;
  /// The raw logs the positions came from (none for a positions file), in order.
  std::vector<DiagnosedLog> logs;
  ForceUnit unit = ForceUnit::kMetersPerSecond2;  ///< of result->gravity
  /// The positions were read from a file taken for a positions file by its row count alone
  /// (InputData::kind_from_row_count): `positions_like_samples` checks they are not a raw log.
  bool positions_by_row_count = false;
  /// The gyroscope calibrated from the same recording, if it was (GyroFindings).
  const GyroCalibration* gyroscope = nullptr;
};

Diagnosis Diagnose(const DiagnosisInput& input);

/// The findings about one raw log and its detection (part of Diagnose): interleaved sensors,
/// still periods not used or joined, the time column.
std::vector<Finding> LogFindings(const RawLog* log, const StaticDetectionResult* detection);
/// The findings about a log's time column (part of LogFindings).
std::vector<Finding> TimeFindings(const TimeAxis& time);
/// The findings about the gyroscope's calibration (part of Diagnose); their codes begin "gyro_".
std::vector<Finding> GyroFindings(const GyroCalibration& gyro);
/// The findings about still periods that were not used (part of Diagnose).
std::vector<Finding> RejectedPeriodFindings(const std::vector<RejectedInterval>& rejected);

}  // namespace accelcal
