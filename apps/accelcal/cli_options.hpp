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
/// The gyroscope's stream in a binary log (--gyro-topic).
void AddGyroTopic(CLI::App* cmd, InputArgs* in);
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
/// A command reading a gyroscope's log: --gyro names a file, and `gyro_only` come with its rates.
void CheckGyroFlags(const CLI::App& cmd, const std::string& gyro,
                    const std::vector<std::string>& gyro_columns,
                    std::initializer_list<const char*> gyro_only);
/// What calibrate and batch check of calibrate's flags before anything is read.
void CheckCalibrationFlags(const CLI::App& cmd, CalibrateArgs* cal);

}  // namespace accelcal::cli
