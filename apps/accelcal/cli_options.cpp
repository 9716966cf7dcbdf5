// The pieces the commands register their options with (cli_options.hpp).
#include "cli_options.hpp"

#include <algorithm>
#include <string>

#include "cli_common.hpp"
#include "core/text_format.hpp"

namespace accelcal::cli {

// An output file name must name something: `-o ""` wrote nothing and said nothing (issue 16).
const CLI::Validator kFileName(
    [](std::string& name) { return name.empty() ? std::string("an empty file name") : ""; },
    "FILE");

// A PX4 device id: a decimal integer from 1 to 2^32 - 1, as written ("-1" wrapped to 2^64 - 1).
const CLI::Validator kDeviceId(
    [](std::string& text) {
      const bool digits = !text.empty() && text.size() <= 10 &&
                          text.find_first_not_of("0123456789") == std::string::npos;
      if (digits && std::stoull(text) >= 1 && std::stoull(text) <= 0xFFFFFFFFull)
        return std::string();
      return "a device id is an integer from 1 to 4294967295 (PX4's are 32-bit), not \"" + text +
             "\"";
    },
    "ID");

// A decimal number, as a log's columns hold them: CLI11 would also take hex ("0x10"), binary and
// an empty list item.
const CLI::Validator kDecimal(
    [](std::string& text) {
      std::size_t i = text.find_first_not_of("+-");
      const bool digits = i <= 1 && i < text.size() &&
                          text.find_first_not_of("0123456789.eE+-") == std::string::npos &&
                          text.find_first_of("0123456789") != std::string::npos;
      return digits ? std::string() : "'" + text + "' is not a decimal number";
    },
    "");

void AddInputOptions(CLI::App* cmd, InputArgs* in, bool with_kind) {
  if (with_kind) {
    cmd->add_option("--input-kind", in->input_kind,
                    "raw (samples), positions (one averaged reading per row) or auto")
        ->capture_default_str();
  }
  cmd->add_option("--columns", in->columns,
                  "x,y,z or time,x,y,z: 1-based column numbers or header names")
      ->delimiter(',');
  cmd->add_option("--rate", in->rate_hz,
                  "sample rate [Hz] for logs without a time column (with one, it must agree)");
  cmd->add_option("--time-unit", in->time_unit,
                  "unit of the time column: s, ms, us, ns, or auto (from its name and step)")
      ->capture_default_str();
  cmd->add_option("--instance", in->instance,
                  "the sensor to read from a file that interleaves several (its value in the "
                  "i, instance, multi_id, device_id or imu column; a ULog topic's multi id)");
  cmd->add_option("--topic", in->topic,
                  "the stream to read from a binary log (a ULog topic such as sensor_accel, a "
                  "DataFlash message such as IMU, a ROS 1 or 2 bag's topic; default: its only "
                  "accelerometer stream), or a MAT-file's variable (default: its only matrix)");
  cmd->add_option("--frame-id", in->frame_id,
                  "a ROS topic on which several sensors publish (its messages name several "
                  "header.frame_id): the frame whose messages to read (inspect lists them)");
  cmd->add_option("--temperature-column", in->temperature_column,
                  "the sensor's temperature [degC] with each sample: a column (number or header "
                  "name) or a binary log's field; default: a header column named temperature or "
                  "temp, PX4's sensor_accel.temperature, ArduPilot's IMU.T; none: not read");
}

const BesideSensor kGyroscopeFlags{
    "gyro",
    "gyroscope",
    "rates",
    "sensor_gyro",
    "the gyro's raw unit, for the start of its fit: rad/s, deg/s, or raw (counts: the scale "
    "starts from the turned angles)",
    "linear (K, b), g-sensitive (K, b and a rate bias in proportion to the specific force), or "
    "auto (the one that predicts held-out rotations better)"};

void AddSensorInput(CLI::App* cmd, const BesideSensor& sensor, SensorInput* in,
                    const std::string& use, const std::string& where) {
  const std::string noun = sensor.noun;
  cmd->add_option(sensor.Flag(), in->log, "the " + noun + "'s log" + use);
  cmd->add_option(sensor.Flag("-columns"), in->columns,
                  "the " + noun + "'s x,y,z (or time,x,y,z) columns, " +
                      internal::ReplaceWords(where, {{"{log}", sensor.Flag().c_str()}}))
      ->delimiter(',');
  cmd->add_option(sensor.Flag("-topic"), in->topic,
                  "the " + noun + "'s stream in a binary log (a ULog topic such as " +
                      sensor.ulog_topic + "; default: its only " + noun +
                      " stream, of --instance when given)");
}

void AddSensorUnits(CLI::App* cmd, const BesideSensor& sensor, std::string* units) {
  cmd->add_option(sensor.Flag("-units"), *units, sensor.units_help)->capture_default_str();
}

void AddSensorModel(CLI::App* cmd, const BesideSensor& sensor, std::string* model) {
  cmd->add_option(sensor.Flag("-model"), *model, sensor.model_help)->capture_default_str();
}

void CheckSensorInput(const CLI::App& cmd, const BesideSensor& sensor, const SensorInput& in,
                      std::initializer_list<const char*> only) {
  if (cmd.count(sensor.Flag()) > 0 && in.log.empty()) {
    throw UsageError(sensor.Flag() + ": the file name is empty");
  }
  if (cmd.count(sensor.Flag("-topic")) > 0 && in.topic.empty()) {
    throw UsageError(sensor.Flag("-topic") + ": an empty topic name");
  }
  if (in.given()) return;
  std::vector<std::string> acting{sensor.Flag("-topic")};
  acting.insert(acting.end(), only.begin(), only.end());
  for (const std::string& name : acting) {
    if (cmd.count(name) > 0) {
      throw UsageError(name + " applies to the " + sensor.noun + ": give its " + sensor.samples +
                       " with " + sensor.Flag() + " LOG or " + sensor.Flag("-columns"));
    }
  }
}

void AddDetectionOptions(CLI::App* cmd, InputArgs* in) {
  auto& d = in->detection;
  cmd->add_option("--window", d.window_s, "static detection: variance window [s]")
      ->capture_default_str();
  cmd->add_option("--min-static", d.min_duration_s, "static detection: shortest interval [s]")
      ->capture_default_str();
  cmd->add_option("--threshold-factor", d.threshold_factor,
                  "static detection: threshold as a multiple of the noise reference")
      ->capture_default_str();
  cmd->add_option("--init-rest", d.init_rest_s,
                  "static detection: take the noise reference from the first S seconds (0: "
                  "from the quietest windows)")
      ->capture_default_str();
}

void AddOutlierOptions(CLI::App* cmd, OutlierArgs* o, const std::string& policy_help) {
  cmd->add_option("--outliers", o->policy, policy_help)->capture_default_str();
  cmd->add_option("--outlier-probability", o->probability,
                  "chance that a calibration whose positions all agree loses one to the test")
      ->capture_default_str();
  cmd->add_option("--max-outliers", o->max_excluded,
                  "most positions the screening may leave out (a warning says when reached)")
      ->capture_default_str();
}

void AddGravityOptions(CLI::App* cmd, GravityArgs* g) {
  auto* gravity = cmd->add_option("--gravity", g->gravity_ms2,
                                  "local gravity magnitude [m/s2] (default 9.80665)");
  auto* latitude = cmd->add_option("--latitude", g->latitude_deg,
                                   "geodetic latitude [deg]: gravity from the WGS-84 formula");
  gravity->excludes(latitude);
  cmd->add_option("--height", g->height_m, "height above the ellipsoid [m], with --latitude")
      ->needs(latitude);
  cmd->add_option("--units", g->units, "unit of the calibrated specific force: m/s2 or g")
      ->capture_default_str();
}

// What calibrate computes from its inputs: every option of calibrate but its inputs and outputs,
// shared by batch, which passes them to each unit's calibrate as given.
void AddCalibrationOptions(CLI::App* cmd, CalibrateArgs* cal) {
  AddInputOptions(cmd, &cal->input, true);
  AddDetectionOptions(cmd, &cal->input);
  AddGravityOptions(cmd, &cal->gravity);
  cmd->add_option("--model", cal->model,
                  "linear, quadratic, or auto (the model that predicts held-out positions "
                  "better)")
      ->capture_default_str();
  cmd->add_option("--bias-model", cal->bias_model,
                  "the bias over the session: constant, linear (a drift), spline:K (K knots "
                  "over the session), or auto (the one that predicts held-out positions "
                  "best); each position at the middle of its still interval")
      ->capture_default_str();
  CLI::Option* random_walk =
      cmd->add_option("--bias-random-walk", cal->bias_random_walk,
                      "with --bias-model spline:K or auto: the bias's random walk "
                      "[m/s^2/sqrt(s)], one value or x,y,z, the prior that lets many knots "
                      "follow a wandering bias")
          ->expected(1, 3)
          ->delimiter(',')
          ->type_name("Q[,Q,Q]");
  cmd->add_option("--noise", cal->noise,
                  "instead of --bias-random-walk: the accelerometer's random walk from "
                  "`accelcal noise --json` (calibrated; its 95% upper bound where the log "
                  "does not resolve it)")
      ->type_name("FILE")
      ->excludes(random_walk);
  cmd->add_option("--thermal", cal->thermal,
                  "parameters that follow temperature: the degrees in T - T_ref of K and b "
                  "(and k2 for the quadratic model), e.g. 1,1, or auto (chosen by held-out "
                  "error); from several files at different temperatures or one ramp")
      ->type_name("K,B[,K2]|auto");
  cmd->add_option("--temperatures", cal->temperatures_c,
                  "with --thermal: one temperature [degC] per input file, for logs without "
                  "their own (see --temperature-column)")
      ->delimiter(',')
      ->check(kDecimal)
      ->type_name("T[,T...]");
  cmd->add_option("--method", cal->method,
                  "joint, two-step, newton-lagrange, modulus, modulus-norm or ellipsoid")
      ->capture_default_str();
  cmd->add_option("--init", cal->init, "auto, ellipsoid or normalized-readings")
      ->capture_default_str();
  cmd->add_option("--frame", cal->frame,
                  "body frame of the result: x-first (body x = sensor x, K lower-triangular, "
                  "paper 000) or z-first (body z = sensor z, K upper-triangular, paper 001, "
                  "imu_tk)")
      ->capture_default_str();
  cmd->add_option("--estimator", cal->estimator,
                  "ml (maximum likelihood) or bias-corrected (removes the bias of order "
                  "sigma^2/g that ML has at MEMS noise levels; same covariance)")
      ->capture_default_str();
  AddOutlierOptions(cmd, &cal->outliers,
                    "a position that disagrees with the others (moved or bumped during its "
                    "interval): exclude it with a warning, flag it only, or off");
  cmd->add_option("--orientations", cal->orientations,
                  "known orientation of every position, in order (a file of directions or "
                  "attitudes, as for design): full misalignment in the platform frame, "
                  "paper 003");
  AddSensorInput(cmd, kGyroscopeFlags, &cal->gyro,
                 ", recorded with the accelerometer on the same clock (a rate sample at each "
                 "accelerometer sample's time): calibrates it too",
                 "in INPUT itself or in the {log} log: 1-based column numbers or header names");
  AddSensorUnits(cmd, kGyroscopeFlags, &cal->gyro_units);
  AddSensorModel(cmd, kGyroscopeFlags, &cal->gyro_model);
  cmd->add_option(
      "--gyro-estimator", cal->gyro_estimator,
      "joint (both sensors and every gravity direction in one fit: the rotations "
      "also calibrate the accelerometer; the default), two-stage (the "
      "accelerometer's calibration held; the default with --orientations, whose "
      "directions are known, and with --thermal), or imutk (imu_tk's method, a baseline: the "
      "bias from the "
      "first still position, K from the turns, no g-sensitivity)");
  cmd->add_option("--gyro-thermal", cal->gyro_thermal,
                  "with --thermal: the degree in T - T_ref of the gyroscope's offsets (0 to 3), "
                  "or auto (chosen by the still positions' held-out rates; the default)")
      ->type_name("D|auto");
  cmd->add_flag("!--no-crossval", cal->cross_validate,
                "skip the leave-one-position-out validation (one refit per position)");
  cmd->add_option("--raw-units", cal->raw_units, "label of the raw unit (e.g. counts)")
      ->capture_default_str();
  cmd->add_option("--max-iterations", cal->max_iterations,
                  "iteration cap of the solver (0: its default)");
}

void AddDateOption(CLI::App* cmd, CalibrateArgs* cal) {
  cmd->add_option("--date", cal->date,
                  "a date for the file's provenance (YYYY-MM-DD[THH:MM[:SS]Z]); without it none "
                  "is written, so the same input gives the same bytes");
}

// The options given to `command` (long names without dashes, with their values as typed; none for
// a flag), in the order the command defines them, except the positional arguments and `skip`:
// what a calibration file's provenance records.
std::vector<std::pair<std::string, std::vector<std::string>>> GivenOptions(
    const CLI::App& command, std::initializer_list<const char*> skip) {
  std::vector<std::pair<std::string, std::vector<std::string>>> given;
  for (const CLI::Option* option : command.get_options()) {
    if (option->count() == 0 || option->get_lnames().empty()) continue;
    const std::string name = option->get_lnames().front();
    if (std::find(skip.begin(), skip.end(), name) != skip.end() || name == "help") continue;
    given.emplace_back(
        name, option->get_expected_min() == 0 ? std::vector<std::string>() : option->results());
  }
  return given;
}

// What calibrate and batch check of calibrate's options before anything is read, and which of
// them were given.
void CheckCalibrationFlags(const CLI::App& cmd, CalibrateArgs* cal) {
  CheckSensorInput(cmd, kGyroscopeFlags, cal->gyro,
                   {"--gyro-units", "--gyro-model", "--gyro-estimator", "--gyro-thermal"});
  if (cmd.count("--gyro-thermal") > 0 && cal->gyro_thermal.empty()) {
    throw UsageError("--gyro-thermal: '' is neither auto nor a degree from 0 to 3");
  }
  for (const char* name : {"--method", "--init", "--frame", "--estimator", "--max-iterations",
                           "--bias-model", "--bias-random-walk", "--noise"}) {
    if (cmd.count(name) > 0) cal->gravity_only_options.emplace_back(name);
  }
  cal->date_given = cmd.count("--date") > 0;
}

}  // namespace accelcal::cli
