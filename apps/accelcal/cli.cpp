// accelcal: command-line front end. The table of commands (each registers its options beside its
// Run: SetUp*, commands.hpp), the parse, and errors mapped to exit codes (RunCommandLine: main.cpp,
// the option-parsing fuzzer, fuzz/fuzz_cli_options.cpp, and the Python package).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <exception>
#include <functional>
#include <optional>
#include <sstream>
#include <string_view>
#include <vector>

#include <CLI/CLI.hpp>

#include "accelcal/error.hpp"
#include "accelcal/version.hpp"
#include "cli_common.hpp"
#include "cli_options.hpp"
#include "commands.hpp"
#include "output.hpp"

namespace {

using namespace accelcal::cli;

// One subcommand of the tool: its name, its line of help, and what registers its options.
struct CommandEntry {
  const char* name;
  const char* description;
  std::function<CommandRun(CLI::App*)> set_up;
};

// The tool's commands, in the order its help lists them.
std::vector<CommandEntry> Commands(const CalibrateRunner& runner) {
  return {
      {"calibrate", "estimate K, b (and k2) from a raw log or a positions file",
       [&runner](CLI::App* cmd) { return SetUpCalibrate(cmd, runner); }},
      {"batch",
       "a production line: calibrate many units as calibrate would, judge each against limits, "
       "and tabulate them (units in parallel; a unit whose calibration is current is not redone)",
       SetUpBatch},
      {"store",
       "a store of calibrations by unit and date: store add STORE CAL.json|BATCH_DIR..., store get "
       "STORE UNIT, store list STORE [UNIT]; each calibration added is compared with the unit's "
       "one before it within their covariances",
       SetUpStore},
      {"compare", "run several calibration methods on the same data and tabulate them",
       SetUpCompare},
      {"detect", "list the static intervals of a raw log", SetUpDetect},
      {"inspect",
       "what a binary log (PX4 ULog, ArduPilot DataFlash, ROS 1 or 2 bag, MAT-file) holds: its "
       "streams, rates, parameters",
       SetUpInspect},
      {"noise", "the Allan deviation of a still log and its noise terms (IEEE Std 952)",
       SetUpNoise},
      {"design", "predict the 1-sigma of every parameter (Cramer-Rao bound) for planned positions",
       SetUpDesign},
      {"montecarlo", "simulate a scenario many times: errors against the Cramer-Rao bound",
       SetUpMonteCarlo},
      {"system-level",
       "paper 003 stage 3: residual accelerometer errors of a space-stable INS from a day of "
       "specific-force and attitude errors on a static, level base",
       SetUpSystemLevel},
      {"gimbal",
       "paper 003 stages 1-2: accelerometer on a three-gimbal platform, coarse (gimbal zero "
       "offsets) and fine (squared-amplitude) device-level calibration",
       SetUpGimbal},
      {"simulate", "write a simulated recording (raw log or positions file) of a known device",
       SetUpSimulate},
      {"apply", "write the calibrated specific force of every sample of a log", SetUpApply},
      {"verify", "check a calibration on a new recording of the same unit (exit 6 when it fails)",
       SetUpVerify},
      {"report", "write the HTML report of a calibration file (and its raw log, when given)",
       SetUpReport},
      {"export", "write a calibration in another tool's format, saying what it cannot hold",
       SetUpExport}};
}

// The first argument that names a command, or "" when none does.
std::string ChosenCommand(int argc, char** argv, const std::vector<CommandEntry>& commands) {
  for (int i = 1; i < argc; ++i) {
    for (const CommandEntry& command : commands) {
      if (std::string_view(argv[i]) == command.name) return command.name;
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

// An option written with an empty value ("--raw-units=") would take the next argument for its
// value in CLI11 ("--raw-units= --model=quadratic" labelled the raw unit "--model=quadratic" and
// dropped the model): refused. Returns the usage error's status, or 0.
int RefuseEmptyValues(int argc, char** argv) {
  for (int i = 1; i < argc && std::string_view(argv[i]) != "--"; ++i) {
    const std::string_view arg = argv[i];
    if (arg.size() > 3 && arg.substr(0, 2) == "--" && arg.back() == '=' &&
        arg.find('=') == arg.size() - 1) {
      WriteErrLine(
          Format("accelcal: usage: %s: an empty value; give one, or leave the option "
                 "out (see --help)\n",
                 std::string(arg.substr(0, arg.size() - 1)).c_str()));
      return kExitUsage;
    }
  }
  return 0;
}

// A list option given twice would be merged by CLI11 ("--gyro-columns 5 --gyro-columns 6,7"
// as 5,6,7): refused as every other option given twice. An empty item ("20,,30", "20,") would
// be dropped by it, the list shortened silently: refused too.
// The lists are the options of the commands set up that CLI11 splits at a delimiter (--noise is
// a list in design only, elsewhere a file whose name may hold commas).
// Returns the usage error's status, or 0.
int RefuseMergedLists(int argc, char** argv,
                      const std::vector<std::pair<CLI::App*, CommandRun>>& commands) {
  std::vector<std::string> lists;
  for (const auto& [command, run] : commands) {
    for (const CLI::Option* option : command->get_options()) {
      const std::string name = option->get_lnames().empty() ? "" : "--" + option->get_lnames()[0];
      if (option->get_delimiter() != '\0' && !name.empty() &&
          std::find(lists.begin(), lists.end(), name) == lists.end()) {
        lists.push_back(name);
      }
    }
  }
  for (const std::string& list_name : lists) {
    const char* list = list_name.c_str();
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
      if (value.empty() || value.front() == ',' || value.back() == ',' ||
          value.find(",,") != std::string_view::npos) {
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
  return 0;
}

// Edits (insertions, deletions, substitutions) that turn `a` into `b`.
std::size_t EditDistance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] != b[j - 1] ? 1 : 0)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

// The first long option on the command line that neither the tool nor the command run has, as
// "calibrate has no option --gyro-unit; did you mean --gyro-units?"; nothing when every one is
// known (the extra arguments are then values).
std::optional<std::string> UnknownOption(
    int argc, char** argv, const CLI::App& app,
    const std::vector<std::pair<CLI::App*, CommandRun>>& commands) {
  const CLI::App* command = nullptr;
  for (const auto& [sub, run] : commands) {
    if (sub->parsed()) command = sub;
  }
  std::vector<std::string> known;
  for (const CLI::App* owner : {&app, command}) {
    if (owner == nullptr) continue;
    for (const CLI::Option* option : owner->get_options()) {
      for (const std::string& name : option->get_lnames()) known.push_back("--" + name);
    }
  }
  for (int i = 1; i < argc && std::string_view(argv[i]) != "--"; ++i) {
    std::string_view arg = argv[i];
    if (arg.size() < 3 || arg.substr(0, 2) != "--") continue;
    const std::string name(arg.substr(0, arg.find('=')));
    if (std::find(known.begin(), known.end(), name) != known.end()) continue;
    std::string said = (command != nullptr ? command->get_name() : std::string("accelcal")) +
                       " has no option " + name;
    std::size_t best = 3;  // a near miss: at most two edits
    std::string nearest;
    for (const std::string& k : known) {
      const std::size_t d = EditDistance(name, k);
      if (d < best) best = d, nearest = k;
    }
    if (!nearest.empty()) said += "; did you mean " + nearest + "?";
    return said;
  }
  return std::nullopt;
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
  const std::vector<CommandEntry> commands = Commands(runner);
  const std::string chosen = ChosenCommand(argc, argv, commands);
  std::vector<std::pair<CLI::App*, CommandRun>> runs;
  for (const CommandEntry& entry : commands) {
    CLI::App* command = app.add_subcommand(entry.name, entry.description);
    if (chosen.empty() || chosen == entry.name) runs.emplace_back(command, entry.set_up(command));
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

  if (const int status = RefuseEmptyValues(argc, argv)) return status;
  if (const int status = RefuseMergedLists(argc, argv, runs)) return status;
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return ExitWith(app, e);
  } catch (const CLI::CallForAllHelp& e) {
    return ExitWith(app, e);
  } catch (const CLI::CallForVersion& e) {
    return ExitWith(app, e);
  } catch (const CLI::ExtrasError& e) {
    // An option the command does not have is named as one, with the nearest it has.
    WriteErrLine("accelcal: usage: " + UnknownOption(argc, argv, app, runs).value_or(e.what()) +
                 " (see --help)\n");
    return kExitUsage;
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
  // The file a DataError of the command is about (empty: none, e.g. a simulation), set by the
  // command; none left from an earlier command of this thread (the Python package runs many).
  DataSubject().clear();
  const auto run = [&]() -> int {
    for (const auto& [command, run_command] : runs) {
      if (*command) return run_command(*command);
    }
    return kExitUsage;
  };
  try {
    const int status = run();
    FinishStdout();
    return status;
  } catch (...) {
    int status = kExitInternal;
    const std::string message = ErrorMessage(std::current_exception(), DataSubject(), &status);
    WriteErrLine("accelcal: " + message + "\n");
    return status;
  }
  return kExitUsage;
}