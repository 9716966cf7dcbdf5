#pragma once
// The subcommands of the accelcal tool: argument structs filled by main.cpp, handlers that call
// the library and do the I/O.

#include <cstdint>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "accelcal/calibrate.hpp"
#include "accelcal/calibrate_unit.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/static_detection.hpp"

namespace CLI {
class App;
}  // namespace CLI

namespace accelcal::cli {

/// Process exit statuses.
enum ExitCode : int {
  kExitOk = 0,
  kExitInternal = 1,      ///< a bug: an unexpected exception
  kExitUsage = 2,         ///< bad command line
  kExitBadInput = 3,      ///< unreadable, malformed or insufficient input data
  kExitNotConverged = 4,  ///< the solver did not converge: nothing written
  kExitOutput = 5,        ///< the output file could not be written
  /// Calibrated, but the result failed its checks (diagnosis.hpp): the file and the report are
  /// written, marked `"verdict": "failed"`, so that the user can see why.
  kExitFailedChecks = 6,
};

struct CalibrateArgs;
/// What `calibrate` runs once its arguments are parsed and checked, in place of RunCalibrate:
/// Python's calibrate_log makes its request from the tool's own options and keeps the result.
using CalibrateRunner = std::function<int(const CalibrateArgs&)>;

/// What runs a command once its options are parsed (`parsed`: its CLI::App, for what was given).
using CommandRun = std::function<int(const CLI::App& parsed)>;

/// Each command registers its options on its CLI::App beside its Run (into arguments of its own),
/// and returns what runs it: the table of commands in cli.cpp calls them.
CommandRun SetUpCalibrate(CLI::App* cmd, const CalibrateRunner& runner);
CommandRun SetUpBatch(CLI::App* cmd);
CommandRun SetUpStore(CLI::App* cmd);
CommandRun SetUpCompare(CLI::App* cmd);
CommandRun SetUpDetect(CLI::App* cmd);
CommandRun SetUpInspect(CLI::App* cmd);
CommandRun SetUpNoise(CLI::App* cmd);
CommandRun SetUpDesign(CLI::App* cmd);
CommandRun SetUpMonteCarlo(CLI::App* cmd);
CommandRun SetUpSystemLevel(CLI::App* cmd);
CommandRun SetUpGimbal(CLI::App* cmd);
CommandRun SetUpSimulate(CLI::App* cmd);
CommandRun SetUpApply(CLI::App* cmd);
CommandRun SetUpVerify(CLI::App* cmd);
CommandRun SetUpReport(CLI::App* cmd);
CommandRun SetUpExport(CLI::App* cmd);

/// The whole tool: parses the arguments, runs the subcommand (`calibrate` through `runner` when
/// one is given), returns the exit status (never exits, never throws).
int RunCommandLine(int argc, char** argv, const CalibrateRunner& runner = {});

/// RunCommandLine with `args` (argv[0] first), this thread's standard output and error appended
/// to `out` and `err` instead (the Python package runs the tool's commands so, in-process and
/// in several threads at once); no signal handlers are installed. `files`: output files written
/// into memory instead of the disk (Console::files, output.hpp).
struct CapturedFile;
int RunCommandLineCaptured(const std::vector<std::string>& args, std::string* out, std::string* err,
                           std::vector<CapturedFile>* files = nullptr,
                           const CalibrateRunner& runner = {});

/// `accelcal --describe-options`: every command's options as JSON (for the Python package).
inline constexpr const char* kDescribeOptionsFlag = "--describe-options";

/// A usage problem found after parsing (bad enum value, conflicting options).
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Error writing an output file.
struct OutputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct InputArgs {
  std::string path;
  /// Further files of the same device (calibrate): their positions are pooled with the first's.
  std::vector<std::string> more_paths;
  std::string input_kind = "auto";
  std::vector<std::string> columns;
  std::optional<double> rate_hz;
  std::string time_unit = "auto";                 // TimeUnit
  std::optional<double> instance;                 // ReadOptions::instance
  std::optional<std::string> topic;               // ReadOptions::topic
  std::optional<std::string> frame_id;            // ReadOptions::frame_id
  std::optional<std::string> temperature_column;  // ReadOptions::temperature
  StaticDetectionOptions detection;
};

struct GravityArgs {
  std::optional<double> gravity_ms2;
  std::optional<double> latitude_deg;
  double height_m = 0;
  std::string units = "m/s2";
};

// --outliers and --outlier-probability (calibrate.hpp OutlierOptions).
struct OutlierArgs {
  std::string policy = "exclude";  // OutlierPolicy
  double probability = 1e-3;       // OutlierOptions::false_alarm_probability
  int max_excluded = 3;            // OutlierOptions::max_excluded
};

struct CalibrateArgs {
  InputArgs input;
  GravityArgs gravity;
  std::string model = "linear";
  std::string method = "joint";
  std::string init = "auto";
  std::string frame = "x-first";
  std::string estimator = "ml";
  std::string bias_model = "constant";  // BiasModel, or auto
  // The spline bias's random-walk prior: q [m/s^2/sqrt(s)], one value or one per axis, or the
  // accelerometer's random walk of an `accelcal noise --json` file.
  std::vector<double> bias_random_walk;
  std::string noise;
  // Parameters that follow temperature (thermal_calibration.hpp): "K,B[,K2]" degrees or "auto"
  // (empty: none), and one temperature [°C] per input file (empty: the logs' own).
  std::string thermal;
  std::vector<double> temperatures_c;
  OutlierArgs outliers;
  std::string orientations;  // known orientations (orientation_file.hpp): platform-frame fit
  // The gyroscope (gyro_calibration.hpp): its log (empty: INPUT itself when columns are given),
  // columns and stream, declared unit, model and estimator.
  SensorInput gyro;
  std::string gyro_units = "raw";
  std::string gyro_model = "auto";
  std::string gyro_estimator;  // empty: joint, or two-stage with known orientations or --thermal
  // With --thermal: the degree of the gyroscope's offsets over temperature, or auto (empty: auto).
  std::string gyro_thermal;
  /// Options that a known-orientation fit does not take, when given explicitly.
  std::vector<std::string> gravity_only_options;
  bool cross_validate = true;
  std::string raw_units = "raw";
  std::string report;  // HTML report path (report.hpp); empty: none
  std::string output;
  bool json = false;
  int max_iterations = 0;   // 0: the solver's default
  std::string date;         // provenance date (calibration_file.hpp); empty: none written
  bool date_given = false;  // --date was given (an empty one is refused, not ignored)
  /// The options given on the command line that change the result, in the order the tool
  /// defines them: the file's `provenance.options` (a flag has no values).
  std::vector<std::pair<std::string, std::vector<std::string>>> given_options;
};

struct CompareArgs {
  InputArgs input;
  GravityArgs gravity;
  std::string model = "linear";
  std::vector<std::string> methods;  // empty: all that fit the model
  std::string init = "auto";
  bool leave_one_out = true;
  std::string reference;  // calibration file: adds paper 001's e_T, e_b
  OutlierArgs outliers;   // screened once, the same positions for every method
  bool json = false;
  SensorInput gyro;  // the gyroscope's log (ReadGyroLog): its estimators compared too
  std::string gyro_units = "raw";
};

struct InspectArgs {
  std::string path;
  bool json = false;
};

struct DetectArgs {
  InputArgs input;
  bool json = false;
};

struct NoiseArgs {
  InputArgs input;
  std::string report;       // HTML report path (noise_report.hpp); empty: none
  std::string calibration;  // empty: the log's own unit
  SensorInput gyro;         // the gyroscope's log (ReadGyroLog)
  bool still = false;       // the longest still interval only
  bool json = false;
  std::string output;  // empty: stdout
};

struct ApplyArgs {
  std::string calibration;
  InputArgs input;
  std::string output;                // empty: stdout
  std::optional<std::string> units;  // convert to this unit
  SensorInput gyro;                  // the gyroscope's log (ReadGyroLog)
};

struct VerifyArgs {
  std::string calibration;
  InputArgs input;      // the new recording, and its detection options
  SensorInput gyro;     // the gyroscope's log (ReadGyroLog)
  GravityArgs gravity;  // the site's, when not the calibration's (units: the calibration's)
  // The log's one temperature [°C], for a calibration over temperature and a log without its own.
  std::optional<double> temperature_c;
  bool json = false;
  std::string output;  // empty: stdout
};

struct ReportArgs {
  std::string calibration;
  InputArgs log;       // path empty: no raw-signal plot
  std::string output;  // empty: stdout
};

struct ExportArgs {
  std::string calibration;
  std::string format;
  std::string output;         // empty: stdout
  std::string raw_unit;       // overrides the file's units.raw (kalibr, px4, ardupilot)
  std::string gyro_raw_unit;  // overrides the gyroscope's units.raw (kalibr)
  int instance = 0;
  std::string c_prefix = "accelcal";
  std::string sensor = "accelerometer";  // imutk: which sensor's triad
  std::string noise;                     // accelcal noise --json output (kalibr-imu, ros, kalibr)
  std::string rostopic = "/imu0";
  std::optional<std::uint64_t> device_id;       // px4: CAL_ACC<n>_ID
  std::optional<std::uint64_t> gyro_device_id;  // px4: CAL_GYRO<n>_ID
  std::string current_params;                   // ardupilot: the .param file in force when logged
  /// The options given on the command line, by ExportOptions' field names (raw_unit, ...): one
  /// the chosen format does not use is refused, never silently ignored.
  std::vector<std::string> given;
};

struct DesignArgs {
  std::string positions;                   // scheme name or CSV file of unit directions
  std::string device;                      // calibration file of the nominal device
  std::vector<double> noise_raw;           // 1 or 3 values: 1σ of one averaged reading [raw]
  std::optional<std::string> model;        // default: the device's
  int choose = 0;                          // > 0: optimal subset of the positions (candidates)
  std::string criterion = "d";             // "d" (det) or "a" (trace of the CRLB)
  std::optional<double> noise_density_ug;  // instead of noise_raw, with rate and duration
  std::optional<double> rate_hz;
  std::optional<double> duration_s;
  std::string bias_model = "constant";  // a drift to plan for (bias_drift.hpp)
  // A temperature schedule (thermal.hpp): the positions at each temperature [°C], and the
  // degrees of K, b (and k2) in T − T_ref.
  std::vector<double> temperatures_c;
  std::vector<int> thermal_degrees = {1, 1};
  bool thermal_degrees_given = false;
  // 1σ targets of the degree-1 coefficients: K's in ppm/K (µrad/K), and b's in mg/K.
  std::vector<double> thermal_target;
  bool json = false;
};

struct MonteCarloArgs {
  std::string scenario = "yang2012";
  int runs = 500;
  std::string method = "joint";
  std::string estimator = "ml";
  std::uint64_t seed = 1;
  int threads = 0;  // 0: all cores
  bool residual_noise = false;
  bool json = false;
};

struct SimulateArgs {
  std::string scenario;   // "yang2012", or empty with --truth
  std::string truth;      // calibration file of the simulated device
  std::string positions;  // scheme or CSV of unit directions (default with --scenario: yang18)
  std::optional<double> noise_density_ug;  // µg/√Hz (relative to the truth's gravity)
  double rate_hz = 100;
  double duration_s = 60;
  bool rate_given = false, duration_given = false;  // wu2018-system has its own defaults
  double transition_s = 4;
  std::uint64_t seed = 1;
  bool raw = false;            // raw log instead of a positions file
  std::string format = "csv";  // of a raw log: csv or ulog
  std::string output;
};

struct SystemLevelArgs {
  std::string series;
  std::optional<double> latitude_deg;
  std::optional<double> gravity_ms2;  // default: WGS-84 normal gravity at the latitude
  bool json = false;
};

// accelcal batch: a production line's units, each calibrated as `accelcal calibrate` would with the
// options given, judged against a limits file (acceptance.hpp), in parallel (cmd_batch.cpp).
struct BatchArgs {
  std::vector<std::string> inputs;  // files, and directories whose files matching `glob` are read
  std::string glob = "*";
  std::string limits;   // limits file (YAML); empty: the calibrations' own checks only
  std::string output;   // the batch's directory
  std::string unit_id;  // a regular expression on file names; empty: the name less its extension
  bool unit_id_given = false;  // --unit-id was given (an empty one too)
  // Where a unit's id comes from: name (the file's), info:KEY or param:KEY (a binary log's
  // information or parameter), device-id (its accelerometer stream's), frame-id (its ROS
  // topic's header.frame_id).
  std::string unit_id_from = "name";
  int jobs = 0;        // units at once; 0: one per core
  bool redo = false;   // calibrate every unit again, even one whose calibration is current
  bool report = true;  // an HTML report per unit
  bool json = false;   // the summary document to stdout instead of the table
  /// The calibrate options given, as GivenOptions lists them: passed to every unit's calibrate
  /// as given (each unit's file records them in its provenance).
  std::vector<std::pair<std::string, std::vector<std::string>>> calibrate_options;
  /// The same, as calibrate takes them (its INPUT each unit's files; its given_options those above
  /// less the date).
  CalibrateArgs calibrate;
};

// accelcal store add|get|list: a directory of calibrations by unit and date, with an index, each
// calibration added compared with the unit's one before it (cmd_store.cpp).
struct StoreArgs {
  std::string action;              // add, get or list
  std::string store;               // the store's directory
  std::vector<std::string> items;  // add: calibration files or batch directories; get, list: a unit
  std::string unit;                // add: the unit of the calibration files given
  std::string date;                // add: their date when they have none; get: the one wanted
  bool json = false;
  std::string output;  // get: where the file goes (empty: stdout)
  /// add: the accelerometer's turn-on bias repeatability [specific-force unit, 1σ], one or x,y,z
  /// (ChangeOptions); empty: none.
  std::vector<double> bias_repeatability;
};

struct GimbalArgs {
  std::string coarse;  // theta1_deg,theta2_deg,theta3_deg,ax,ay,az per position
  std::string fine;    // ax,ay,az per position (re-zeroed platform), optional
  GravityArgs gravity;
  bool json = false;
};

int RunCalibrate(const CalibrateArgs& args);
int RunBatch(const BatchArgs& args);
int RunStore(const StoreArgs& args);
int RunGimbal(const GimbalArgs& args);
int RunSystemLevel(const SystemLevelArgs& args);
int RunSimulate(const SimulateArgs& args);
int RunMonteCarlo(const MonteCarloArgs& args);
int RunDesign(const DesignArgs& args);
int RunDetect(const DetectArgs& args);
int RunInspect(const InspectArgs& args);
int RunCompare(const CompareArgs& args);
int RunApply(const ApplyArgs& args);
int RunNoise(const NoiseArgs& args);
int RunExport(const ExportArgs& args);
int RunReport(const ReportArgs& args);
int RunVerify(const VerifyArgs& args);

}  // namespace accelcal::cli
