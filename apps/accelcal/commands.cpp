#include "commands.hpp"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <sstream>
#include <stdexcept>

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

namespace {

// Ranges of the options that take physical quantities (issue 16): beyond them a value is a
// mistake (a unit slip, a typo), never a calibration.
constexpr double kMaxRate_hz = 1e6;
constexpr double kMinGravity_ms2 = 1.0, kMaxGravity_ms2 = 100.0;
constexpr double kMaxHeight_m = 20000.0;

template <typename T>
T ParseEnum(std::optional<T> value, const std::string& text, const char* option,
            const char* allowed) {
  if (!value) throw UsageError(std::string(option) + ": '" + text + "' is not one of " + allowed);
  return *value;
}

OutlierOptions ParseOutlierOptions(const OutlierArgs& args) {
  OutlierOptions options;
  options.policy = ParseEnum(OutlierPolicyFromString(args.policy), args.policy, "--outliers",
                             "exclude, flag, off");
  options.false_alarm_probability = args.probability;
  options.max_excluded = args.max_excluded;
  return options;
}

// One input file as read, with its static intervals when it is a raw log.
struct LoadedFile {
  std::string path;
  InputData data;
  std::optional<StaticDetectionResult> detection;
};

// The input files of a calibration (sessions of one device: positions pooled in file order, time
// never joined across files).
struct LoadedInput {
  std::vector<LoadedFile> files;
  std::vector<Position> positions;
  /// The file of each position, when there are several files (else empty).
  std::vector<std::string> position_file;
  /// The first raw log, for the report's signal plot (nullptr: none).
  const LoadedFile* FirstRaw() const {
    for (const LoadedFile& f : files) {
      if (f.data.kind == InputKind::kRaw) return &f;
    }
    return nullptr;
  }
};

// Why detection found nothing, with the options that act on it.
DataError NoStaticInterval(const StaticDetectionResult& d) {
  const std::string reason = NoStaticIntervalReason(d);
  return DataError(reason + (reason.find("turning") != std::string::npos
                                 ? "; --verbose lists them"
                                 : "; try --threshold-factor or --min-static"));
}

ReadOptions MakeReadOptions(const InputArgs& in) {
  ReadOptions options;
  options.kind = ParseEnum(InputKindFromString(in.input_kind), in.input_kind, "--input-kind",
                           "auto, raw, positions");
  options.columns = in.columns;
  // A rate that is no rate is a usage error before anything is read (issue 16).
  if (in.rate_hz && !(*in.rate_hz > 0 && *in.rate_hz <= kMaxRate_hz)) {
    throw UsageError(Format("--rate must be a number of Hz in (0, %g]", kMaxRate_hz));
  }
  options.rate_hz = in.rate_hz;
  options.time_unit = ParseEnum(TimeUnitFromString(in.time_unit), in.time_unit, "--time-unit",
                                "auto, s, ms, us, ns");
  if (in.instance && !std::isfinite(*in.instance)) {
    throw UsageError("--instance must be a finite number");
  }
  options.instance = in.instance;
  return options;
}

LoadedFile LoadFile(const InputArgs& in, const std::string& path) {
  LoadedFile loaded;
  loaded.path = path;
  const auto start = std::chrono::steady_clock::now();
  ReadOptions read = MakeReadOptions(in);
  ProgressBar bar("reading");
  read.progress = bar.ByteCallback();
  loaded.data = ReadInput(path, read);
  bar.Finish();
  Detail("read %s in %.1f ms\n", path.c_str(),
         1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  if (loaded.data.kind == InputKind::kPositions) return loaded;
  loaded.detection = DetectStaticIntervals(loaded.data.raw, in.detection);
  const StaticDetectionResult& d = *loaded.detection;
  Detail(
      "detection: %.6g Hz, window %zu samples, noise reference %.4g raw^2, threshold %.4g raw^2: "
      "%zu intervals, %zu still periods not used\n",
      d.rate_hz, d.window_samples, d.noise_reference, d.threshold, d.intervals.size(),
      d.rejected.size());
  for (const RejectedInterval& r : d.rejected) {
    if (r.cause == RejectedInterval::Cause::kClipped) {  // a position the user meant to record
      Warn("%s: the still period %.3f-%.3f s is not used: %s\n", path.c_str(), r.t_begin_s,
           r.t_end_s, r.reason.c_str());
    } else {
      Detail("  not used: %.3f-%.3f s, %s\n", r.t_begin_s, r.t_end_s, r.reason.c_str());
    }
  }
  if (loaded.detection->intervals.empty()) throw NoStaticInterval(d);
  return loaded;
}

LoadedInput LoadInput(const InputArgs& in) {
  if (auto why = in.detection.Validate()) throw UsageError(*why);
  LoadedInput loaded;
  std::vector<std::string> paths{in.path};
  paths.insert(paths.end(), in.more_paths.begin(), in.more_paths.end());
  for (const std::string& path : paths) {
    try {
      loaded.files.push_back(LoadFile(in, path));
    } catch (const DataError& e) {  // what is wrong with one file of several names that file
      if (paths.size() == 1) throw;
      throw InputError(path, 0, e.what());
    }
    const LoadedFile& f = loaded.files.back();
    const std::vector<Position> positions = f.data.kind == InputKind::kPositions
                                                ? f.data.positions
                                                : PositionsFromIntervals(f.detection->intervals);
    loaded.positions.insert(loaded.positions.end(), positions.begin(), positions.end());
    if (paths.size() > 1) loaded.position_file.resize(loaded.positions.size(), path);
  }
  return loaded;
}

struct Gravity {
  double in_unit;  // gravity magnitude in the output unit
  double ms2;      // the same in m/s²
  ForceUnit unit;
  std::string origin;
};

Gravity ResolveGravity(const GravityArgs& args) {
  Gravity g;
  g.unit = ParseEnum(ForceUnitFromString(args.units), args.units, "--units", "m/s2, g");
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

std::string Vec(const Vec3& v, const char* fmt = "%14.8g") {
  return Format(fmt, v(0)) + Format(fmt, v(1)) + Format(fmt, v(2));
}

void PrintInput(const LoadedInput& in) {
  for (const LoadedFile& f : in.files) {
    if (f.data.kind == InputKind::kPositions) {
      Say("input     %s: %zu positions (%s)\n", f.path.c_str(), f.data.positions.size(),
          f.data.kind_reason.c_str());
      continue;
    }
    const StaticDetectionResult& d = *f.detection;
    Say("input     %s: raw log, %zu samples at %.6g Hz (%s)\n", f.path.c_str(),
        f.data.raw.samples.size(), d.rate_hz, f.data.kind_reason.c_str());
    Say("detection %zu static intervals (window %zu samples, threshold %.4g raw^2 = %.3g x "
        "noise reference)\n",
        d.intervals.size(), d.window_samples, d.threshold,
        d.noise_reference > 0 ? d.threshold / d.noise_reference : 0.0);
  }
  if (in.files.size() > 1) {
    Say("pooled    %zu positions from %zu files\n", in.positions.size(), in.files.size());
  }
}

// The three parameter pairs with the largest |correlation|: what the positions cannot separate.
void PrintStrongestCorrelations(const Eigen::MatrixXd& covariance,
                                const std::vector<ParameterSlot>& slots) {
  struct Pair {
    double rho;
    Eigen::Index i, j;
  };
  std::vector<Pair> pairs;
  for (Eigen::Index i = 0; i < covariance.rows(); ++i) {
    for (Eigen::Index j = 0; j < i; ++j) {
      const double rho = covariance(i, j) / std::sqrt(covariance(i, i) * covariance(j, j));
      if (std::isfinite(rho)) pairs.push_back({rho, i, j});
    }
  }
  const std::size_t shown = std::min<std::size_t>(3, pairs.size());
  std::partial_sort(pairs.begin(), pairs.begin() + static_cast<std::ptrdiff_t>(shown), pairs.end(),
                    [](const Pair& a, const Pair& b) { return std::abs(a.rho) > std::abs(b.rho); });
  Say("  strongest correlations:");
  for (std::size_t k = 0; k < shown; ++k) {
    Say("%s %s/%s %+.3f", k ? "," : "",
        std::string(slots[static_cast<std::size_t>(pairs[k].i)].name).c_str(),
        std::string(slots[static_cast<std::size_t>(pairs[k].j)].name).c_str(), pairs[k].rho);
  }
  Say("\n");
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

void PrintCalibration(const CalibrationResult& r, const std::vector<Position>& positions,
                      const std::vector<std::string>& position_file, const Gravity& g,
                      const std::string& raw_unit) {
  const char* u = g.unit == ForceUnit::kMetersPerSecond2 ? "m/s2" : "g";
  const bool have_std = r.covariance.size() > 0;
  const auto& slots = ParameterSlots(r.model, r.frame);
  Say("\nmodel     %s, p = K f + b + k2 * f^2, frame %s, gravity %.9g %s (%s)\n",
      std::string(ToString(r.model)).c_str(), std::string(ToString(r.frame)).c_str(), g.in_unit, u,
      g.origin.c_str());
  const std::string noise =
      r.noise_source == "samples"
          ? Format("noise of each interval's samples, x %.3g scatter ratio", r.scatter_ratio)
          : std::string("noise from the residuals");
  Say("\nparameters (K in %s per %s, b in %s, k2 in %s per %s^2; +- 1 sigma, %s)\n",
      raw_unit.c_str(), u, raw_unit.c_str(), raw_unit.c_str(), u, noise.c_str());
  const Eigen::VectorXd theta = Pack(r.params, slots);
  for (std::size_t i = 0; i < slots.size(); ++i) {
    const auto idx = static_cast<Eigen::Index>(i);
    if (have_std) {
      Say("  %-5s %18.10g +- %.3g\n", std::string(slots[i].name).c_str(), theta(idx),
          std::sqrt(r.covariance(idx, idx)));
    } else {
      Say("  %-5s %18.10g\n", std::string(slots[i].name).c_str(), theta(idx));
    }
  }
  if (have_std) PrintStrongestCorrelations(r.covariance, slots);
  const EngineeringParameters e = ToEngineering(r.params, r.gravity);
  const double ug = 1e6 / r.gravity;
  // ±1σ propagated from the parameter covariance, when there is one.
  std::optional<EngineeringStd> sd;
  if (have_std) {
    sd = EngineeringUncertainty(r.params, r.model, r.frame, r.gravity, r.covariance);
  }
  // Values ± their 1σ (`sigma` empty: none).
  const auto pm = [&](const Eigen::VectorXd& v, const Eigen::VectorXd& sigma, double scale,
                      const char* format) {
    std::string text;
    for (Eigen::Index i = 0; i < v.size(); ++i) {
      text += Format(format, v(i) * scale);
      if (sigma.size() > 0) text += Format(" +- %.2g", sigma(i) * scale);
      text += i + 1 < v.size() ? "   " : "";
    }
    return text;
  };
  const auto sd_of = [&](auto member) {
    return sd ? Eigen::VectorXd(*sd.*member) : Eigen::VectorXd();
  };
  Say("\nengineering (%s conventions%s)\n",
      r.frame == Frame::kPlatform ? "paper 003 eq. (5)" : "paper 000 Table 3",
      sd ? "; +- 1 sigma propagated from the parameters" : "");
  Say("  scale factor     %s  %s/%s\n",
      pm(e.scale_factor, sd_of(&EngineeringStd::scale_factor), 1.0, "%.10g").c_str(),
      raw_unit.c_str(), u);
  const Misalignment tau = MisalignmentOf(r.params.K, r.frame);
  std::string names;
  for (std::string_view name : tau.names) names += (names.empty() ? "" : ", ") + std::string(name);
  Say("  misalignment     %s\n", names.c_str());
  Say("                   %s  arcsec\n",
      pm(tau.rad, sd_of(&EngineeringStd::misalignment_rad), kArcsecPerRad, "%.4f").c_str());
  Say("  bias             %s  %s\n",
      pm(e.bias_force, sd_of(&EngineeringStd::bias_force), 1.0, "%.6g").c_str(), u);
  Say("                   %s  ug\n",
      pm(e.bias_force, sd_of(&EngineeringStd::bias_force), ug, "%.6g").c_str());
  if (r.model == ModelKind::kQuadratic) {
    Say("  squared coeff.   %s  g/g^2\n",
        pm(e.k2_g_per_g2, sd_of(&EngineeringStd::k2_g_per_g2), 1.0, "%.4g").c_str());
  }
  const std::vector<Vec3> means = Means(positions);
  const std::vector<double> errors = GravityNormErrors(r.params, means, r.gravity);
  Say("\npositions (|f|-g in %s, residual p - mu in %s)\n", u, raw_unit.c_str());
  Say("  %3s %8s %42s %12s %36s\n", "#", "samples", "mean", "|f|-g", "residual");
  for (std::size_t k = 0; k < positions.size(); ++k) {
    Say("  %3zu %8zu %s %12.4g %s%s\n", k + 1, positions[k].samples, Vec(positions[k].mean).c_str(),
        errors[k], Vec(r.residuals[k], "%12.4g").c_str(), r.excluded(k) ? "  excluded" : "");
  }
  for (const OutlierFinding& o : r.outliers) {
    Say("%s  %s\n", o.excluded ? "excluded " : "flagged  ",
        OutlierMessage(o, positions, errors, u, position_file).c_str());
  }
  if (!r.outlier_note.empty()) Say("screening %s\n", r.outlier_note.c_str());
  const std::optional<double> before = GravityNormRmsUncalibrated(means, r.gravity);
  const std::vector<double> used_errors = r.InFit(errors);  // outliers excluded
  Say("\nrms |f|-g  before: %s   after: %.6g %s%s\n",
      before ? Format("%.6g %s", *before, u).c_str()
             : Format("n/a (raw readings are not in %s)", u).c_str(),
      Rms(used_errors), u, used_errors.size() < errors.size() ? " (positions in the fit)" : "");
  if (r.crossval_rms) {
    Say("held-out  rms |f|-g %.6g %s (each position corrected by a fit without it)\n",
        *r.crossval_rms, u);
  } else if (!r.crossval_note.empty()) {
    Say("held-out  n/a: %s\n", r.crossval_note.c_str());
  }
  Say("solver    %s\n", r.summary.BriefReport().c_str());
  if (!r.summary.initialization_note.empty()) {
    Say("note      %s\n", r.summary.initialization_note.c_str());
  }
}

std::string FormatNumber(double v) {
  char buf[32];
  const auto res = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, res.ptr);
}

// A JSON array of three shortest round-trip numbers.
std::string JsonVector(const Vec3& v) {
  return "[" + FormatNumber(v(0)) + ", " + FormatNumber(v(1)) + ", " + FormatNumber(v(2)) + "]";
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

}  // namespace

namespace {

void PrintModelSelection(const ModelSelection& s, bool requested_auto) {
  if (requested_auto) {
    Say("model     auto -> %s: %s\n", std::string(ToString(s.chosen)).c_str(), s.reason.c_str());
  } else {
    Say("model     quadratic (requested); the data support %s: %s\n",
        std::string(ToString(s.chosen)).c_str(), s.reason.c_str());
  }
  if (s.quadratic && std::isfinite(s.k2_t.sum())) {
    Say("          squared coefficients k2/sigma: %.3g %.3g %.3g (significant beyond %.3g)\n",
        s.k2_t(0), s.k2_t(1), s.k2_t(2), s.k2_t_threshold);
  }
}

}  // namespace

namespace {

// What the command line adds to a finding: the option that acts on it.
const char* OptionHint(const Finding& f) {
  if (f.code == "units") {
    return f.message.find("calibrate in g") != std::string::npos ? " (--units g)"
                                                                 : " (--units m/s2)";
  }
  if (f.code == "outlier_limit") return " (--max-outliers)";
  if (f.code == "time_unit") return " (--time-unit)";
  if (f.code == "positions_like_samples") return " (--input-kind raw)";
  return "";
}

// Warnings and failures on stderr (outliers and still periods not used are told where found).
void PrintFindings(const Diagnosis& diagnosis, const std::string& path) {
  for (const Finding& f : diagnosis.findings) {
    if (f.code == "outlier" || f.code == "rejected_period") continue;
    if (f.severity == Severity::kFailure) {
      std::fprintf(stderr, "accelcal: %s: failed check (%s): %s%s\n", path.c_str(), f.code.c_str(),
                   f.message.c_str(), OptionHint(f));
    } else if (f.severity == Severity::kWarning) {
      Warn("%s: %s%s\n", path.c_str(), f.message.c_str(), OptionHint(f));
    }
  }
}

// The end of every calibrate: the file to -o, then the file to stdout (--json) or the summary
// (`input_note`, when not empty, printed after the input's description).
int WriteCalibration(const CalibrateArgs& args, const LoadedInput& in, const Gravity& g,
                     const CalibrationResult& result, const ModelSelection* selection,
                     const std::string& input_note) {
  DiagnosisInput diagnosis_input;
  diagnosis_input.result = &result;
  diagnosis_input.positions = &in.positions;
  diagnosis_input.max_excluded = args.outliers.max_excluded;
  diagnosis_input.selection = selection;
  for (const LoadedFile& f : in.files) {
    if (f.data.kind == InputKind::kRaw) {
      diagnosis_input.logs.push_back({f.path, &f.data.raw, &*f.detection});
    }
  }
  diagnosis_input.unit = g.unit;
  for (const LoadedFile& f : in.files) {
    diagnosis_input.positions_by_row_count |= f.data.kind_from_row_count;
  }
  const Diagnosis diagnosis = Diagnose(diagnosis_input);
  CalibrationFileInfo info;
  info.unit = g.unit;
  info.raw_unit = args.raw_units;
  info.source = args.input.path;
  if (in.files.size() > 1) {
    for (const LoadedFile& f : in.files) info.sources.push_back(f.path);
    for (const std::string& file : in.position_file) {
      info.position_source.push_back(static_cast<int>(
          std::find(info.sources.begin(), info.sources.end(), file) - info.sources.begin()));
    }
  }
  info.positions = in.positions;
  info.model_selection = selection;
  info.model_requested = args.model;
  info.diagnosis = &diagnosis;
  const std::string json = CalibrationToJson(result, info);
  // Everything is rendered before anything is written: a failure leaves no file behind.
  std::string report;
  if (!args.report.empty()) {
    ReportInput input;
    input.calibration_json = json;
    input.calibration_name = args.output.empty() ? args.input.path : args.output;
    if (const LoadedFile* raw = in.FirstRaw()) {  // the report plots one log: the first
      input.log = &raw->data.raw;
      input.rejected = raw->detection->rejected;
    }
    report = RenderReport(input);
  }
  {  // both files or neither
    std::optional<OutputFile> file, report_file;
    if (!args.output.empty()) file.emplace(args.output).Write(json);
    if (!args.report.empty()) report_file.emplace(args.report).Write(report);
    CommitAll({file ? &*file : nullptr, report_file ? &*report_file : nullptr});
  }
  const std::vector<double> errors =
      GravityNormErrors(result.params, Means(in.positions), result.gravity);
  for (const OutlierFinding& o : result.outliers) {
    Warn("%s: %s%s\n", args.input.path.c_str(),
         OutlierMessage(o, in.positions, errors,
                        g.unit == ForceUnit::kMetersPerSecond2 ? "m/s2" : "g", in.position_file)
             .c_str(),
         o.excluded ? " It was left out of the fit." : " It was kept in the fit.");
  }
  PrintFindings(diagnosis, args.input.path);
  if (args.json) {
    WriteFileAtomically("-", json);
  } else {
    PrintInput(in);
    Say("%s", input_note.c_str());
    PrintCalibration(result, in.positions, in.position_file, g, args.raw_units);
    if (selection) PrintModelSelection(*selection, args.model == "auto");
    for (const Finding& f : diagnosis.findings) {
      if (f.severity == Severity::kNote) Say("note      %s\n", f.message.c_str());
    }
    Say("verdict   %s\n", std::string(ToString(diagnosis.verdict())).c_str());
    if (!args.output.empty()) Say("wrote     %s\n", args.output.c_str());
    if (!args.report.empty()) Say("report    %s\n", args.report.c_str());
  }
  if (diagnosis.verdict() == Verdict::kFailed) {
    std::fprintf(stderr,
                 "accelcal: %s: the calibration failed its checks: written, but marked "
                 "\"verdict\": \"failed\"; do not use it as it is\n",
                 args.input.path.c_str());
    return kExitFailedChecks;
  }
  return kExitOk;
}

// calibrate --orientations: the platform-frame least squares of known_orientation.hpp.
int RunCalibrateKnownOrientations(const CalibrateArgs& args) {
  if (!args.gravity_only_options.empty()) {
    throw UsageError(args.gravity_only_options.front() +
                     " does not apply with --orientations (a closed-form fit in the platform "
                     "frame)");
  }
  if (args.model == "auto") {
    throw UsageError("--model auto is not available with --orientations: give linear or quadratic");
  }
  KnownOrientationOptions options;
  options.model =
      ParseEnum(ModelKindFromString(args.model), args.model, "--model", "linear, quadratic");
  options.cross_validate = args.cross_validate;
  options.outliers = ParseOutlierOptions(args.outliers);
  const Gravity g = ResolveGravity(args.gravity);
  options.gravity = g.in_unit;
  if (auto why = options.Validate()) throw UsageError(*why);
  const OrientationFile orientations = ReadOrientations(args.orientations);
  const LoadedInput in = LoadInput(args.input);
  if (orientations.directions.size() != in.positions.size()) {
    throw DataError(args.orientations + " has " + std::to_string(orientations.directions.size()) +
                    " orientations for the " + std::to_string(in.positions.size()) +
                    " positions of " + args.input.path);
  }
  options.reading_sigmas = SigmasOfMeans(in.positions);
  const CalibrationResult result =
      CalibrateKnownOrientations(Means(in.positions), orientations.directions, options);
  return WriteCalibration(args, in, g, result, nullptr,
                          Format("orient.   %s: %zu known orientations\n",
                                 args.orientations.c_str(), orientations.directions.size()));
}

}  // namespace

int RunCalibrate(const CalibrateArgs& args) {
  {
    std::vector<std::string> inputs = args.input.more_paths;
    inputs.push_back(args.input.path);
    inputs.push_back(args.orientations);
    CheckOutputs({{"-o", args.output}, {"--report", args.report}}, inputs);
  }
  if (!args.orientations.empty()) return RunCalibrateKnownOrientations(args);
  CalibrationOptions options;
  const bool auto_model = args.model == "auto";
  options.model = auto_model ? ModelKind::kLinear
                             : ParseEnum(ModelKindFromString(args.model), args.model, "--model",
                                         "linear, quadratic, auto");
  options.method = ParseEnum(SolverMethodFromString(args.method), args.method, "--method",
                             "joint, two-step, newton-lagrange, modulus, modulus-norm, ellipsoid");
  options.initialization = ParseEnum(InitializationFromString(args.init), args.init, "--init",
                                     "auto, ellipsoid, normalized-readings");
  if (args.frame == "platform") {
    throw UsageError(
        "--frame platform is the frame of known orientations: give them with "
        "--orientations");
  }
  options.frame = ParseEnum(FrameFromString(args.frame), args.frame, "--frame", "x-first, z-first");
  options.estimator = ParseEnum(EstimatorFromString(args.estimator), args.estimator, "--estimator",
                                "ml, bias-corrected");
  options.outliers = ParseOutlierOptions(args.outliers);
  options.cross_validate = args.cross_validate;
  if (auto_model && !args.cross_validate) {
    throw UsageError(
        "--model auto decides on held-out error: it needs the cross-validation that "
        "--no-crossval turns off");
  }
  const Gravity g = ResolveGravity(args.gravity);
  options.gravity = g.in_unit;
  if (args.max_iterations > 0) {
    options.two_step.max_sweeps = args.max_iterations;
    options.joint.max_iterations = args.max_iterations;
    options.modulus.max_iterations = args.max_iterations;
    options.newton_lagrange.max_iterations = args.max_iterations;
  }
  if (auto why = options.Validate()) throw UsageError(*why);
  if (auto_model) {
    CalibrationOptions quadratic = options;
    quadratic.model = ModelKind::kQuadratic;
    if (auto why = quadratic.Validate()) throw UsageError("--model auto: " + *why);
  }
  const LoadedInput in = LoadInput(args.input);
  const std::vector<Vec3> means = Means(in.positions);
  options.reading_sigmas = SigmasOfMeans(in.positions);  // empty: noise from the residuals
  // For a quadratic fit (asked for, or a candidate of --model auto) the linear fit is the
  // comparison: both with held-out validation, decided by ModelSelection's rule.
  const ModelChoice choice = CalibrateChoosingModel(means, options, auto_model);
  const CalibrationResult& result = choice.result;
  const std::optional<ModelSelection>& selection = choice.selection;
  if (!result.summary.converged()) {
    std::fprintf(stderr, "accelcal: %s: the solver did not converge: %s; nothing written\n",
                 args.input.path.c_str(), result.summary.termination_message.c_str());
    return kExitNotConverged;
  }
  return WriteCalibration(args, in, g, result, selection ? &*selection : nullptr, "");
}

int RunCompare(const CompareArgs& args) {
  CompareOptions options;
  options.base.model =
      ParseEnum(ModelKindFromString(args.model), args.model, "--model", "linear, quadratic");
  options.base.initialization = ParseEnum(InitializationFromString(args.init), args.init, "--init",
                                          "auto, ellipsoid, normalized-readings");
  const Gravity g = ResolveGravity(args.gravity);
  options.base.gravity = g.in_unit;
  options.leave_one_out = args.leave_one_out;
  if (!args.reference.empty()) {
    options.reference =
        ParseCalibrationJson(ReadFileToString(args.reference, kMaxSmallFileBytes), args.reference)
            .params;
  }
  for (const std::string& name : args.methods) {
    options.methods.push_back(
        ParseEnum(SolverMethodFromString(name), name, "--methods",
                  "joint, two-step, newton-lagrange, modulus, modulus-norm, ellipsoid"));
  }
  options.base.outliers = ParseOutlierOptions(args.outliers);
  if (auto why = options.base.Validate()) throw UsageError(*why);
  for (SolverMethod m : options.methods) {
    CalibrationOptions o = options.base;
    o.method = m;
    if (auto why = o.Validate()) throw UsageError(*why);
  }
  const LoadedInput in = LoadInput(args.input);
  const std::vector<Vec3> means = Means(in.positions);
  const Comparison comparison = CompareMethods(means, options);
  const std::vector<MethodComparison>& rows = comparison.methods;
  const char* unit = g.unit == ForceUnit::kMetersPerSecond2 ? "m/s2" : "g";
  // The screening's findings, with |f| - g under the first maximum-likelihood fit (all methods
  // were fitted to the same positions).
  if (!comparison.outliers.empty()) {
    const MethodComparison* reference = nullptr;
    for (const MethodComparison& r : rows) {
      if (!r.error && (reference == nullptr || (IsMaximumLikelihood(r.method) &&
                                                !IsMaximumLikelihood(reference->method)))) {
        reference = &r;
      }
    }
    const std::vector<double> errors =
        reference != nullptr
            ? GravityNormErrors(reference->result.params, means, options.base.gravity)
            : std::vector<double>(means.size(), std::nan(""));
    for (const OutlierFinding& o : comparison.outliers) {
      Warn("%s: %s%s\n", args.input.path.c_str(),
           OutlierMessage(o, in.positions, errors, unit, in.position_file).c_str(),
           o.excluded ? " It was left out of every method's fit." : " It was kept in the fits.");
    }
  }
  std::string screened;  // "7, 12": the positions no method was fitted to
  for (const OutlierFinding& o : comparison.outliers) {
    if (o.excluded) screened += (screened.empty() ? "" : ", ") + std::to_string(o.position + 1);
  }
  const std::vector<ParameterSlot>& slots = ParameterSlots(options.base.model);
  std::string out;
  if (args.json) {
    // Built by hand to keep nlohmann out of the CLI's dependencies; numbers are shortest
    // round-trip decimals, failures are null with the reason. No timings: output is reproducible.
    auto number = [](const std::optional<double>& v) {
      return v && std::isfinite(*v) ? FormatNumber(*v) : std::string("null");
    };
    auto quoted = [](const std::string& text) {
      std::string q = "\"";
      for (char c : text) {
        if (c == '"' || c == '\\') q.push_back('\\');
        q.push_back(c);
      }
      return q + "\"";
    };
    out += "{\n  \"source\": " + quoted(args.input.path) + ",\n  \"model\": \"" +
           std::string(ToString(options.base.model)) +
           "\",\n  \"gravity\": " + FormatNumber(g.in_unit) +
           ",\n  \"positions\": " + std::to_string(means.size()) +
           ",\n  \"positions_used\": " + std::to_string(comparison.positions_used.size()) +
           ",\n  \"outliers\": [";
    for (std::size_t i = 0; i < comparison.outliers.size(); ++i) {
      const OutlierFinding& o = comparison.outliers[i];
      out += (i ? ", " : "") +
             Format("{\"position\": %d, \"excluded\": %s, \"t\": ", o.position + 1,
                    o.excluded ? "true" : "false") +
             number(o.t) + ", \"threshold\": " + number(o.threshold) + "}";
    }
    out += "]";
    if (!comparison.outlier_note.empty()) {
      out += ",\n  \"outlier_note\": " + quoted(comparison.outlier_note);
    }
    out += ",\n  \"methods\": [";
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const MethodComparison& r = rows[i];
      out += i ? ",\n    {" : "\n    {";
      out += "\"method\": \"" + std::string(ToString(r.method)) + "\"";
      if (r.error) {
        out += ", \"error\": " + quoted(*r.error) + "}";
        continue;
      }
      const Eigen::VectorXd theta = Pack(r.result.params, options.base.model);
      out += ", \"parameters\": {";
      for (std::size_t j = 0; j < slots.size(); ++j) {
        out += (j ? ", \"" : "\"") + std::string(slots[j].name) +
               "\": " + FormatNumber(theta(static_cast<Eigen::Index>(j)));
      }
      out += "}, \"modular_square_mean\": " + number(r.modular_square_mean) +
             ", \"modular_square_std\": " + number(r.modular_square_std) +
             ", \"gravity_norm_rms\": " + number(r.gravity_norm_rms) +
             ", \"leave_one_out_rms\": " + number(r.leave_one_out_rms);
      if (r.leave_one_out_error)
        out += ", \"leave_one_out_error\": " + quoted(*r.leave_one_out_error);
      if (r.leave_one_out_from) {
        out += ", \"leave_one_out_from\": \"" + std::string(ToString(*r.leave_one_out_from)) + "\"";
      }
      if (r.against_reference) {
        out += ", \"e_T_percent\": " + number(r.against_reference->e_T_percent) +
               ", \"e_b_percent\": " + number(r.against_reference->e_b_percent);
      }
      out += ", \"iterations\": " + std::to_string(r.result.summary.iterations) + "}";
    }
    out += rows.empty() ? "]\n}\n" : "\n  ]\n}\n";
  } else {
    out += Format("%s: %zu positions, %s model, gravity %.9g %s\n", args.input.path.c_str(),
                  means.size(), std::string(ToString(options.base.model)).c_str(), g.in_unit,
                  std::string(ToString(g.unit)).c_str());
    if (!screened.empty()) {
      out += Format("every method fitted to %zu positions: position%s %s left out (screening)\n",
                    comparison.positions_used.size(),
                    screened.find(',') != std::string::npos ? "s" : "", screened.c_str());
    }
    if (!comparison.outlier_note.empty()) out += "screening " + comparison.outlier_note + "\n";
    out += "\n";
    out += Format("%-18s", "");
    for (const MethodComparison& r : rows)
      out += Format("%17s", std::string(ToString(r.method)).c_str());
    out += "\n";
    auto row = [&](const char* label, auto value) {
      out += Format("%-18s", label);
      for (const MethodComparison& r : rows) out += r.error ? Format("%17s", "-") : value(r);
      out += "\n";
    };
    for (std::size_t j = 0; j < slots.size(); ++j) {
      row(std::string(slots[j].name).c_str(), [&](const MethodComparison& r) {
        return Format("%17.10g",
                      Pack(r.result.params, options.base.model)(static_cast<Eigen::Index>(j)));
      });
    }
    row("|f|^2/g^2 mean",
        [](const MethodComparison& r) { return Format("%17.10f", r.modular_square_mean); });
    row("|f|^2/g^2 std",
        [](const MethodComparison& r) { return Format("%17.4e", r.modular_square_std); });
    row("rms |f|-g",
        [](const MethodComparison& r) { return Format("%17.4e", r.gravity_norm_rms); });
    row("held-out rms", [](const MethodComparison& r) {
      if (!r.leave_one_out_rms) return Format("%17s", "n/a");
      return Format(r.leave_one_out_from ? "%16.4e*" : "%17.4e", *r.leave_one_out_rms);
    });
    if (options.reference) {
      row("e_T [%]", [](const MethodComparison& r) {
        return Format("%17.4f", r.against_reference->e_T_percent);
      });
      row("e_b [%]", [](const MethodComparison& r) {
        return Format("%17.4f", r.against_reference->e_b_percent);
      });
    }
    row("iterations",
        [](const MethodComparison& r) { return Format("%17d", r.result.summary.iterations); });
    row("time [us]",
        [](const MethodComparison& r) { return Format("%17.0f", r.result.summary.time_s * 1e6); });
    for (const MethodComparison& r : rows) {
      if (r.error) out += "\n" + std::string(ToString(r.method)) + ": " + *r.error;
      if (r.leave_one_out_error) {
        out += "\n" + std::string(ToString(r.method)) + " held-out: " + *r.leave_one_out_error;
      }
    }
    out +=
        "\nheld-out rms: |f_k| - g with position k predicted by a fit without it;\n"
        "* shared with the first solver that reached the same optimum (same estimator).\n";
  }
  WriteFileAtomically("-", out);
  return kExitOk;
}

int RunDetect(const DetectArgs& args) {
  InputArgs in = args.input;
  ReadOptions read = MakeReadOptions(in);
  read.kind = InputKind::kRaw;
  if (auto why = in.detection.Validate()) throw UsageError(*why);
  const InputData data = ReadInput(in.path, read);
  const StaticDetectionResult d = DetectStaticIntervals(data.raw, in.detection);
  if (d.intervals.empty()) throw NoStaticInterval(d);
  std::string out;
  if (args.json) {
    out += "{\n  \"source\": \"" + in.path + "\",\n";
    out += Format("  \"samples\": %zu,\n  \"rate_hz\": %s,\n  \"window_samples\": %zu,\n",
                  data.raw.samples.size(), FormatNumber(d.rate_hz).c_str(), d.window_samples);
    out += "  \"noise_reference\": " + FormatNumber(d.noise_reference) +
           ",\n  \"threshold\": " + FormatNumber(d.threshold) + ",\n";
    if (const std::optional<TimeAxis>& t = data.raw.time) {
      out += "  \"time\": {\"unit\": \"" + std::string(ToString(t->unit)) +
             "\", \"origin_s\": " + FormatNumber(t->origin_s) +
             ", \"gaps\": " + std::to_string(t->gaps.size()) + "},\n";
    }
    out += "  \"intervals\": [";
    for (std::size_t i = 0; i < d.intervals.size(); ++i) {
      const StaticInterval& s = d.intervals[i];
      out += i ? ",\n    " : "\n    ";
      out += Format("{\"begin\": %zu, \"end\": %zu, \"samples\": %zu, ", s.begin, s.end, s.count());
      out +=
          "\"t_begin\": " + FormatNumber(s.t_begin_s) + ", \"t_end\": " + FormatNumber(s.t_end_s);
      out += ", \"mean\": [" + FormatNumber(s.mean(0)) + ", " + FormatNumber(s.mean(1)) + ", " +
             FormatNumber(s.mean(2)) + "], \"std\": [" + FormatNumber(s.std(0)) + ", " +
             FormatNumber(s.std(1)) + ", " + FormatNumber(s.std(2)) + "]}";
    }
    out += d.intervals.empty() ? "]\n}\n" : "\n  ]\n}\n";
  } else {
    out += Format(
        "%s: %zu samples at %.6g Hz; window %zu samples; threshold %.4g raw^2 "
        "(noise reference %.4g)\n",
        in.path.c_str(), data.raw.samples.size(), d.rate_hz, d.window_samples, d.threshold,
        d.noise_reference);
    // What the time column was found to be, and the still periods not used (diagnosis.hpp).
    for (const Finding& f : LogFindings(&data.raw, &d)) out += "# " + VisibleLine(f.message) + "\n";
    out += Format("%3s %9s %9s %11s %11s %8s %40s %33s\n", "#", "begin", "end", "t_begin", "t_end",
                  "samples", "mean", "std");
    for (std::size_t i = 0; i < d.intervals.size(); ++i) {
      const StaticInterval& s = d.intervals[i];
      out += Format("%3zu %9zu %9zu %11.4f %11.4f %8zu %s %s\n", i + 1, s.begin, s.end, s.t_begin_s,
                    s.t_end_s, s.count(), Vec(s.mean, "%13.7g ").c_str(),
                    Vec(s.std, "%10.4g ").c_str());
    }
    out += Format("%zu static intervals\n", d.intervals.size());
  }
  WriteFileAtomically("-", out);
  return kExitOk;
}

// A calibration that failed its checks is written so that its reasons can be read, never used.
void RefuseFailed(const LoadedCalibration& cal, const std::string& path) {
  if (cal.verdict == "failed") {
    throw InputError(path, 0,
                     "this calibration failed its checks (\"verdict\": \"failed\"; its "
                     "\"diagnostics\" say why): it is not applied or exported");
  }
}

int RunApply(const ApplyArgs& args) {
  CheckOutputs({{"-o", args.output}}, {args.calibration, args.input.path});
  const LoadedCalibration cal = ParseCalibrationJson(
      ReadFileToString(args.calibration, kMaxSmallFileBytes), args.calibration);
  RefuseFailed(cal, args.calibration);
  ForceUnit unit = cal.unit;
  if (args.units)
    unit = ParseEnum(ForceUnitFromString(*args.units), *args.units, "--units", "m/s2, g");
  double factor = 1.0;  // calibration unit -> output unit
  if (cal.unit == ForceUnit::kMetersPerSecond2 && unit == ForceUnit::kStandardGravity) {
    factor = 1.0 / kStandardGravity_ms2;
  } else if (cal.unit == ForceUnit::kStandardGravity && unit == ForceUnit::kMetersPerSecond2) {
    factor = kStandardGravity_ms2;
  }
  ReadOptions read = MakeReadOptions(args.input);
  read.kind = InputKind::kRaw;
  ProgressBar bar("reading");
  read.progress = bar.ByteCallback();
  const InputData data = ReadInput(args.input.path, read);
  bar.Finish();
  const RawLog& log = data.raw;
  const bool has_time = !log.time_s.empty();
  // Every reading is checked before anything is written; the output is then streamed.
  for (std::size_t i = 0; i < log.samples.size(); ++i) {
    if (!SpecificForce(cal.params, log.samples[i])) {
      throw InputError(args.input.path, log.line[i],
                       "the reading lies outside the range the quadratic model can invert");
    }
  }
  OutputFile file(args.output.empty() ? "-" : args.output);  // buffers: one Write per row
  file.Write("# accelcal apply " + VisibleLine(args.calibration) + ": specific force in " +
             std::string(ToString(unit)) + "\n");
  if (log.time) {  // the clock stated once: times are seconds from the first sample
    file.Write("# time: seconds from the first sample, at " + FormatNumber(log.time->origin_s) +
               " s on the log's clock (read in " + std::string(ToString(log.time->unit)) + ")\n");
  }
  file.Write(has_time ? "time,x,y,z\n" : "x,y,z\n");
  char row[128];
  for (std::size_t i = 0; i < log.samples.size(); ++i) {
    const Vec3 f = *SpecificForce(cal.params, log.samples[i]);
    char* p = row;
    const auto number = [&](double v, char end) {
      p = std::to_chars(p, row + sizeof row, v).ptr;
      *p++ = end;
    };
    if (has_time) number(log.time_s[i], ',');
    for (int a = 0; a < 3; ++a) number(f(a) * factor, a < 2 ? ',' : '\n');
    file.Write(std::string_view(row, static_cast<std::size_t>(p - row)));
  }
  file.Commit();
  return kExitOk;
}

int RunReport(const ReportArgs& args) {
  CheckOutputs({{"-o", args.output}}, {args.calibration, args.log.path});
  ReportInput input;
  input.calibration_json = ReadFileToString(args.calibration, kMaxSmallFileBytes);
  input.calibration_name = args.calibration;
  InputData data;
  if (!args.log.path.empty()) {
    if (auto why = args.log.detection.Validate()) throw UsageError(*why);
    ReadOptions read = MakeReadOptions(args.log);
    read.kind = InputKind::kRaw;
    data = ReadInput(args.log.path, read);
    input.log = &data.raw;
    // The same detection as calibrate's (same options) says which still periods were not used.
    input.rejected = DetectStaticIntervals(data.raw, args.log.detection).rejected;
  }
  WriteFileAtomically(args.output.empty() ? "-" : args.output, RenderReport(input));
  if (!args.output.empty()) {
    for (const std::string& w : ReportWarnings(input)) Say("warning: %s\n", w.c_str());
    Say("report    %s\n", args.output.c_str());
  }
  return kExitOk;
}

int RunExport(const ExportArgs& args) {
  CheckOutputs({{"-o", args.output}}, {args.calibration});
  std::string names;
  for (const ExportFormat f : AllExportFormats())
    names += (names.empty() ? "" : ", ") + std::string(ToString(f));
  const ExportFormat format =
      ParseEnum(ExportFormatFromString(args.format), args.format, "--to", names.c_str());
  const std::string text = ReadFileToString(args.calibration, kMaxSmallFileBytes);
  const LoadedCalibration cal = ParseCalibrationJson(text, args.calibration);
  RefuseFailed(cal, args.calibration);
  ExportOptions options;
  options.raw_unit = args.raw_unit;
  options.instance = args.instance;
  options.c_prefix = args.c_prefix;
  ExportResult exported;
  try {
    exported = ExportCalibration(cal, text, format, options);
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  } catch (const DataError& e) {
    throw InputError(args.calibration, 0, e.what());
  }
  // The file (or stdout) gets the export alone; what it means and what it lost goes to the
  // terminal: stdout when the export went to a file, else stderr.
  WriteFileAtomically(args.output.empty() ? "-" : args.output, exported.text);
  std::string note = exported.convention + "\n";
  const ExportLoss& loss = exported.loss;
  const std::string unit_name(ToString(cal.unit));
  const char* unit = unit_name.c_str();
  note += loss.dropped.empty() ? "exact: nothing of the model is dropped\n"
                               : "dropped: " + loss.dropped + "\n";
  if (loss.positions > 0 && !loss.dropped.empty()) {
    note += Format(
        "on the calibration's %d positions: corrected specific force off by %.3g %s max, %.3g %s "
        "RMS; RMS of |f| - g %.3g %s (full model %.3g %s)\n",
        loss.positions, loss.max_error, unit, loss.rms_error, unit, loss.norm_rms_export, unit,
        loss.norm_rms_full, unit);
  } else if (!loss.dropped.empty()) {
    note += "the file holds no positions to measure the loss on\n";
  }
  if (CurrentVerbosity() != Verbosity::kQuiet) {
    std::fputs(note.c_str(), args.output.empty() ? stderr : stdout);
  }
  return kExitOk;
}

namespace {

// Planned directions: a named scheme, or a file with one unit vector per row.
std::vector<Vec3> PlannedDirections(const std::string& spec) {
  if (std::optional<std::vector<Vec3>> scheme = SchemeDirections(spec)) return *scheme;
  return ReadOrientations(spec).directions;
}

}  // namespace

int RunDesign(const DesignArgs& args) {
  const bool from_density = args.noise_density_ug.has_value();
  if (from_density == !args.noise_raw.empty()) {
    throw UsageError("give --noise, or --noise-density with --rate and --duration");
  }
  if (from_density && (!args.rate_hz || !args.duration_s)) {
    throw UsageError("--noise-density needs --rate and --duration");
  }
  if (!from_density && args.noise_raw.size() != 1 && args.noise_raw.size() != 3) {
    throw UsageError("--noise takes one value or three (x,y,z)");
  }
  const LoadedCalibration device =
      ParseCalibrationJson(ReadFileToString(args.device, kMaxSmallFileBytes), args.device);
  Vec3 sigma;
  if (from_density) {
    // One averaged reading: density · √rate per sample (µg relative to the device's gravity),
    // over rate · duration samples, mapped to each raw axis by the length of its row of K.
    const double samples = *args.rate_hz * *args.duration_s;
    const double sigma_force =
        *args.noise_density_ug * 1e-6 * device.gravity * std::sqrt(*args.rate_hz / samples);
    for (int i = 0; i < 3; ++i) sigma(i) = device.params.K.row(i).norm() * sigma_force;
  } else {
    sigma = args.noise_raw.size() == 1
                ? Vec3::Constant(args.noise_raw[0])
                : Vec3(args.noise_raw[0], args.noise_raw[1], args.noise_raw[2]);
  }
  if (!sigma.allFinite() || !(sigma.minCoeff() > 0)) {
    throw UsageError(
        "the noise must be positive (--noise, or --noise-density, --rate, --duration)");
  }
  const ModelKind model = args.model ? ParseEnum(ModelKindFromString(*args.model), *args.model,
                                                 "--model", "linear, quadratic")
                                     : device.model;
  std::vector<Vec3> directions = PlannedDirections(args.positions);
  LoadedCalibration nominal = device;
  if (device.frame == Frame::kPlatform) {
    // A platform-frame device (known-orientation fit) has a full K. The orientation-free bound
    // is computed for the same linear device in its x-first form (frame.hpp), the planned
    // directions rotated with it.
    if (model != ModelKind::kLinear) {
      throw UsageError(
          "design: a quadratic platform-frame device has no orientation-free "
          "equivalent (the squared terms act on platform axes); use --model linear");
    }
    const FrameChange change = ChangeFrame(device.params.K, Frame::kXFirst);
    nominal.params.K = change.K;
    nominal.params.k2.setZero();
    for (Vec3& c : directions) c = change.Q_old_new.transpose() * c;
  }
  std::string chosen_note;
  if (args.choose > 0) {
    if (args.criterion != "d" && args.criterion != "a") {
      throw UsageError("--criterion: '" + args.criterion + "' is not one of d, a");
    }
    std::vector<int> chosen;
    try {
      chosen = args.criterion == "d" ? ChooseDOptimal(nominal.params, model, device.gravity,
                                                      directions, sigma, args.choose)
                                     : ChooseAOptimal(nominal.params, model, device.gravity,
                                                      directions, sigma, args.choose);
    } catch (const std::invalid_argument& e) {
      throw UsageError(std::string("--choose: ") + e.what());
    }
    std::vector<Vec3> subset;
    for (int k : chosen) subset.push_back(directions[static_cast<std::size_t>(k)]);
    const std::vector<Vec3> yang18 = Yang18Directions();
    const double d_efficiency =
        std::exp((LogDetInformation(nominal.params, model, device.gravity, subset, sigma) -
                  LogDetInformation(nominal.params, model, device.gravity, yang18, sigma)) /
                 NumParameters(model));
    const double a_efficiency = TraceCrlb(nominal.params, model, device.gravity, yang18, sigma) /
                                TraceCrlb(nominal.params, model, device.gravity, subset, sigma);
    chosen_note = Format(
        "%s-optimal %d of %zu candidates; against yang18: D-efficiency %.4f ((det I / det "
        "I_yang18)^(1/%d)), A-efficiency %.4f (tr CRLB_yang18 / tr CRLB, parameters in the "
        "device's relative metric); > 1: better",
        args.criterion == "d" ? "D" : "A", args.choose, directions.size(), d_efficiency,
        NumParameters(model), a_efficiency);
    directions = std::move(subset);
  }
  const PlannedUncertainty planned =
      PredictUncertainty(nominal.params, model, device.gravity, directions, sigma);
  const auto& slots = ParameterSlots(model, planned.frame);
  std::string out;
  if (args.json) {
    out += "{\n  \"positions\": " + std::to_string(directions.size()) + ",\n";
    out += "  \"model\": \"" + std::string(ToString(model)) + "\",\n";
    out += "  \"frame\": \"" + std::string(ToString(planned.frame)) + "\",\n";
    out += "  \"noise_raw\": " + JsonVector(sigma) + ",\n";
    if (args.choose > 0) {
      out += "  \"chosen\": [";
      for (std::size_t k = 0; k < directions.size(); ++k) {
        out += (k ? ", " : "") + JsonVector(directions[k]);
      }
      out += "],\n  \"choice\": \"" + chosen_note + "\",\n";
    }
    out += "  \"observable\": " + std::string(planned.observable ? "true" : "false") + ",\n";
    out += "  \"reciprocal_condition\": " + FormatNumber(planned.rcond) + ",\n";
    out += "  \"weakest\": " +
           (planned.weakest.empty() ? std::string("null") : "\"" + planned.weakest + "\"") + ",\n";
    out += "  \"parameter_order\": [";
    for (std::size_t i = 0; i < slots.size(); ++i) {
      out += (i ? ", \"" : "\"") + std::string(slots[i].name) + "\"";
    }
    out += "],\n";
    if (planned.observable) {
      const Mat33& K = planned.std.K;
      out += "  \"std\": {\"K\": [" + JsonVector(K.row(0).transpose()) + ", " +
             JsonVector(K.row(1).transpose()) + ", " + JsonVector(K.row(2).transpose()) +
             "], \"bias\": " + JsonVector(planned.std.bias) +
             ", \"k2\": " + JsonVector(planned.std.k2) + "},\n  \"crlb\": [";
      for (Eigen::Index i = 0; i < planned.crlb.rows(); ++i) {
        out += i ? ",\n    [" : "\n    [";
        for (Eigen::Index j = 0; j < planned.crlb.cols(); ++j) {
          out += (j ? ", " : "") + FormatNumber(planned.crlb(i, j));
        }
        out += "]";
      }
      out += "]\n}\n";
    } else {
      out += "  \"std\": null,\n  \"crlb\": null\n}\n";
    }
  } else {
    out += Format(
        "design    %zu positions (%s), %s model in the %s frame, noise %.4g %.4g %.4g "
        "raw per averaged reading\n",
        directions.size(), args.positions.c_str(), std::string(ToString(model)).c_str(),
        std::string(ToString(planned.frame)).c_str(), sigma(0), sigma(1), sigma(2));
    if (args.choose > 0) {
      out += chosen_note + "\n";
      for (const Vec3& c : directions) out += Format("  %+.6f %+.6f %+.6f\n", c(0), c(1), c(2));
    }
    if (!planned.observable) {
      out += Format(
          "NOT OBSERVABLE: these positions do not determine parameter %s (reciprocal "
          "condition %.2g); add positions with other orientations\n",
          planned.weakest.c_str(), planned.rcond);
    } else {
      out += "predicted 1 sigma (Cramer-Rao bound; raw units as the device file)\n";
      for (std::size_t i = 0; i < slots.size(); ++i) {
        const auto index = static_cast<Eigen::Index>(i);
        out += Format("  %-5s %.4g\n", std::string(slots[i].name).c_str(),
                      std::sqrt(planned.crlb(index, index)));
      }
      if (!planned.weakest.empty()) {
        out += Format("poorly determined: %s (reciprocal condition %.2g)\n",
                      planned.weakest.c_str(), planned.rcond);
      }
    }
  }
  WriteFileAtomically("-", out);
  return planned.observable ? kExitOk : kExitBadInput;
}

int RunMonteCarlo(const MonteCarloArgs& args) {
  const std::optional<Scenario> scenario = ScenarioByName(args.scenario);
  if (!scenario) {
    throw UsageError("--scenario: '" + args.scenario + "' is not one of yang2012, sunxu2020");
  }
  if (args.runs < 2 || args.runs > kMaxMonteCarloRuns) {
    throw UsageError(Format("--runs must be from 2 to %d", kMaxMonteCarloRuns));
  }
  if (args.threads < 0) throw UsageError("--threads must be 0 (all cores) or positive");
  MonteCarloOptions options;
  options.runs = args.runs;
  options.seed = args.seed;
  options.threads = args.threads;
  options.known_noise = !args.residual_noise;
  options.calibration.method = ParseEnum(SolverMethodFromString(args.method), args.method,
                                         "--method", "joint, two-step, newton-lagrange");
  if (!IsMaximumLikelihood(options.calibration.method)) {
    throw UsageError(
        "--method: the Monte Carlo compares maximum-likelihood methods with the "
        "bound: joint, two-step or newton-lagrange");
  }
  options.calibration.estimator = ParseEnum(EstimatorFromString(args.estimator), args.estimator,
                                            "--estimator", "ml, bias-corrected");
  options.calibration.model = scenario->model;
  if (auto why = options.calibration.Validate()) throw UsageError(*why);
  ProgressBar bar("montecarlo " + args.scenario);
  options.progress = [&bar](int done, int total) { bar.Update(done, total); };
  const MonteCarloResult r = RunMonteCarlo(*scenario, options);
  bar.Finish();
  std::string out;
  if (args.json) {
    out += "{\n  \"scenario\": \"" + r.scenario + "\",\n  \"method\": \"" +
           std::string(ToString(r.method)) + "\",\n  \"estimator\": \"" + args.estimator +
           "\",\n  \"runs\": " + std::to_string(r.runs) +
           ",\n  \"failed\": " + std::to_string(r.failed) +
           ",\n  \"coverage\": " + FormatNumber(r.coverage) +
           ",\n  \"inclination_error_rms_arcsec\": " + FormatNumber(r.inclination_error_rms_arcsec);
    if (scenario->random_attitudes > 0) {
      out += ",\n  \"e_T_percent_mean\": " + FormatNumber(r.e_T_percent_mean) +
             ",\n  \"e_b_percent_mean\": " + FormatNumber(r.e_b_percent_mean) +
             ",\n  \"diag_T_bias\": " + JsonVector(r.diag_T_bias) +
             ",\n  \"diag_T_bias_standard_error\": " + JsonVector(r.diag_T_bias_standard_error) +
             ",\n  \"diag_T_bias_expected\": " + JsonVector(r.diag_T_bias_expected);
    }
    out += ",\n  \"parameters\": [";
    for (std::size_t i = 0; i < r.errors.size(); ++i) {
      const ErrorStatistics& e = r.errors[i];
      out += (i ? ",\n    " : "\n    ") + std::string("{\"name\": \"") + e.name +
             "\", \"unit\": \"" + e.unit + "\", \"min\": " + FormatNumber(e.min) +
             ", \"max\": " + FormatNumber(e.max) + ", \"mean\": " + FormatNumber(e.mean) +
             ", \"median\": " + FormatNumber(e.median) + ", \"std\": " + FormatNumber(e.std) +
             ", \"rmse\": " + FormatNumber(e.rmse) + ", \"crlb\": " + FormatNumber(e.crlb) +
             ", \"ratio\": " + FormatNumber(e.ratio) +
             ", \"rmse_ratio\": " + FormatNumber(e.rmse_ratio) + "}";
    }
    out += "\n  ]\n}\n";
  } else {
    out +=
        Format("montecarlo %s, %d runs, %s solver, %s estimator (%d failed)\n", r.scenario.c_str(),
               r.runs, std::string(ToString(r.method)).c_str(), args.estimator.c_str(), r.failed);
    out += Format("  %-7s %-6s %10s %10s %10s %10s %10s %10s %10s %8s %9s\n", "error", "unit",
                  "min", "max", "mean", "median", "std", "RMSE", "CRLB", "std/CRLB", "RMSE/CRLB");
    for (const ErrorStatistics& e : r.errors) {
      out += Format("  %-7s %-6s %10.4g %10.4g %10.4g %10.4g %10.4g %10.4g %10.4g %8.3f %9.3f\n",
                    e.name.c_str(), e.unit.c_str(), e.min, e.max, e.mean, e.median, e.std, e.rmse,
                    e.crlb, e.ratio, e.rmse_ratio);
    }
    out += Format("coverage of the reported 1-sigma intervals: %.1f %% (noise %s)\n",
                  100 * r.coverage, args.residual_noise ? "from the residuals" : "known");
    out += Format("inclination vector error: rms %.3f arcsec\n", r.inclination_error_rms_arcsec);
    if (scenario->random_attitudes > 0) {
      out += Format("paper 001 eq. (20): mean e_T %.4f %%, mean e_b %.4f %%\n", r.e_T_percent_mean,
                    r.e_b_percent_mean);
      out += Format(
          "bias of diag(T) (z-first): %.3g %.3g %.3g (+- %.2g %.2g %.2g); sigma^2/T_ii "
          "%.3g %.3g %.3g\n",
          r.diag_T_bias(0), r.diag_T_bias(1), r.diag_T_bias(2), r.diag_T_bias_standard_error(0),
          r.diag_T_bias_standard_error(1), r.diag_T_bias_standard_error(2),
          r.diag_T_bias_expected(0), r.diag_T_bias_expected(1), r.diag_T_bias_expected(2));
    }
  }
  WriteFileAtomically("-", out);
  return kExitOk;
}

namespace {

// Paper 001 §4.1 as a positions file: eq. (19)'s device (g units, z-first), 300 Gaussian attitudes
// from the seed, σ = 0.1 g per averaged reading, written as 100 samples of σ = 1 g so that
// calibrate takes the known noise (SigmasOfMeans) as it would from a raw log.
std::string SunXu2020Positions(const SimulateArgs& args) {
  if (args.raw) {
    throw UsageError(
        "--scenario sunxu2020 is defined on averaged readings (sigma = 0.1 g per "
        "position): use --positions-out");
  }
  if (!args.truth.empty() || !args.positions.empty() || args.noise_density_ug) {
    throw UsageError("--scenario sunxu2020 fixes the device, the attitudes and the noise");
  }
  const std::vector<Vec3> means =
      SimulateLinearPositions(SunXu2020Ta(), SunXu2020Ba(), SunXu2020Directions(300, args.seed),
                              kSunXu2020Sigma_g, args.seed + 1000);
  const double samples = 100;
  return PositionsCsv(means, samples, Vec3::Constant(kSunXu2020Sigma_g * std::sqrt(samples)));
}

}  // namespace

int RunSystemLevel(const SystemLevelArgs& args) {
  const double latitude = *args.latitude_deg;
  if (!(std::abs(latitude) < 89)) throw UsageError("--latitude must lie in (-89, 89) degrees");
  if (std::abs(latitude) < 1) {
    throw UsageError(
        "--latitude: within 1 degree of the equator sin L vanishes and the second "
        "harmonics of the attitude errors carry no information (eq. (32), (33))");
  }
  const double g = args.gravity_ms2 ? *args.gravity_ms2 : NormalGravityWgs84_ms2(latitude);
  if (!(g > 0) || !std::isfinite(g)) throw UsageError("--gravity must be a positive number");
  SystemLevelEstimator estimator(latitude * 3.14159265358979323846 / 180.0, g);
  ProgressBar bar("system-level");
  ReadSeries(
      args.series, [&](const SystemSample& s) { estimator.Add(s); }, bar.ByteCallback());
  bar.Finish();
  const SystemLevelResult r = estimator.Finish();
  const auto fourier = [](const FourierCoefficients& f) {
    return "{\"mean\": " + FormatNumber(f.mean) + ", \"c1\": " + FormatNumber(f.c1) +
           ", \"s1\": " + FormatNumber(f.s1) + ", \"c2\": " + FormatNumber(f.c2) +
           ", \"s2\": " + FormatNumber(f.s2) + "}";
  };
  std::string out;
  if (args.json) {
    out += "{\n  \"samples\": " + std::to_string(r.samples) +
           ",\n  \"latitude_deg\": " + FormatNumber(latitude) +
           ",\n  \"gravity_ms2\": " + FormatNumber(g) +
           ",\n  \"noise_ms2\": " + JsonVector(r.noise_ms2) +
           ",\n  \"x1_noise_correction\": " + FormatNumber(r.x1_noise_correction) +
           ",\n  \"combined\": {";
    for (int i = 0; i < 5; ++i) {
      out += (i ? ", " : "") + Format("\"x%d\": {\"value\": ", i + 1) + FormatNumber(r.x(i)) +
             ", \"std\": " + FormatNumber(r.x_std(i)) + "}";
    }
    out += "},\n  \"fourier\": {\"pitch\": " + fourier(r.pitch) +
           ", \"pitch_std\": " + fourier(r.pitch_std) + ",\n    \"roll\": " + fourier(r.roll) +
           ", \"roll_std\": " + fourier(r.roll_std) +
           "},\n  \"separated\": {\"rank\": " + std::to_string(r.rank) + ", \"determined\": {";
    for (std::size_t i = 0; i < r.determined.size(); ++i) {
      out += (i ? ", " : "") + std::string("\"") + r.determined[i].name +
             "\": {\"value\": " + FormatNumber(r.determined[i].value) +
             ", \"std\": " + FormatNumber(r.determined[i].std) + "}";
    }
    out += "}, \"undetermined\": [";
    for (std::size_t i = 0; i < r.undetermined.size(); ++i) {
      out += (i ? ", \"" : "\"") + r.undetermined[i] + "\"";
    }
    out += "]}\n}\n";
  } else {
    out += Format("system-level  %s: %ld samples, latitude %.6g deg, g %.9g m/s2\n",
                  args.series.c_str(), r.samples, latitude, g);
    out += Format(
        "noise         %.3g %.3g %.3g m/s2 per axis (successive differences); x1 "
        "corrected by E|n|^2/(2g^2) = %.3g\n",
        r.noise_ms2(0), r.noise_ms2(1), r.noise_ms2(2), r.x1_noise_correction);
    out += "combined coefficients, eq. (21)-(25) [rad]\n";
    for (int i = 0; i < 5; ++i) {
      out += Format("  x%d  %+.5e +- %.2e\n", i + 1, r.x(i), r.x_std(i));
    }
    const auto line = [](const char* name, const FourierCoefficients& f,
                         const FourierCoefficients& sd) {
      return Format(
          "  %-5s mean %+.4e +- %.1e  c1 %+.4e +- %.1e  s1 %+.4e +- %.1e  c2 %+.4e +- "
          "%.1e  s2 %+.4e +- %.1e\n",
          name, f.mean, sd.mean, f.c1, sd.c1, f.s1, sd.s1, f.c2, sd.c2, f.s2, sd.s2);
    };
    out += "attitude errors, Fourier coefficients of S = Earth rate x t [rad]\n";
    out += line("pitch", r.pitch, r.pitch_std) + line("roll", r.roll, r.roll_std);
    out += Format("separated, eq. (39)-(41) (rank %d of 6)\n", r.rank);
    for (const Estimate& e : r.determined) {
      out += Format("  %-34s %+.5e +- %.2e\n", e.name.c_str(), e.value, e.std);
    }
    if (!r.undetermined.empty()) {
      std::string names;
      for (const std::string& n : r.undetermined) names += (names.empty() ? "" : ", ") + n;
      out += "  not determined on their own (only in the combinations above): " + names + "\n";
    }
  }
  WriteFileAtomically("-", out);
  return kExitOk;
}

namespace {

// Rows of `columns` numbers (commas or whitespace; `#` comments; a header line whose first field
// is no number is skipped).
std::vector<std::vector<double>> ReadTable(const std::string& path, std::size_t columns) {
  const std::string text = ReadFileToString(path, kMaxSmallFileBytes);
  std::vector<std::vector<double>> rows;
  std::istringstream lines(text);
  std::string line;
  std::size_t number = 0;
  bool first = true;  // a header is allowed on the first non-blank line only
  while (std::getline(lines, line)) {
    ++number;
    line = line.substr(0, line.find('#'));
    for (char& ch : line) {
      if (ch == ',' || ch == '\t' || ch == '\r') ch = ' ';
    }
    std::istringstream fields(line);
    std::vector<double> row;
    std::string field;
    bool numeric = true;
    while (fields >> field) {
      char* end = nullptr;
      const double v = std::strtod(field.c_str(), &end);
      if (end == field.c_str() || *end != '\0') {
        numeric = false;
        break;
      }
      row.push_back(v);
    }
    if (row.empty() && numeric) continue;  // blank
    const bool header = first && !numeric && row.empty();
    first = false;
    if (header) continue;
    if (!numeric || row.size() != columns) {
      throw InputError(path, number, "expected " + std::to_string(columns) + " numbers");
    }
    for (double v : row) {
      if (!std::isfinite(v)) throw InputError(path, number, "a value is not finite");
    }
    rows.push_back(std::move(row));
  }
  if (rows.empty()) throw InputError(path, 0, "no rows");
  return rows;
}

std::string BetaJson(const Eigen::Matrix<double, 6, 1>& beta) {
  static const char* const kNames[6] = {"beta_xz", "beta_xy", "beta_yz",
                                        "beta_yx", "beta_zy", "beta_zx"};
  std::string out = "{";
  for (int i = 0; i < 6; ++i) {
    out += (i ? ", \"" : "\"") + std::string(kNames[i]) + "\": " + FormatNumber(beta(i));
  }
  return out + "}";
}

std::string DeviceJson(const PlatformAccelerometer& d) {
  return "{\"sf_inverse\": " + JsonVector(d.s) + ", \"bias\": " + JsonVector(d.bias) +
         ", \"beta_rad\": " + BetaJson(d.beta) + ", \"k_nl\": " + JsonVector(d.k_nl) + "}";
}

}  // namespace

int RunGimbal(const GimbalArgs& args) {
  const Gravity g = ResolveGravity(args.gravity);
  constexpr double kDeg = 3.14159265358979323846 / 180.0;
  std::vector<Vec3> commanded, outputs;
  for (const std::vector<double>& row : ReadTable(args.coarse, 6)) {
    commanded.emplace_back(row[0] * kDeg, row[1] * kDeg, row[2] * kDeg);
    outputs.emplace_back(row[3], row[4], row[5]);
  }
  const CoarseCalibrationResult coarse = CoarseCalibration(outputs, commanded, g.in_unit);
  std::optional<FineCalibrationResult> fine;
  if (!args.fine.empty()) {
    std::vector<Vec3> fine_outputs;
    for (const std::vector<double>& row : ReadTable(args.fine, 3)) {
      fine_outputs.emplace_back(row[0], row[1], row[2]);
    }
    fine = FineCalibration(fine_outputs, coarse.device, g.in_unit);
  }
  std::string out;
  if (args.json) {
    out += "{\n  \"gravity\": " + FormatNumber(g.in_unit) +
           ",\n  \"coarse\": {\"device\": " + DeviceJson(coarse.device) +
           ",\n    \"offsets_rad\": {\"theta20\": " + FormatNumber(coarse.offsets(1)) +
           ", \"theta30\": " + FormatNumber(coarse.offsets(2)) + "}, \"std\": [";
    for (int i = 0; i < 14; ++i) out += (i ? ", " : "") + FormatNumber(coarse.std(i));
    out +=
        "],\n    \"parameter_order\": [\"s_x\", \"s_y\", \"s_z\", \"b_x\", \"b_y\", "
        "\"b_z\", \"beta_xz\", \"beta_xy\", \"beta_yz\", \"beta_yx\", \"beta_zy\", "
        "\"beta_zx\", \"theta20\", \"theta30\"],\n    \"residual_rms\": " +
        FormatNumber(coarse.residual_rms) +
        ", \"converged\": " + (coarse.converged ? "true" : "false") + ", \"note\": \"" +
        coarse.note + "\"}";
    if (fine) {
      out += ",\n  \"fine\": {\"device\": " + DeviceJson(fine->device) + ",\n    \"dx\": [";
      for (int i = 0; i < 12; ++i) out += (i ? ", " : "") + FormatNumber(fine->dx(i));
      out += "], \"dx_std\": [";
      for (int i = 0; i < 12; ++i) out += (i ? ", " : "") + FormatNumber(fine->dx_std(i));
      out += "],\n    \"residual_rms\": " + FormatNumber(fine->residual_rms) +
             ", \"converged\": " + (fine->converged ? "true" : "false") + ", \"note\": \"" +
             fine->note + "\"}";
    }
    out += "\n}\n";
  } else {
    const auto device = [&](const PlatformAccelerometer& d) {
      std::string text = Format("  SF^-1   %.10g %.10g %.10g\n", d.s(0), d.s(1), d.s(2));
      text += Format("  bias    %.6g %.6g %.6g\n", d.bias(0), d.bias(1), d.bias(2));
      text += Format("  beta    xz %.2f  xy %.2f  yz %.2f  yx %.2f  zy %.2f  zx %.2f arcsec\n",
                     d.beta(0) / kDeg * 3600, d.beta(1) / kDeg * 3600, d.beta(2) / kDeg * 3600,
                     d.beta(3) / kDeg * 3600, d.beta(4) / kDeg * 3600, d.beta(5) / kDeg * 3600);
      return text;
    };
    out += Format("coarse    %zu positions, %s after %d iterations, residual rms %.3g\n",
                  outputs.size(), coarse.converged ? "converged" : "NOT CONVERGED",
                  coarse.iterations, coarse.residual_rms);
    out += device(coarse.device);
    out += Format("  offsets theta20 %.2f +- %.2f arcsec, theta30 %.2f +- %.2f arcsec\n",
                  coarse.offsets(1) / kDeg * 3600, coarse.std(12) / kDeg * 3600,
                  coarse.offsets(2) / kDeg * 3600, coarse.std(13) / kDeg * 3600);
    out += "  note    " + coarse.note + "\n";
    if (fine) {
      out += Format("fine      %s after %d iterations, residual rms %.3g\n",
                    fine->converged ? "converged" : "NOT CONVERGED", fine->iterations,
                    fine->residual_rms);
      out += device(fine->device);
      out += Format("  K_nl    %.4g %.4g %.4g per output unit\n", fine->device.k_nl(0),
                    fine->device.k_nl(1), fine->device.k_nl(2));
      out += "  note    " + fine->note + "\n";
    }
  }
  WriteFileAtomically("-", out);
  const bool ok = coarse.converged && (!fine || fine->converged);
  return ok ? kExitOk : kExitNotConverged;
}

namespace {

// A simulated log or series beyond this many samples (28 hours at 1 kHz; several GB of text) is
// an option typed wrong, not a recording anyone wants.
constexpr double kMaxSimulatedSamples = 1e8;

void CheckSimulatedSamples(double samples, const char* options) {
  if (!(samples <= kMaxSimulatedSamples)) {
    throw UsageError(Format("%s asks for %.3g samples; at most %g are simulated", options, samples,
                            kMaxSimulatedSamples));
  }
}

}  // namespace

int RunSimulate(const SimulateArgs& args) {
  CheckOutputs({{"-o", args.output}}, {args.truth, args.positions});
  if (args.scenario == "wu2018-system") {
    if (!args.truth.empty() || !args.positions.empty() || args.noise_density_ug || args.raw) {
      throw UsageError("--scenario wu2018-system takes only --seed, --rate, --duration and -o");
    }
    if (args.output.empty()) {
      throw UsageError("--scenario wu2018-system writes a binary series: give -o FILE");
    }
    SystemSimulationOptions o;
    o.seed = args.seed;
    if (args.rate_given) o.rate_hz = args.rate_hz;
    if (args.duration_given) o.duration_s = args.duration_s;
    if (!(o.rate_hz > 0 && o.rate_hz <= kMaxRate_hz) || !(o.duration_s > 0)) {
      throw UsageError(Format("--rate must be in (0, %g] Hz and --duration positive", kMaxRate_hz));
    }
    CheckSimulatedSamples(o.rate_hz * o.duration_s, "--rate x --duration");
    OutputFile file(args.output);  // streamed: the series is never held whole
    std::string bytes;
    AppendSeriesHeader(&bytes);
    file.Write(bytes);
    SimulateSystemLevel(o, [&](const SystemSample& s) {
      bytes.clear();
      AppendSeriesSample(s, &bytes);
      file.Write(bytes);
    });
    file.Commit();
    return kExitOk;
  }
  if (args.scenario == "sunxu2020") {
    WriteFileAtomically(args.output.empty() ? "-" : args.output, SunXu2020Positions(args));
    return kExitOk;
  }
  ModelParameters truth;
  double gravity = 0;
  std::string positions = args.positions;
  std::optional<double> density = args.noise_density_ug;
  if (!args.scenario.empty()) {
    if (args.scenario != "yang2012") {
      throw UsageError("--scenario: '" + args.scenario +
                       "' is not one of yang2012, sunxu2020, wu2018-system");
    }
    if (!args.truth.empty()) throw UsageError("give --scenario or --truth, not both");
    truth = Yang2012Truth();
    gravity = kYang2012Gravity_ms2;
    if (positions.empty()) positions = "yang18";
    if (!density) density = 10.0;
  } else {
    if (args.truth.empty()) throw UsageError("give --scenario or --truth");
    const LoadedCalibration cal =
        ParseCalibrationJson(ReadFileToString(args.truth, kMaxSmallFileBytes), args.truth);
    truth = cal.params;
    gravity = cal.gravity;
    if (positions.empty()) throw UsageError("--positions is required with --truth");
    if (!density) throw UsageError("--noise-density is required with --truth");
  }
  if (!(*density > 0) || !(args.rate_hz > 0) || !(args.duration_s > 0) ||
      !(args.transition_s >= 0) || !std::isfinite(*density) || !std::isfinite(args.duration_s) ||
      !std::isfinite(args.transition_s)) {
    throw UsageError(
        "--noise-density, --rate and --duration must be positive, --transition "
        "zero or positive");
  }
  if (!(args.rate_hz <= kMaxRate_hz)) {
    throw UsageError(Format("--rate must be a number of Hz in (0, %g]", kMaxRate_hz));
  }
  // A position averages round(duration x rate) samples: at least one, and a whole number a
  // positions file can state (2^53).
  const double per_position = std::round(args.duration_s * args.rate_hz);
  if (!(per_position >= 1 && per_position <= 9007199254740992.0)) {
    throw UsageError(
        Format("--duration x --rate must be 1 to 2^53 samples per position (%g)", per_position));
  }
  const std::vector<Vec3> directions = PlannedDirections(positions);
  // Per-sample white noise in the specific-force unit (µg relative to the device's gravity),
  // mapped to each raw axis by the length of its row of K.
  const double sigma_force = *density * 1e-6 * gravity * std::sqrt(args.rate_hz);
  Vec3 sigma_raw;
  for (int i = 0; i < 3; ++i) sigma_raw(i) = truth.K.row(i).norm() * sigma_force;
  if (args.raw) {
    RawLogSimulation options;
    options.rate_hz = args.rate_hz;
    options.static_s = args.duration_s;
    options.transition_s = args.transition_s;
    options.sigma_raw_per_sample = sigma_raw;
    options.seed = args.seed;
    CheckSimulatedSamples(SimulatedSampleCount(directions.size(), options),
                          "positions x (--duration + --transition) x --rate");
    OutputFile file(args.output.empty() ? "-" : args.output);  // streamed, never held whole
    file.Write("time,x,y,z\n");
    SimulateRawLog(truth, gravity, directions, options, [&](double t, const Vec3& p) {
      file.Write(FormatNumber(t) + "," + FormatNumber(p(0)) + "," + FormatNumber(p(1)) + "," +
                 FormatNumber(p(2)) + "\n");
    });
    file.Commit();
    return kExitOk;
  }
  const std::vector<Vec3> means =
      SimulatePositions(truth, gravity, directions, sigma_raw / std::sqrt(per_position), args.seed);
  WriteFileAtomically(args.output.empty() ? "-" : args.output,
                      PositionsCsv(means, per_position, sigma_raw));
  return kExitOk;
}

}  // namespace accelcal::cli
