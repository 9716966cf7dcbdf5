#pragma once
/// @file calibrate_unit.hpp
/// A unit calibrated from its recordings, as `accelcal calibrate` does it: the accelerometer's
/// files read and cut into positions (load_positions.hpp), its model and bias model chosen, the
/// fit (calibrate.hpp, known_orientation.hpp or thermal_calibration.hpp), the gyroscope from the
/// same recording (gyro_calibration.hpp), the diagnosis (diagnosis.hpp) and the provenance of the
/// calibration file. One piece for the tool's `calibrate` and `batch` and for Python: each edge
/// fills a UnitRequest from its own arguments and renders the result (CalibrationToJson,
/// RenderReport, its summary). It reads, never writes or prints; progress goes to the callbacks.
///
/// Options are named in messages as the Python keywords name them (the tool's long options with
/// `_` for `-`), each marked {{name}} in OptionError::marked() and in UnitOutcome::notes, so that
/// every edge states the same rule in its own words (RenderOptionNames).

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "accelcal/calibration_file.hpp"
#include "accelcal/diagnosis.hpp"
#include "accelcal/gyro_calibration.hpp"
#include "accelcal/load_positions.hpp"
#include "accelcal/model_selection.hpp"
#include "accelcal/orientation_file.hpp"
#include "accelcal/thermal.hpp"
#include "accelcal/thermal_calibration.hpp"

namespace accelcal {

/// Positions whose temperatures span this much get a finding (`temperature_span`) suggesting a
/// calibration over temperature: a MEMS part's scale moves by 100-300 ppm/K, 0.1-0.3 % over 10 K.
inline constexpr double kTemperatureSpanNote_K = 10;

/// A sensor's samples beside the accelerometer's, on the same clock (the gyroscope's rates:
/// ReadGyroInput); each field's name in messages is the sensor's prefix and the field's
/// (`gyro`, `gyro_columns`, `gyro_topic`).
struct SensorInput {
  std::string log;                   ///< its file; empty: the first input, read again
  std::vector<std::string> columns;  ///< x,y,z or time,x,y,z; empty: the default
  std::string topic;                 ///< its stream in a binary log; empty: found
  bool given() const { return !log.empty() || !columns.empty(); }
};

/// What a unit's calibration is asked for; each field's name in messages in `backquotes`.
struct UnitRequest {
  // What is read.
  /// `input`: the accelerometer's files, raw logs or positions files ("-": standard input);
  /// several are sessions of one unit, their positions pooled in order.
  std::vector<std::string> inputs;
  /// How they are read and cut into positions (`columns`, `rate`, `time_unit`, `instance`,
  /// `topic`, `frame_id`, `temperature_column` and the detection's options); its callbacks report
  /// on each file (a progress display, details) and may throw a more specific error.
  LoadOptions load;
  std::optional<SensorInput> gyro;  ///< none: the accelerometer alone
  /// `orientations`: a file of each position's known orientation (orientation_file.hpp): the
  /// platform-frame fit of known_orientation.hpp; empty: none (orientation-free).
  std::string orientations;
  /// The spline bias's random-walk prior q [m/s²/√s]: `bias_random_walk` (one value or x,y,z),
  /// or the accelerometer's random walk of an `accelcal noise --json` file (`noise`).
  std::vector<double> bias_random_walk;
  std::string noise;
  /// `temperatures`: one temperature [°C] per input, for `thermal`; empty: the logs' own.
  std::vector<double> temperatures_c;

  // The accelerometer's fit.
  std::optional<ModelKind> model = ModelKind::kLinear;  ///< `model`; none: auto
  /// `method`, `init`, `frame`, `estimator`: none when not asked for (joint, auto, x-first, ml);
  /// a known-orientation fit takes none of them.
  std::optional<SolverMethod> method;
  std::optional<Initialization> init;
  std::optional<Frame> frame;
  std::optional<Estimator> estimator;
  /// `bias_model`: none when not asked for (constant); `bias_model_auto`: chosen on held-out
  /// error (SelectBiasModel).
  std::optional<BiasModel> bias_model;
  bool bias_model_auto = false;
  /// `thermal`: parameters that follow temperature, of `thermal_degrees` (none: auto, chosen on
  /// held-out error).
  bool thermal = false;
  std::optional<ThermalDegrees> thermal_degrees;
  OutlierOptions outliers;     ///< `outliers`, `outlier_probability`, `max_outliers`
  bool cross_validate = true;  ///< false: `no_crossval`
  int max_iterations = 0;      ///< `max_iterations`; 0: each solver's default
  /// Gravity at the site [m/s²] (resolved from `gravity`, `latitude` and `height`), and the unit
  /// of the calibration (`units`); `latitude` also takes the Earth rate's vertical part out of the
  /// gyroscope's still rates.
  ForceUnit units = ForceUnit::kMetersPerSecond2;
  double gravity_ms2 = kStandardGravity_ms2;
  std::optional<double> latitude_deg;
  /// `raw_units`: the label of the accelerometer's raw unit; none: its binary-log stream's unit by
  /// specification, else "raw".
  std::optional<std::string> raw_units;

  // The gyroscope's fit (with `gyro`).
  GyroUnit gyro_units = GyroUnit::kRaw;         ///< `gyro_units`
  std::optional<GyroModelKind> gyro_model;      ///< `gyro_model`; none: auto
  std::optional<GyroEstimator> gyro_estimator;  ///< `gyro_estimator`; none: joint, or two-stage
                                                ///< with known orientations or `thermal`
  /// `gyro_thermal`: the degree of its offsets over temperature; `gyro_thermal_auto`: chosen on
  /// held-out error (the default with `thermal`).
  std::optional<int> gyro_thermal;
  bool gyro_thermal_auto = false;

  /// The file's provenance as the caller states it: the command, its options as given, the date
  /// (its inputs are added as read).
  Provenance provenance;

  /// Gravity in the calibration's unit.
  double GravityInUnit() const;

  /// Why the request cannot be calibrated as it stands (options that conflict, values out of
  /// range), before anything is read, with option names marked {{name}}; nothing when it can.
  std::optional<std::string> Validate() const;
};

/// A unit calibrated: what its calibration file, summary and report are rendered from.
struct UnitOutcome {
  LoadedInput input;  ///< the files as read (the report plots the first raw log)
  /// The accelerometer's calibration: the joint fit with the gyroscope's rotations when there was
  /// one, else the positions' fit.
  CalibrationResult accelerometer;
  std::vector<Vec3> mean_sigmas;  ///< the 1σ of each position's mean as the fit took it
  std::optional<ModelSelection> model_selection;
  std::string model_requested;  ///< "linear", "quadratic" or "auto"
  std::optional<BiasModelSelection> bias_model_selection;
  std::optional<ThermalDegreeSelection> thermal_selection;
  std::optional<OrientationFile> orientations;
  /// The gyroscope: its log as read, and its calibration with the log's name (the first input
  /// when it was read again) and the label of its raw unit.
  struct Gyroscope {
    InputData data;
    UnitGyroscope calibration;
  };
  std::optional<Gyroscope> gyroscope;
  ForceUnit unit = ForceUnit::kMetersPerSecond2;  ///< the calibration's specific-force unit
  std::string raw_unit;                           ///< the accelerometer's raw unit's label
  /// The diagnosis of everything above; of a fit that did not converge too (`not_converged`).
  Diagnosis diagnosis;
  Provenance provenance;
  /// Lines for the summary, after the input's description (options marked {{name}}).
  std::string notes;
  /// The solver converged: there is a calibration to write. Otherwise nothing is to be written.
  bool converged() const { return accelerometer.summary.converged(); }
  /// The calibration file's description of this outcome (CalibrationToJson): pointers into it.
  CalibrationFileInfo FileInfo() const;
};

/// Calibrates the unit `request` describes. Throws OptionError for a request Validate refuses
/// (before anything is read), InputError for a file that cannot be read or used, DataError for
/// data that do not determine a calibration (a DataError of the gyroscope's names its log:
/// DataError::file). A solver that does not converge is returned (converged() false), its
/// termination in accelerometer.summary, diagnosed, without the gyroscope.
UnitOutcome CalibrateUnit(const UnitRequest& request);

/// The one raw log a gyroscope is calibrated beside (its turns between the positions); OptionError
/// for several inputs or a positions file.
const RawLog& TheRawLogForGyro(const LoadedInput& in);

/// Why the gyroscope's rates cannot be read as `gyro` asks beside the accelerometer's log
/// `accel_path` read with `accel_columns` (options marked {{name}}), or nothing.
std::optional<std::string> GyroInputProblem(const std::string& accel_path,
                                            const std::vector<std::string>& accel_columns,
                                            const SensorInput& gyro);

/// The gyroscope's log beside the accelerometer's `accel_path` (ReadGyroInput), with `read`'s
/// options (`fingerprint`: its size and SHA-256, for the provenance). Throws OptionError for what
/// GyroInputProblem refuses, InputError as ReadGyroInput with the reader's options named for the
/// gyroscope ({{gyro_columns}}, {{gyro_topic}}).
InputData ReadGyroLog(const std::string& accel_path, const ReadOptions& read,
                      const SensorInput& gyro);

}  // namespace accelcal
