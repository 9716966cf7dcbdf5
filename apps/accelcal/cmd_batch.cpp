// accelcal batch: a production line's units. Each unit's files are calibrated as calibrate does
// (the library's CalibrateUnit, from the same request) with the options given, so that a unit's
// file and report are exactly what `accelcal calibrate` writes; each calibration is then judged
// against the limits (acceptance.hpp), and one summary table lists every unit. Units run in
// parallel, a unit that fails never stops the others, and a unit whose calibration is current (same
// inputs, options, date and accelcal version, by its own provenance) is not calibrated again.
#include <fnmatch.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <thread>

#include <dirent.h>

#include "accelcal/acceptance.hpp"
#include "accelcal/calibration_file.hpp"
#include "accelcal/json_text.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/native_log.hpp"
#include "accelcal/sha256.hpp"
#include "accelcal/version.hpp"
#include "batch_units.hpp"
#include "cli_common.hpp"
#include "cli_options.hpp"
#include "commands.hpp"
#include "output.hpp"
#include "unit_id_pattern.hpp"

namespace accelcal::cli {
namespace {

using Json = nlohmann::ordered_json;
using batch::Joined;
using batch::Unit;
using batch::UnitStatus;
using internal::VisibleLine;

// The regular files of `dir` whose names match `glob` (hidden ones left out), sorted by name;
// `skipped` counts the other entries that match (directories, FIFOs, devices).
std::vector<std::string> DirectoryFiles(const std::string& dir, const std::string& glob,
                                        std::vector<std::string>* skipped) {
  DIR* d = ::opendir(dir.c_str());
  if (d == nullptr) {
    throw InputError(dir, 0, std::string("cannot list the directory: ") + std::strerror(errno));
  }
  std::vector<std::string> names;
  while (const dirent* e = ::readdir(d)) {
    const std::string name = e->d_name;
    if (name.empty() || name[0] == '.' || ::fnmatch(glob.c_str(), name.c_str(), 0) != 0) continue;
    names.push_back(name);
  }
  ::closedir(d);
  std::sort(names.begin(), names.end());
  std::vector<std::string> files;
  const std::string prefix = dir.back() == '/' ? dir : dir + "/";
  for (const std::string& name : names) {
    struct stat st {};
    if (::stat((prefix + name).c_str(), &st) == 0 && S_ISREG(st.st_mode)) {
      files.push_back(prefix + name);
    } else {
      skipped->push_back(prefix + name);
    }
  }
  return files;
}

std::string BaseName(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

// The unit id of a file: the regular expression's first group (or its whole match) searched in
// the file's name, or the name less its extension.
std::string UnitIdOf(const std::string& path, const std::optional<UnitIdPattern>& pattern,
                     std::string* problem) {
  const std::string name = BaseName(path);
  if (!pattern) {
    const std::size_t dot = name.find_last_of('.');
    return dot == 0 || dot == std::string::npos ? name : name.substr(0, dot);
  }
  std::optional<std::string> id = pattern->Search(name);
  if (!id) {
    *problem = "its name does not match the unit id pattern";
    return name;
  }
  return *id;
}

std::string OptionValue(const BatchArgs& args, const char* option) {
  for (const auto& [name, values] : args.calibrate_options) {
    if (name == option && !values.empty()) return values.front();
  }
  return "";
}

// The unit id a binary log gives itself (--unit-id-from): a string of its information (info:KEY,
// such as PX4's sys_uuid, the board's processor's unique id), one of its parameters (param:KEY,
// such as ArduPilot's BRD_SERIAL_NUM), its accelerometer stream's device id (device-id; of
// --topic and --instance when given), or a ROS accelerometer topic's header.frame_id (frame-id;
// of --topic when given).
std::string UnitIdFromLog(const std::string& path, const BatchArgs& args, std::string* problem) {
  LogInventory log;
  try {
    log = InspectLog(path);
  } catch (const InputError& e) {
    *problem = "no unit id from the log (" + args.unit_id_from + "): " + e.reason();
    return BaseName(path);
  }
  const std::string& from = args.unit_id_from;
  const auto listing = [](const auto& map) {
    std::string keys;
    for (const auto& entry : map) {
      if (keys.size() > 200) return keys + ", ...";
      keys += (keys.empty() ? "" : ", ") + entry.first;
    }
    return keys.empty() ? std::string("none") : keys;
  };
  if (from.rfind("info:", 0) == 0) {
    const auto it = log.info.find(from.substr(5));
    if (it == log.info.end()) {
      *problem =
          "the log has no information '" + from.substr(5) + "' (it has " + listing(log.info) + ")";
      return BaseName(path);
    }
    return it->second;
  }
  if (from.rfind("param:", 0) == 0) {
    const auto it = log.parameters.find(from.substr(6));
    if (it == log.parameters.end()) {
      *problem = "the log has no parameter '" + from.substr(6) + "'";
      return BaseName(path);
    }
    const double v = it->second;
    return v == std::floor(v) && std::abs(v) < 1e15 ? Format("%.0f", v) : FormatNumber(v);
  }
  // device-id, frame-id: of the accelerometer streams the calibration could read.
  const bool frame = from == "frame-id";
  const std::string topic = OptionValue(args, "topic"), instance = OptionValue(args, "instance");
  const auto accelerometer = [](const LogStreamInfo& s) {
    const auto sensors = KnownSensors(s.type);
    return std::find(sensors.begin(), sensors.end(), "accelerometer") != sensors.end();
  };
  std::set<std::string> ids;
  for (const LogStreamInfo& s : log.streams) {
    if (!accelerometer(s)) continue;
    if (!topic.empty() && s.topic != topic) continue;
    if (!instance.empty() && std::to_string(s.instance) != instance) continue;
    if (frame && s.frame_id) ids.insert(*s.frame_id);
    if (!frame && s.device_id) ids.insert(std::to_string(*s.device_id));
  }
  const char* what = frame ? "frame id" : "device id";
  if (ids.empty()) {
    // What the log has: its accelerometer streams (or, without one, all its streams), each with
    // its type and the id asked for.
    const bool any = std::any_of(log.streams.begin(), log.streams.end(), accelerometer);
    std::string streams;
    for (const LogStreamInfo& s : log.streams) {
      if (any && !accelerometer(s)) continue;
      if (streams.size() > 300) {
        streams += ", ...";
        break;
      }
      std::string id = "none";
      if (frame && s.frame_id) id = "'" + *s.frame_id + "'";
      if (!frame && s.device_id) id = std::to_string(*s.device_id);
      streams += (streams.empty() ? "" : ", ") + s.topic +
                 (s.instance != 0 ? " instance " + std::to_string(s.instance) : "") +
                 (s.type != s.topic ? " (" + s.type + ", " : " (") + what + " " + id + ")";
    }
    *problem = std::string("the log has no accelerometer stream") +
               (topic.empty() ? "" : " " + topic) +
               (instance.empty() ? "" : " instance " + instance) + " with a " + what +
               (frame ? " (a sensor_msgs/Imu topic's header.frame_id)" : "") +
               (any ? "; its accelerometer streams: " : "; its streams: ") +
               (streams.empty() ? "none" : streams);
    return BaseName(path);
  }
  if (ids.size() != 1) {
    *problem = "its accelerometer streams have " + std::to_string(ids.size()) + " " + what +
               "s: choose one with --topic" + (frame ? "" : " and --instance");
    return BaseName(path);
  }
  return *ids.begin();
}

// name, size and SHA-256 of a file, as a calibration's provenance records an input.
InputRecord Record(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, "cannot be read");
  Sha256 sha;
  std::uint64_t bytes = 0;
  std::vector<char> buffer(1 << 16);
  while (in) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    const auto n = static_cast<std::size_t>(in.gcount());
    sha.Update(buffer.data(), n);
    bytes += n;
  }
  if (in.bad()) throw InputError(path, 0, "could not be read to its end");
  return {path, bytes, sha.HexDigest()};
}

// The files a unit's calibration reads beyond its own, in the order its provenance lists them
// (cmd_calibrate.cpp MakeProvenance): the orientations, then the gyroscope's log.
std::vector<std::string> SharedInputs(const BatchArgs& args) {
  std::vector<std::string> files;
  for (const char* option : {"orientations", "gyro"}) {
    for (const auto& [name, values] : args.calibrate_options) {
      if (name == option && !values.empty()) files.push_back(values.front());
    }
  }
  return files;
}

// The options a unit's provenance records: those given, less the date (recorded apart), as the
// unit's calibrate request writes them.
Json ProvenanceOptions(const BatchArgs& args) {
  return GivenOptionsJson(args.calibrate.given_options);
}

// Whether the unit's calibration file (its bytes `text`) is current: written by this accelcal
// from the same inputs (by name, size and SHA-256), options and date, with its report when one is
// wanted.
bool Current(const BatchArgs& args, const Unit& unit, const std::string& text,
             const std::string& cal_path, bool has_report, const std::vector<InputRecord>& shared) {
  if (args.report && !has_report) return false;
  try {
    const LoadedCalibration cal = ParseCalibrationJson(text, cal_path);
    const Provenance& p = cal.provenance;
    if (p.accelcal_version != Version() || p.command != "accelcal calibrate" ||
        p.options != ProvenanceOptions(args) || p.date != OptionValue(args, "date")) {
      return false;
    }
    std::vector<InputRecord> expected;
    for (const std::string& f : unit.files) expected.push_back(Record(f));
    expected.insert(expected.end(), shared.begin(), shared.end());
    if (p.inputs.size() != expected.size()) return false;
    for (std::size_t i = 0; i < expected.size(); ++i) {
      if (p.inputs[i].name != expected[i].name || p.inputs[i].bytes != expected[i].bytes ||
          p.inputs[i].sha256 != expected[i].sha256) {
        return false;
      }
    }
    return true;
  } catch (const std::exception&) {
    return false;  // unreadable or not a calibration: calibrated again
  }
}

// The calibrate request of a unit's files: the options as given (a usage error for what they
// cannot be), a log without a still period said with the options that act on it as calibrate
// says it.
UnitRequest UnitRequestOf(const BatchArgs& args, const std::vector<std::string>& files) {
  CalibrateArgs cal = args.calibrate;
  cal.input.path = files.front();
  cal.input.more_paths.assign(files.begin() + 1, files.end());
  Gravity g{};
  UnitRequest request = CalibrateRequest(cal, &g);
  request.load.after_file = [](const LoadedFile& f) {
    if (f.detection && f.detection->intervals.empty()) throw NoStaticInterval(*f.detection);
  };
  return request;
}

// A unit: its directory OUT/units/ID opened without following a link (Directory), calibrate run
// in-process with its two files kept in memory, and those written by batch itself into that
// directory (a link planted anywhere below OUT can send nothing elsewhere). The calibration's
// SHA-256 is of the bytes judged, so the summary names exactly the file it judged.
void RunUnit(const BatchArgs& args, const std::vector<InputRecord>& shared,
             const Directory& units_dir, Unit* unit) {
  if (!unit->problem.empty()) return;
  const std::string dir = units_dir.Shown(unit->id);
  const std::string cal_path = dir + "/calibration.json";
  bool made = false;  // the unit's directory, made for it: removed again when left empty
  try {
    made = !units_dir.Has(unit->id);
    const Directory unit_dir = units_dir.Sub(unit->id, true);
    const auto fail = [&](const std::string& why) {
      unit->message = why;
      if (made) units_dir.RemoveEmpty(unit->id);
    };
    // batch replaces only regular files it wrote: a link there could send its output over a
    // file of the user's.
    bool has_calibration = false, has_report = false;
    for (const char* name : {"calibration.json", "report.html"}) {
      struct stat st {};
      if (!unit_dir.Has(name, &st)) continue;
      if (S_ISLNK(st.st_mode)) {
        return fail(unit_dir.Shown(name) +
                    " is a symbolic link: batch replaces only the files it wrote");
      }
      if (!S_ISREG(st.st_mode)) {
        return fail(unit_dir.Shown(name) + " is not a regular file: not replaced");
      }
      (name[0] == 'c' ? has_calibration : has_report) = true;
    }
    std::string text;
    if (has_calibration) text = unit_dir.Read("calibration.json", kMaxSmallFileBytes);
    if (!args.redo && has_calibration && Current(args, *unit, text, cal_path, has_report, shared)) {
      unit->reused = true;
      unit->exit_status = kExitOk;
    } else {
      // A file there that is not a calibration is not batch's: not replaced.
      if (has_calibration) {
        try {
          ParseCalibrationJson(text, cal_path);
        } catch (const std::exception&) {
          return fail(cal_path + " exists and is not a calibration file: not replaced");
        }
      }
      // Calibrated as calibrate would (the library's unit), its files rendered in memory. On an
      // error an earlier calibration there is kept (it may be the user's, or read-only): it is
      // not current, so it is neither reported nor taken as current by a later batch.
      RenderedCalibration rendered;
      try {
        const UnitOutcome outcome = CalibrateUnit(UnitRequestOf(args, unit->files));
        if (!outcome.converged()) {
          unit->exit_status = kExitNotConverged;
          return fail(DidNotConverge(unit->files.front(), outcome));
        }
        rendered = RenderCalibration(outcome, cal_path, args.report);
        unit->exit_status =
            outcome.diagnosis.verdict() == Verdict::kFailed ? kExitFailedChecks : kExitOk;
      } catch (const std::exception&) {
        return fail(
            ErrorMessage(std::current_exception(), unit->files.front(), &unit->exit_status));
      }
      // Both files or neither; an earlier calibration that is read-only is kept (and the unit is
      // an error: its calibration is not of the current files).
      OutputFile cal_file(unit_dir, "calibration.json");
      cal_file.Write(rendered.json);
      std::optional<OutputFile> report_file;
      if (args.report) report_file.emplace(unit_dir, "report.html").Write(rendered.report);
      CommitAll({&cal_file, report_file ? &*report_file : nullptr});
      // A report of an earlier calibration would describe other data.
      if (!args.report) unit_dir.Remove("report.html");
      text = std::move(rendered.json);
    }
    unit->calibration = ParseCalibrationJson(text, cal_path);
    unit->sha256 = Sha256Hex(text);
  } catch (const std::exception& e) {
    unit->exit_status = kExitInternal;
    unit->message = e.what();
    if (made) units_dir.RemoveEmpty(unit->id);
  }
}

// The pattern --unit-id gives file names (with --unit-id-from name), and --unit-id-from checked.
std::optional<UnitIdPattern> UnitIdPatternOf(const BatchArgs& args) {
  std::optional<UnitIdPattern> pattern;
  if (args.unit_id_given && args.unit_id.empty()) {
    throw UsageError("--unit-id is empty: give a regular expression whose first group is the id");
  }
  if (!args.unit_id.empty()) pattern.emplace(args.unit_id);
  const std::string& from = args.unit_id_from;
  const bool keyed = (from.rfind("info:", 0) == 0 && from.size() > 5) ||
                     (from.rfind("param:", 0) == 0 && from.size() > 6);
  if (from != "name" && from != "device-id" && from != "frame-id" && !keyed) {
    throw UsageError("--unit-id-from '" + from +
                     "': name, device-id, frame-id, info:KEY or param:KEY");
  }
  if (from != "name" && args.unit_id_given) {
    throw UsageError("--unit-id is a pattern on file names: it goes with --unit-id-from name");
  }
  return pattern;
}

// The files: those given, and the matching regular files of each directory given; each once.
std::vector<std::string> InputFiles(const BatchArgs& args) {
  std::vector<std::string> files;
  std::vector<std::string> skipped;
  for (const std::string& input : args.inputs) {
    if (input.empty()) throw UsageError("an input's name is empty");
    if (input == "-") {
      throw UsageError("batch reads files and directories, not standard input ('-')");
    }
    if (IsDirectory(input)) {
      const std::vector<std::string> found = DirectoryFiles(input, args.glob, &skipped);
      if (found.empty()) {
        Warn("%s: no file matches --glob '%s'\n", input.c_str(), args.glob.c_str());
      }
      files.insert(files.end(), found.begin(), found.end());
      continue;
    }
    struct stat st {};
    if (::stat(input.c_str(), &st) != 0) {
      throw InputError(input, 0, std::string("cannot be read: ") + std::strerror(errno));
    }
    if (!S_ISREG(st.st_mode)) {
      throw InputError(input, 0,
                       "not a regular file: batch reads each input twice (its SHA-256, then "
                       "its data), which a FIFO or a device cannot give");
    }
    files.push_back(input);
  }
  if (!skipped.empty()) {
    std::string names;
    for (std::size_t i = 0; i < skipped.size() && i < 5; ++i) names += (i ? ", " : "") + skipped[i];
    Warn(
        "%zu entries matching --glob are not regular files (a directory, a FIFO, a broken link): "
        "skipped: %s%s\n",
        skipped.size(), names.c_str(), skipped.size() > 5 ? ", ..." : "");
  }
  if (files.empty()) throw UsageError("no input file: give files or directories that hold some");
  // The same file twice (given twice, or given and in a directory given) is a mistake.
  std::map<std::pair<dev_t, ino_t>, std::string> seen;
  for (const std::string& f : files) {
    struct stat st {};
    if (::stat(f.c_str(), &st) != 0) continue;
    const auto [at, fresh] = seen.emplace(std::make_pair(st.st_dev, st.st_ino), f);
    if (!fresh) throw UsageError(f + " is " + at->second + " again: give each file once");
  }
  return files;
}

// The output directory is none of the inputs' directories.
void CheckNotAnInput(const BatchArgs& args, const Directory& out_dir) {
  struct stat out_st {};
  if (::fstat(out_dir.fd(), &out_st) != 0) {
    throw OutputError(args.output + ": cannot be read: " + std::strerror(errno));
  }
  for (const std::string& input : args.inputs) {
    struct stat st {};
    if (IsDirectory(input) && ::stat(input.c_str(), &st) == 0 && st.st_dev == out_st.st_dev &&
        st.st_ino == out_st.st_ino) {
      throw UsageError("-o " + args.output + " is the input directory " + input +
                       ": its summary files would be taken for units; give another");
    }
  }
}

// The units, by id: a file's id from its name; files with one id are sessions of one unit.
std::vector<Unit> UnitsOf(const BatchArgs& args, const std::vector<std::string>& files,
                          const std::optional<UnitIdPattern>& pattern) {
  std::map<std::string, Unit> by_id;
  std::vector<Unit> misnamed;
  for (const std::string& f : files) {
    std::string problem;
    const std::string id = args.unit_id_from == "name" ? UnitIdOf(f, pattern, &problem)
                                                       : UnitIdFromLog(f, args, &problem);
    if (problem.empty()) problem = UnitIdProblem(id);
    if (!problem.empty()) {
      Unit u;
      u.id = id;
      u.files = {f};
      u.problem = f + ": " + problem;
      misnamed.push_back(std::move(u));
      continue;
    }
    Unit& u = by_id[id];
    u.id = id;
    u.files.push_back(f);
  }
  std::vector<Unit> units;
  for (auto& [id, u] : by_id) {
    // A unit's sessions in name order: the order given (a shell's glob, a locale's) changes
    // nothing.
    std::sort(u.files.begin(), u.files.end());
    units.push_back(std::move(u));
  }
  for (Unit& u : misnamed) units.push_back(std::move(u));
  // By id, then (error rows of one id) by their files: the order the inputs were given changes
  // nothing.
  std::sort(units.begin(), units.end(), [](const Unit& a, const Unit& b) {
    return a.id != b.id ? a.id < b.id : a.files < b.files;
  });
  return units;
}

// The calibrate options, checked once for all units.
void CheckUnitOptions(const BatchArgs& args, const std::vector<Unit>& units) {
  // One gyroscope log given to every unit would calibrate each unit's accelerometer with another
  // unit's gyroscope.
  if (units.size() > 1 && !OptionValue(args, "gyro").empty()) {
    throw UsageError(
        "--gyro names one gyroscope log for every unit: give each unit's rates in its own "
        "recording, with --gyro-columns (or --gyro-topic in a binary log)");
  }
  // calibrate's own checks of the options, before any unit, on inputs that cannot exist (so
  // that nothing is read), as many as each unit has: a usage error for every count of files is
  // the options', the same for every unit. One for some counts only (--temperatures with one
  // value per file) is those units' error.
  std::set<std::size_t> counts;
  for (const Unit& u : units) {
    if (u.problem.empty()) counts.insert(u.files.size());
  }
  std::string usage_error;
  std::size_t usage_errors = 0;
  for (const std::size_t count : counts) {
    std::vector<std::string> probe;
    for (std::size_t i = 0; i < count; ++i) {
      probe.push_back("/dev/null/accelcal-batch-option-check-" + std::to_string(i));
    }
    try {
      const UnitRequest request = UnitRequestOf(args, probe);
      if (auto why = request.Validate()) throw OptionError(*why);
    } catch (const std::exception&) {
      int status = kExitOk;
      const std::string message = ErrorMessage(std::current_exception(), "", &status);
      if (status != kExitUsage) throw;
      ++usage_errors;
      usage_error = message;
    }
  }
  if (!counts.empty() && usage_errors == counts.size()) {
    const std::string usage = "usage: ";
    throw UsageError(usage_error.compare(0, usage.size(), usage) == 0
                         ? usage_error.substr(usage.size())
                         : usage_error);
  }
}

// The shared inputs are hashed once; then the units, `jobs` at a time.
void RunUnits(const BatchArgs& args, const Directory& units_dir, std::vector<Unit>* all) {
  std::vector<Unit>& units = *all;
  std::vector<InputRecord> shared;
  for (const std::string& f : SharedInputs(args)) shared.push_back(Record(f));
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  const std::size_t jobs = std::min<std::size_t>(
      args.jobs > 0 ? static_cast<std::size_t>(args.jobs) : cores, units.size());
  std::atomic<std::size_t> next{0}, done{0};
  std::vector<std::thread> workers;
  for (std::size_t j = 0; j < jobs; ++j) {
    workers.emplace_back([&] {
      for (std::size_t i; (i = next++) < units.size(); ++done) {
        RunUnit(args, shared, units_dir, &units[i]);
      }
    });
  }
  {
    ProgressBar bar("batch");
    while (done < units.size()) {
      bar.Update(static_cast<long>(done), static_cast<long>(units.size()));
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  }
  for (std::thread& w : workers) w.join();
}

// Each unit's line, and the counts, on stdout.
void SayUnits(const std::vector<Unit>& units, const std::array<int, 3>& counts,
              const std::string& csv_path, const std::string& json_path) {
  // Ids as a line shows them, padded to the longest up to 40 bytes.
  std::size_t width = 4;
  for (const Unit& u : units) width = std::max(width, std::min<std::size_t>(40, u.id.size()));
  for (const Unit& u : units) {
    std::string detail = u.status == UnitStatus::kError
                             ? u.message
                             : Joined(
                                   [&] {
                                     std::vector<std::string> t;
                                     for (const LimitFailure& f : u.acceptance.failures) {
                                       t.push_back(f.text);
                                     }
                                     return t;
                                   }(),
                                   "; ");
    const std::string line =
        Format("%-*s  %-5s  %s", static_cast<int>(width), VisibleLine(u.id).c_str(), Name(u.status),
               VisibleLine(detail).c_str());
    Say("%s\n", line.substr(0, line.find_last_not_of(' ') + 1).c_str());
  }
  const auto reused =
      std::count_if(units.begin(), units.end(), [](const Unit& u) { return u.reused; });
  Say("%zu units: %d pass, %d fail, %d error (%ld calibrations current, not redone); "
      "summary %s, %s\n",
      units.size(), counts[0], counts[1], counts[2], static_cast<long>(reused), csv_path.c_str(),
      json_path.c_str());
}

}  // namespace

int RunBatch(const BatchArgs& args) {
  // The limits first: a mistake there is found before anything is calibrated.
  std::optional<AcceptanceLimits> limits;
  std::string limits_sha256;  // of the bytes read (a pipe cannot be read twice)
  if (!args.limits.empty()) {
    const std::string text = ReadFileToString(args.limits, kMaxSmallFileBytes);
    limits = ParseLimits(text, args.limits);
    limits_sha256 = Sha256Hex(text);
  }
  const std::optional<UnitIdPattern> pattern = UnitIdPatternOf(args);
  if (args.jobs < 0 || args.jobs > 1024) {
    throw UsageError("--jobs " + std::to_string(args.jobs) + ": from 1 to 1024 (0: one per core)");
  }
  const std::vector<std::string> files = InputFiles(args);
  // The output directory, made when missing (a link there is the user's and followed); never
  // one of the inputs' directories. Everything below it is opened without following links.
  const Directory out_dir = Directory::Open(args.output, true);
  CheckNotAnInput(args, out_dir);
  // One batch at a time per directory: two at once would replace each other's units between
  // judging and summing up, and a summary would pass a calibration that another run replaced.
  // The second is refused rather than made to wait: a batch runs for minutes to hours, and two
  // lines writing into one directory is a mistake better said at once than hidden by a queue.
  const DirectoryLock lock(out_dir, ".lock", true, false, true);
  if (lock.busy()) {
    throw OutputError(args.output + ": another batch is writing into it (it holds " +
                      out_dir.Shown(".lock") +
                      "): run this one when it has finished, or give another -o");
  }
  const Directory units_dir = out_dir.Sub("units", true);
  const std::string csv_path = args.output + "/summary.csv";
  const std::string json_path = args.output + "/summary.json";
  std::vector<std::string> all_inputs = files;
  if (!args.limits.empty()) all_inputs.push_back(args.limits);
  CheckOutputs({{"summary", csv_path}, {"summary", json_path}}, all_inputs);

  std::vector<Unit> units = UnitsOf(args, files, pattern);
  CheckUnitOptions(args, units);
  RunUnits(args, units_dir, &units);

  const batch::Summary summary = batch::Summarise(args, limits, limits_sha256, &units);
  const std::array<int, 3>& counts = summary.counts;
  const std::string json_text = JsonText(summary.doc);
  OutputFile csv_file(out_dir, "summary.csv"), json_file(out_dir, "summary.json");
  csv_file.Write(summary.csv);
  json_file.Write(json_text);
  CommitAll({&csv_file, &json_file});

  if (args.json) {
    WriteOut(json_text);
  } else {
    SayUnits(units, counts, csv_path, json_path);
  }
  if (counts[1] + counts[2] == 0) return kExitOk;
  // Said on stderr too, as a calibration that fails its checks is: stdout may go to a file.
  WriteErrLine(
      Format("accelcal: %d of %zu units failed their limits or checks, %d could not be "
             "calibrated (%s)\n",
             counts[1], units.size(), counts[2], csv_path.c_str()));
  return kExitFailedChecks;
}

CommandRun SetUpBatch(CLI::App* cmd) {
  auto a = std::make_shared<BatchArgs>();
  auto calibrate = std::make_shared<CalibrateArgs>();  // passed on as given
  cmd->add_option("INPUT", a->inputs,
                  "the units' recordings: files, and directories whose files are read")
      ->required();
  cmd->add_option("-o,--output", a->output,
                  "the batch's directory: units/ID/calibration.json and report.html, "
                  "summary.csv and summary.json (made when missing)")
      ->required()
      ->check(kFileName);
  cmd->add_option("--limits", a->limits,
                  "acceptance limits (YAML, docs/batch.md); without: a unit passes when its "
                  "calibration passes its own checks")
      ->check(kFileName);
  cmd->add_option("--unit-id", a->unit_id,
                  "a regular expression searched in each file's name: its first group (or "
                  "the match) is the unit's id; files with one id are one unit's sessions "
                  "(default: the name less its extension)")
      ->type_name("REGEX");
  cmd->add_option("--unit-id-from", a->unit_id_from,
                  "where a unit's id comes from: name (the file's, see --unit-id), info:KEY (a "
                  "binary log's information, e.g. info:sys_uuid, a PX4 board's), param:KEY (a "
                  "log's parameter, e.g. param:BRD_SERIAL_NUM, an ArduPilot board's), "
                  "device-id (the accelerometer stream's: the same on every board of a "
                  "design, see docs/batch.md), or frame-id (a ROS Imu topic's "
                  "header.frame_id, where each unit's frame has its own name)")
      ->capture_default_str();
  cmd->add_option("--glob", a->glob, "the files read from a directory given")
      ->capture_default_str();
  cmd->add_option("--jobs", a->jobs, "units calibrated at once (0: one per core)")
      ->capture_default_str();
  cmd->add_flag("--redo", a->redo,
                "calibrate every unit again, even one whose calibration is current");
  cmd->add_flag("!--no-report", a->report, "no HTML report per unit");
  cmd->add_flag("--json", a->json, "print the summary document instead of the table");
  AddCalibrationOptions(cmd, calibrate.get());
  AddDateOption(cmd, calibrate.get());
  return [a, calibrate](const CLI::App& parsed) {
    CheckCalibrationFlags(parsed, calibrate.get());
    a->unit_id_given = parsed.count("--unit-id") > 0;
    a->calibrate_options = GivenOptions(parsed, {"output", "limits", "unit-id", "unit-id-from",
                                                 "glob", "jobs", "redo", "no-report", "json"});
    for (const auto& option : a->calibrate_options) {  // the date is the provenance's own
      if (option.first != "date") calibrate->given_options.push_back(option);
    }
    a->calibrate = *calibrate;
    return RunBatch(*a);
  };
}

}  // namespace accelcal::cli
