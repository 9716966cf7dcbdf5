// A unit calibrated from its recordings (calibrate_unit.hpp): the three fits (orientation-free,
// known orientations, over temperature), the gyroscope beside them, the diagnosis and provenance.
#include "accelcal/calibrate_unit.hpp"

#include <algorithm>
#include <array>
#include <filesystem>
#include <future>
#include <system_error>

#include "accelcal/error.hpp"
#include "accelcal/known_orientation.hpp"
#include "accelcal/noise_file.hpp"
#include "accelcal/position_noise.hpp"
#include "core/median.hpp"
#include "core/text_format.hpp"
#include "pipeline/unit_options.hpp"

namespace accelcal {
namespace {

using internal::Format;

// The spline bias's random-walk prior q [m/s²/√s] per axis, and where it is from.
struct RandomWalk {
  Vec3 q_ms2 = Vec3::Zero();
  std::string source;                                       // empty: not given
  std::array<bool, 3> upper_bound = {false, false, false};  // the noise file's 95 % upper bound
  bool given() const { return !source.empty(); }
};

// The prior as asked for; the noise file read (small) and its values checked.
RandomWalk ReadRandomWalk(const UnitRequest& r) {
  RandomWalk out;
  if (!r.noise.empty()) {
    const ImuNoise noise = ParseNoiseJson(ReadFileToString(r.noise, kMaxSmallFileBytes), r.noise);
    out.q_ms2 = noise.accelerometer.random_walk;
    for (std::size_t a = 0; a < 3; ++a) {
      out.upper_bound[a] = !noise.accelerometer.random_walk_resolved[a];
      const double q = out.q_ms2(static_cast<Eigen::Index>(a));
      if (!(q >= kMinRandomWalk && q <= kMaxRandomWalk)) {
        throw DataError(
            Format("%s: the accelerometer's random walk on %c, %g m/s^2/sqrt(s), is outside %g to "
                   "%g: not a bias's random walk",
                   r.noise.c_str(), "xyz"[a], q, kMinRandomWalk, kMaxRandomWalk));
      }
    }
    out.source = r.noise;
  } else if (!r.bias_random_walk.empty()) {
    const std::vector<double>& v = r.bias_random_walk;
    for (std::size_t i = 0; i < 3; ++i) {
      out.q_ms2(static_cast<Eigen::Index>(i)) = v.size() == 1 ? v[0] : v[i];
    }
    out.source = "{{bias_random_walk}}";
  }
  return out;
}

std::string Vec(const Vec3& v, const char* fmt) {
  return Format(fmt, v(0)) + Format(fmt, v(1)) + Format(fmt, v(2));
}

// q in raw units per √s: K q per axis (the walk of specific force w shows as K w in the readings),
// K from a constant-bias fit of the positions; its line of the summary appended to `notes`.
Vec3 RandomWalkInRaw(const RandomWalk& walk, const std::vector<Vec3>& means,
                     const CalibrationOptions& options, const UnitRequest& r, std::string* notes) {
  if (options.reading_sigmas.empty()) {
    throw DataError("a random walk of the bias weighs each position by the noise of its samples: " +
                    r.inputs.front() + " has positions without samples (give the raw log)");
  }
  CalibrationOptions constant = options;
  constant.model = ModelKind::kLinear;
  constant.bias_model = BiasModel{};
  constant.position_times_s.clear();
  constant.cross_validate = false;
  constant.reading_sigmas.clear();
  const CalibrationResult fit = Calibrate(means, constant);
  const Vec3 q_unit = walk.q_ms2 * (r.GravityInUnit() / r.gravity_ms2);
  const Vec3 q_raw = (fit.params.K.cwiseAbs2() * q_unit.cwiseAbs2()).cwiseSqrt();
  std::string bounds;
  for (std::size_t a = 0; a < 3; ++a) {
    if (walk.upper_bound[a]) bounds += std::string(bounds.empty() ? "" : ", ") + "xyz"[a];
  }
  if (!bounds.empty()) {
    bounds = "; " + bounds + ": its 95% upper bound, the noise log does not resolve " +
             (bounds.size() > 1 ? "them" : "it");
  }
  *notes += Format("prior     bias random walk %s m/s^2/sqrt(s) (%s%s): %s raw/sqrt(s)\n",
                   Vec(walk.q_ms2, " %.3g").c_str() + 1, walk.source.c_str(), bounds.c_str(),
                   Vec(q_raw, " %.3g").c_str() + 1);
  if (!(q_raw.allFinite() && q_raw.minCoeff() > 0)) {
    throw DataError(
        Format("the bias random walk %s m/s^2/sqrt(s) is %s raw/sqrt(s) through K: outside what "
               "this sensor's readings can hold",
               Vec(walk.q_ms2, " %.3g").c_str() + 1, Vec(q_raw, " %.3g").c_str() + 1));
  }
  return q_raw;
}

// The middle time of each position's still interval [s], or why the positions have none: a
// positions file holds means only, and the clocks of several files are not one time.
std::vector<double> PositionTimes(const LoadedInput& in, std::string* why) {
  if (in.files.size() > 1) {
    *why = "the positions come from " + std::to_string(in.files.size()) +
           " files, whose times are not one clock";
    return {};
  }
  std::vector<double> times;
  for (const Position& p : in.positions) {
    if (!p.interval) {
      *why = in.files.front().path +
             " holds the positions' means without their times (a raw log gives them)";
      return {};
    }
    times.push_back(0.5 * (p.interval->t_begin_s + p.interval->t_end_s));
  }
  return times;
}

// The longest pause between two positions when it is over 5 times the median pause and a minute:
// a drift is fitted straight (or between knots) across it, which nothing between them checks.
std::optional<Finding> DriftAcrossGap(const std::vector<double>& times, const BiasModel& model) {
  if (model.constant() || times.size() < 3) return std::nullopt;
  std::vector<double> sorted = times;
  std::sort(sorted.begin(), sorted.end());
  std::vector<double> pauses;
  std::size_t longest = 0;
  for (std::size_t k = 1; k < sorted.size(); ++k) {
    pauses.push_back(sorted[k] - sorted[k - 1]);
    if (pauses.back() > pauses[longest]) longest = pauses.size() - 1;
  }
  const double median = internal::Median(pauses);
  if (!(pauses[longest] > 5 * median && pauses[longest] > 60)) return std::nullopt;
  return Finding{
      "drift_across_gap",
      Severity::kWarning,
      Format("no position between %.6g s and %.6g s (%.0f s, %.0f times the median pause): the "
             "%s bias is fitted across that time as if it drifted as it did around it",
             sorted[longest], sorted[longest + 1], pauses[longest], pauses[longest] / median,
             ToString(model).c_str()),
      {{"pause_s", pauses[longest]}, {"median_pause_s", median}}};
}

// Each position's temperature: its file's from `temperatures`, else its own (read with its log).
std::vector<double> PositionTemperatures(const UnitRequest& r, LoadedInput* in,
                                         std::string* notes) {
  std::vector<double> temps;
  const auto file_of = [&](std::size_t k) -> const std::string& {
    return in->position_file.empty() ? r.inputs.front() : in->position_file[k];
  };
  if (!r.temperatures_c.empty()) {
    bool own = false;
    for (std::size_t k = 0; k < in->positions.size(); ++k) {
      std::size_t i = 0;
      while (i < in->files.size() && in->files[i].path != file_of(k)) ++i;
      own |= in->positions[k].temperature_c.has_value();
      const double t = r.temperatures_c.at(i) + 0.0;  // -0 written as 0
      in->positions[k].temperature_c = t;
      temps.push_back(t);
    }
    if (own) {
      *notes +=
          "          temperatures: {{temperatures}}, one per file, not the logs' own readings\n";
    }
    return temps;
  }
  for (std::size_t k = 0; k < in->positions.size(); ++k) {
    const Position& p = in->positions[k];
    if (!p.temperature_c) {
      // A column found by its name whose values were no temperature (kelvin, counts) was left
      // out with a note: said here, where it matters.
      std::string left_out;
      for (const LoadedFile& f : in->files) {
        if (f.path == file_of(k) && !f.data.raw.temperature_note.empty()) {
          left_out = " (" + f.data.raw.temperature_note + ")";
        }
      }
      throw InputError(file_of(k), 0,
                       "{{thermal}} needs each position's temperature, and position " +
                           std::to_string(k + 1) + " has none" + left_out +
                           ": give the log's temperature column ({{temperature_column}}) or one "
                           "temperature per file ({{temperatures}})");
    }
    temps.push_back(*p.temperature_c);
  }
  return temps;
}

// The gyroscope's log, when it is a regular file of its own, read on a thread of its own while
// the accelerometer's is loaded and fitted: the same data, and what reading it throws is thrown
// where it was read before, after the accelerometer's fit (whose errors come first). Standard
// input, a FIFO or a device is read in turn: two readers must not share one.
class GyroLogAhead {
 public:
  explicit GyroLogAhead(const UnitRequest& r) : r_(r), read_(r.load.read) {
    read_.fingerprint = true;
    read_.progress = nullptr;  // the accelerometer's display
    std::error_code error;
    const std::string& log = r.gyro->log;
    if (!log.empty() && log != "-" && log != r.inputs.front() &&
        std::filesystem::is_regular_file(log, error)) {
      pending_ = std::async(std::launch::async | std::launch::deferred, [this] { return Read(); });
    }
  }
  InputData Take() { return pending_.valid() ? pending_.get() : Read(); }

 private:
  InputData Read() const { return ReadGyroLog(r_.inputs.front(), read_, *r_.gyro); }
  const UnitRequest& r_;
  ReadOptions read_;  // copied before the accelerometer's reading changes its display
  std::future<InputData> pending_;
};

// The gyroscope's options, its offsets over temperature about the accelerometer's T_ref.
GyroCalibrationOptions GyroOptionsWithTReference(const UnitRequest& r,
                                                 const CalibrationResult& accel) {
  GyroCalibrationOptions o = GyroOptionsOf(r);
  if (o.thermal && accel.thermal) o.thermal->t_ref_c = accel.thermal->params.t_ref_c;
  return o;
}

void CalibrateGyroscope(const UnitRequest& r, GyroLogAhead* ahead, UnitOutcome* out) {
  const RawLog& accel_log = TheRawLogForGyro(out->input);
  UnitOutcome::Gyroscope g;
  const std::string& path = r.gyro->log.empty() ? r.inputs.front() : r.gyro->log;
  g.data = ahead->Take();
  try {
    static_cast<GyroCalibration&>(g.calibration) =
        CalibrateGyro(accel_log, g.data.raw, out->input.positions, out->accelerometer,
                      GyroOptionsWithTReference(r, out->accelerometer));
  } catch (const NotConvergedError& e) {  // what is refused is the gyroscope's
    throw NotConvergedError(e.what(), path);
  } catch (const DataError& e) {
    throw DataError(e.what(), path);
  }
  g.calibration.source = path;
  // The label of its raw unit: its declared unit, else its binary-log stream's by specification,
  // else the accelerometer's raw label unless that names a force unit.
  if (g.calibration.unit != GyroUnit::kRaw) {
    g.calibration.raw_unit = std::string(NameOf(r.gyro_units));
  } else if (g.data.stream && !g.data.stream->unit.empty()) {
    g.calibration.raw_unit = g.data.stream->unit;
  } else {
    g.calibration.raw_unit =
        ForceUnitFromString(out->raw_unit) ? std::string("raw") : out->raw_unit;
  }
  // The joint fit's accelerometer is the file's: the rotations refined it.
  if (g.calibration.accelerometer) out->accelerometer = *g.calibration.accelerometer;
  out->gyroscope = std::move(g);
}

// The raw unit's label: as asked for, else the unit every input's binary-log stream has by its
// specification (PX4's sensor_accel, ArduPilot's IMU, a ROS Imu: m/s2), else "raw".
std::string RawUnitLabel(const UnitRequest& r, const LoadedInput& in) {
  if (r.raw_units) return *r.raw_units;
  std::string unit;
  for (const LoadedFile& f : in.files) {
    if (!f.data.stream || f.data.stream->unit.empty()) return "raw";
    if (!unit.empty() && unit != f.data.stream->unit) return "raw";
    unit = f.data.stream->unit;
  }
  return unit.empty() ? "raw" : unit;
}

// The diagnosis and provenance of an outcome.
void Conclude(const UnitRequest& r, UnitOutcome* out) {
  DiagnosisInput d;
  d.result = &out->accelerometer;
  d.positions = &out->input.positions;
  d.max_excluded = r.outliers.max_excluded;
  d.selection = out->model_selection ? &*out->model_selection : nullptr;
  for (const LoadedFile& f : out->input.files) {
    if (f.data.kind == InputKind::kRaw) d.logs.push_back({f.path, &f.data.raw, &*f.detection});
    d.positions_by_row_count |= f.data.kind_from_row_count;
  }
  d.unit = r.units;
  if (out->gyroscope) d.gyroscope = &out->gyroscope->calibration;
  out->diagnosis = Diagnose(d);
  out->provenance = r.provenance;
  out->provenance.inputs = InputRecords(out->input);
  if (out->orientations) {
    out->provenance.inputs.push_back(
        {r.orientations, out->orientations->bytes, out->orientations->sha256});
  }
  if (out->gyroscope && !r.gyro->log.empty()) {
    const UnitOutcome::Gyroscope& g = *out->gyroscope;
    out->provenance.inputs.push_back(
        {g.calibration.source, g.data.bytes, g.data.sha256, g.data.stream});
  }
}

// The accelerometer's files read and cut into positions, and the labels of their units.
UnitOutcome Load(const UnitRequest& r) {
  UnitOutcome out;
  out.input = LoadPositions(r.inputs, r.load);
  out.raw_unit = RawUnitLabel(r, out.input);
  out.unit = r.units;
  return out;
}

// A log the reader found cut short: " (FILE ends early: why)", for each; empty when none was.
std::string CutShortNote(const LoadedInput& in) {
  std::string note;
  for (const LoadedFile& f : in.files) {
    if (f.data.kind == InputKind::kRaw && !f.data.raw.read_warning.empty()) {
      note += " (" + f.path + " ends early: " + f.data.raw.read_warning + ")";
    }
  }
  return note;
}

// `fit()`, and a fit it refuses (too few positions, a term not observable) from a log cut short
// said so: the part lost may have held what it lacks, and the warning that says so comes only with
// a result.
template <typename Fit>
auto NotingCutShort(const LoadedInput& in, Fit&& fit) -> decltype(fit()) {
  try {
    return fit();
  } catch (const DataError& e) {
    const std::string note = CutShortNote(in);
    if (note.empty() || dynamic_cast<const NotConvergedError*>(&e) != nullptr) throw;
    throw DataError(e.what() + note, e.file());
  }
}

UnitOutcome KnownOrientations(const UnitRequest& r) {
  KnownOrientationOptions options = KnownOrientationOptionsOf(r);
  OrientationFile orientation_file = ReadOrientations(r.orientations);
  UnitOutcome out = Load(r);
  out.orientations = std::move(orientation_file);
  const OrientationFile& orientations = *out.orientations;
  if (orientations.directions.size() != out.input.positions.size()) {
    throw DataError(r.orientations + " has " + std::to_string(orientations.directions.size()) +
                    " orientations for the " + std::to_string(out.input.positions.size()) +
                    " positions of " + r.inputs.front());
  }
  options.reading_sigmas = ReadingSigmas(out.input);
  out.mean_sigmas = options.reading_sigmas;
  out.model_requested = std::string(NameOf(options.model));
  out.accelerometer = NotingCutShort(out.input, [&] {
    return CalibrateKnownOrientations(Means(out.input.positions), orientations.directions, options);
  });
  out.notes = Format("orient.   %s: %zu known orientations\n", r.orientations.c_str(),
                     orientations.directions.size());
  if (r.gyro) {
    // The gyroscope on top of the known directions: its K_g maps into the platform frame.
    GyroLogAhead now(r);
    CalibrateGyroscope(r, &now, &out);
  }
  Conclude(r, &out);
  return out;
}

UnitOutcome OverTemperature(const UnitRequest& r) {
  std::optional<GyroLogAhead> gyro_ahead;
  if (r.gyro) gyro_ahead.emplace(r);
  UnitOutcome out = Load(r);
  out.model_requested = std::string(NameOf(r.model.value_or(ModelKind::kLinear)));
  ThermalOptions thermal;
  thermal.base = CalibrationOptionsOf(r);
  thermal.temperatures_c = PositionTemperatures(r, &out.input, &out.notes);
  thermal.cross_validate = r.cross_validate;
  if (r.outliers.policy != OutlierPolicy::kOff) {
    out.notes +=
        "          outliers: not screened with {{thermal}} (a discordant position shows in its "
        "held-out error)\n";
  }
  const std::vector<Vec3> means = Means(out.input.positions);
  ThermalResult fit;
  try {
    NotingCutShort(out.input, [&] {
      if (r.thermal_degrees) {
        thermal.degrees = *r.thermal_degrees;
        fit = CalibrateThermal(means, thermal);
      } else {
        out.thermal_selection = SelectThermalDegrees(means, thermal);
        fit = out.thermal_selection->result;
      }
    });
  } catch (const DataError& e) {
    throw DataError(std::string("{{thermal}}: ") + e.what());
  }
  out.accelerometer = AsCalibrationResult(fit, thermal.temperatures_c);
  // A fit that did not converge is diagnosed too (not_converged); the gyroscope builds on none.
  if (gyro_ahead && out.converged()) CalibrateGyroscope(r, &*gyro_ahead, &out);
  Conclude(r, &out);
  return out;
}

// Positions that span a range of temperature they were calibrated as if it did not matter over.
std::optional<Finding> TemperatureSpan(const std::vector<Position>& positions) {
  double lo = kTemperatureRange_C[1], hi = kTemperatureRange_C[0];
  for (const Position& p : positions) {
    if (p.temperature_c) lo = std::min(lo, *p.temperature_c), hi = std::max(hi, *p.temperature_c);
  }
  if (!(hi - lo >= kTemperatureSpanNote_K)) return std::nullopt;
  return Finding{"temperature_span",
                 Severity::kNote,
                 Format("the positions span %.3g K (%.4g to %.4g degC); parameters that follow "
                        "temperature may describe them better",
                        hi - lo, lo, hi),
                 {{"span_K", hi - lo}, {"lowest_C", lo}, {"highest_C", hi}}};
}

// The bias model, chosen when asked for (`options` takes it and the positions' times).
void ChooseBiasModel(const UnitRequest& r, const std::vector<Vec3>& means,
                     CalibrationOptions* options, UnitOutcome* out) {
  if (options->bias_model.constant() && !r.bias_model_auto) return;
  std::string why;
  options->position_times_s = PositionTimes(out->input, &why);
  if (!why.empty() && !r.bias_model_auto) {
    throw DataError("{{bias_model}} " + BiasModelText(r) + " needs each position's time: " + why);
  }
  if (!r.bias_model_auto) return;
  // With the model chosen too, the bias is chosen under the quadratic model, which holds whichever
  // model is true (so that squared terms are not taken for a drift), then the model under that
  // bias; the linear model when the quadratic one cannot be fitted.
  std::optional<BiasModelSelection>& selection = out->bias_model_selection;
  if (!r.model) {
    CalibrationOptions quadratic = *options;
    quadratic.model = ModelKind::kQuadratic;
    try {
      selection = SelectBiasModel(means, quadratic);
    } catch (const DataError&) {  // too few positions for it: the linear model decides
    }
  }
  if (!selection) selection = SelectBiasModel(means, *options);
  if (!why.empty()) selection->reason = "no position has a time: " + why;
  options->bias_model = selection->chosen;
  if (options->bias_model.constant()) options->position_times_s.clear();
}

UnitOutcome OrientationFree(const UnitRequest& r) {
  CalibrationOptions options = CalibrationOptionsOf(r);
  const RandomWalk random_walk = ReadRandomWalk(r);
  std::optional<GyroLogAhead> gyro_ahead;
  if (r.gyro) gyro_ahead.emplace(r);
  UnitOutcome out = Load(r);
  out.model_requested = r.model ? std::string(NameOf(*r.model)) : "auto";
  const std::vector<Vec3> means = Means(out.input.positions);
  options.reading_sigmas = ReadingSigmas(out.input);  // empty: noise from the residuals
  out.mean_sigmas = options.reading_sigmas;
  std::vector<Finding> unit_findings;
  if (auto span = TemperatureSpan(out.input.positions)) unit_findings.push_back(*span);
  if (random_walk.given()) {
    options.bias_random_walk = RandomWalkInRaw(random_walk, means, options, r, &out.notes);
  }
  ModelChoice choice = NotingCutShort(out.input, [&] {
    ChooseBiasModel(r, means, &options, &out);
    // For a quadratic fit (asked for, or a candidate of the model's choice) the linear fit is the
    // comparison: both with held-out validation, decided by ModelSelection's rule.
    return CalibrateChoosingModel(means, options, !r.model);
  });
  out.accelerometer = std::move(choice.result);
  out.model_selection = std::move(choice.selection);
  if (out.accelerometer.drift) {
    if (auto gap = DriftAcrossGap(out.accelerometer.drift->times_s, options.bias_model)) {
      unit_findings.push_back(*gap);
    }
  }
  if (random_walk.given() && !(out.accelerometer.drift && out.accelerometer.drift->random_walk)) {
    out.notes += "          unused: the bias chosen is " + ToString(options.bias_model) +
                 ", and the prior is a spline's\n";
  }
  // A fit that did not converge is diagnosed too (not_converged); the gyroscope builds on none.
  if (gyro_ahead && out.converged()) CalibrateGyroscope(r, &*gyro_ahead, &out);
  Conclude(r, &out);
  for (Finding& f : unit_findings) out.diagnosis.findings.push_back(std::move(f));
  return out;
}

}  // namespace

InputData ReadGyroLog(const std::string& accel_path, const ReadOptions& read,
                      const SensorInput& gyro) {
  if (auto why = GyroInputProblem(accel_path, read.columns, gyro)) throw OptionError(*why);
  try {
    return ReadGyroInput(accel_path, read, gyro.log, gyro.columns, gyro.topic);
  } catch (const InputError& e) {
    // The reader's "columns option" is the rates' columns here.
    throw InputError(
        e.file(), e.line(),
        internal::ReplaceWords(
            e.reason(), {{"the columns option's entry", "{{gyro_columns}} entry"},
                         {"the columns option", "{{gyro_columns}}"},
                         {"the topic and instance options", "{{gyro_topic}} and {{instance}}"},
                         {"the topic option", "{{gyro_topic}}"},
                         {"the frame option", "{{frame_id}}"},
                         {"the time unit option", "{{time_unit}}"},
                         {"the rate option", "{{rate}}"},
                         {"the other stream of this file", "the accelerometer"}}));
  }
}

const RawLog& TheRawLogForGyro(const LoadedInput& in) {
  if (in.files.size() != 1 || in.files.front().data.kind != InputKind::kRaw) {
    throw OptionError(
        "the gyroscope is calibrated from one raw log (its turns between the positions): give "
        "one {{input}} that is a raw log");
  }
  return in.files.front().data.raw;
}

CalibrationFileInfo UnitOutcome::FileInfo() const {
  CalibrationFileInfo info;
  info.unit = unit;
  info.raw_unit = raw_unit;
  info.source = input.files.front().path;
  if (input.files.size() > 1) {
    for (const LoadedFile& f : input.files) info.sources.push_back(f.path);
    for (const std::string& file : input.position_file) {
      info.position_source.push_back(static_cast<int>(
          std::find(info.sources.begin(), info.sources.end(), file) - info.sources.begin()));
    }
  }
  info.positions = input.positions;
  info.mean_sigmas = mean_sigmas;
  info.model_selection = model_selection ? &*model_selection : nullptr;
  info.model_requested = model_requested;
  info.bias_model_selection = bias_model_selection ? &*bias_model_selection : nullptr;
  info.diagnosis = &diagnosis;
  info.provenance = provenance;
  if (gyroscope) {
    info.gyroscope = &gyroscope->calibration;
  }
  return info;
}

UnitOutcome CalibrateUnit(const UnitRequest& request) {
  if (auto why = request.Validate()) throw OptionError(*why);
  if (!request.orientations.empty()) return KnownOrientations(request);
  if (request.thermal) return OverTemperature(request);
  return OrientationFree(request);
}

}  // namespace accelcal
