// accelcal design and montecarlo: the Cramer-Rao bound planned, and reached in simulation.
#include "commands.hpp"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "accelcal/design.hpp"
#include "accelcal/montecarlo.hpp"
#include "accelcal/simulate.hpp"
#include "cli_common.hpp"
#include "cli_options.hpp"
#include "output.hpp"

namespace accelcal::cli {
// --thermal-target looks for a schedule of at most this many temperatures.
constexpr int kMaxTargetTemperatures = 50;

namespace {

// What design planned, for its report.
struct DesignPlan {
  ModelKind model = ModelKind::kLinear;
  Vec3 sigma = Vec3::Zero();
  std::vector<Vec3> directions;
  DesignResult design;
  std::string chosen_note;
  // Why the plan determines nothing, for the report and for stderr.
  std::string unobservable;
  std::optional<PlannedDriftCost> drift;
  std::string drift_text;
  std::optional<ThermalDegrees> degrees;
  std::optional<PlannedThermal> thermal;
  std::string thermal_text, thermal_reason;
  std::vector<EngineeringValue> engineering;
  std::optional<std::vector<double>> target_schedule;
  std::string target_text;
};

void CheckNoiseFlags(const DesignArgs& args) {
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
}

// The noise of one averaged reading, in raw units: --noise, or --noise-density at --rate over
// --duration.
Vec3 ReadingNoise(const DesignArgs& args, const LoadedCalibration& device) {
  Vec3 sigma;
  if (args.noise_density_ug) {
    // One averaged reading: rate · duration samples.
    sigma = RawNoiseFromDensity(device.params, device.gravity, *args.noise_density_ug,
                                *args.rate_hz, *args.rate_hz * *args.duration_s);
  } else {
    sigma = args.noise_raw.size() == 1
                ? Vec3::Constant(args.noise_raw[0])
                : Vec3(args.noise_raw[0], args.noise_raw[1], args.noise_raw[2]);
  }
  if (!sigma.allFinite() || !(sigma.minCoeff() > 0)) {
    throw UsageError(
        "the noise must be positive (--noise, or --noise-density, --rate, --duration)");
  }
  return sigma;
}

// The positions: --positions, or the --choose best of them by --criterion.
void PlanPositions(const DesignArgs& args, const LoadedCalibration& device, DesignPlan* plan) {
  DesignOptions options;
  options.device = device.params;
  options.frame = device.frame;
  options.model = args.model ? ParseChoice<ModelKind>(*args.model, "--model") : device.model;
  options.gravity = device.gravity;
  options.sigma_raw = plan->sigma;
  options.choose = args.choose;
  options.criterion = ParseChoice<DesignCriterion>(args.criterion, "--criterion");
  if (auto why = options.Validate()) {
    throw UsageError(WithFlags(
        *why, {{"choose", "--choose"}, {"the model must be linear", "use --model linear"}}));
  }
  const std::vector<Vec3> candidates = PlannedDirections(args.positions);
  try {
    plan->design = Design(candidates, options);
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("--choose: ") + e.what());
  }
  plan->model = options.model;
  const DesignResult& design = plan->design;
  for (int k : design.chosen) plan->directions.push_back(candidates[static_cast<std::size_t>(k)]);
  if (args.choose > 0) {
    plan->chosen_note = Format(
        "%s-optimal %d of %zu candidates; against yang18: D-efficiency %.4f ((det I / det "
        "I_yang18)^(1/%d)), A-efficiency %.4f (tr CRLB_yang18 / tr CRLB, parameters in the "
        "device's relative metric); > 1: better",
        options.criterion == DesignCriterion::kD ? "D" : "A", args.choose, candidates.size(),
        design.d_efficiency, NumParameters(plan->model), design.a_efficiency);
    if (!design.summary.converged) plan->chosen_note += "; " + design.summary.termination_message;
  }
  plan->unobservable = Format(
      "these positions do not determine parameter %s (reciprocal condition %.2g); add positions "
      "with other orientations",
      design.planned.weakest.c_str(), design.planned.rcond);
}

// A drift to plan for: each parameter's 1σ with it over without it, and advice when the order
// lets the drift take up a parameter.
void PlanDrift(const DesignArgs& args, const LoadedCalibration& device, DesignPlan* plan) {
  if (args.bias_model == "constant") return;
  const std::optional<BiasModel> bias = BiasModelFromString(args.bias_model);
  if (!bias) {
    throw UsageError("--bias-model: '" + args.bias_model + "' is none of constant, linear, " +
                     "spline:K (K from 2 to " + std::to_string(kMaxBiasKnots) + ")");
  }
  const PlannedUncertainty& planned = plan->design.planned;
  if (!planned.observable) return;
  const auto& slots = ParameterSlots(plan->model, planned.frame);
  plan->drift = PredictDriftCost(device.params, plan->model, device.gravity, plan->directions,
                                 plan->sigma, *bias);
  const PlannedDriftCost& drift = *plan->drift;
  std::string& drift_text = plan->drift_text;
  if (!drift.observable) {
    drift_text = Format(
        "drift     a %s bias is NOT determined by these positions in this order: record the "
        "orientations again later in the session (each axis up and down early and late)\n",
        args.bias_model.c_str());
    return;
  }
  const double worst = drift.inflation(drift.worst);
  drift_text = Format(
      "drift     with a %s bias (positions in the order given, one a minute): each "
      "parameter's 1 sigma grows by the factor\n",
      args.bias_model.c_str());
  for (std::size_t i = 0; i < slots.size(); ++i) {
    drift_text += Format("  %-5s x%.3f\n", std::string(slots[i].name).c_str(),
                         drift.inflation(static_cast<Eigen::Index>(i)));
  }
  drift_text += worst > 1.5
                    ? Format(
                          "advice    the order lets the drift take up %s (x%.2f): visit every "
                          "orientation early and late, each up followed by its down (go through "
                          "the positions, then back through them in reverse, ending where you "
                          "began)\n",
                          std::string(slots[std::size_t(drift.worst)].name).c_str(), worst)
                    : Format(
                          "advice    the order keeps the drift apart from the parameters (largest "
                          "factor %.2f, %s)\n",
                          worst, std::string(slots[std::size_t(drift.worst)].name).c_str());
}

// The temperature coefficients --thermal-degrees plans at --temperatures, checked whatever the
// positions determine; std::nullopt without --temperatures.
std::optional<ThermalDegrees> PlannedDegrees(const DesignArgs& args, ModelKind model) {
  if (args.thermal_degrees_given && args.temperatures_c.empty()) {
    throw UsageError("--thermal-degrees plans a temperature schedule: give --temperatures too");
  }
  if (args.temperatures_c.empty()) return std::nullopt;
  ThermalDegrees degrees;
  degrees.K = args.thermal_degrees[0];
  degrees.bias = args.thermal_degrees[1];
  degrees.k2 = args.thermal_degrees.size() > 2 ? args.thermal_degrees[2] : 0;
  for (double t : args.temperatures_c) {
    if (!(std::isfinite(t) && t >= -273.15 && t < 1000)) {
      throw UsageError(Format("--temperatures: %g degC is outside -273.15 to 1000 degC", t));
    }
  }
  try {
    (void)ThermalSlots(model, degrees);
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("--thermal-degrees: ") + e.what());
  }
  if (degrees.Max() == 0) {
    throw UsageError("--thermal-degrees " + degrees.ToString() +
                     " has no temperature coefficient to plan");
  }
  if (args.bias_model != "constant") {
    throw UsageError(
        "--temperatures plans a bias constant in time: give it without "
        "--bias-model");
  }
  return degrees;
}

// A temperature schedule: each temperature coefficient's 1σ, in engineering units per K^d.
void PlanThermal(const DesignArgs& args, const LoadedCalibration& device, DesignPlan* plan) {
  plan->degrees = PlannedDegrees(args, plan->model);
  if (!plan->degrees) return;
  const ThermalDegrees& degrees = *plan->degrees;
  if (!plan->design.planned.observable) {
    plan->thermal_reason = "the positions do not determine the parameters at one temperature";
    plan->thermal_text = "thermal   not planned: " + plan->thermal_reason + "\n";
    return;
  }
  plan->thermal =
      PredictThermalUncertainty(device.params, plan->model, device.gravity, plan->directions,
                                args.temperatures_c, plan->sigma, degrees);
  const PlannedThermal& thermal = *plan->thermal;
  if (!thermal.observable) {
    plan->thermal_reason = Format(
        "these temperatures cannot separate degrees %s: record the orientations at %d "
        "temperatures or more, at least %g K apart",
        degrees.ToString().c_str(), degrees.Max() + 1, kMinThermalSeparation_K);
    plan->thermal_text = "thermal   NOT determined: " + plan->thermal_reason + "\n";
    return;
  }
  const double t_ref = std::abs(thermal.t_ref_c) < 1e-9 ? 0.0 : thermal.t_ref_c;
  plan->thermal_text = Format(
      "thermal   %zu positions at each of %zu temperature%s (T_ref %.4g degC), degrees %s: "
      "1 sigma of each coefficient (x-first frame; per K^d)\n",
      plan->directions.size(), args.temperatures_c.size(),
      args.temperatures_c.size() == 1 ? "" : "s", t_ref, degrees.ToString().c_str());
  const std::vector<ThermalSlot> tslots = ThermalSlots(plan->model, degrees);
  const Mat33 K = ChangeFrame(device.params.K, Frame::kXFirst).K;
  for (std::size_t i = 0; i < tslots.size(); ++i) {
    if (tslots[i].degree == 0) continue;
    const ParameterSlot& s = tslots[i].slot;
    const double sd = thermal.sigma(static_cast<Eigen::Index>(i));
    const EngineeringValue e = ThermalEngineering(tslots[i], sd, K, device.gravity);
    plan->engineering.push_back(e);
    plan->thermal_text += Format("  %-5s d%d  %.4g raw  (%.3g %s)\n", std::string(s.name).c_str(),
                                 tslots[i].degree, sd, e.value, e.unit.c_str());
  }
}

// --thermal-target: the fewest temperatures, evenly spaced over the schedule's span, whose
// coefficients per K reach the targets (K's in ppm/K or µrad/K, b's in mg/K).
void PlanThermalTarget(const DesignArgs& args, const LoadedCalibration& device, DesignPlan* plan) {
  if (args.thermal_target.empty()) return;
  if (!plan->degrees) {
    throw UsageError("--thermal-target plans a temperature schedule: give --temperatures too");
  }
  for (double x : args.thermal_target) {
    if (!(x > 0 && std::isfinite(x))) {
      throw UsageError(Format("--thermal-target: %g is not a positive 1 sigma", x));
    }
  }
  const auto [lo, hi] = std::minmax_element(args.temperatures_c.begin(), args.temperatures_c.end());
  if (*hi - *lo < kMinThermalSeparation_K) {
    throw UsageError(
        Format("--thermal-target spreads temperatures over the span of "
               "--temperatures: give two at least %g K apart",
               kMinThermalSeparation_K));
  }
  const double target_K = args.thermal_target[0];
  const std::optional<double> target_b =
      args.thermal_target.size() > 1 ? std::optional<double>(args.thermal_target[1]) : std::nullopt;
  const std::string wanted = Format("1 sigma per K <= %g ppm/K (urad/K) on K", target_K) +
                             (target_b ? Format(", <= %g mg/K on b", *target_b) : std::string());
  if (!plan->thermal || !plan->thermal->observable) return;
  const ThermalDegrees& degrees = *plan->degrees;
  std::optional<std::vector<double>>& target_schedule = plan->target_schedule;
  const std::vector<ThermalSlot> tslots = ThermalSlots(plan->model, degrees);
  const Mat33 K = ChangeFrame(device.params.K, Frame::kXFirst).K;
  for (int n = std::max(2, degrees.Max() + 1); n <= kMaxTargetTemperatures && !target_schedule;
       ++n) {
    std::vector<double> temps;
    for (int i = 0; i < n; ++i) temps.push_back(*lo + (*hi - *lo) * i / (n - 1));
    const PlannedThermal p = PredictThermalUncertainty(
        device.params, plan->model, device.gravity, plan->directions, temps, plan->sigma, degrees);
    bool reached = p.observable;
    for (std::size_t i = 0; i < tslots.size() && reached; ++i) {
      if (tslots[i].degree != 1) continue;
      const ParameterGroup g = tslots[i].slot.group;
      const std::optional<double> target = g == ParameterGroup::kK      ? target_K
                                           : g == ParameterGroup::kBias ? target_b
                                                                        : std::nullopt;
      const double sd = p.sigma(static_cast<Eigen::Index>(i));
      if (target && ThermalEngineering(tslots[i], sd, K, device.gravity).value > *target) {
        reached = false;
      }
    }
    if (reached) target_schedule = temps;
  }
  if (target_schedule) {
    std::string list;
    for (double t : *target_schedule) list += (list.empty() ? "" : ", ") + Format("%.4g", t);
    plan->target_text = Format(
        "target    %s: %zu temperatures evenly spaced from %.4g to %.4g degC (%s), each with "
        "these positions\n",
        wanted.c_str(), target_schedule->size(), *lo, *hi, list.c_str());
  } else {
    plan->target_text = Format(
        "target    %s: NOT reached with %d temperatures from %.4g to %.4g degC; widen the "
        "span, add positions or average each longer\n",
        wanted.c_str(), kMaxTargetTemperatures, *lo, *hi);
  }
}

std::string DesignJson(const DesignArgs& args, const DesignPlan& plan) {
  const PlannedUncertainty& planned = plan.design.planned;
  const ModelKind model = plan.model;
  const auto& slots = ParameterSlots(model, planned.frame);
  const std::vector<Vec3>& directions = plan.directions;
  const std::optional<PlannedDriftCost>& drift = plan.drift;
  const std::optional<PlannedThermal>& thermal = plan.thermal;
  const std::optional<ThermalDegrees>& degrees = plan.degrees;
  using Json = nlohmann::ordered_json;
  Json doc;
  doc["positions"] = directions.size();
  doc["model"] = ToString(model);
  doc["frame"] = ToString(planned.frame);
  doc["noise_raw"] = JsonArray(plan.sigma);
  if (args.choose > 0) {
    Json& chosen = doc["chosen"] = Json::array();
    for (const Vec3& c : directions) chosen.push_back(JsonArray(c));
    doc["choice"] = plan.chosen_note;
  }
  doc["observable"] = planned.observable;
  doc["reciprocal_condition"] = planned.rcond;
  doc["weakest"] = planned.weakest.empty() ? Json() : Json(planned.weakest);
  Json& order = doc["parameter_order"] = Json::array();
  for (const ParameterSlot& slot : slots) order.push_back(std::string(slot.name));
  if (planned.observable) {
    const Mat33& K = planned.std.K;
    doc["std"] = {{"K",
                   {JsonArray(K.row(0).transpose()), JsonArray(K.row(1).transpose()),
                    JsonArray(K.row(2).transpose())}},
                  {"bias", JsonArray(planned.std.bias)},
                  {"k2", JsonArray(planned.std.k2)}};
    Json& crlb = doc["crlb"] = Json::array();
    for (Eigen::Index i = 0; i < planned.crlb.rows(); ++i) {
      Json row = Json::array();
      for (Eigen::Index j = 0; j < planned.crlb.cols(); ++j) row.push_back(planned.crlb(i, j));
      crlb.push_back(std::move(row));
    }
  } else {
    doc["std"] = nullptr;
    doc["crlb"] = nullptr;
  }
  if (drift) {
    Json& d = doc["drift"];
    d["bias_model"] = ToString(drift->bias_model);
    d["observable"] = drift->observable;
    if (drift->observable) {
      d["inflation"] = Json::array();
      for (Eigen::Index i = 0; i < drift->inflation.size(); ++i) {
        d["inflation"].push_back(drift->inflation(i));
      }
      d["worst"] = std::string(slots[std::size_t(drift->worst)].name);
    }
  }
  if (degrees) {
    Json& t = doc["thermal"];
    t["temperatures"] = args.temperatures_c;
    if (!args.thermal_target.empty()) {
      Json& target = t["target"];
      target["K_ppm_per_K"] = args.thermal_target[0];
      if (args.thermal_target.size() > 1) target["b_mg_per_K"] = args.thermal_target[1];
      target["schedule"] = plan.target_schedule ? Json(*plan.target_schedule) : Json(nullptr);
    }
    t["frame"] = "x-first";
    t["degrees"] = {{"K", degrees->K}, {"bias", degrees->bias}, {"k2", degrees->k2}};
    t["observable"] = thermal && thermal->observable;
    if (!plan.thermal_reason.empty()) t["reason"] = plan.thermal_reason;
    if (thermal) t["t_ref"] = std::abs(thermal->t_ref_c) < 1e-9 ? 0.0 : thermal->t_ref_c;
    if (thermal && thermal->observable) {
      Json& coefficients = t["order"] = Json::array();
      for (const ThermalSlot& s : ThermalSlots(model, thermal->degrees)) {
        coefficients.push_back(ThermalSlotName(s));
      }
      t["std"] = Json::array();
      for (Eigen::Index i = 0; i < thermal->sigma.size(); ++i) {
        t["std"].push_back(thermal->sigma(i));
      }
      Json& e = t["std_engineering"] = Json::array();
      for (const EngineeringValue& x : plan.engineering)
        e.push_back({{"value", x.value}, {"unit", x.unit}});
    }
  }
  return JsonText(doc);
}

std::string DesignText(const DesignArgs& args, const DesignPlan& plan) {
  const PlannedUncertainty& planned = plan.design.planned;
  const ModelKind model = plan.model;
  const auto& slots = ParameterSlots(model, planned.frame);
  const std::vector<Vec3>& directions = plan.directions;
  std::string out;
  out += Format(
      "design    %zu positions (%s), %s model in the %s frame, noise %.4g %.4g %.4g "
      "raw per averaged reading\n",
      directions.size(), args.positions.c_str(), std::string(ToString(model)).c_str(),
      std::string(ToString(planned.frame)).c_str(), plan.sigma(0), plan.sigma(1), plan.sigma(2));
  if (args.choose > 0) {
    out += plan.chosen_note + "\n";
    for (const Vec3& c : directions) out += Format("  %+.6f %+.6f %+.6f\n", c(0), c(1), c(2));
  }
  if (!planned.observable) {
    out += "NOT OBSERVABLE: " + plan.unobservable + "\n";
  } else {
    out += "predicted 1 sigma (Cramer-Rao bound; raw units as the device file)\n";
    for (std::size_t i = 0; i < slots.size(); ++i) {
      const auto index = static_cast<Eigen::Index>(i);
      out += Format("  %-5s %.4g\n", std::string(slots[i].name).c_str(),
                    std::sqrt(planned.crlb(index, index)));
    }
    if (!planned.weakest.empty()) {
      out += Format("poorly determined: %s (reciprocal condition %.2g)\n", planned.weakest.c_str(),
                    planned.rcond);
    }
    out += plan.drift_text;
  }
  out += plan.thermal_text;
  out += plan.target_text;
  return out;
}

}  // namespace

int RunDesign(const DesignArgs& args) {
  CheckNoiseFlags(args);
  const LoadedCalibration device =
      ParseCalibrationJson(ReadFileToString(args.device, kMaxSmallFileBytes), args.device);
  DesignPlan plan;
  plan.sigma = ReadingNoise(args, device);
  PlanPositions(args, device, &plan);
  PlanDrift(args, device, &plan);
  PlanThermal(args, device, &plan);
  PlanThermalTarget(args, device, &plan);
  WriteFileAtomically("-", args.json ? DesignJson(args, plan) : DesignText(args, plan));
  // A plan that determines nothing is an error: said on stderr too, as every error is (the
  // output may go to a file, and a caller of the status reads stderr for its reason).
  if (!plan.design.planned.observable) {
    WriteErrLine("accelcal: " + plan.unobservable + "\n");
    return kExitBadInput;
  }
  if (plan.degrees && !(plan.thermal && plan.thermal->observable)) {
    WriteErrLine("accelcal: " + plan.thermal_reason + "\n");
    return kExitBadInput;
  }
  return kExitOk;
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
  options.calibration.method = ParseChoice<SolverMethod>(
      args.method, "--method",
      {SolverMethod::kJoint, SolverMethod::kTwoStep, SolverMethod::kNewtonLagrange});
  if (!IsMaximumLikelihood(options.calibration.method)) {
    throw UsageError(
        "--method: the Monte Carlo compares maximum-likelihood methods with the "
        "bound: joint, two-step or newton-lagrange");
  }
  options.calibration.estimator = ParseChoice<Estimator>(args.estimator, "--estimator");
  options.calibration.model = scenario->model;
  if (auto why = options.calibration.Validate()) throw OptionError(*why);
  ProgressBar bar("montecarlo " + args.scenario);
  options.progress = [&bar](int done, int total) { bar.Update(done, total); };
  const MonteCarloResult r = RunMonteCarlo(*scenario, options);
  bar.Finish();
  std::string out;
  if (args.json) {
    using Json = nlohmann::ordered_json;
    Json doc;
    doc["scenario"] = r.scenario;
    doc["method"] = ToString(r.method);
    doc["estimator"] = args.estimator;
    doc["runs"] = r.runs;
    doc["failed"] = r.failed;
    doc["coverage"] = r.coverage;
    doc["inclination_error_rms_arcsec"] = r.inclination_error_rms_arcsec;
    if (scenario->random_attitudes > 0) {
      doc["e_T_percent_mean"] = r.e_T_percent_mean;
      doc["e_b_percent_mean"] = r.e_b_percent_mean;
      doc["diag_T_bias"] = JsonArray(r.diag_T_bias);
      doc["diag_T_bias_standard_error"] = JsonArray(r.diag_T_bias_standard_error);
      doc["diag_T_bias_expected"] = JsonArray(r.diag_T_bias_expected);
    }
    Json& parameters = doc["parameters"] = Json::array();
    for (const ErrorStatistics& e : r.errors) {
      parameters.push_back({{"name", e.name},
                            {"unit", e.unit},
                            {"min", e.min},
                            {"max", e.max},
                            {"mean", e.mean},
                            {"median", e.median},
                            {"std", e.std},
                            {"rmse", e.rmse},
                            {"crlb", e.crlb},
                            {"ratio", e.ratio},
                            {"rmse_ratio", e.rmse_ratio}});
    }
    out = JsonText(doc);
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

CommandRun SetUpDesign(CLI::App* cmd) {
  auto a = std::make_shared<DesignArgs>();
  cmd->add_option("--positions", a->positions,
                  "yang18, six, random:N[:SEED], or a file of unit directions (x,y,z) or "
                  "attitudes (roll_deg,pitch_deg[,yaw_deg] or qw,qx,qy,qz; body to level, z up)")
      ->required();
  cmd->add_option("--device", a->device, "calibration file of the nominal device")->required();
  cmd->add_option("--noise", a->noise_raw,
                  "1 sigma of one averaged reading in raw units: one value or three (x,y,z)")
      ->delimiter(',')
      ->expected(1, 3);
  cmd->add_option("--temperatures", a->temperatures_c,
                  "plan a temperature schedule: the positions recorded at each of these "
                  "temperatures [degC], comma-separated")
      ->delimiter(',')
      ->check(kDecimal);
  cmd->add_option("--thermal-degrees", a->thermal_degrees,
                  "with --temperatures: the degrees in T - T_ref of K and b (and k2 for the "
                  "quadratic model), e.g. 1,1")
      ->delimiter(',')
      ->expected(2, 3)
      ->type_name("K,B[,K2]")
      ->capture_default_str();
  cmd->add_option("--thermal-target", a->thermal_target,
                  "with --temperatures: 1 sigma targets of the coefficients per K, of K in "
                  "ppm/K (urad/K off the diagonal) and of b in mg/K; says how many "
                  "temperatures over the same span reach them")
      ->delimiter(',')
      ->expected(1, 2)
      ->type_name("S[,B]");
  cmd->add_option("--noise-density", a->noise_density_ug,
                  "instead of --noise: white noise [ug/sqrt(Hz)], with --rate and --duration");
  cmd->add_option("--rate", a->rate_hz, "sample rate [Hz], with --noise-density");
  cmd->add_option("--duration", a->duration_s, "still time per position [s], with --noise-density");
  cmd->add_option("--model", a->model, "linear or quadratic (default: the device's)");
  cmd->add_option("--bias-model", a->bias_model,
                  "linear or spline:K: what fitting a drifting bias costs the positions, "
                  "recorded in the order given, one a minute")
      ->capture_default_str();
  cmd->add_option("--choose", a->choose,
                  "choose this many of the positions (the candidates) by --criterion; compared "
                  "with paper 000's yang18");
  cmd->add_option("--criterion", a->criterion,
                  "with --choose: d (maximise det of the information, D-optimal) or a (minimise "
                  "the trace of the CRLB, parameters in the device's relative metric, A-optimal)")
      ->capture_default_str();
  cmd->add_flag("--json", a->json, "machine-readable output");
  return [a](const CLI::App& parsed) {
    DataSubject() = a->positions;
    a->thermal_degrees_given = parsed.count("--thermal-degrees") > 0;
    return RunDesign(*a);
  };
}

CommandRun SetUpMonteCarlo(CLI::App* cmd) {
  auto a = std::make_shared<MonteCarloArgs>();
  cmd->add_option("--scenario", a->scenario,
                  "yang2012 (paper 000 Table 3/4) or sunxu2020 (paper 001 section 4.1)")
      ->capture_default_str();
  cmd->add_option("--runs", a->runs, "number of runs")->capture_default_str();
  cmd->add_option("--method", a->method, "joint, two-step or newton-lagrange")
      ->capture_default_str();
  cmd->add_option("--estimator", a->estimator, "ml or bias-corrected")->capture_default_str();
  cmd->add_option("--seed", a->seed, "seed of the first run's noise")->capture_default_str();
  cmd->add_option("--threads", a->threads, "threads (0: all cores)")->capture_default_str();
  cmd->add_flag("--residual-noise", a->residual_noise,
                "covariance from the residuals instead of the known noise");
  cmd->add_flag("--json", a->json, "machine-readable output");
  return [a](const CLI::App& /*parsed*/) { return RunMonteCarlo(*a); };
}

}  // namespace accelcal::cli
