#pragma once
/// @file calibration_file.hpp
/// The calibration file: JSON, `format` "accelcal-calibration". Version 2 (written since issue
/// 17) holds the sensors of one unit under `sensors` (today `sensors.accelerometer`, with every
/// key version 1 had at its top level) and `provenance` (which accelcal, which options, which
/// input bytes). Version 1 files are still read everywhere. docs/calibration-file.md lists every
/// key. Writing is deterministic (same result, same provenance → same bytes), through the one
/// JSON writer (json_text.hpp).

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "accelcal/calibrate.hpp"
#include "accelcal/diagnosis.hpp"
#include "accelcal/gravity.hpp"
#include "accelcal/gyro_calibration.hpp"
#include "accelcal/load_positions.hpp"
#include "accelcal/model_selection.hpp"
#include "accelcal/native_log.hpp"
#include "accelcal/positions.hpp"

namespace accelcal {

/// The version CalibrationToJson writes; ParseCalibrationJson reads it and every earlier one.
inline constexpr int kCalibrationFileVersion = 2;

/// One input file a calibration read: its name as given, its size and the SHA-256 of its bytes
/// (sha256.hpp), so that a file can be matched to the recording it came from.
struct InputRecord {
  std::string name;
  std::uint64_t bytes = 0;
  std::string sha256;  ///< 64 lowercase hexadecimal digits; empty when not hashed (not written)
  /// The stream of a binary log it was read from (written as `stream`), when it was one.
  std::optional<SourceStream> stream{};
};

/// Where a calibration came from: written as `provenance`.
struct Provenance {
  /// What made it, e.g. "accelcal calibrate" or "accelcal Python calibrate_log"; empty: the
  /// library, called directly.
  std::string command;
  /// The options that change the result, as the caller names and spells them (the tool: each
  /// option given on its command line, without the ones that only choose where output goes).
  nlohmann::ordered_json options = nlohmann::ordered_json::object();
  std::vector<InputRecord> inputs;
  /// A date (YYYY-MM-DD, optionally THH:MM[:SS] and Z or ±HH:MM) given by the caller; empty:
  /// none is written, so that the same input gives the same bytes.
  std::string date;
  /// Read from a file: the accelcal version that wrote it (empty in version 1). Writing always
  /// states this library's Version().
  std::string accelcal_version;
};

/// The files of a calibration's input, in order, as its provenance records them.
std::vector<InputRecord> InputRecords(const LoadedInput& input);

/// Why a provenance date is not one, or nothing when it is.
std::optional<std::string> CheckProvenanceDate(const std::string& date);

/// What the file needs besides the CalibrationResult.
struct CalibrationFileInfo {
  ForceUnit unit = ForceUnit::kMetersPerSecond2;
  std::string raw_unit = "raw";  ///< label of the raw unit, e.g. "counts"
  std::string source;            ///< input file name (the first, when there are several)
  /// Several input files (sessions of one device, positions pooled): their names, written as
  /// `sources`, and the index into them of each position, written as `positions[].file`.
  std::vector<std::string> sources;
  std::vector<int> position_source;
  std::vector<Position> positions;  ///< the positions that were fitted, same order as the result
  /// The 1σ of each position's mean as the fit took it (CalibrationOptions::reading_sigmas),
  /// written as `positions[].mean_sigma`; empty: not written (noise from the residuals).
  std::vector<Vec3> mean_sigmas;
  /// When the linear and quadratic models were compared (model "auto", or "quadratic" with the
  /// linear fit as comparison): written as `model_selection`.
  const ModelSelection* model_selection = nullptr;
  std::string model_requested;  ///< "linear", "quadratic" or "auto"
  /// When the bias model was chosen (bias model "auto"): written as `bias_model_selection`.
  const BiasModelSelection* bias_model_selection = nullptr;
  /// Written as `verdict` and `diagnostics`; when null, Diagnose() of the result, the positions
  /// and the model selection (without the log's findings).
  const Diagnosis* diagnosis = nullptr;
  Provenance provenance;  ///< accelcal_version is ignored: Version() is written
  /// The gyroscope calibrated from the same recording, written as `sensors.gyroscope`.
  const UnitGyroscope* gyroscope = nullptr;
};

/// Serialises a calibration as a version-2 document (json_text.hpp's layout, trailing newline).
/// Throws std::invalid_argument for a provenance date CheckProvenanceDate refuses.
std::string CalibrationToJson(const CalibrationResult& result, const CalibrationFileInfo& info);

/// One position as the file records it (`positions[]`).
struct FilePosition {
  Vec3 mean = Vec3::Zero();  ///< raw
  std::optional<std::size_t> samples;
  std::optional<Vec3> std;         ///< raw, per axis, one sample
  std::optional<Vec3> mean_sigma;  ///< raw, per axis, the 1σ of the mean as the fit took it
  /// `interval`: sample indices [begin, end) and times [s], for positions from a raw log.
  struct Interval {
    double begin = 0, end = 0, t_begin = 0, t_end = 0;
  };
  std::optional<Interval> interval;
  std::optional<Vec3> direction;  ///< estimated (or known) unit gravity direction
  std::optional<Vec3> residual;   ///< p − μ, raw
  std::optional<double> gravity_norm_error, crossval_error;
  /// `time` and `drift_offset`: the position's time [s] and D φ(t) [raw], with a drifting bias.
  std::optional<double> time;
  std::optional<Vec3> drift_offset;
  std::optional<double> temperature;  ///< the sensor's mean temperature [°C], when read
  bool excluded = false;
  std::optional<int> file;  ///< index into `sources`
};

/// The solver's record (`solver`), as far as a reader needs it.
struct SolverRecord {
  std::string method, estimator = "ml";
  std::optional<long long> iterations;  ///< none when absent or not an integer
  bool converged = true;
};

/// A calibration file, read: every key a reader uses (apply, export, report, compare, Python),
/// each checked once, for the accelerometer.
struct LoadedCalibration {
  int version = kCalibrationFileVersion;  ///< of the file it was read from
  ModelKind model = ModelKind::kLinear;
  Frame frame = Frame::kXFirst;
  ModelParameters params;
  double gravity = 0;
  ForceUnit unit = ForceUnit::kMetersPerSecond2;
  std::string raw_unit = "raw";         ///< `units.raw` (a label given at calibration)
  std::vector<Vec3> position_means;     ///< `positions[].mean` [raw]; empty when the file has none
  std::vector<FilePosition> positions;  ///< `positions`, same order
  std::string source;                   ///< `source`: the calibrated input's name, when present
  /// `verdict` ("ok", "warnings", "failed"); empty in a file written before diagnoses existed.
  /// In version 2 the worse of the file's and the accelerometer's.
  std::string verdict;
  /// `covariance` in the order of ParameterSlots(model, frame); empty when the file has null.
  Eigen::MatrixXd covariance;
  /// `bias_drift`, when the bias was fitted as a function of time (bias_drift.hpp): `params.bias`
  /// is then the bias at its reference time; its times are the positions' `time`.
  std::optional<BiasDrift> drift;
  /// `thermal`, when the parameters follow temperature (thermal.hpp): `params` is θ(T_ref) and
  /// `covariance` its block; temperatures_c are the positions' `temperature`.
  std::optional<ThermalTerms> thermal;
  /// `thermal.temperature_range`: the temperatures [°C] its fit spans.
  std::optional<std::pair<double, double>> thermal_range_c;
  std::optional<double> gravity_norm_rms_before, gravity_norm_rms_after, crossval_rms;
  /// `noise.sigma_raw`: the residual σ̂ of the position means along the fitted surface's normal
  /// [raw], when present.
  std::optional<double> noise_sigma_raw;
  /// The degrees of freedom of the noise level the covariance was scaled by, when that level was
  /// estimated from the fit's residuals (`noise.degrees_of_freedom`, unless `noise.source` is
  /// "samples" and not `inflated`); none when it came from the samples' own scatter.
  std::optional<double> covariance_dof;
  SolverRecord solver;
  /// `diagnostics`; none in a file written before diagnoses existed.
  std::optional<std::vector<Finding>> diagnostics;
  Provenance provenance;  ///< version 2; empty in version 1
  /// `sensors.gyroscope` (version 2), when the file holds one: what calibrate made of it, as far
  /// as the file holds it (UnitGyroscope).
  std::optional<UnitGyroscope> gyroscope;
  bool has_gyroscope() const { return gyroscope.has_value(); }
};

/// The gyroscope's section (`sensors.gyroscope`; G in `force_unit`, the accelerometer's) and
/// back, as CalibrationToJson writes and ParseCalibrationJson reads it: Python pickles a
/// gyroscope so. InputError naming `source` for a section that is not one.
nlohmann::ordered_json GyroscopeToJson(const UnitGyroscope& gyroscope, ForceUnit force_unit);
UnitGyroscope GyroscopeFromJson(const nlohmann::ordered_json& section, const std::string& source);

/// Parses a calibration file's text (version 1 or 2); throws InputError naming `source` for
/// anything missing, mistyped or inconsistent (unknown format/version, a key twice in an object,
/// K not triangular as its frame requires, non-finite numbers, a covariance that is not P x P for
/// the model's P parameters).
LoadedCalibration ParseCalibrationJson(const std::string& text, const std::string& source);

}  // namespace accelcal
