// The pieces every command shares: option values, inputs, gravity, numbers (cli_common.hpp).
#include "cli_common.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "accelcal/calibrate_unit.hpp"
#include "accelcal/calibration_file.hpp"
#include "accelcal/compare.hpp"
#include "accelcal/design.hpp"
#include "accelcal/diagnosis.hpp"
#include "accelcal/engineering.hpp"
#include "accelcal/error.hpp"
#include "accelcal/export.hpp"
#include "accelcal/frame.hpp"
#include "accelcal/gimbal_platform.hpp"
#include "accelcal/gravity.hpp"
#include "accelcal/known_orientation.hpp"
#include "accelcal/model_selection.hpp"
#include "accelcal/montecarlo.hpp"
#include "accelcal/orientation_file.hpp"
#include "accelcal/report.hpp"
#include "accelcal/series_file.hpp"
#include "accelcal/simulate.hpp"
#include "accelcal/system_level.hpp"
#include "output.hpp"

namespace accelcal::cli {

OutlierOptions ParseOutlierOptions(const OutlierArgs& args) {
  OutlierOptions options;
  options.policy = ParseChoice<OutlierPolicy>(args.policy, "--outliers");
  options.false_alarm_probability = args.probability;
  options.max_excluded = args.max_excluded;
  return options;
}

DataError NoStaticInterval(const StaticDetectionResult& d) {
  const std::string reason = NoStaticIntervalReason(d);
  return DataError(reason + (reason.find("turning") != std::string::npos
                                 ? "; --verbose lists them"
                                 : "; try --threshold-factor or --min-static"));
}

ReadOptions MakeReadOptions(const InputArgs& in) {
  ReadOptions options;
  options.kind = ParseChoice<InputKind>(in.input_kind, "--input-kind");
  if (!in.columns.empty() && in.columns.size() != 3 && in.columns.size() != 4) {
    throw UsageError("--columns takes x,y,z or time,x,y,z");
  }
  options.columns = in.columns;
  // A rate that is no rate is a usage error before anything is read (issue 16).
  if (in.rate_hz && !(*in.rate_hz >= kMinRate_hz && *in.rate_hz <= kMaxRate_hz)) {
    throw UsageError(Format("--rate must be a number of Hz in [%g, %g]", kMinRate_hz, kMaxRate_hz));
  }
  options.rate_hz = in.rate_hz;
  options.time_unit = ParseChoice<TimeUnit>(in.time_unit, "--time-unit");
  if (in.instance && !std::isfinite(*in.instance)) {
    throw UsageError("--instance must be a finite number");
  }
  options.instance = in.instance;
  if (in.topic) {
    if (in.topic->empty()) throw UsageError("--topic: an empty topic name");
    options.topic = *in.topic;
  }
  if (in.frame_id) {
    if (in.frame_id->empty()) throw UsageError("--frame-id: an empty frame name");
    options.frame_id = *in.frame_id;
  }
  if (in.temperature_column) {
    if (in.temperature_column->empty()) throw UsageError("--temperature-column: an empty name");
    options.temperature = *in.temperature_column;
  }
  return options;
}

void ReportLoading(LoadOptions* options) {
  auto bar = std::make_shared<std::optional<ProgressBar>>();
  auto start = std::make_shared<std::chrono::steady_clock::time_point>();
  options->before_file = [options, bar, start](const std::string&) {
    *start = std::chrono::steady_clock::now();
    bar->emplace("reading");
    options->read.progress = (*bar)->ByteCallback();
  };
  options->after_file = [bar, start](const LoadedFile& loaded) {
    (*bar)->Finish();
    Detail("read %s in %.1f ms\n", loaded.path.c_str(),
           1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - *start).count());
    if (!loaded.detection) return;
    const StaticDetectionResult& d = *loaded.detection;
    Detail(
        "detection: %.6g Hz, window %zu samples, noise reference %.4g raw^2, threshold %.4g "
        "raw^2: %zu intervals, %zu still periods not used\n",
        d.rate_hz, d.window_samples, d.noise_reference, d.threshold, d.intervals.size(),
        d.rejected.size());
    for (const RejectedInterval& r : d.rejected) {
      if (r.cause == RejectedInterval::Cause::kClipped) {  // a position the user meant to record
        Warn("%s: the still period %.3f-%.3f s is not used: %s\n", loaded.path.c_str(), r.t_begin_s,
             r.t_end_s, r.reason.c_str());
      } else {
        Detail("  not used: %.3f-%.3f s, %s\n", r.t_begin_s, r.t_end_s, r.reason.c_str());
      }
    }
    if (d.intervals.empty()) throw NoStaticInterval(d);  // with the options that act on it
  };
}

LoadedInput LoadInput(const InputArgs& in) {
  if (auto why = in.detection.Validate()) throw UsageError(*why);
  LoadOptions options;
  options.read = MakeReadOptions(in);
  options.detection = in.detection;
  ReportLoading(&options);
  std::vector<std::string> paths{in.path};
  paths.insert(paths.end(), in.more_paths.begin(), in.more_paths.end());
  return LoadPositions(paths, options);
}

void CheckGyroColumns(const InputArgs& input, const SensorInput& gyro) {
  if (auto why = GyroInputProblem(input.path, input.columns, gyro)) {
    throw UsageError(WithCliFlags(*why));
  }
}

InputData ReadGyroLog(const InputArgs& input, const SensorInput& gyro, bool fingerprint) {
  CheckGyroColumns(input, gyro);
  ReadOptions read = MakeReadOptions(input);
  read.fingerprint = fingerprint;
  return accelcal::ReadGyroLog(input.path, read, gyro);
}

std::string CliFlag(const std::string& name) {
  if (name == "input") return "INPUT";
  std::string flag = "--" + name;
  std::replace(flag.begin(), flag.end(), '_', '-');
  return flag;
}

std::string WithCliFlags(const std::string& marked) { return RenderOptionNames(marked, CliFlag); }

std::string DidNotConverge(const std::string& path, const UnitOutcome& unit) {
  return path + ": the solver did not converge: " + unit.accelerometer.summary.termination_message +
         "; nothing written";
}

std::string ErrorMessage(const std::exception_ptr& error, const std::string& subject, int* status) {
  try {
    std::rethrow_exception(error);
  } catch (const UsageError& e) {
    *status = kExitUsage;
    return std::string("usage: ") + e.what();
  } catch (const OptionError& e) {  // the library's rule, in the tool's words
    *status = kExitUsage;
    return "usage: " + WithCliFlags(e.marked());
  } catch (const InputError& e) {
    *status = kExitBadInput;
    return WithReaderFlags(WithCliFlags(e.what()));
  } catch (const NotConvergedError& e) {
    *status = kExitNotConverged;
    return (e.file().empty() ? subject : e.file()) + ": " + WithCliFlags(e.what()) +
           "; nothing written";
  } catch (const DataError& e) {
    *status = kExitBadInput;
    const std::string& about = e.file().empty() ? subject : e.file();
    return (about.empty() ? "" : about + ": ") + WithCliFlags(e.what());
  } catch (const OutputError& e) {
    *status = kExitOutput;
    return e.what();
  } catch (const std::bad_alloc&) {
    *status = kExitBadInput;
    return "out of memory: the input (or what an option asks for) needs more memory than this "
           "machine can give";
  } catch (const std::exception& e) {
    *status = kExitInternal;
    return std::string("internal error: ") + e.what();
  }
}

std::string& DataSubject() {
  thread_local std::string subject;  // per thread: the Python package runs commands in several
  return subject;
}

Gravity ResolveGravity(const GravityArgs& args) {
  Gravity g;
  g.unit = ParseChoice<ForceUnit>(args.units, "--units");
  if (args.gravity_ms2 && args.latitude_deg) {
    throw UsageError("--gravity and --latitude exclude each other");
  }
  if (args.gravity_ms2) {
    if (!(*args.gravity_ms2 >= kMinGravity_ms2 && *args.gravity_ms2 <= kMaxGravity_ms2)) {
      throw UsageError(
          Format("--gravity must be a number of m/s2 in [%g, %g] (9.78-9.83 on "
                 "Earth's surface)",
                 kMinGravity_ms2, kMaxGravity_ms2));
    }
    g.ms2 = *args.gravity_ms2;
    g.origin = "given";
  } else if (args.latitude_deg) {
    if (!(std::abs(*args.latitude_deg) <= 90)) throw UsageError("--latitude must lie in [-90, 90]");
    // The WGS-84 normal-gravity formula is a series in height: within ±20 km of the ellipsoid
    // (deep mines to high-flying aircraft); at 1e9 m it gives 720,084 m/s2.
    if (!(std::abs(args.height_m) <= kMaxHeight_m)) {
      throw UsageError(Format("--height must lie in [-%g, %g] m (the WGS-84 formula's range)",
                              kMaxHeight_m, kMaxHeight_m));
    }
    g.ms2 = NormalGravityWgs84_ms2(*args.latitude_deg, args.height_m);
    g.origin =
        Format("WGS-84 normal gravity at %.6g deg, %.6g m", *args.latitude_deg, args.height_m);
  } else {
    g.ms2 = kStandardGravity_ms2;
    g.origin = "standard gravity (default)";
  }
  g.in_unit = g.unit == ForceUnit::kMetersPerSecond2 ? g.ms2 : g.ms2 / kStandardGravity_ms2;
  return g;
}

std::string Vec(const Vec3& v, const char* fmt) {
  return Format(fmt, v(0)) + Format(fmt, v(1)) + Format(fmt, v(2));
}

// One discordant position, for the summary and the warning.
// `position_file`: the file of each position when there are several (LoadedInput).
std::string OutlierMessage(const OutlierFinding& o, const std::vector<Position>& positions,
                           const std::vector<double>& errors, const char* unit,
                           const std::vector<std::string>& position_file) {
  const auto k = static_cast<std::size_t>(o.position);
  std::string where;
  const std::string file = position_file.empty() ? "" : position_file[k] + " ";
  if (positions[k].interval) {
    where = Format(" (%s%.2f-%.2f s)", file.c_str(), positions[k].interval->t_begin_s,
                   positions[k].interval->t_end_s);
  } else if (!file.empty()) {
    where = " (" + position_file[k] + ")";
  }
  const std::string test =
      o.statistic == OutlierStatistic::kFisherF
          ? Format(
                "F = %.1f, beyond %.2f (Fisher F, 3 and %d degrees of freedom); moved or "
                "bumped during its interval, or not in the orientation the file gives?",
                o.t, o.threshold, o.degrees_of_freedom)
          : Format(
                "t = %.1f, beyond %.2f (Student t, %d degrees of freedom); moved or bumped "
                "during its interval?",
                o.t, o.threshold, o.degrees_of_freedom);
  return Format("position %d%s disagrees with the others: |f|-g %.3g %s under the fit %s it; %s",
                o.position + 1, where.c_str(), errors[k], unit, o.excluded ? "without" : "with",
                test.c_str());
}

bool IsDirectory(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

std::string UnitIdProblem(const std::string& id) {
  if (id.empty()) return "the unit id is empty";
  if (id.size() > 128) return "the unit id is longer than 128 bytes";
  // Named as a line can show it: a control character escaped, a byte that is not UTF-8 as \xHH.
  const std::string shown = "the unit id '" + internal::VisibleLine(id) + "'";
  if (id[0] == '.') return shown + " begins with '.'";
  if (id.front() == ' ' || id.back() == ' ') return shown + " begins or ends with a space";
  for (std::size_t i = 0; i < id.size();) {
    const internal::CodePoint c = internal::DecodeUtf8(id, i);
    // Not UTF-8: the summary's JSON could not hold it as it is, and two ids would read alike.
    if (c.value < 0) return shown + " is not UTF-8 text";
    // Controls and direction or width formatting: an id that would not read as it is.
    if (c.value == '/' || internal::IsInvisible(c.value) ||
        (c.value >= 0x200B && c.value <= 0x200F) || (c.value >= 0x202A && c.value <= 0x202E) ||
        (c.value >= 0x2060 && c.value <= 0x2069)) {
      return shown + " holds a '/', a control character or a direction or width format character";
    }
    i += c.length;
  }
  return "";
}

nlohmann::ordered_json GivenOptionsJson(
    const std::vector<std::pair<std::string, std::vector<std::string>>>& given) {
  nlohmann::ordered_json options = nlohmann::ordered_json::object();
  for (const auto& [name, values] : given) {
    options[name] = values.empty()       ? nlohmann::ordered_json(true)
                    : values.size() == 1 ? nlohmann::ordered_json(values.front())
                                         : nlohmann::ordered_json(values);
  }
  return options;
}

std::string FormatNumber(double v) {
  char buf[32];
  const auto res = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, res.ptr);
}

// A positions file as calibrate reads it: averaged readings with their sample count and the
// per-axis standard deviation of one sample.
std::string PositionsCsv(const std::vector<Vec3>& means, double samples, const Vec3& sample_sigma) {
  std::string out = "x,y,z,n,sx,sy,sz\n";
  for (const Vec3& p : means) {
    out += FormatNumber(p(0)) + "," + FormatNumber(p(1)) + "," + FormatNumber(p(2)) + "," +
           FormatNumber(samples) + "," + FormatNumber(sample_sigma(0)) + "," +
           FormatNumber(sample_sigma(1)) + "," + FormatNumber(sample_sigma(2)) + "\n";
  }
  return out;
}

nlohmann::ordered_json JsonArray(const Vec3& v) { return {v(0), v(1), v(2)}; }

std::string WithFlags(std::string message,
                      std::initializer_list<std::pair<const char*, const char*>> flags) {
  return internal::ReplaceWords(std::move(message), flags);
}

std::string WithReaderFlags(const std::string& message) {
  return WithFlags(message, {{"the columns option's entry", "--columns entry"},
                             {"the columns option", "--columns"},
                             {"the topic and instance options", "--topic and --instance"},
                             {"the topic option", "--topic"},
                             {"the frame option", "--frame-id"},
                             {"the temperature column", "--temperature-column"},
                             {"the temperature option", "--temperature-column"},
                             {"the time unit option", "--time-unit"},
                             {"the rate option", "--rate"},
                             {"input kind \"raw\"", "--input-kind raw"}});
}

// A calibration that failed its checks is written so that its reasons can be read, never used.
void RefuseFailed(const LoadedCalibration& cal, const std::string& path) {
  if (cal.verdict == "failed") {
    throw InputError(path, 0,
                     "this calibration failed its checks (\"verdict\": \"failed\"; its "
                     "\"diagnostics\" say why): it is not applied or exported");
  }
}

EngineeringValue ThermalEngineering(const ThermalSlot& slot, double raw, const Mat33& K_x_first,
                                    double gravity) {
  const ParameterSlot& s = slot.slot;
  const double kii = std::abs(K_x_first(s.row, s.row));
  const std::string per = slot.degree == 1 ? "/K" : Format("/K^%d", slot.degree);
  if (s.group == ParameterGroup::kK) {
    return s.row == s.col ? EngineeringValue{1e6 * raw / kii, "ppm" + per}
                          : EngineeringValue{1e6 * raw / kii, "urad" + per};
  }
  if (s.group == ParameterGroup::kBias) return {1e3 * raw / kii / gravity, "mg" + per};
  return {1e6 * raw * gravity / kii, "ug/g^2" + per};
}

void WarnOtherTemperatureSensor(const LoadedCalibration& cal, const std::string& path,
                                const std::string& source, const char* use) {
  if (!cal.gyroscope || !cal.gyroscope->thermal) return;
  const std::string& fitted_at = cal.gyroscope->thermal->temperature_source;
  if (fitted_at.empty() || SameTemperatureSensor(fitted_at, source)) return;
  Warn(
      "%s: the gyroscope's offsets over temperature were fitted at the temperatures of %s, and "
      "these rates are %s at those of %s: one die may run warmer than the other\n",
      path.c_str(), VisibleLine(fitted_at).c_str(), use, VisibleLine(source).c_str());
}

void RefuseLeftOutTemperature(const LoadedCalibration& cal, const RawLog& log,
                              const std::string& path) {
  if (!cal.thermal || log.temperature_note.empty()) return;
  for (double t : log.temperature_c) {
    if (std::isfinite(t)) return;  // some readings have one
  }
  throw InputError(path, 0,
                   "the calibration's parameters follow temperature, and this log's temperature "
                   "was left out (" +
                       log.temperature_note +
                       "): give its column in degC with --temperature-column, or "
                       "--temperature-column none to use the parameters at T_ref");
}

void WarnVaryingNotUsed(const LoadedCalibration& cal, const std::string& path, const char* use) {
  if (cal.thermal) {
    Warn(
        "%s: its parameters follow temperature (degrees %s); they are %s at one temperature, "
        "T_ref = %.6g degC, not at the temperature of each reading\n",
        path.c_str(), cal.thermal->params.degrees.ToString().c_str(), use,
        cal.thermal->params.t_ref_c);
  }
  if (cal.gyroscope && cal.gyroscope->thermal && cal.gyroscope->thermal->bias.degree() > 0) {
    Warn(
        "%s: its gyroscope's offsets follow temperature (degree %d); they are %s at one "
        "temperature, T_ref = %.6g degC, not at the temperature of each reading\n",
        path.c_str(), cal.gyroscope->thermal->bias.degree(), use,
        cal.gyroscope->thermal->bias.t_ref_c);
  }
  if (!cal.drift) return;
  Warn(
      "%s: its bias drifted within its session (a %s bias); it is %s with one bias, the "
      "value at t = %.6g s of that session (its positions' mean time), not the drift\n",
      path.c_str(), ToString(cal.drift->basis.model).c_str(), use, cal.drift->basis.t_ref_s);
}

// Planned directions: a named scheme, or a file with one unit vector per row.
std::vector<Vec3> PlannedDirections(const std::string& spec) {
  if (std::optional<std::vector<Vec3>> scheme = SchemeDirections(spec)) return *scheme;
  return ReadOrientations(spec).directions;
}

}  // namespace accelcal::cli
