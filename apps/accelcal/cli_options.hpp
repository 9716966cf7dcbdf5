#pragma once
// What the commands register their options with (CLI11), each beside its Run (SetUp*,
// commands.hpp): the option groups several commands share, the validators, what a command checks of
// the flags given, and what a calibration file records of them.
#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>

#include "commands.hpp"

namespace accelcal::cli {

/// A file name that names something (`-o ""` is refused).
extern const CLI::Validator kFileName;
/// A PX4 device id: a decimal integer from 1 to 2^32 - 1.
extern const CLI::Validator kDeviceId;
/// A decimal number (CLI11 alone would take hex and binary too).
extern const CLI::Validator kDecimal;

/// How a log is read (--columns, --rate, --time-unit, --instance, --topic, --frame-id,
/// --temperature-column; --input-kind `with_kind`).
void AddInputOptions(CLI::App* cmd, InputArgs* in, bool with_kind);

/// A sensor read beside the accelerometer from a log on the same clock, as the tool names its
/// options: one entry per sensor, from which every command that reads it registers the same
/// flags (--gyro LOG, --gyro-columns, --gyro-topic; calibrate's --gyro-units and --gyro-model)
/// and checks them the same way. A new sensor gets them by one entry.
struct BesideSensor {
  const char* prefix;      ///< of its flags: "gyro" for --gyro, --gyro-columns, ...
  const char* noun;        ///< "gyroscope"
  const char* samples;     ///< what its log holds: "rates"
  const char* ulog_topic;  ///< its usual ULog topic, for the help: "sensor_gyro"
  const char* units_help;  ///< --<prefix>-units: its raw unit's choices, for the start of its fit
  const char* model_help;  ///< --<prefix>-model: its models' choices
  std::string Flag(const char* suffix = "") const { return "--" + std::string(prefix) + suffix; }
};
/// The sensors read beside the accelerometer.
extern const BesideSensor kGyroscopeFlags;

/// Its log, columns and stream in a binary log. `use`: what the command does with its log, after
/// "the <noun>'s log"; `where`: where its columns are, "{log}" standing for its log's flag.
void AddSensorInput(CLI::App* cmd, const BesideSensor& sensor, SensorInput* in,
                    const std::string& use, const std::string& where);
/// Its raw unit (--<prefix>-units) and model (--<prefix>-model), for the commands that fit it.
void AddSensorUnits(CLI::App* cmd, const BesideSensor& sensor, std::string* units);
void AddSensorModel(CLI::App* cmd, const BesideSensor& sensor, std::string* model);
/// What a command reading its log checks of the flags given: its log named by a name, its
/// stream's name not empty, and `only` (the options acting on this sensor alone) given with its
/// samples (its log or columns).
void CheckSensorInput(const CLI::App& cmd, const BesideSensor& sensor, const SensorInput& in,
                      std::initializer_list<const char*> only);
/// The static detection's options (--window, --min-static, --threshold-factor, --init-rest).
void AddDetectionOptions(CLI::App* cmd, InputArgs* in);
/// The screening of positions (--outliers, --outlier-probability, --max-outliers).
void AddOutlierOptions(CLI::App* cmd, OutlierArgs* o, const std::string& policy_help);
/// Gravity at the site and the calibration's unit (--gravity, --latitude, --height, --units).
void AddGravityOptions(CLI::App* cmd, GravityArgs* g);
/// Every option of calibrate but its inputs and outputs: calibrate's and batch's.
void AddCalibrationOptions(CLI::App* cmd, CalibrateArgs* cal);
/// The provenance's date (--date).
void AddDateOption(CLI::App* cmd, CalibrateArgs* cal);

/// The options given to `command` (long names without dashes, their values as typed; none for a
/// flag), in the order the command defines them, but the positional arguments and `skip`.
std::vector<std::pair<std::string, std::vector<std::string>>> GivenOptions(
    const CLI::App& command, std::initializer_list<const char*> skip);
/// What calibrate and batch check of calibrate's flags before anything is read.
void CheckCalibrationFlags(const CLI::App& cmd, CalibrateArgs* cal);

}  // namespace accelcal::cli
