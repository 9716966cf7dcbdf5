// accelcal noise: the Allan deviation of a still log and the IEEE noise terms fitted to it.
#include "commands.hpp"

#include <array>
#include <cmath>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "accelcal/calibration_file.hpp"
#include "accelcal/gravity.hpp"
#include "accelcal/gyro_calibration.hpp"
#include "accelcal/gyro_model.hpp"
#include "accelcal/noise.hpp"
#include "accelcal/noise_report.hpp"
#include "accelcal/sample_clock.hpp"
#include "cli_common.hpp"
#include "cli_options.hpp"
#include "core/text_format.hpp"
#include "output.hpp"

namespace accelcal::cli {

using internal::VisibleLine;

namespace {

constexpr double kPi = 3.14159265358979323846;
// Samples lost beyond this fraction bias the white noise by half of it (the period is then the
// mean step): refused.
constexpr double kMaxLostFraction = 1e-3;
// At rest a calibrated sensor reads its gravity to within its calibration error and the site's
// difference (≪ 1 %); a calibration 2 % away is another sensor's.
constexpr double kMaxGravityDeparture = 0.02;
// A term this many σ below 0 is not chance (0.13 % of logs each): the terms are not a result.
constexpr double kFailZ = 3;

// How one sensor's terms are shown: the unit of its samples and, for the text, a scale to the
// unit engineers quote each term in.
struct Display {
  std::string sample_unit;  // of the samples and of B
  // Per term (Q, N, B, K, R): the factor from the SI value and the unit shown.
  std::array<double, kNoiseTerms> factor;
  std::array<std::string, kNoiseTerms> unit;
};

Display RawDisplay(const std::string& unit) {
  return {unit, {1, 1, 1, 1, 1}, {unit + "·s", unit + "/√Hz", unit, unit + "/√s", unit + "/s"}};
}

Display AccelDisplay(ForceUnit unit) {
  const double to_ug =
      1e6 / (unit == ForceUnit::kMetersPerSecond2 ? kStandardGravity_ms2 : 1.0);  // per unit
  Display d{std::string(ToString(unit)),
            {to_ug, to_ug, to_ug, to_ug, to_ug},
            {"µg·s", "µg/√Hz", "µg", "µg/√s", "µg/s"}};
  return d;
}

Display GyroDisplay() {
  const double deg = 180 / kPi;
  // N in °/s/√Hz; B in °/h; K in °/h/√h (rad/s/√s · 3600 · 60); Q in ° (rad·s); R in °/h².
  return {"rad/s",
          {deg, deg, deg * 3600, deg * 3600 * 60, deg * 3600 * 3600},
          {"°", "°/s/√Hz", "°/h", "°/h/√h", "°/h²"}};
}

struct Sensor {
  std::string name;  // "accelerometer", "gyroscope"
  std::string source;
  Display display;
  NoiseAnalysis noise;
  // Per axis, what the terms do not describe (AxisNotes) and whether they are no result:
  // written once in WriteNoise, read by the text, the JSON and the verdict.
  std::array<std::vector<std::string>, 3> notes;
  std::array<bool, 3> failed{};
};

std::string TermText(const NoiseTermEstimate& e, double factor) {
  if (!e.fitted) return "-";
  if (!e.resolved) return e.high > 0 ? "< " + Format("%.3g", e.high * factor) : "below 0";
  return Format("%.4g ± %.2g", e.value * factor, e.sigma * factor);
}

// What the terms fitted to one axis do not describe, as notes; `failed` is set when one of them
// makes the terms unfit to use (the fit did not settle, a term other than quantization below 0).
std::vector<std::string> AxisNotes(const NoiseModelFit& fit, bool* failed) {
  std::vector<std::string> notes;
  if (!fit.converged) {
    notes.push_back(
        Format("the fit did not settle in %d rounds: its terms are not a result", fit.iterations));
    *failed = true;
  }
  std::string far, near;  // below 0 by 3σ or more (not chance), by 1.96-3σ (1 log in 10)
  for (NoiseTerm t : fit.below_zero) {
    if (t == NoiseTerm::kQuantization) {
      notes.push_back(
          "the shortest averaging times fall below white noise (quantization comes out below 0): "
          "the sensor filters its output before it is sampled, so neighbouring samples are "
          "correlated; the white noise is the level above the filter's time");
      continue;
    }
    const double z = fit.terms[static_cast<std::size_t>(t)].z;
    std::string& list = z <= -kFailZ ? far : near;
    list += Format("%s%s (%.1fσ)", list.empty() ? "" : ", ", ToString(t), z);
  }
  if (!far.empty()) {
    notes.push_back("the fit puts " + far +
                    " below 0, beyond chance: the five terms do not describe this axis' noise (a "
                    "vibration, a drift that is not a ramp), and the other terms take up what is "
                    "missing: they are not a result");
    *failed = true;
  }
  if (!near.empty()) {
    notes.push_back("the fit puts " + near +
                    " below 0 beyond its 95 % interval: with four terms that happens by chance in "
                    "about 1 log in 10; a log that shows it again is not described by the terms");
  }
  if (fit.chi2_p < 1e-3) {
    notes.push_back(Format(
        "the terms leave χ² = %.1f for %d degrees of freedom (p = %.2g): they do not describe "
        "this axis' noise well (a vibration or a disturbance at some averaging time?): read them "
        "with care",
        fit.chi2, fit.dof, fit.chi2_p));
  }
  return notes;
}

nlohmann::ordered_json SensorJson(const Sensor& s) {
  nlohmann::ordered_json j;
  j["source"] = s.source;
  j["unit"] = s.display.sample_unit;
  j["samples"] = s.noise.samples;
  j["sample_period_s"] = s.noise.sample_period_s;
  nlohmann::ordered_json& axes = j["axes"] = nlohmann::ordered_json::array();
  for (int a = 0; a < 3; ++a) {
    const AxisNoise& axis = s.noise.axes[static_cast<std::size_t>(a)];
    nlohmann::ordered_json ja;
    ja["axis"] = std::string(1, "xyz"[a]);
    nlohmann::ordered_json& terms = ja["terms"];
    const char* units[kNoiseTerms] = {"unit*s", "unit/sqrt(Hz)", "unit", "unit/sqrt(s)", "unit/s"};
    for (int t = 0; t < kNoiseTerms; ++t) {
      const NoiseTermEstimate& e = axis.fit.terms[static_cast<std::size_t>(t)];
      if (!e.fitted) continue;
      terms[ToString(NoiseTerm(t))] = {{"value", e.value},       {"sigma", e.sigma},
                                       {"low", e.low},           {"high", e.high},
                                       {"resolved", e.resolved}, {"unit", units[t]}};
    }
    nlohmann::ordered_json below = nlohmann::ordered_json::array();
    for (NoiseTerm t : axis.fit.below_zero) below.push_back(ToString(t));
    ja["notes"] = s.notes[static_cast<std::size_t>(a)];
    ja["fit"] = {{"chi2", axis.fit.chi2},
                 {"dof", axis.fit.dof},
                 {"p", axis.fit.chi2_p},
                 {"below_zero", below},
                 {"iterations", axis.fit.iterations},
                 {"converged", axis.fit.converged}};
    nlohmann::ordered_json& points = ja["allan"] = nlohmann::ordered_json::array();
    for (std::size_t i = 0; i < axis.points.size(); ++i) {
      const AllanPoint& p = axis.points[i];
      points.push_back(
          {{"tau_s", p.tau_s},
           {"adev", std::sqrt(p.avar)},
           {"low", axis.fit.intervals[i].low},
           {"high", axis.fit.intervals[i].high},
           {"edf", axis.fit.edf[i]},
           {"model_adev", axis.fit.model_avar[i] >= 0
                              ? nlohmann::ordered_json(std::sqrt(axis.fit.model_avar[i]))
                              : nlohmann::ordered_json()},
           {"m", p.m},
           {"stride", p.stride},
           {"terms", p.terms}});
    }
    axes.push_back(ja);
  }
  return j;
}

std::string SensorText(const Sensor& s) {
  const NoiseAnalysis& n = s.noise;
  std::string out =
      Format("%s (%s): %zu samples at %.6g Hz (%.1f s), in %s\n", s.name.c_str(),
             VisibleLine(s.source).c_str(), n.samples, 1 / n.sample_period_s,
             static_cast<double>(n.samples) * n.sample_period_s, s.display.sample_unit.c_str());
  // White noise first: the figure a data sheet and an estimator ask for.
  const int order[kNoiseTerms] = {1, 2, 3, 0, 4};
  out += Format("  %-4s", "axis");
  for (int t : order) {
    out += Format(" %26s", (std::string(ToString(NoiseTerm(t))) + " [" +
                            s.display.unit[static_cast<std::size_t>(t)] + "]")
                               .c_str());
  }
  out += "\n";
  for (int a = 0; a < 3; ++a) {
    const AxisNoise& axis = n.axes[static_cast<std::size_t>(a)];
    out += Format("  %-4c", "xyz"[a]);
    for (int t : order) {
      out += Format(" %26s", TermText(axis.fit.terms[static_cast<std::size_t>(t)],
                                      s.display.factor[static_cast<std::size_t>(t)])
                                 .c_str());
    }
    out += "\n";
  }
  // What the terms do not describe, said where the figures are.
  for (int a = 0; a < 3; ++a) {
    for (const std::string& note : s.notes[static_cast<std::size_t>(a)]) {
      out += Format("  # %c: %s\n", "xyz"[a], note.c_str());
    }
  }
  return out;
}

// The rate a noise analysis takes: the time column's (its samples over its span), else --rate.
// A given rate that differs from the time column's is said: the density scales with its root.
double RateFor(const std::string& path, const std::optional<double>& clock_hz,
               const std::optional<double>& given_hz) {
  if (!clock_hz) {
    if (!given_hz) {
      throw UsageError(path +
                       " has no time column: give the sample rate with --rate (or the columns "
                       "with --columns time,x,y,z)");
    }
    return *given_hz;
  }
  if (given_hz && std::abs(*given_hz / *clock_hz - 1) > kRateTolerance) {
    throw InputError(path, 0,
                     Format("the given rate %.6g Hz contradicts the time column, whose samples "
                            "come at %.6g Hz",
                            *given_hz, *clock_hz));
  }
  if (given_hz && std::abs(*given_hz / *clock_hz - 1) > 1e-3) {
    Warn(
        "%s: --rate %.6g Hz given, but the time column's samples come at %.6g Hz: its rate is "
        "taken\n",
        VisibleLine(path).c_str(), *given_hz, *clock_hz);
  }
  return *clock_hz;
}

// The Allan variance of a log joined across a gap is not the sensor's.
[[noreturn]] void RefuseGap(const std::string& path, std::uint32_t line, const TimeGap& gap,
                            double lost) {
  throw InputError(path, line,
                   Format("a gap in the samples (%.6g s to %.6g s after the first; %.0f samples "
                          "lost in all): the Allan deviation needs one unbroken stream at one rate",
                          gap.t_before_s, gap.t_after_s, lost));
}

// Samples lost (at a gap: said as one), samples beyond the span's room, or a rate that changes
// make the Allan variance's τ wrong: refused. A jittery clock, or one that delivers samples in
// bursts, loses none: its samples catch up within the span.
void RefuseIrregularClock(const std::string& path, const SampleClockReport& clock,
                          const TimeGap* gap, std::uint32_t gap_line,
                          const std::optional<double>& given_hz) {
  if (clock.lost_fraction > kMaxLostFraction && gap != nullptr) {
    RefuseGap(path, gap_line, *gap, clock.lost);
  }
  if (clock.rate_departs()) {
    throw InputError(
        path, clock.first_departing_line,
        Format("from about this line the samples come at %.6g Hz where the log starts at %.6g "
               "Hz (%.3g %% away, beyond the %.2g %% its timestamps explain; at most %.3g %% "
               "away): the rate changes within the log, or samples are lost there; the Allan "
               "deviation needs one stream at one rate",
               clock.first_departing_rate_hz, clock.reference_rate_hz,
               100 * std::abs(clock.first_departing_rate_hz / clock.reference_rate_hz - 1),
               100 * clock.tolerance, 100 * clock.worst_departure));
  }
  if (clock.two_readings()) {
    // Steps mostly shorter than the span's: samples lost, or timestamps rounded; the rate says.
    const double lost = clock.span_s / clock.median_step_s - double(clock.samples - 1);
    const auto near = [&](double period) {
      return given_hz && std::abs(*given_hz * period - 1) <= 0.01;
    };
    if (near(clock.median_step_s)) {
      throw InputError(path, clock.first_long_line,
                       Format("%.0f samples are missing from a %.6g Hz stream (%.2g %% of the "
                              "log), the first before this line: the Allan deviation takes the "
                              "samples one period apart",
                              lost, 1 / clock.median_step_s, 100 * lost / double(clock.samples)));
    }
    if (!near(clock.period_s)) {
      throw InputError(
          path, 0,
          Format("the steps are mostly %.6g s (%.6g Hz), but the log's %.6g s hold a step every "
                 "%.6g s (%.6g Hz): either %.0f samples (%.2g %%) of a %.6g Hz stream are lost, or "
                 "the timestamps are rounded coarser than the samples come; give --rate with "
                 "the sensor's rate to say which",
                 clock.median_step_s, 1 / clock.median_step_s, clock.span_s, clock.period_s,
                 1 / clock.period_s, lost, 100 * lost / double(clock.samples),
                 1 / clock.median_step_s));
    }
  }
  if (clock.lost_fraction > kMaxLostFraction) {
    throw InputError(
        path, clock.first_long_line,
        Format("%.0f samples are missing (%.2g %% of the log: its %.6g s hold %.0f steps of "
               "%.6g s, the sampling period), the first step of 1.5 periods or more "
               "before this line: the Allan deviation takes the samples one period apart, and "
               "the white noise would come out %.2g %% high",
               clock.lost, 100 * clock.lost_fraction, clock.span_s, clock.span_s / clock.period_s,
               clock.period_s, 100 * (std::sqrt(1 + clock.lost_fraction) - 1)));
  }
  if (clock.lost_fraction < -kMaxLostFraction) {
    throw InputError(
        path, 0,
        Format("%.0f samples more than the log's %.6g s hold at a sample every %.6g s (the "
               "sampling period): rows written twice, or two streams interleaved?",
               -clock.lost, clock.span_s, clock.period_s));
  }
}

// A sensor that moved is refused: its Allan deviation is not its noise. `line_of` gives the line
// of a sample analysed (0: unknown).
void RefuseMotion(const std::string& path, const NoiseAnalysis& noise, bool still_option,
                  const std::function<std::uint32_t(std::size_t)>& line_of) {
  const Stillness& s = noise.stillness;
  if (s.still) return;
  throw InputError(
      path, line_of(s.at_sample),
      Format("the sensor moves: the mean of its %c axis over %zu samples changes by %.4g at "
             "%.6g s after the first sample analysed, %.3g times the typical %s %.3g; the "
             "Allan deviation of a moving sensor is not its noise%s",
             "xyz"[s.axis], kStillBlockSamples, s.largest_change,
             static_cast<double>(s.at_sample) * noise.sample_period_s,
             s.largest_change / s.typical_change,
             s.beyond_steps ? "step between neighbouring samples" : "change", s.typical_change,
             still_option ? " (the longest still interval holds a knock or a turn)"
                          : ": give --still to take the longest still interval"));
}

// A glitch (a bus error, a saturated reading) is refused: one step of 70σ among 20000 samples
// puts the white noise 5 % high, ten of them 50 %.
void RefuseSpikes(const std::string& path, const NoiseAnalysis& noise,
                  const std::function<std::uint32_t(std::size_t)>& line_of) {
  const Spikes& s = noise.spikes;
  if (s.clean) return;
  throw InputError(
      path, line_of(s.at_sample),
      Format("a spike: the %c axis steps by %.4g from the sample before (%.6g s after the first "
             "sample analysed), %.3g times the typical step %.3g (for Gaussian noise the largest "
             "of a day's steps is some 8): a glitch biases the white noise high; remove the "
             "sample, or analyse the samples either side of it",
             "xyz"[s.axis], s.largest_step,
             static_cast<double>(s.at_sample) * noise.sample_period_s,
             s.largest_step / s.typical_step, s.typical_step));
}

// A calibration from another sensor (or another unit) shows at rest: |f| is not its gravity.
void RefuseForeignCalibration(const std::string& path, const std::string& calibration,
                              const LoadedCalibration& cal, const NoiseAnalysis& noise) {
  const double norm = noise.mean.norm();
  if (std::abs(norm / cal.gravity - 1) <= kMaxGravityDeparture) return;
  throw InputError(
      path, 0,
      Format("calibrated by %s, the sensor at rest reads |f| = %.6g %s where that "
             "calibration's gravity is %.6g %s (%.3g %% away): the calibration is "
             "not this sensor's, or not for this log's unit",
             VisibleLine(calibration).c_str(), norm, ToString(cal.unit).data(), cal.gravity,
             ToString(cal.unit).data(), 100 * std::abs(norm / cal.gravity - 1)));
}

// The calibrated specific force of `count` raw readings (their lines `line`, for the error).
std::vector<Vec3> SpecificForces(const LoadedCalibration& cal, const Vec3* raw,
                                 const std::uint32_t* line, std::size_t count,
                                 const std::string& path) {
  std::vector<Vec3> forces(count);
  for (std::size_t k = 0; k < count; ++k) {
    const std::optional<Vec3> f = SpecificForce(cal.params, raw[k]);
    if (!f) {
      throw InputError(path, line[k],
                       "the reading lies outside the range the quadratic model can invert");
    }
    forces[k] = *f;
  }
  return forces;
}

int WriteNoise(const NoiseArgs& args, bool calibrated, std::size_t begin, std::size_t end,
               double rate_hz, const std::optional<TimeAxis>& time, std::vector<Sensor> sensors) {
  // Each axis' notes, and the verdict: failed when an axis' terms are not a result.
  bool failed = false;
  std::vector<std::string> reasons;
  for (Sensor& s : sensors) {
    for (std::size_t a = 0; a < 3; ++a) {
      s.notes[a] = AxisNotes(s.noise.axes[a].fit, &s.failed[a]);
      if (s.failed[a]) reasons.push_back(s.name + " " + std::string(1, "xyz"[a]));
      failed = failed || s.failed[a];
    }
  }
  // How the time column was read (its unit decides the rate: a unit misread is a density 31.6
  // times off), or that the rate was given: said in the text, the JSON and the report.
  const std::string time_note = time ? time->unit_reason : std::string("none: the rate given");
  std::string out;
  if (args.json) {
    nlohmann::ordered_json doc;
    doc["source"] = args.input.path;
    if (calibrated) doc["calibration"] = args.calibration;
    doc["first_sample"] = begin + 1;
    doc["last_sample"] = end;
    doc["rate_hz"] = rate_hz;
    doc["time_unit"] = time_note;
    doc["verdict"] = failed ? "failed" : "passed";
    if (failed) doc["failed_axes"] = reasons;
    doc["model"] =
        "sigma^2(tau) = 3 Q^2/tau^2 + N^2/tau + (2 ln2/pi) B^2 + K^2 tau/3 + R^2 tau^2/2 "
        "(IEEE Std 952-1997 Annex C); intervals 95 %";
    for (const Sensor& s : sensors) doc[s.name] = SensorJson(s);
    out = JsonText(doc);
  } else {
    out += "# time: " + VisibleLine(time_note) + "\n";
    if (args.still) {
      out += Format("# the longest still interval: samples %zu-%zu\n", begin + 1, end);
    }
    for (const Sensor& s : sensors) out += SensorText(s);
    out +=
        "# σ²(τ) = 3Q²/τ² + N²/τ + (2 ln 2/π)B² + K²τ/3 + R²τ²/2 (IEEE Std 952 Annex C) fitted to "
        "the overlapping Allan variance; ± 1σ; \"< x\": not resolved, 95 % upper bound\n";
    if (failed) {
      std::string list;
      for (const std::string& r : reasons) list += (list.empty() ? "" : ", ") + r;
      out += "# verdict: failed: the terms of " + list + " are not a result (see the notes)\n";
    }
  }
  std::string report;
  if (!args.report.empty()) {
    NoiseReportInput page;
    page.title = args.input.path;
    page.time_note = time_note;
    page.verdict = failed ? "failed: the terms of " + reasons.front() +
                                (reasons.size() > 1 ? " and others" : "") +
                                " are not a result (see the notes)"
                          : "passed";
    for (const Sensor& s : sensors) {
      NoiseReportSensor r;
      r.name = s.name;
      r.source = s.source;
      r.sample_unit = s.display.sample_unit;
      r.term_unit = s.display.unit;
      r.term_factor = s.display.factor;
      r.analysis = &s.noise;
      r.notes = s.notes;
      page.sensors.push_back(std::move(r));
    }
    report = RenderNoiseReport(page);
  }
  {  // both files or neither
    OutputFile file(args.output.empty() ? "-" : args.output);
    file.Write(out);
    std::optional<OutputFile> report_file;
    if (!args.report.empty()) report_file.emplace(args.report).Write(report);
    CommitAll({&file, report_file ? &*report_file : nullptr});
  }
  if (failed) {
    Warn("the noise terms failed their checks (%s): see the notes\n",
         reasons.empty() ? "" : reasons.front().c_str());
    return kExitFailedChecks;
  }
  return kExitOk;
}

// A binary log cut short (a crashed vehicle's) is analysed up to where it stops, which is said.
void WarnCutShort(const std::string& path, const std::string& read_warning) {
  if (!read_warning.empty()) {
    Warn("%s: %s: the samples before it were analysed\n", VisibleLine(path).c_str(),
         VisibleLine(read_warning).c_str());
  }
}

// The whole log, streamed through the accumulators: memory bounded by the reader's blocks.
int StreamNoise(const NoiseArgs& args, const ReadOptions& read,
                const std::optional<double>& given_hz,
                const std::optional<LoadedCalibration>& cal) {
  NoiseAccumulator accumulator(1.0);  // the period only scales τ: given at the end
  std::optional<SampleClockCheck> clock;
  // The line of each axis' largest step so far, taken while its piece is at hand.
  std::array<std::size_t, 3> step_at{};
  std::array<std::uint32_t, 3> step_line{};
  const StreamedLog log = StreamRawLog(args.input.path, read, [&](const RawLog& piece) {
    if (piece.time) {
      if (!clock) clock.emplace(*piece.time);
      clock->Add(piece.time_s.data(), piece.line.data(), piece.time_s.size());
    }
    const std::size_t first = accumulator.samples();
    if (!cal) {
      accumulator.Add(piece.samples.data(), piece.samples.size());
    } else {
      const std::vector<Vec3> forces = SpecificForces(*cal, piece.samples.data(), piece.line.data(),
                                                      piece.samples.size(), args.input.path);
      accumulator.Add(forces.data(), forces.size());
    }
    for (int a = 0; a < 3; ++a) {
      const std::size_t at = accumulator.largest_step_sample(a);
      if (at != step_at[std::size_t(a)] && at >= first) {
        step_at[std::size_t(a)] = at;
        step_line[std::size_t(a)] = piece.line[at - first];
      }
    }
  });
  WarnCutShort(args.input.path, log.read_warning);
  std::optional<double> clock_hz;
  if (clock) {
    const SampleClockReport report = clock->Finish();
    RefuseIrregularClock(args.input.path, report,
                         log.gap_lines.empty() ? nullptr : &log.time->gaps.front(),
                         log.gap_lines.empty() ? 0 : log.gap_lines.front(), given_hz);
    clock_hz = report.rate_hz;
  }
  const double rate_hz = RateFor(args.input.path, clock_hz, given_hz);
  Sensor accel;
  accel.name = "accelerometer";
  accel.source = args.input.path;
  accel.display = cal ? AccelDisplay(cal->unit) : RawDisplay("raw");
  accel.noise = accumulator.Finish(1 / rate_hz);
  RefuseMotion(args.input.path, accel.noise, false, [](std::size_t) { return 0u; });
  RefuseSpikes(args.input.path, accel.noise, [&](std::size_t k) {
    for (int a = 0; a < 3; ++a) {
      if (step_at[std::size_t(a)] == k) return step_line[std::size_t(a)];
    }
    return 0u;
  });
  if (cal) RefuseForeignCalibration(args.input.path, args.calibration, *cal, accel.noise);
  return WriteNoise(args, cal.has_value(), 0, log.samples, rate_hz, log.time, {std::move(accel)});
}

}  // namespace

int RunNoise(const NoiseArgs& args) {
  CheckOutputs({{"-o", args.output}, {"--report", args.report}},
               {args.input.path, args.calibration, args.gyro.log});
  if (auto why = args.input.detection.Validate()) throw UsageError(*why);
  const bool gyro = args.gyro.given();
  if (gyro) CheckGyroColumns(args.input, args.gyro);
  std::optional<LoadedCalibration> cal;
  if (!args.calibration.empty()) {
    cal = ParseCalibrationJson(ReadFileToString(args.calibration, kMaxSmallFileBytes),
                               args.calibration);
    RefuseFailed(*cal, args.calibration);
  }
  ReadOptions read = MakeReadOptions(args.input);
  read.kind = InputKind::kRaw;
  // The given rate is the noise analysis' own to check against the time column's clock (it tells
  // lost samples from coarse timestamps, SampleClockReport::two_readings), not the reader's.
  const std::optional<double> given_hz = read.rate_hz;
  read.rate_hz.reset();
  // A still log alone is streamed (a day's log in bounded memory); --still and the gyroscope
  // need the log whole (detection, the two streams sample by sample).
  if (!args.still && !gyro) return StreamNoise(args, read, given_hz, cal);
  InputData data = ReadInput(args.input.path, read);
  WarnCutShort(args.input.path, data.raw.read_warning);
  // Without a time column the given rate is the log's (the detection of --still needs one).
  if (!data.raw.time && given_hz) data.raw.rate_hz = given_hz;
  const RawLog& log = data.raw;
  // The samples analysed: the whole log, or its longest still interval.
  std::size_t begin = 0, end = log.samples.size();
  if (args.still) {
    const StaticDetectionResult d = DetectStaticIntervals(log, args.input.detection);
    if (d.intervals.empty()) throw NoStaticInterval(d);
    const StaticInterval* longest = &d.intervals.front();
    for (const StaticInterval& s : d.intervals) {
      if (s.count() > longest->count()) longest = &s;
    }
    begin = longest->begin;
    end = longest->end;
    // Less a detection window at each end: the detector's windows blur an interval's edges, and
    // the first movement of a turn (a step of 27 typical ones 0.3 s before the Xsens rest ends)
    // is no noise of the sensor at rest.
    if (end - begin > 4 * d.window_samples) {
      begin += d.window_samples;
      end -= d.window_samples;
    }
  }
  const auto count = static_cast<std::size_t>(end - begin);
  // The clock of the samples analysed: their rate, over their own span.
  std::optional<double> clock_hz;
  if (log.time) {
    SampleClockCheck clock(*log.time);
    clock.Add(log.time_s.data() + begin, log.line.data() + begin, count);
    const SampleClockReport report = clock.Finish();
    const TimeGap* gap = nullptr;
    for (const TimeGap& g : log.time->gaps) {
      if (g.index > begin && g.index < end) {
        gap = &g;
        break;
      }
    }
    RefuseIrregularClock(args.input.path, report, gap, gap ? log.line[gap->index] : 0, given_hz);
    clock_hz = report.rate_hz;
  }
  const double rate_hz = RateFor(args.input.path, clock_hz, given_hz);
  const double period = 1 / rate_hz;
  const auto line_of = [&](std::size_t k) {
    return begin + k < log.line.size() ? log.line[begin + k] : 0u;
  };
  // Calibrated, the accelerometer's specific force, which the gyroscope's g-sensitivity takes too.
  std::vector<Vec3> forces;
  if (cal) {
    forces = SpecificForces(*cal, log.samples.data() + begin, log.line.data() + begin, count,
                            args.input.path);
  }
  std::vector<Sensor> sensors;
  {
    Sensor accel;
    accel.name = "accelerometer";
    accel.source = args.input.path;
    accel.display = cal ? AccelDisplay(cal->unit) : RawDisplay("raw");
    accel.noise = cal ? AnalyseNoise(forces, period)
                      : AnalyseNoise(std::vector<Vec3>(log.samples.begin() + std::ptrdiff_t(begin),
                                                       log.samples.begin() + std::ptrdiff_t(end)),
                                     period);
    RefuseMotion(args.input.path, accel.noise, args.still, line_of);
    RefuseSpikes(args.input.path, accel.noise, line_of);
    if (cal) RefuseForeignCalibration(args.input.path, args.calibration, *cal, accel.noise);
    sensors.push_back(std::move(accel));
  }
  if (gyro) {
    const InputData rates = ReadGyroLog(args.input, args.gyro, false);
    if (!args.gyro.log.empty()) WarnCutShort(args.gyro.log, rates.raw.read_warning);
    CheckGyroClock(log, rates.raw);
    if (rates.raw.samples.size() != log.samples.size()) {
      throw InputError(args.gyro.log.empty() ? args.input.path : args.gyro.log, 0,
                       Format("%zu gyroscope samples beside %zu of the accelerometer: the two "
                              "streams must have one row each per sample",
                              rates.raw.samples.size(), log.samples.size()));
    }
    Sensor g;
    g.name = "gyroscope";
    g.source = args.gyro.log.empty() ? args.input.path : args.gyro.log;
    std::vector<Vec3> samples(rates.raw.samples.begin() + static_cast<std::ptrdiff_t>(begin),
                              rates.raw.samples.begin() + static_cast<std::ptrdiff_t>(end));
    if (cal && cal->has_gyroscope()) {
      for (std::size_t k = 0; k < samples.size(); ++k) {
        const std::optional<Vec3> w = BodyRate(cal->gyroscope->params, samples[k], forces[k]);
        if (!w) throw DataError(args.calibration + ": its gyroscope's K_g is singular");
        samples[k] = *w;
      }
      g.display = GyroDisplay();
    } else {
      if (cal) {
        Warn("%s: it holds no gyroscope calibration: the gyroscope's noise is in its raw unit\n",
             args.calibration.c_str());
      }
      g.display = RawDisplay("raw");
    }
    g.noise = AnalyseNoise(samples, period);
    // A turn about the vertical moves the gyroscope, not the accelerometer.
    const auto rate_line = [&](std::size_t k) {
      return begin + k < rates.raw.line.size() ? rates.raw.line[begin + k] : 0u;
    };
    RefuseMotion(g.source, g.noise, args.still, rate_line);
    RefuseSpikes(g.source, g.noise, rate_line);
    sensors.push_back(std::move(g));
  }
  return WriteNoise(args, cal.has_value(), begin, end, rate_hz, log.time, std::move(sensors));
}

CommandRun SetUpNoise(CLI::App* cmd) {
  auto a = std::make_shared<NoiseArgs>();
  cmd->add_option("LOG", a->input.path, "raw log of the sensor held still")->required();
  AddInputOptions(cmd, &a->input, false);
  AddDetectionOptions(cmd, &a->input);
  cmd->add_option("--calibration", a->calibration,
                  "calibration file (JSON): the samples calibrated first (else the log's unit)");
  AddSensorInput(cmd, kGyroscopeFlags, &a->gyro, " on the same clock: its noise too",
                 "in LOG or the {log} log");
  cmd->add_flag("--still", a->still,
                "only the longest still interval of the log (a calibration log's rest)");
  cmd->add_flag("--json", a->json, "machine-readable output");
  cmd->add_option("--report", a->report,
                  "HTML report: the Allan deviation plotted with its bands and the fit")
      ->check(kFileName);
  cmd->add_option("-o,--output", a->output, "output file (default: stdout)")->check(kFileName);
  return [a](const CLI::App& parsed) {
    CheckSensorInput(parsed, kGyroscopeFlags, a->gyro, {});
    DataSubject() = a->input.path;
    return RunNoise(*a);
  };
}

}  // namespace accelcal::cli
