#pragma once
// What the commands of the accelcal tool share (cli_common.cpp): option values checked and
// converted, the input files of a calibration read and detected, gravity resolved, numbers written
// shortest round-trip.

#include <algorithm>
#include <exception>
#include <initializer_list>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "accelcal/json_text.hpp"

#include "accelcal/calibrate_unit.hpp"
#include "accelcal/calibration_file.hpp"
#include "accelcal/error.hpp"
#include "accelcal/gravity.hpp"
#include "accelcal/load_positions.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/static_detection.hpp"
#include "commands.hpp"

namespace accelcal::cli {

// Ranges of the options that take physical quantities (issue 16): beyond them a value is a
// mistake (a unit slip, a typo), never a calibration.
constexpr double kMinRate_hz = kMinLogRate_hz;  // time_axis.hpp
constexpr double kMaxRate_hz = kMaxLogRate_hz;
constexpr double kMinGravity_ms2 = 1.0, kMaxGravity_ms2 = 100.0;
constexpr double kMaxHeight_m = 20000.0;

template <typename T>
T ParseEnum(std::optional<T> value, const std::string& text, const char* option,
            const char* allowed) {
  if (!value) throw UsageError(std::string(option) + ": '" + text + "' is not one of " + allowed);
  return *value;
}

// The methods and starts a user chooses for an orientation-free fit (known-orientation and a
// given start are the library's, chosen by other means).
inline constexpr std::initializer_list<SolverMethod> kOrientationFreeMethods = {
    SolverMethod::kJoint,   SolverMethod::kTwoStep,     SolverMethod::kNewtonLagrange,
    SolverMethod::kModulus, SolverMethod::kModulusNorm, SolverMethod::kEllipsoid};
inline constexpr std::initializer_list<Initialization> kInitializations = {
    Initialization::kAuto, Initialization::kEllipsoidFit, Initialization::kNormalizedReadings};

// The value of an enum option named `text`, one of `allowed` (default: any the library names);
// else a usage error listing the choices from the library's name table (names.hpp).
template <typename T>
T ParseChoice(const std::string& text, const char* option, std::initializer_list<T> allowed = {}) {
  const std::optional<T> value = FromName<T>(text);
  bool ok = value.has_value();
  if (ok && allowed.size() > 0)
    ok = std::find(allowed.begin(), allowed.end(), *value) != allowed.end();
  if (!ok) ParseEnum<T>(std::nullopt, text, option, NameList<T>(allowed).c_str());
  return *value;
}

OutlierOptions ParseOutlierOptions(const OutlierArgs& args);

// Why detection found nothing, with the options that act on it.
DataError NoStaticInterval(const StaticDetectionResult& d);

ReadOptions MakeReadOptions(const InputArgs& in);

/// The file a DataError of the running command is about, for its message (empty: none, e.g. a
/// simulation); a command may change it while it works on another file (the gyroscope's log).
std::string& DataSubject();

/// The usage errors of the gyroscope's log and columns (ReadGyroLog checks them too), for a
/// command to raise before it reads anything.
void CheckGyroColumns(const InputArgs& input, const SensorInput& gyro);

/// The reading of a calibration's input files reported as the tool does: a progress display,
/// details, still periods not used, a log without a still one with the options that act on it.
/// The callbacks refer to `options`, which must stay where it is while they are used.
void ReportLoading(LoadOptions* options);
// The input files of a calibration, read, detected and pooled.
LoadedInput LoadInput(const InputArgs& in);
/// The gyroscope's log beside the accelerometer's `input`: `gyro.log` (empty: `input` itself,
/// read again for its columns), read with `input`'s options, its columns (x,y,z or time,x,y,z;
/// with 3 in `input` itself, `input`'s time column in front when its columns name one) and its
/// topic. `fingerprint`: hash a separate file for the provenance. Usage errors for bad columns or
/// standard input read twice; InputError naming the file for what it holds.
InputData ReadGyroLog(const InputArgs& input, const SensorInput& gyro, bool fingerprint);

/// The tool's name of an option the library names (calibrate_unit.hpp: the Python keyword):
/// its flag (--gyro-columns), or INPUT; and a library message with its marked names so named.
std::string CliFlag(const std::string& name);
std::string WithCliFlags(const std::string& marked);

/// The tool's message for a calibration whose solver did not converge (without "accelcal: "):
/// calibrate's and batch's.
std::string DidNotConverge(const std::string& path, const UnitOutcome& unit);

/// The tool's message for an error a command threw (without "accelcal: "), and its exit status:
/// `subject` is the file a DataError is about when it names none (DataError::file).
std::string ErrorMessage(const std::exception_ptr& error, const std::string& subject, int* status);

struct Gravity {
  double in_unit;  // gravity magnitude in the output unit
  double ms2;      // the same in m/s²
  ForceUnit unit;
  std::string origin;
};
Gravity ResolveGravity(const GravityArgs& args);

/// The library's request for calibrate's options as given (their values parsed; their rules are
/// the library's, UnitRequest::Validate), and the gravity resolved: calibrate's and batch's.
UnitRequest CalibrateRequest(const CalibrateArgs& args, Gravity* g);

/// A unit's calibration file and (when `report`) its HTML report, rendered (`name`: the file's
/// name as the report gives it).
struct RenderedCalibration {
  std::string json, report;
};
RenderedCalibration RenderCalibration(const UnitOutcome& unit, const std::string& name,
                                      bool report);

// Three numbers in a printf format.
std::string Vec(const Vec3& v, const char* fmt = "%14.8g");

// One discordant position, for the summary and the warning.
// `position_file`: the file of each position when there are several (LoadedInput).
std::string OutlierMessage(const OutlierFinding& o, const std::vector<Position>& positions,
                           const std::vector<double>& errors, const char* unit,
                           const std::vector<std::string>& position_file);

// Shortest round-trip decimal.
std::string FormatNumber(double v);
// A positions file as calibrate reads it: averaged readings with their sample count and the
// per-axis standard deviation of one sample.
std::string PositionsCsv(const std::vector<Vec3>& means, double samples, const Vec3& sample_sigma);

// Three numbers as a JSON array.
nlohmann::ordered_json JsonArray(const Vec3& v);

/// Whether `path` is a directory (or a link to one).
bool IsDirectory(const std::string& path);

/// Why `id` cannot name a unit's directory (batch, store), or "" when it can.
std::string UnitIdProblem(const std::string& id);

/// Options as given (CalibrateArgs::given_options) as a calibration file's `provenance.options`
/// records them: a flag true, one value a string, several a list.
nlohmann::ordered_json GivenOptionsJson(
    const std::vector<std::pair<std::string, std::vector<std::string>>>& given);

// A library message with the names of the options it mentions (the library's field names, as
// Python spells them: c_prefix) replaced by the command line's flags (--c-prefix): the library
// speaks neutrally, the tool names what the user types.
std::string WithFlags(std::string message,
                      std::initializer_list<std::pair<const char*, const char*>> flags);

// A message of the library's readers with the tool's flags for the options it names ("the columns
// option" is --columns).
std::string WithReaderFlags(const std::string& message);

// A warning when the gyroscope's rates are taken at another sensor's temperature (`source`,
// GyroTemperatureSource) than its offsets over temperature were fitted at: one die may run warmer.
void WarnOtherTemperatureSensor(const LoadedCalibration& cal, const std::string& path,
                                const std::string& source, const char* use);

// A calibration whose parameters follow temperature, and a log whose temperature column, found
// by its name, held no temperature in degC (kelvin, counts) and was left out: an InputError
// naming the column, rather than the parameters at T_ref in silence.
void RefuseLeftOutTemperature(const LoadedCalibration& cal, const RawLog& log,
                              const std::string& path);

// A calibration that failed its checks is written so that its reasons can be read, never used.
void RefuseFailed(const LoadedCalibration& cal, const std::string& path);
/// Warns that a calibration whose bias drifted within its session is used with one bias, its
/// value at the drift's reference time, and one whose parameters follow temperature with its
/// parameters at T_ref (`use`: what the command does with it, e.g. "applied").
void WarnVaryingNotUsed(const LoadedCalibration& cal, const std::string& path, const char* use);

// A temperature coefficient (raw units per K^d) in engineering units per K^d: scale in ppm of
// itself, misalignment in µrad, bias in mg, k2 in µg/g² (engineering.hpp), through K's diagonal
// (x-first) and gravity.
struct EngineeringValue {
  double value;
  std::string unit;
};
EngineeringValue ThermalEngineering(const ThermalSlot& slot, double raw, const Mat33& K_x_first,
                                    double gravity);

// Planned directions: a named scheme, or a file with one unit vector per row.
std::vector<Vec3> PlannedDirections(const std::string& spec);

}  // namespace accelcal::cli
