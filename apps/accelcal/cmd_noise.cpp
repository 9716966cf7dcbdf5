// accelcal noise: the Allan deviation of a still log and the IEEE noise terms fitted to it.
#include "commands.hpp"

#include <cmath>
#include <string>
#include <vector>

#include "accelcal/calibration_file.hpp"
#include "accelcal/gravity.hpp"
#include "accelcal/gyro_calibration.hpp"
#include "accelcal/gyro_model.hpp"
#include "accelcal/noise.hpp"
#include "cli_common.hpp"
#include "core/text_format.hpp"
#include "output.hpp"

namespace accelcal::cli {

using internal::VisibleLine;

namespace {

constexpr double kPi = 3.14159265358979323846;

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
};

std::string TermText(const NoiseTermEstimate& e, double factor) {
  if (!e.fitted) return "-";
  if (!e.resolved) return e.high > 0 ? "< " + Format("%.3g", e.high * factor) : "below 0";
  return Format("%.4g ± %.2g", e.value * factor, e.sigma * factor);
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
    if (!axis.fit.converged) out += "  (the fit did not settle)";
    out += "\n";
  }
  // What the terms do not describe, said where the figures are.
  for (int a = 0; a < 3; ++a) {
    const NoiseModelFit& fit = n.axes[static_cast<std::size_t>(a)].fit;
    std::string others;
    for (NoiseTerm t : fit.below_zero) {
      if (t == NoiseTerm::kQuantization) {
        out += Format(
            "  # %c: the shortest averaging times fall below white noise (quantization comes out "
            "below 0): the sensor filters its output before it is sampled, so neighbouring "
            "samples are correlated; the white noise is the level above the filter's time\n",
            "xyz"[a]);
      } else {
        others += std::string(others.empty() ? "" : ", ") + ToString(t);
      }
    }
    if (!others.empty()) {
      out += Format(
          "  # %c: the fit puts %s below 0 beyond its uncertainty: the five terms do not describe "
          "this axis' noise (a vibration, a drift that is not a ramp), and the other terms take "
          "up what is missing: read them with care\n",
          "xyz"[a], others.c_str());
    } else if (fit.chi2_p < 1e-3) {
      out += Format(
          "  # %c: the terms leave χ² = %.1f for %d degrees of freedom (p = %.2g): they do not "
          "describe this axis' noise well (a vibration or a disturbance at some averaging time?)\n",
          "xyz"[a], fit.chi2, fit.dof, fit.chi2_p);
    }
  }
  return out;
}

// The rate a noise analysis needs: the time column's or --rate.
double RequireRate(const std::string& path, const std::optional<double>& rate_hz) {
  if (!rate_hz) {
    throw UsageError(path +
                     " has no time column: give the sample rate with --rate (or the columns "
                     "with --columns time,x,y,z)");
  }
  return *rate_hz;
}

// The Allan variance of a log joined across a gap is not the sensor's.
[[noreturn]] void RefuseGap(const std::string& path, std::uint32_t line, const TimeGap& gap) {
  throw InputError(path, line,
                   Format("a gap in the samples (%.6g s to %.6g s after the first): the Allan "
                          "deviation needs one unbroken stream at one rate",
                          gap.t_before_s, gap.t_after_s));
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
               double rate_hz, const std::vector<Sensor>& sensors) {
  std::string out;
  if (args.json) {
    nlohmann::ordered_json doc;
    doc["source"] = args.input.path;
    if (calibrated) doc["calibration"] = args.calibration;
    doc["first_sample"] = begin + 1;
    doc["last_sample"] = end;
    doc["rate_hz"] = rate_hz;
    doc["model"] =
        "sigma^2(tau) = 3 Q^2/tau^2 + N^2/tau + (2 ln2/pi) B^2 + K^2 tau/3 + R^2 tau^2/2 "
        "(IEEE Std 952-1997 Annex C); intervals 95 %";
    for (const Sensor& s : sensors) doc[s.name] = SensorJson(s);
    out = JsonText(doc);
  } else {
    if (args.still) {
      out += Format("# the longest still interval: samples %zu-%zu\n", begin + 1, end);
    }
    for (const Sensor& s : sensors) out += SensorText(s);
    out +=
        "# σ²(τ) = 3Q²/τ² + N²/τ + (2 ln 2/π)B² + K²τ/3 + R²τ²/2 (IEEE Std 952 Annex C) fitted to "
        "the overlapping Allan variance; ± 1σ; \"< x\": not resolved, 95 % upper bound\n";
  }
  WriteFileAtomically(args.output.empty() ? "-" : args.output, out);
  return kExitOk;
}

// The whole log, streamed through the accumulators: memory bounded by the reader's blocks.
int StreamNoise(const NoiseArgs& args, const ReadOptions& read,
                const std::optional<LoadedCalibration>& cal) {
  NoiseAccumulator accumulator(1.0);  // the period only scales τ: given at the end
  const StreamedLog log = StreamRawLog(args.input.path, read, [&](const RawLog& piece) {
    if (!cal) {
      accumulator.Add(piece.samples.data(), piece.samples.size());
      return;
    }
    const std::vector<Vec3> forces = SpecificForces(*cal, piece.samples.data(), piece.line.data(),
                                                    piece.samples.size(), args.input.path);
    accumulator.Add(forces.data(), forces.size());
  });
  const double rate_hz = RequireRate(args.input.path, log.rate_hz);
  if (!log.gap_lines.empty()) {
    RefuseGap(args.input.path, log.gap_lines.front(), log.time->gaps.front());
  }
  Sensor accel;
  accel.name = "accelerometer";
  accel.source = args.input.path;
  accel.display = cal ? AccelDisplay(cal->unit) : RawDisplay("raw");
  accel.noise = accumulator.Finish(1 / rate_hz);
  return WriteNoise(args, cal.has_value(), 0, log.samples, rate_hz, {accel});
}

}  // namespace

int RunNoise(const NoiseArgs& args) {
  CheckOutputs({{"-o", args.output}}, {args.input.path, args.calibration, args.gyro});
  if (auto why = args.input.detection.Validate()) throw UsageError(*why);
  const bool gyro = !args.gyro.empty() || !args.gyro_columns.empty();
  if (gyro) CheckGyroColumns(args.input, args.gyro, args.gyro_columns);
  std::optional<LoadedCalibration> cal;
  if (!args.calibration.empty()) {
    cal = ParseCalibrationJson(ReadFileToString(args.calibration, kMaxSmallFileBytes),
                               args.calibration);
    RefuseFailed(*cal, args.calibration);
  }
  ReadOptions read = MakeReadOptions(args.input);
  read.kind = InputKind::kRaw;
  // A still log alone is streamed (a day's log in bounded memory); --still and the gyroscope
  // need the log whole (detection, the two streams sample by sample).
  if (!args.still && !gyro) return StreamNoise(args, read, cal);
  const InputData data = ReadInput(args.input.path, read);
  const RawLog& log = data.raw;
  const double rate_hz = RequireRate(args.input.path, log.rate_hz);
  if (log.time && !log.time->gaps.empty()) {
    const TimeGap& gap = log.time->gaps.front();
    RefuseGap(args.input.path, log.line[gap.index], gap);
  }
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
  }
  const double period = 1 / rate_hz;
  const auto count = static_cast<std::size_t>(end - begin);
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
    sensors.push_back(std::move(accel));
  }
  if (gyro) {
    const InputData rates = ReadGyroLog(args.input, args.gyro, args.gyro_columns, false);
    CheckGyroClock(log, rates.raw);
    if (rates.raw.samples.size() != log.samples.size()) {
      throw InputError(args.gyro.empty() ? args.input.path : args.gyro, 0,
                       Format("%zu gyroscope samples beside %zu of the accelerometer: the two "
                              "streams must have one row each per sample",
                              rates.raw.samples.size(), log.samples.size()));
    }
    Sensor g;
    g.name = "gyroscope";
    g.source = args.gyro.empty() ? args.input.path : args.gyro;
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
    sensors.push_back(std::move(g));
  }
  return WriteNoise(args, cal.has_value(), begin, end, rate_hz, sensors);
}

}  // namespace accelcal::cli
