// accelcal: command-line front end. Parses arguments, calls the library, maps errors to exit codes
// (RunCommandLine: main.cpp, and the option-parsing fuzzer, fuzz/fuzz_cli_options.cpp).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <exception>
#include <sstream>
#include <string_view>
#include <vector>

#include <CLI/CLI.hpp>

#include "accelcal/error.hpp"
#include "accelcal/version.hpp"
#include "cli_common.hpp"
#include "commands.hpp"
#include "output.hpp"

namespace {

using namespace accelcal::cli;

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

// The gyroscope's stream in a binary log, for the commands that read its rates (--gyro).
void AddGyroTopic(CLI::App* cmd, InputArgs* in) {
  cmd->add_option("--gyro-topic", in->gyro_topic,
                  "the gyroscope's stream in a binary log (a ULog topic such as sensor_gyro; "
                  "default: its only gyroscope stream, of --instance when given)");
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
  cmd->add_option("--gyro", cal->gyro,
                  "the gyroscope's log, recorded with the accelerometer on the same clock "
                  "(a rate sample at each accelerometer sample's time): calibrates it too");
  cmd->add_option("--gyro-columns", cal->gyro_columns,
                  "the gyroscope's x,y,z (or time,x,y,z) columns, in INPUT itself or in the "
                  "--gyro log: 1-based column numbers or header names")
      ->delimiter(',');
  AddGyroTopic(cmd, &cal->input);
  cmd->add_option("--gyro-units", cal->gyro_units,
                  "the gyro's raw unit, for the start of its fit: rad/s, deg/s, or raw "
                  "(counts: the scale starts from the turned angles)")
      ->capture_default_str();
  cmd->add_option("--gyro-model", cal->gyro_model,
                  "linear (K, b), g-sensitive (K, b and a rate bias in proportion to the "
                  "specific force), or auto (the one that predicts held-out rotations better)")
      ->capture_default_str();
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

// The first argument that names a command, or "" when none does (a command missing from this
// list is only slower to start: every command's options are then set up).
std::string ChosenCommand(int argc, char** argv) {
  static constexpr const char* kCommands[] = {
      "calibrate",  "batch",        "store",  "compare",  "detect", "inspect", "noise",  "design",
      "montecarlo", "system-level", "gimbal", "simulate", "apply",  "report",  "export", "verify"};
  for (int i = 1; i < argc; ++i) {
    for (const char* command : kCommands) {
      if (std::string_view(argv[i]) == command) return command;
    }
  }
  return "";
}

// CLI11's help and version, through the tool's console.
int ExitWith(const CLI::App& app, const CLI::Error& e) {
  std::ostringstream out, err;
  const int status = app.exit(e, out, err);
  WriteOut(out.str());
  WriteErr(err.str());
  return status;
}

// Every command's options as JSON, for the Python package (accelcal.cli), which makes a function of
// each command from it: the tool's own definitions, so that the functions cannot drift from them.
std::string DescribeOptions(const CLI::App& app) {
  using Json = nlohmann::ordered_json;
  const auto describe = [](const CLI::Option* opt) {
    Json o;
    const bool positional = !opt->nonpositional();
    o["name"] = positional ? opt->get_name() : opt->get_lnames().front();
    o["positional"] = positional;
    o["flag"] = opt->get_expected_max() == 0;
    o["description"] = opt->get_description();
    o["default"] = opt->get_default_str().empty() ? Json() : Json(opt->get_default_str());
    o["required"] = opt->get_required();
    o["many"] = opt->get_items_expected_max() > 1;
    o["delimiter"] =
        opt->get_delimiter() == '\0' ? Json() : Json(std::string(1, opt->get_delimiter()));
    return o;
  };
  Json doc;
  doc["version"] = std::string(accelcal::Version());
  Json& global = doc["options"] = Json::array();
  for (const CLI::Option* opt : app.get_options()) {
    if (opt->get_lnames().empty() || opt->get_lnames().front() == "help" ||
        opt->get_lnames().front() == "version") {
      continue;
    }
    global.push_back(describe(opt));
  }
  Json& commands = doc["commands"] = Json::array();
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; })) {
    Json c;
    c["name"] = sub->get_name();
    c["description"] = sub->get_description();
    Json& options = c["options"] = Json::array();
    for (const CLI::Option* opt : sub->get_options()) {
      if (!opt->get_lnames().empty() && opt->get_lnames().front() == "help") continue;
      options.push_back(describe(opt));
    }
    commands.push_back(std::move(c));
  }
  return accelcal::JsonText(doc);
}

// What a command that reads a gyroscope's log checks of its flags: a --gyro given names a file,
// and the options that only act on the gyro (`gyro_only`) come with its rates.
void CheckGyroFlags(const CLI::App& cmd, const std::string& gyro,
                    const std::vector<std::string>& gyro_columns,
                    std::initializer_list<const char*> gyro_only) {
  if (cmd.count("--gyro") > 0 && gyro.empty()) {
    throw accelcal::cli::UsageError("--gyro: the file name is empty");
  }
  if (!gyro.empty() || !gyro_columns.empty()) return;
  if (cmd.count("--gyro-topic") > 0) {
    throw accelcal::cli::UsageError(
        "--gyro-topic applies to the gyroscope: give its rates with --gyro LOG or --gyro-columns");
  }
  for (const char* name : gyro_only) {
    if (cmd.count(name) > 0) {
      throw accelcal::cli::UsageError(std::string(name) +
                                      " applies to the gyroscope: give its rates with --gyro LOG "
                                      "or --gyro-columns");
    }
  }
}

// What calibrate and batch check of calibrate's options before anything is read, and which of
// them were given.
void CheckCalibrationFlags(const CLI::App& cmd, CalibrateArgs* cal) {
  CheckGyroFlags(cmd, cal->gyro, cal->gyro_columns,
                 {"--gyro-units", "--gyro-model", "--gyro-estimator", "--gyro-thermal"});
  if (cmd.count("--gyro-thermal") > 0 && cal->gyro_thermal.empty()) {
    throw accelcal::cli::UsageError("--gyro-thermal: '' is neither auto nor a degree from 0 to 3");
  }
  for (const char* name : {"--method", "--init", "--frame", "--estimator", "--max-iterations",
                           "--bias-model", "--bias-random-walk", "--noise"}) {
    if (cmd.count(name) > 0) cal->gravity_only_options.emplace_back(name);
  }
  cal->date_given = cmd.count("--date") > 0;
}

}  // namespace

int accelcal::cli::RunCommandLineCaptured(const std::vector<std::string>& args, std::string* out,
                                          std::string* err, std::vector<CapturedFile>* files,
                                          const CalibrateRunner& runner) {
  // The host program's locale may write a decimal comma (Python's locale.setlocale): the
  // command reads its options and writes its numbers in "C", in this thread only.
  const accelcal::internal::ClassicLocale c_locale;
  struct Restore {  // this thread's console and verbosity as they were, however it ends
    Console console;
    Verbosity verbosity;
    ~Restore() {
      SetConsole(console);
      SetVerbosity(verbosity);
    }
  } restore{SetConsole({out, err, files}), CurrentVerbosity()};
  std::vector<std::string> copies = args;
  std::vector<char*> argv;
  for (std::string& a : copies) argv.push_back(a.data());
  argv.push_back(nullptr);
  return RunCommandLine(static_cast<int>(copies.size()), argv.data(), runner);
}

int accelcal::cli::RunCommandLine(int argc, char** argv, const CalibrateRunner& runner) {
  CLI::App app{
      "accelcal: calibration of triaxial accelerometers from static multi-position recordings"};
  app.require_subcommand(1);
  app.fallthrough();  // --quiet and --verbose may also follow the subcommand
  app.set_version_flag("--version", "accelcal " + std::string(accelcal::Version()));

  // Only the chosen command's options are set up (CLI11 builds each option's parser and help at
  // once): every command when none is named (then the tool's help or error lists them all).
  const std::string chosen = ChosenCommand(argc, argv);
  const auto Wanted = [&](const CLI::App* command) {
    return chosen.empty() || chosen == command->get_name();
  };
  CalibrateArgs cal;
  CLI::App* calibrate =
      app.add_subcommand("calibrate", "estimate K, b (and k2) from a raw log or a positions file");
  std::vector<std::string> calibrate_inputs;
  if (Wanted(calibrate)) {
    calibrate
        ->add_option("INPUT", calibrate_inputs,
                     "raw logs or positions files (several: sessions of one device, positions "
                     "pooled; - reads standard input)")
        ->required();
    AddCalibrationOptions(calibrate, &cal);
    calibrate->add_option("-o,--output", cal.output, "write the calibration file (JSON) here")
        ->check(kFileName);
    calibrate
        ->add_option("--report", cal.report,
                     "write the HTML report here (self-contained: plots, parameters, warnings)")
        ->check(kFileName);
    AddDateOption(calibrate, &cal);
    calibrate->add_flag("--json", cal.json,
                        "print the calibration file to stdout instead of the summary");
  }

  BatchArgs bat;
  CalibrateArgs bat_cal;  // the calibrate options batch takes, passed on as given
  CLI::App* batch = app.add_subcommand(
      "batch",
      "a production line: calibrate many units as calibrate would, judge each against limits, "
      "and tabulate them (units in parallel; a unit whose calibration is current is not redone)");
  if (Wanted(batch)) {
    batch
        ->add_option("INPUT", bat.inputs,
                     "the units' recordings: files, and directories whose files are read")
        ->required();
    batch
        ->add_option("-o,--output", bat.output,
                     "the batch's directory: units/ID/calibration.json and report.html, "
                     "summary.csv and summary.json (made when missing)")
        ->required()
        ->check(kFileName);
    batch
        ->add_option("--limits", bat.limits,
                     "acceptance limits (YAML, docs/batch.md); without: a unit passes when its "
                     "calibration passes its own checks")
        ->check(kFileName);
    batch
        ->add_option("--unit-id", bat.unit_id,
                     "a regular expression searched in each file's name: its first group (or "
                     "the match) is the unit's id; files with one id are one unit's sessions "
                     "(default: the name less its extension)")
        ->type_name("REGEX");
    batch
        ->add_option("--unit-id-from", bat.unit_id_from,
                     "where a unit's id comes from: name (the file's, see --unit-id), info:KEY (a "
                     "binary log's information, e.g. info:sys_uuid, a PX4 board's), param:KEY (a "
                     "log's parameter, e.g. param:BRD_SERIAL_NUM, an ArduPilot board's), "
                     "device-id (the accelerometer stream's: the same on every board of a "
                     "design, see docs/batch.md), or frame-id (a ROS Imu topic's "
                     "header.frame_id, where each unit's frame has its own name)")
        ->capture_default_str();
    batch->add_option("--glob", bat.glob, "the files read from a directory given")
        ->capture_default_str();
    batch->add_option("--jobs", bat.jobs, "units calibrated at once (0: one per core)")
        ->capture_default_str();
    batch->add_flag("--redo", bat.redo,
                    "calibrate every unit again, even one whose calibration is current");
    batch->add_flag("!--no-report", bat.report, "no HTML report per unit");
    batch->add_flag("--json", bat.json, "print the summary document instead of the table");
    AddCalibrationOptions(batch, &bat_cal);
    AddDateOption(batch, &bat_cal);
  }

  StoreArgs sto;
  CLI::App* store = app.add_subcommand(
      "store",
      "a store of calibrations by unit and date: store add STORE CAL.json|BATCH_DIR..., store get "
      "STORE UNIT, store list STORE [UNIT]; each calibration added is compared with the unit's "
      "one before it within their covariances");
  if (Wanted(store)) {
    store->add_option("ACTION", sto.action, "add, get or list")->required();
    store->add_option("STORE", sto.store, "the store's directory (made by the first add)")
        ->required()
        ->check(kFileName);
    store->add_option("ITEMS", sto.items,
                      "add: calibration files, or batch directories (their passing units); get: "
                      "the unit; list: a unit (default: every unit)");
    store->add_option("--unit", sto.unit,
                      "add: the unit of the calibration files given (a batch directory names "
                      "its own; with one, only that unit is added)");
    store->add_option("--date", sto.date,
                      "add: the date of calibrations whose provenance has none (default: today, "
                      "UTC); get: the calibration of that date (YYYY-MM-DD: its latest that day; "
                      "default: the unit's latest)");
    store->add_option("-o,--output", sto.output, "get: write the calibration file here")
        ->check(kFileName);
    store->add_flag("--json", sto.json, "list: the index's entries; add: what was added");
    store
        ->add_option("--bias-repeatability", sto.bias_repeatability,
                     "add: the accelerometer's turn-on bias repeatability (1 sigma, in the "
                     "calibrations' specific-force unit; one value or x,y,z: a MEMS part's bias "
                     "moves between power-ups by more than a calibration's covariance holds)")
        ->expected(1, 3)
        ->delimiter(',')
        ->check(kDecimal)
        ->type_name("Q[,Q,Q]");
  }

  CompareArgs cmp;
  CLI::App* compare = app.add_subcommand(
      "compare", "run several calibration methods on the same data and tabulate them");
  if (Wanted(compare)) {
    compare->add_option("INPUT", cmp.input.path, "raw log or positions file")->required();
    AddInputOptions(compare, &cmp.input, true);
    AddDetectionOptions(compare, &cmp.input);
    AddGravityOptions(compare, &cmp.gravity);
    compare->add_option("--model", cmp.model, "linear or quadratic")->capture_default_str();
    compare->add_option("--methods", cmp.methods, "comma-separated (default: all for the model)")
        ->delimiter(',');
    compare->add_option("--init", cmp.init, "auto, ellipsoid or normalized-readings")
        ->capture_default_str();
    compare->add_flag("!--no-held-out", cmp.leave_one_out, "skip the leave-one-position-out fits");
    AddOutlierOptions(compare, &cmp.outliers,
                      "screen the positions once (maximum-likelihood fit) and fit every method to "
                      "the same ones: exclude a disagreeing position, flag it only, or off");
    compare->add_option("--reference", cmp.reference,
                        "a known calibration (JSON): adds paper 001's e_T and e_b per method");
    compare->add_flag("--json", cmp.json, "machine-readable output");
    compare->add_option("--gyro", cmp.gyro,
                        "the gyroscope's log on the same clock: compare its estimators too "
                        "(imu_tk's method, two-stage and joint, linear and g-sensitive)");
    compare
        ->add_option("--gyro-columns", cmp.gyro_columns,
                     "the gyroscope's x,y,z (or time,x,y,z) columns, in INPUT or the --gyro log")
        ->delimiter(',');
    AddGyroTopic(compare, &cmp.input);
    compare
        ->add_option("--gyro-units", cmp.gyro_units,
                     "the gyro's raw unit, for the start of its fits: rad/s, deg/s, or raw")
        ->capture_default_str();
  }

  DetectArgs det;
  CLI::App* detect = app.add_subcommand("detect", "list the static intervals of a raw log");
  if (Wanted(detect)) {
    detect->add_option("LOG", det.input.path, "raw log")->required();
    AddInputOptions(detect, &det.input, false);
    AddDetectionOptions(detect, &det.input);
    detect->add_flag("--json", det.json, "machine-readable output");
  }

  InspectArgs ins;
  CLI::App* inspect = app.add_subcommand(
      "inspect",
      "what a binary log (PX4 ULog, ArduPilot DataFlash, ROS 1 or 2 bag, MAT-file) holds: its "
      "streams, rates, parameters");
  if (Wanted(inspect)) {
    inspect->add_option("LOG", ins.path, "binary log")->required();
    inspect->add_flag("--json", ins.json, "machine-readable output");
  }

  NoiseArgs noi;
  CLI::App* noise = app.add_subcommand(
      "noise", "the Allan deviation of a still log and its noise terms (IEEE Std 952)");
  if (Wanted(noise)) {
    noise->add_option("LOG", noi.input.path, "raw log of the sensor held still")->required();
    AddInputOptions(noise, &noi.input, false);
    AddDetectionOptions(noise, &noi.input);
    noise->add_option(
        "--calibration", noi.calibration,
        "calibration file (JSON): the samples calibrated first (else the log's unit)");
    noise->add_option("--gyro", noi.gyro, "the gyroscope's log on the same clock: its noise too");
    noise
        ->add_option("--gyro-columns", noi.gyro_columns,
                     "the gyroscope's x,y,z (or time,x,y,z) columns, in LOG or the --gyro log")
        ->delimiter(',');
    AddGyroTopic(noise, &noi.input);
    noise->add_flag("--still", noi.still,
                    "only the longest still interval of the log (a calibration log's rest)");
    noise->add_flag("--json", noi.json, "machine-readable output");
    noise
        ->add_option("--report", noi.report,
                     "HTML report: the Allan deviation plotted with its bands and the fit")
        ->check(kFileName);
    noise->add_option("-o,--output", noi.output, "output file (default: stdout)")->check(kFileName);
  }

  DesignArgs des;
  CLI::App* design = app.add_subcommand(
      "design", "predict the 1-sigma of every parameter (Cramer-Rao bound) for planned positions");
  if (Wanted(design)) {
    design
        ->add_option("--positions", des.positions,
                     "yang18, six, random:N[:SEED], or a file of unit directions (x,y,z) or "
                     "attitudes (roll_deg,pitch_deg[,yaw_deg] or qw,qx,qy,qz; body to level, z up)")
        ->required();
    design->add_option("--device", des.device, "calibration file of the nominal device")
        ->required();
    design
        ->add_option("--noise", des.noise_raw,
                     "1 sigma of one averaged reading in raw units: one value or three (x,y,z)")
        ->delimiter(',')
        ->expected(1, 3);
    design
        ->add_option("--temperatures", des.temperatures_c,
                     "plan a temperature schedule: the positions recorded at each of these "
                     "temperatures [degC], comma-separated")
        ->delimiter(',')
        ->check(kDecimal);
    design
        ->add_option("--thermal-degrees", des.thermal_degrees,
                     "with --temperatures: the degrees in T - T_ref of K and b (and k2 for the "
                     "quadratic model), e.g. 1,1")
        ->delimiter(',')
        ->expected(2, 3)
        ->type_name("K,B[,K2]")
        ->capture_default_str();
    design
        ->add_option("--thermal-target", des.thermal_target,
                     "with --temperatures: 1 sigma targets of the coefficients per K, of K in "
                     "ppm/K (urad/K off the diagonal) and of b in mg/K; says how many "
                     "temperatures over the same span reach them")
        ->delimiter(',')
        ->expected(1, 2)
        ->type_name("S[,B]");
    design->add_option("--noise-density", des.noise_density_ug,
                       "instead of --noise: white noise [ug/sqrt(Hz)], with --rate and --duration");
    design->add_option("--rate", des.rate_hz, "sample rate [Hz], with --noise-density");
    design->add_option("--duration", des.duration_s,
                       "still time per position [s], with --noise-density");
    design->add_option("--model", des.model, "linear or quadratic (default: the device's)");
    design
        ->add_option("--bias-model", des.bias_model,
                     "linear or spline:K: what fitting a drifting bias costs the positions, "
                     "recorded in the order given, one a minute")
        ->capture_default_str();
    design->add_option(
        "--choose", des.choose,
        "choose this many of the positions (the candidates) by --criterion; compared "
        "with paper 000's yang18");
    design
        ->add_option(
            "--criterion", des.criterion,
            "with --choose: d (maximise det of the information, D-optimal) or a (minimise "
            "the trace of the CRLB, parameters in the device's relative metric, A-optimal)")
        ->capture_default_str();
    design->add_flag("--json", des.json, "machine-readable output");
  }

  MonteCarloArgs mc;
  CLI::App* montecarlo = app.add_subcommand(
      "montecarlo", "simulate a scenario many times: errors against the Cramer-Rao bound");
  if (Wanted(montecarlo)) {
    montecarlo
        ->add_option("--scenario", mc.scenario,
                     "yang2012 (paper 000 Table 3/4) or sunxu2020 (paper 001 section 4.1)")
        ->capture_default_str();
    montecarlo->add_option("--runs", mc.runs, "number of runs")->capture_default_str();
    montecarlo->add_option("--method", mc.method, "joint, two-step or newton-lagrange")
        ->capture_default_str();
    montecarlo->add_option("--estimator", mc.estimator, "ml or bias-corrected")
        ->capture_default_str();
    montecarlo->add_option("--seed", mc.seed, "seed of the first run's noise")
        ->capture_default_str();
    montecarlo->add_option("--threads", mc.threads, "threads (0: all cores)")
        ->capture_default_str();
    montecarlo->add_flag("--residual-noise", mc.residual_noise,
                         "covariance from the residuals instead of the known noise");
    montecarlo->add_flag("--json", mc.json, "machine-readable output");
  }

  SystemLevelArgs sys;
  CLI::App* system_level = app.add_subcommand(
      "system-level",
      "paper 003 stage 3: residual accelerometer errors of a space-stable INS from a day of "
      "specific-force and attitude errors on a static, level base");
  if (Wanted(system_level)) {
    system_level->add_option("SERIES", sys.series, "series file (binary or t,fx,fy,fz,roll,pitch)")
        ->required();
    system_level->add_option("--latitude", sys.latitude_deg, "latitude of the base [deg]")
        ->required();
    system_level->add_option("--gravity", sys.gravity_ms2,
                             "local gravity [m/s2] (default: WGS-84 normal gravity)");
    system_level->add_flag("--json", sys.json, "machine-readable output");
  }

  GimbalArgs gim;
  CLI::App* gimbal = app.add_subcommand(
      "gimbal",
      "paper 003 stages 1-2: accelerometer on a three-gimbal platform, coarse (gimbal zero "
      "offsets) and fine (squared-amplitude) device-level calibration");
  if (Wanted(gimbal)) {
    gimbal
        ->add_option("COARSE", gim.coarse,
                     "commanded gimbal angles and mean output per position: "
                     "theta1_deg,theta2_deg,theta3_deg,ax,ay,az (Table 1's 18 positions)")
        ->required();
    gimbal->add_option("--fine", gim.fine,
                       "mean outputs ax,ay,az of the fine stage's positions, measured after "
                       "re-zeroing the gimbals by the coarse offsets");
    AddGravityOptions(gimbal, &gim.gravity);
    gimbal->add_flag("--json", gim.json, "machine-readable output");
  }

  SimulateArgs sim;
  CLI::App* simulate = app.add_subcommand(
      "simulate", "write a simulated recording (raw log or positions file) of a known device");
  if (Wanted(simulate)) {
    simulate->add_option(
        "--scenario", sim.scenario,
        "yang2012: paper 000's device, 18 positions, 10 ug/sqrt(Hz), 100 Hz, 60 s; "
        "sunxu2020: paper 001's, 300 Gaussian attitudes, 0.1 g per position; "
        "wu2018-system: paper 003's system-level series (Tables 2-3, 40 deg, "
        "5e-3 m/s2, 100 Hz, 24 h; binary, -o required)");
    simulate->add_option("--truth", sim.truth, "calibration file of the simulated device");
    simulate->add_option("--positions", sim.positions,
                         "yang18, six, random:N[:SEED], or a file of unit directions or attitudes "
                         "(as for design)");
    simulate->add_option("--noise-density", sim.noise_density_ug, "white noise [ug/sqrt(Hz)]");
    simulate->add_option("--rate", sim.rate_hz, "sample rate [Hz]")->capture_default_str();
    simulate->add_option("--duration", sim.duration_s, "still time per position [s]")
        ->capture_default_str();
    simulate->add_option("--transition", sim.transition_s, "turning time between positions [s]")
        ->capture_default_str();
    simulate->add_option("--seed", sim.seed, "noise seed")->capture_default_str();
    simulate->add_flag("--raw", sim.raw, "write a raw log (time,x,y,z) instead of positions");
    simulate->add_flag("!--positions-out", sim.raw,
                       "write a positions file x,y,z,n,sx,sy,sz (the default)");
    simulate
        ->add_option("--format", sim.format,
                     "of a raw log: csv (time,x,y,z), ulog (PX4's sensor_accel), dataflash "
                     "(ArduPilot's IMU records), both float32; rosbag (ROS 1 bag, "
                     "sensor_msgs/Imu), mcap (ROS 2, zstd chunks) or db3 (ROS 2 SQLite), each "
                     "/imu/data stamped from 0 s; or mat (MATLAB v5: a 4 x N matrix imu of "
                     "time, x, y, z per column)")
        ->capture_default_str();
    simulate->add_option("-o,--output", sim.output, "output file (default: stdout)")
        ->check(kFileName);
  }

  ApplyArgs apply;
  CLI::App* apply_cmd =
      app.add_subcommand("apply", "write the calibrated specific force of every sample of a log");
  if (Wanted(apply_cmd)) {
    apply_cmd->add_option("CAL", apply.calibration, "calibration file (JSON)")->required();
    apply_cmd->add_option("LOG", apply.input.path, "raw log")->required();
    AddInputOptions(apply_cmd, &apply.input, false);
    apply_cmd->add_option("-o,--output", apply.output, "output file (default: stdout)")
        ->check(kFileName);
    apply_cmd->add_option("--units", apply.units,
                          "output unit m/s2 or g (default: the calibration's)");
    apply_cmd->add_option("--gyro", apply.gyro,
                          "the gyroscope's log on the same clock: its body rates [rad/s] too");
    apply_cmd
        ->add_option("--gyro-columns", apply.gyro_columns,
                     "the gyroscope's x,y,z (or time,x,y,z) columns, in LOG or the --gyro log")
        ->delimiter(',');
    AddGyroTopic(apply_cmd, &apply.input);
  }

  VerifyArgs ver;
  CLI::App* verify = app.add_subcommand(
      "verify", "check a calibration on a new recording of the same unit (exit 6 when it fails)");
  if (Wanted(verify)) {
    verify->add_option("CAL", ver.calibration, "calibration file (JSON)")->required();
    verify->add_option("LOG", ver.input.path, "a new raw log: still positions with turns between")
        ->required();
    AddInputOptions(verify, &ver.input, false);
    AddDetectionOptions(verify, &ver.input);
    auto* gravity = verify->add_option("--gravity", ver.gravity.gravity_ms2,
                                       "this site's gravity [m/s2] (default: the calibration's)");
    auto* latitude = verify->add_option("--latitude", ver.gravity.latitude_deg,
                                        "this site's latitude [deg]: gravity from WGS-84");
    gravity->excludes(latitude);
    verify->add_option("--height", ver.gravity.height_m, "height above the ellipsoid [m]")
        ->needs(latitude);
    verify
        ->add_option("--temperature", ver.temperature_c,
                     "the log's temperature [degC], for a calibration whose parameters follow "
                     "temperature and a log without its own (as calibrate's --temperatures)")
        ->check(kDecimal);
    verify->add_option("--gyro", ver.gyro,
                       "the gyroscope's log on the same clock: its turns verified too");
    verify
        ->add_option("--gyro-columns", ver.gyro_columns,
                     "the gyroscope's x,y,z (or time,x,y,z) columns, in LOG or the --gyro log")
        ->delimiter(',');
    AddGyroTopic(verify, &ver.input);
    verify->add_flag("--json", ver.json, "machine-readable output");
    verify->add_option("-o,--output", ver.output, "output file (default: stdout)")
        ->check(kFileName);
  }

  ReportArgs rep;
  CLI::App* report_cmd = app.add_subcommand(
      "report", "write the HTML report of a calibration file (and its raw log, when given)");
  if (Wanted(report_cmd)) {
    report_cmd->add_option("CAL", rep.calibration, "calibration file (JSON)")->required();
    report_cmd->add_option("LOG", rep.log.path, "the raw log it was calibrated from (optional)");
    AddInputOptions(report_cmd, &rep.log, false);
    AddDetectionOptions(report_cmd, &rep.log);
    report_cmd->add_option("-o,--output", rep.output, "HTML file (default: stdout)")
        ->check(kFileName);
  }

  ExportArgs exp;
  CLI::App* export_cmd = app.add_subcommand(
      "export", "write a calibration in another tool's format, saying what it cannot hold");
  if (Wanted(export_cmd)) {
    export_cmd->add_option("CAL", exp.calibration, "calibration file (JSON)")->required();
    export_cmd
        ->add_option("--to", exp.format,
                     "json, yaml, kalibr, px4, ardupilot, c-header, imutk, kalibr-imu, ros, "
                     "openvins or basalt (docs/conventions.md)")
        ->required();
    export_cmd
        ->add_option("--noise", exp.noise,
                     "the sensor's noise (accelcal noise --json, calibrated): kalibr-imu, ros, "
                     "openvins and basalt need it, kalibr writes its keys beside the model")
        ->check(kFileName);
    export_cmd
        ->add_option("--rostopic", exp.rostopic,
                     "the IMU's topic (kalibr-imu, openvins, kalibr with --noise)")
        ->capture_default_str();
    export_cmd->add_option("-o,--output", exp.output, "output file (default: stdout)")
        ->check(kFileName);
    export_cmd->add_option("--raw-unit", exp.raw_unit,
                           "unit of the calibrated raw readings, m/s2 or g, when the file's label "
                           "is another (kalibr, px4, ardupilot need readings in m/s2)");
    export_cmd->add_option(
        "--gyro-raw-unit", exp.gyro_raw_unit,
        "unit of the gyroscope's calibrated raw rates, rad/s or deg/s, when the "
        "file's label is another (kalibr, openvins, basalt need rates in rad/s)");
    export_cmd
        ->add_option("--instance", exp.instance,
                     "accelerometer index: PX4 CAL_ACC<n>, ArduPilot INS_ACC / INS_ACC2 / INS_ACC3")
        ->capture_default_str();
    export_cmd
        ->add_option("--device-id", exp.device_id,
                     "px4: the sensor's device id for CAL_ACC<n>_ID (default: the one of the "
                     "ULog stream calibrated)")
        ->check(kDeviceId);
    export_cmd
        ->add_option("--gyro-device-id", exp.gyro_device_id,
                     "px4: the gyroscope's device id for CAL_GYRO<n>_ID (default: the one of the "
                     "ULog stream calibrated)")
        ->check(kDeviceId);
    export_cmd
        ->add_option("--current-params", exp.current_params,
                     "ardupilot: the parameters in force when the log was recorded (.param "
                     "file), composed with a calibration of IMU or ACC records (default: the "
                     "log's PARM values)")
        ->check(kFileName);
    export_cmd->add_option("--c-prefix", exp.c_prefix, "prefix of the C identifiers (c-header)")
        ->capture_default_str();
    export_cmd
        ->add_option("--sensor", exp.sensor,
                     "accelerometer or gyroscope: the triad imutk writes (c-header writes both)")
        ->capture_default_str();
  }

  bool quiet = false, verbose = false;
  auto* quiet_flag =
      app.add_flag("-q,--quiet", quiet, "say nothing but errors (results still go where asked)");
  app.add_flag("-v,--verbose", verbose,
               "also print diagnostics on stderr (detection thresholds, timings)")
      ->excludes(quiet_flag);

  if (argc == 2 && std::string_view(argv[1]) == kDescribeOptionsFlag) {
    WriteOut(DescribeOptions(app));
    return kExitOk;
  }

  // A list option given twice would be merged by CLI11 ("--gyro-columns 5 --gyro-columns 6,7"
  // as 5,6,7): refused as every other option given twice. An empty item ("20,,30", "20,") would
  // be dropped by it, the list shortened silently: refused too.
  // --noise is a list in design only (elsewhere a file, whose name may hold commas).
  std::string_view command;
  for (int i = 1; i < argc && command.empty(); ++i) {
    if (argv[i][0] != '-') command = argv[i];
  }
  for (const char* list :
       {"--columns", "--gyro-columns", "--methods", "--noise", "--bias-random-walk",
        "--temperatures", "--thermal-degrees", "--thermal-target", "--bias-repeatability"}) {
    const bool items = std::string_view(list) != "--noise" || command == "design";
    int given = 0;
    for (int i = 1; i < argc && std::string_view(argv[i]) != "--"; ++i) {
      const std::string_view arg = argv[i], name = list;
      const bool joined =
          arg.substr(0, name.size()) == name && arg.size() > name.size() && arg[name.size()] == '=';
      if (arg != name && !joined) continue;
      ++given;
      const std::string_view value = joined         ? arg.substr(name.size() + 1)
                                     : i + 1 < argc ? std::string_view(argv[i + 1])
                                                    : std::string_view("x");
      if (items && (value.empty() || value.front() == ',' || value.back() == ',' ||
                    value.find(",,") != std::string_view::npos)) {
        WriteErrLine(
            Format("accelcal: usage: %s '%s' has an empty item: give each value once, "
                   "comma-separated (see --help)\n",
                   list, std::string(value).c_str()));
        return kExitUsage;
      }
    }
    if (given > 1) {
      WriteErrLine(
          Format("accelcal: usage: %s given %d times: give it once (a list's values "
                 "comma-separated; see --help)\n",
                 list, given));
      return kExitUsage;
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return ExitWith(app, e);
  } catch (const CLI::CallForAllHelp& e) {
    return ExitWith(app, e);
  } catch (const CLI::CallForVersion& e) {
    return ExitWith(app, e);
  } catch (const CLI::ParseError& e) {
    // Said as every other usage error is; an option given twice by what it is.
    std::string what = e.what();
    const std::string twice = ": At Most 1 required but received ";
    if (const std::size_t at = what.find(twice); at != std::string::npos) {
      what =
          what.substr(0, at) + " given " + what.substr(at + twice.size()) + " times: give it once";
    }
    WriteErrLine(Format("accelcal: usage: %s (see --help)\n", what.c_str()));
    return kExitUsage;
  }

  SetVerbosity(quiet ? Verbosity::kQuiet : verbose ? Verbosity::kVerbose : Verbosity::kNormal);
  if (!calibrate_inputs.empty()) {
    cal.input.path = calibrate_inputs.front();
    cal.input.more_paths.assign(calibrate_inputs.begin() + 1, calibrate_inputs.end());
  }
  const auto start = std::chrono::steady_clock::now();
  struct Timer {  // reports the whole command's time when verbose, however it ends
    std::chrono::steady_clock::time_point start;
    ~Timer() {
      Detail("done in %.1f ms\n",
             1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
  } timer{start};
  InstallCleanupHandlers();
  // The command, then stdout checked: a summary that did not reach a full disk is an error too.
  // The file a DataError of the command is about (empty: none, e.g. a simulation).
  std::string& data_subject = DataSubject();
  const auto run = [&]() -> int {
    if (*calibrate) {
      data_subject = cal.input.path;
      CheckCalibrationFlags(*calibrate, &cal);
      cal.given_options = GivenOptions(*calibrate, {"output", "report", "json", "date"});
      return runner ? runner(cal) : RunCalibrate(cal);
    }
    if (*store) return RunStore(sto);
    if (*batch) {
      CheckCalibrationFlags(*batch, &bat_cal);
      bat.unit_id_given = batch->count("--unit-id") > 0;
      bat.calibrate_options = GivenOptions(*batch, {"output", "limits", "unit-id", "unit-id-from",
                                                    "glob", "jobs", "redo", "no-report", "json"});
      for (const auto& option : bat.calibrate_options) {  // the date is the provenance's own
        if (option.first != "date") bat_cal.given_options.push_back(option);
      }
      bat.calibrate = bat_cal;
      return RunBatch(bat);
    }
    if (*detect) {
      data_subject = det.input.path;
      return RunDetect(det);
    }
    if (*inspect) {
      data_subject = ins.path;
      return RunInspect(ins);
    }
    if (*noise) {
      CheckGyroFlags(*noise, noi.gyro, noi.gyro_columns, {});
      data_subject = noi.input.path;
      return RunNoise(noi);
    }
    if (*compare) {
      CheckGyroFlags(*compare, cmp.gyro, cmp.gyro_columns, {"--gyro-units"});
      data_subject = cmp.input.path;
      return RunCompare(cmp);
    }
    if (*apply_cmd) {
      CheckGyroFlags(*apply_cmd, apply.gyro, apply.gyro_columns, {});
      data_subject = apply.input.path;
      return RunApply(apply);
    }
    if (*export_cmd) {
      data_subject = exp.calibration;
      for (const char* name :
           {"raw-unit", "gyro-raw-unit", "instance", "c-prefix", "sensor", "noise", "rostopic",
            "device-id", "gyro-device-id", "current-params"}) {
        if (export_cmd->count(std::string("--") + name) > 0) exp.given.push_back(name);
      }
      return RunExport(exp);
    }
    if (*verify) {
      CheckGyroFlags(*verify, ver.gyro, ver.gyro_columns, {});
      data_subject = ver.input.path;
      return RunVerify(ver);
    }
    if (*report_cmd) {
      data_subject = rep.log.path.empty() ? rep.calibration : rep.log.path;
      return RunReport(rep);
    }
    if (*design) {
      data_subject = des.positions;
      des.thermal_degrees_given = design->count("--thermal-degrees") > 0;
      return RunDesign(des);
    }
    if (*montecarlo) return RunMonteCarlo(mc);
    if (*simulate) {
      sim.rate_given = simulate->count("--rate") > 0;
      sim.duration_given = simulate->count("--duration") > 0;
      return RunSimulate(sim);
    }
    if (*system_level) {
      data_subject = sys.series;
      return RunSystemLevel(sys);
    }
    if (*gimbal) {
      data_subject = gim.coarse;
      return RunGimbal(gim);
    }
    return kExitUsage;
  };
  try {
    const int status = run();
    FinishStdout();
    return status;
  } catch (...) {
    int status = kExitInternal;
    const std::string message = ErrorMessage(std::current_exception(), data_subject, &status);
    WriteErrLine("accelcal: " + message + "\n");
    return status;
  }
  return kExitUsage;
}
