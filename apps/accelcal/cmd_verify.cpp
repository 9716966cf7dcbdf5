// accelcal verify: a calibration applied to a new recording of the same unit, each still
// position's |f| - g against the error the calibration predicts (verify.hpp).
#include "commands.hpp"

#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "accelcal/calibration_file.hpp"
#include "accelcal/gravity.hpp"
#include "accelcal/gyro_calibration.hpp"
#include "accelcal/verify.hpp"
#include "cli_common.hpp"
#include "cli_options.hpp"
#include "core/text_format.hpp"
#include "output.hpp"

namespace accelcal::cli {

using internal::Format;
using internal::VisibleLine;

namespace {

// What the calibration's own positions scattered by beyond their noise [raw]: its residual σ̂
// less the mean noise of its position means: their `mean_sigma` as the fit took them (from batch
// means, the samples' correlation included), else σ²/n per axis (white samples; a filtered
// sensor's are noisier, which leaves this larger and the test more lenient). All of σ̂ when its
// positions carry no noise. The file's σ̂ is there (RunVerify refuses a file without it).
double MisfitSigma(const LoadedCalibration& cal) {
  double sum = 0;
  std::size_t count = 0;
  for (const FilePosition& p : cal.positions) {
    if (p.excluded) continue;
    if (p.mean_sigma) {
      sum += p.mean_sigma->squaredNorm() / 3;
    } else if (p.std && p.samples && *p.samples > 0) {
      sum += p.std->squaredNorm() / 3 / static_cast<double>(*p.samples);
    } else {
      continue;
    }
    ++count;
  }
  const double noise2 = count > 0 ? sum / static_cast<double>(count) : 0.0;
  return std::sqrt(std::max(0.0, *cal.noise_sigma_raw * *cal.noise_sigma_raw - noise2));
}

std::string VecText(const Vec3& v) { return Format("[%.6g, %.6g, %.6g]", v(0), v(1), v(2)); }

// A number, or null where there is none (a reading the model cannot invert).
nlohmann::ordered_json NumberOrNull(double v) {
  return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(nullptr);
}

nlohmann::ordered_json ParametersJson(const std::vector<VerifiedParameter>& parameters) {
  nlohmann::ordered_json list = nlohmann::ordered_json::array();
  for (const VerifiedParameter& p : parameters) {
    list.push_back(
        {{"name", p.name}, {"detectable", NumberOrNull(p.detectable)}, {"sigma", p.sigma}});
  }
  return list;
}

// The calibration under test, as its file holds it (its thermal terms, when it has them).
VerifiedCalibration UnderTest(const LoadedCalibration& cal, const std::string& path) {
  VerifiedCalibration under_test;
  under_test.model = cal.model;
  under_test.frame = cal.frame;
  under_test.params = cal.params;
  under_test.covariance = cal.covariance;
  under_test.gravity = cal.gravity;
  under_test.misfit_sigma_raw = MisfitSigma(cal);
  if (cal.thermal) {
    under_test.thermal.emplace(cal.thermal->params);
    under_test.covariance = cal.thermal->covariance;  // of the thermal coefficients
    if (under_test.covariance.size() == 0) {
      throw InputError(path, 0,
                       "holds no covariance of its thermal coefficients: verify predicts the "
                       "error from it; calibrate again");
    }
    if (cal.thermal_range_c) under_test.thermal_range_c = *cal.thermal_range_c;
  }
  return under_test;
}

// The calibration holds what verify predicts the error from: its parameters' covariance and its
// residual noise (and, with `gyro`, its gyroscope's covariance and scatter ratios).
void CheckPredictable(const LoadedCalibration& cal, const std::string& path, bool gyro) {
  // The prediction needs the calibration's uncertainty: without it every good calibration of a
  // real sensor would fail (its parameters taken as exact, its misfit as none).
  const std::string method = cal.solver.method.empty() ? "?" : cal.solver.method;
  if (cal.covariance.size() == 0) {
    throw InputError(path, 0,
                     "holds no covariance of its parameters (its method '" + method +
                         "' gives none): verify predicts the error from it; calibrate with the "
                         "maximum-likelihood methods (the default)");
  }
  if (!cal.noise_sigma_raw) {
    throw InputError(path, 0,
                     "holds no noise.sigma_raw (its positions' residual level): verify predicts "
                     "the error from it; calibrate again");
  }
  if (gyro && !cal.gyroscope) {
    throw UsageError(path +
                     " holds no gyroscope calibration: there is nothing to verify the rates "
                     "against (leave out --gyro)");
  }
  if (gyro && cal.gyroscope->covariance.size() == 0) {
    throw InputError(path, 0,
                     "its gyroscope holds no covariance: verify predicts the turns' error from "
                     "it; calibrate again");
  }
  if (gyro && (std::isnan(cal.gyroscope->rotation_scatter_ratio) ||
               std::isnan(cal.gyroscope->still_scatter_ratio))) {
    throw InputError(
        path, 0,
        std::string("its gyroscope holds no noise.") +
            (std::isnan(cal.gyroscope->rotation_scatter_ratio) ? "rotation_scatter_ratio"
                                                               : "still_scatter_ratio") +
            " (the scatter of its turns or still rates over their rate noise): "
            "verify predicts their error from it; calibrate again");
  }
}

// --temperature: every position judged at it, not at the log's own.
void JudgeAtTemperature(const VerifyArgs& args, const LoadedCalibration& cal,
                        std::vector<Position>* positions) {
  if (!cal.thermal) {
    throw UsageError("--temperature is for a calibration whose parameters follow temperature");
  }
  if (!InTemperatureRange(*args.temperature_c)) {
    throw UsageError(Format("--temperature: %g is outside %g to %g degC", *args.temperature_c,
                            kTemperatureRange_C[0], kTemperatureRange_C[1]));
  }
  bool own = false;
  for (Position& p : *positions) {
    own |= p.temperature_c.has_value();
    p.temperature_c = *args.temperature_c + 0.0;
  }
  if (own) {
    Warn("%s: its positions are judged at --temperature %g degC, not at the log's own\n",
         args.input.path.c_str(), *args.temperature_c);
  }
}

// The positions recorded outside the range the calibration was fitted over, said as apply says it.
void WarnOutsideRange(const VerifyArgs& args, const VerifiedCalibration& under_test,
                      const Verification& v) {
  std::size_t held = 0;
  for (const VerifiedPosition& p : v.positions) {
    held += p.temperature_c < under_test.thermal_range_c.first - 1 ||
            p.temperature_c > under_test.thermal_range_c.second + 1;
  }
  if (held > 0) {
    Warn(
        "%s: %zu of its %zu positions were recorded more than 1 K outside %g .. %g degC, the "
        "range the calibration was fitted over: judged at the nearest end\n",
        args.input.path.c_str(), held, v.positions.size(), under_test.thermal_range_c.first,
        under_test.thermal_range_c.second);
  }
}

// The gyroscope's turns and still rates in --gyro's log, against the error its calibration
// predicts.
GyroVerification VerifyRates(const VerifyArgs& args, const LoadedCalibration& cal,
                             const VerifiedCalibration& under_test, const InputData& data,
                             const std::vector<Position>& positions) {
  InputData rates = ReadGyroLog(args.input, args.gyro, false);
  CheckGyroClock(data.raw, rates.raw);
  // Offsets over temperature: taken out of each rate at its temperature, as calibrate did.
  if (const std::optional<GyroThermal>& b = cal.gyroscope->thermal; b && b->bias.degree() > 0) {
    WarnOtherTemperatureSensor(cal, args.calibration, GyroTemperatureSource(rates.raw, data.raw),
                               "verified");
    const std::vector<double> t_c = GyroSampleTemperatures(rates.raw, data.raw);
    const auto [lo, hi] = cal.gyroscope->thermal->range_c;
    for (std::size_t k = 0; k < t_c.size(); ++k) {
      rates.raw.samples[k] -= b->bias.OffsetChange(std::clamp(t_c[k], lo, hi));
    }
  }
  VerifiedGyroscope g;
  g.model = cal.gyroscope->model;
  g.params = cal.gyroscope->params;
  g.covariance = cal.gyroscope->covariance;
  g.rotation_scatter_ratio = cal.gyroscope->rotation_scatter_ratio;
  g.still_scatter_ratio = cal.gyroscope->still_scatter_ratio;
  return VerifyGyroscope(under_test, g, data.raw, rates.raw, positions);
}

// What verify found, for its report and its status.
struct Findings {
  VerifiedCalibration under_test;
  std::string gravity_origin = "the calibration's";
  Verification v;                      // the accelerometer's
  std::optional<GyroVerification> gv;  // the gyroscope's, with --gyro
  bool checks_hold = false;
  bool passed = false;
  const char* verdict = "";
  std::string why;       // why it failed, both sensors' reasons
  std::string untested;  // the parameters this log does not test
};

void Conclude(Findings* f) {
  const Verification& v = f->v;
  const std::optional<GyroVerification>& gv = f->gv;
  const bool checks_hold = f->checks_hold = v.passed && (!gv || gv->passed);
  std::string& why = f->why = v.reason;  // why it failed, both sensors' reasons
  if (gv && !gv->passed) why += (why.empty() ? "" : "; ") + ("the gyroscope: " + gv->reason);
  std::string& untested = f->untested;
  for (const std::string& name : v.untested) untested += (untested.empty() ? "" : ", ") + name;
  if (gv) {
    for (const std::string& name : gv->untested) {
      untested += (untested.empty() ? "" : ", ") + name;
    }
  }
  // A log that cannot test some of the parameters verifies only the others: the checks holding
  // is then no pass (one position tests 2 of 9), but inconclusive.
  const bool passed = f->passed = checks_hold && untested.empty();
  f->verdict = !checks_hold ? "failed" : passed ? "passed" : "inconclusive";
  if (checks_hold && !passed) {
    why = "this log does not test " + untested +
          " (its positions and turns do not excite them enough): record one that does";
  }
}

std::string VerifyJson(const VerifyArgs& args, const LoadedCalibration& cal, const Findings& f) {
  const Verification& v = f.v;
  const std::optional<GyroVerification>& gv = f.gv;
  const std::string unit(ToString(cal.unit));
  nlohmann::ordered_json doc;
  doc["calibration"] = args.calibration;
  doc["log"] = args.input.path;
  doc["unit"] = unit;
  doc["gravity"] = f.under_test.gravity;
  doc["gravity_origin"] = f.gravity_origin;
  doc["misfit_sigma_raw"] = f.under_test.misfit_sigma_raw;
  doc["verdict"] = f.verdict;  // written again below, after the gyroscope
  doc["accelerometer_verdict"] = v.passed ? "passed" : "failed";
  if (!v.passed) {
    doc["reason"] = v.reason;
  } else if (f.checks_hold && !f.passed) {
    doc["reason"] = f.why;
  }
  doc["chi2"] = v.chi2;
  doc["dof"] = v.dof;
  doc["p_value"] = v.p_value;
  doc["significance"] = VerifyOptions().significance;
  doc["rms_error"] = v.rms_error;
  doc["rms_predicted"] = v.rms_predicted;
  nlohmann::ordered_json off = nlohmann::ordered_json::array();
  for (const std::size_t k : v.off_positions) off.push_back(k + 1);
  doc["off_positions"] = off;
  nlohmann::ordered_json list = nlohmann::ordered_json::array();
  for (std::size_t k = 0; k < v.positions.size(); ++k) {
    const VerifiedPosition& p = v.positions[k];
    list.push_back({{"position", k + 1},
                    {"t_begin_s", p.t_begin_s},
                    {"t_end_s", p.t_end_s},
                    {"samples", p.samples},
                    {"temperature", NumberOrNull(p.temperature_c)},
                    {"mean_raw", {p.mean_raw(0), p.mean_raw(1), p.mean_raw(2)}},
                    {"error", NumberOrNull(p.error)},
                    {"sigma", NumberOrNull(p.sigma)},
                    {"sigma_parameters", p.sigma_parameters},
                    {"sigma_noise", p.sigma_noise},
                    {"sigma_misfit", p.sigma_misfit},
                    {"z", NumberOrNull(p.z)}});
  }
  doc["positions"] = list;
  doc["parameters"] = ParametersJson(v.parameters);
  doc["untested"] = v.untested;
  if (gv) {
    nlohmann::ordered_json turns = nlohmann::ordered_json::array();
    for (const VerifiedTurn& t : gv->turns) {
      turns.push_back({{"from", t.from + 1},
                       {"to", t.to + 1},
                       {"duration_s", t.duration_s},
                       {"error_deg", t.error_deg},
                       {"predicted_deg", t.predicted_deg},
                       {"z", t.z}});
    }
    doc["gyroscope"] = {
        {"verdict", gv->passed ? "passed" : "failed"},
        {"reason", gv->reason},
        {"chi2", gv->chi2},
        {"dof", gv->dof},
        {"turns_chi2", gv->turns_chi2},
        {"turns_dof", gv->turns_dof},
        {"stills_chi2", gv->stills_chi2},
        {"stills_dof", gv->stills_dof},
        {"p_value", gv->p_value},
        {"rms_error_deg", gv->rms_error_deg},
        {"rms_predicted_deg", gv->rms_predicted_deg},
        {"session_bias_raw",
         {gv->session_bias_raw(0), gv->session_bias_raw(1), gv->session_bias_raw(2)}},
        {"bias_change_raw",
         {gv->bias_change_raw(0), gv->bias_change_raw(1), gv->bias_change_raw(2)}},
        {"turns", turns},
        {"parameters", ParametersJson(gv->parameters)},
        {"untested", gv->untested}};
  } else {
    doc["gyroscope"] =
        cal.has_gyroscope() ? "not verified: give its log (--gyro)" : "none in the calibration";
  }
  doc["verdict"] = f.verdict;
  return JsonText(doc);
}

std::string VerifyText(const VerifyArgs& args, const LoadedCalibration& cal, const Findings& f) {
  const Verification& v = f.v;
  const std::optional<GyroVerification>& gv = f.gv;
  const std::string unit(ToString(cal.unit));
  std::string out;
  out += "# accelcal verify " + VisibleLine(args.calibration) + " on " +
         VisibleLine(args.input.path) + ": " + std::to_string(v.positions.size()) +
         " still positions\n";
  out += Format(
      "# |f| - g [%s] against the error the calibration predicts: its parameters' "
      "covariance, each position's noise, its own misfit (%.3g raw); g = %.9g %s (%s)\n",
      unit.c_str(), f.under_test.misfit_sigma_raw, f.under_test.gravity, unit.c_str(),
      f.gravity_origin.c_str());
  if (f.under_test.thermal) {
    out += Format(
        "# each position judged at its own temperature (degrees %s about T_ref %.6g degC, held "
        "to %.6g .. %.6g degC)\n",
        f.under_test.thermal->degrees.ToString().c_str(), f.under_test.thermal->t_ref_c,
        f.under_test.thermal_range_c.first, f.under_test.thermal_range_c.second);
  }
  out += "position  t_begin_s  t_end_s  samples  error  sigma  z\n";
  for (std::size_t k = 0; k < v.positions.size(); ++k) {
    const VerifiedPosition& p = v.positions[k];
    out += Format("%zu  %.3f  %.3f  %zu  %.4g  %.3g  %+.2f\n", k + 1, p.t_begin_s, p.t_end_s,
                  p.samples, p.error, p.sigma, p.z);
  }
  out += Format(
      "# chi2 = %.4g for %d positions (p = %.3g); RMS of |f| - g %.3g %s, predicted %.3g %s\n",
      v.chi2, v.dof, v.p_value, v.rms_error, unit.c_str(), v.rms_predicted, unit.c_str());
  if (!f.untested.empty()) {
    out +=
        "# not tested by this log (an error of 10 of the calibration's sigma would go "
        "unseen): " +
        f.untested + "\n";
  }
  if (gv) {
    out += Format("# gyroscope: the session's bias %s raw (%s from the calibration's)\n",
                  VecText(gv->session_bias_raw).c_str(), VecText(gv->bias_change_raw).c_str());
    out += "turn  duration_s  error_deg  predicted_deg  z\n";
    for (const VerifiedTurn& t : gv->turns) {
      out += Format("%zu-%zu  %.3f  %.4f  %.4f  %.2f\n", t.from + 1, t.to + 1, t.duration_s,
                    t.error_deg, t.predicted_deg, t.z);
    }
    out += Format(
        "# gyroscope: chi2 = %.4g for %d (the %zu turns' %.4g for %d, the still rates' %.4g "
        "for %d; p = %.3g); turns' RMS error %.3g deg, predicted %.3g deg\n",
        gv->chi2, gv->dof, gv->turns.size(), gv->turns_chi2, gv->turns_dof, gv->stills_chi2,
        gv->stills_dof, gv->p_value, gv->rms_error_deg, gv->rms_predicted_deg);
  } else if (cal.has_gyroscope()) {
    out += "# the gyroscope: not verified (give its log: --gyro)\n";
  }
  out += f.passed ? std::string("# verdict: passed\n")
                  : std::string("# verdict: ") + f.verdict + ": " + f.why + "\n";
  return out;
}

}  // namespace

int RunVerify(const VerifyArgs& args) {
  CheckOutputs({{"-o", args.output}}, {args.calibration, args.input.path, args.gyro.log});
  if (auto why = args.input.detection.Validate()) throw UsageError(*why);
  const bool gyro = args.gyro.given();
  if (gyro) CheckGyroColumns(args.input, args.gyro);
  const LoadedCalibration cal = ParseCalibrationJson(
      ReadFileToString(args.calibration, kMaxSmallFileBytes), args.calibration);
  RefuseFailed(cal, args.calibration);
  {  // parameters over temperature are followed (each position at its own); a drift is not
    LoadedCalibration said = cal;
    said.thermal.reset();
    said.gyroscope.reset();
    WarnVaryingNotUsed(said, args.calibration, "verified");
  }
  CheckPredictable(cal, args.calibration, gyro);
  Findings f;
  f.under_test = UnderTest(cal, args.calibration);
  if (args.gravity.gravity_ms2 || args.gravity.latitude_deg) {
    GravityArgs site = args.gravity;
    site.units = std::string(ToString(cal.unit));
    const Gravity g = ResolveGravity(site);
    f.under_test.gravity = g.in_unit;
    f.gravity_origin = g.origin;
  }
  ReadOptions read = MakeReadOptions(args.input);
  read.kind = InputKind::kRaw;
  const InputData data = ReadInput(args.input.path, read);
  if (!args.temperature_c) RefuseLeftOutTemperature(cal, data.raw, args.input.path);
  const StaticDetectionResult detection = DetectStaticIntervals(data.raw, args.input.detection);
  if (detection.intervals.empty()) throw NoStaticInterval(detection);
  std::vector<Position> positions = PositionsFromIntervals(detection.intervals);
  if (args.temperature_c) JudgeAtTemperature(args, cal, &positions);
  f.v = VerifyCalibration(f.under_test, data.raw, positions);
  if (f.under_test.thermal) WarnOutsideRange(args, f.under_test, f.v);
  if (gyro) f.gv = VerifyRates(args, cal, f.under_test, data, positions);
  Conclude(&f);
  const std::string out = args.json ? VerifyJson(args, cal, f) : VerifyText(args, cal, f);
  WriteFileAtomically(args.output.empty() ? "-" : args.output, out);
  if (f.checks_hold && !f.passed) {
    Warn("%s: inconclusive on %s: %s\n", args.calibration.c_str(), args.input.path.c_str(),
         f.why.c_str());
    return kExitFailedChecks;
  }
  if (!f.untested.empty()) {
    Warn("%s: this log does not test %s (its positions and turns do not excite them enough)\n",
         args.input.path.c_str(), f.untested.c_str());
  }
  if (!f.passed) {
    Warn("%s does not hold on %s: %s\n", args.calibration.c_str(), args.input.path.c_str(),
         f.why.c_str());
    return kExitFailedChecks;
  }
  return kExitOk;
}

CommandRun SetUpVerify(CLI::App* cmd) {
  auto a = std::make_shared<VerifyArgs>();
  cmd->add_option("CAL", a->calibration, "calibration file (JSON)")->required();
  cmd->add_option("LOG", a->input.path, "a new raw log: still positions with turns between")
      ->required();
  AddInputOptions(cmd, &a->input, false);
  AddDetectionOptions(cmd, &a->input);
  auto* gravity = cmd->add_option("--gravity", a->gravity.gravity_ms2,
                                  "this site's gravity [m/s2] (default: the calibration's)");
  auto* latitude = cmd->add_option("--latitude", a->gravity.latitude_deg,
                                   "this site's latitude [deg]: gravity from WGS-84");
  gravity->excludes(latitude);
  cmd->add_option("--height", a->gravity.height_m, "height above the ellipsoid [m]")
      ->needs(latitude);
  cmd->add_option("--temperature", a->temperature_c,
                  "the log's temperature [degC], for a calibration whose parameters follow "
                  "temperature and a log without its own (as calibrate's --temperatures)")
      ->check(kDecimal);
  AddSensorInput(cmd, kGyroscopeFlags, &a->gyro, " on the same clock: its turns verified too",
                 "in LOG or the {log} log");
  cmd->add_flag("--json", a->json, "machine-readable output");
  cmd->add_option("-o,--output", a->output, "output file (default: stdout)")->check(kFileName);
  return [a](const CLI::App& parsed) {
    CheckSensorInput(parsed, kGyroscopeFlags, a->gyro, {});
    DataSubject() = a->input.path;
    return RunVerify(*a);
  };
}

}  // namespace accelcal::cli
