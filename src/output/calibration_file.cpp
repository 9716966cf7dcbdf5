#include "accelcal/calibration_file.hpp"

#include <cmath>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "accelcal/engineering.hpp"
#include "accelcal/error.hpp"
#include "accelcal/frame.hpp"
#include "accelcal/json_text.hpp"
#include "accelcal/version.hpp"
#include "output/calibration_file_sections.hpp"

namespace accelcal {

namespace {

using nlohmann::ordered_json;

ordered_json ToJson(const Vec3& v) { return ordered_json::array({v(0), v(1), v(2)}); }

ordered_json ToJson(const Mat33& m) {
  ordered_json rows = ordered_json::array();
  for (int i = 0; i < 3; ++i) rows.push_back(ordered_json::array({m(i, 0), m(i, 1), m(i, 2)}));
  return rows;
}

ordered_json ToJson(const Eigen::MatrixXd& m) {
  ordered_json rows = ordered_json::array();
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    ordered_json row = ordered_json::array();
    for (Eigen::Index j = 0; j < m.cols(); ++j) row.push_back(m(i, j));
    rows.push_back(row);
  }
  return rows;
}

ordered_json Nullable(const std::optional<double>& v) {
  return v && std::isfinite(*v) ? ordered_json(*v) : ordered_json(nullptr);
}

std::string Equation(Frame frame) {
  const std::string common =
      "p = K f + b + k2 * f^2 (element-wise square); p raw, f specific force in the body frame ";
  switch (frame) {
    case Frame::kXFirst:
      return common + "(x = sensor x, y in the sensor x-y plane), K lower-triangular";
    case Frame::kZFirst:
      return common + "(z = sensor z, y in the sensor y-z plane), K upper-triangular";
    case Frame::kPlatform:
      break;
  }
  return common + "(the platform frame of the known orientations), K full";
}

// `bias_drift`: the basis, D and the joint covariance of the model's parameters and D.
ordered_json DriftSection(const BiasDrift& drift) {
  ordered_json doc;
  doc["model"] = ToString(drift.basis.model);
  doc["t_ref"] = drift.basis.t_ref_s;
  if (drift.basis.model.kind == BiasModelKind::kLinear) {
    doc["basis"] = "b(t) = b + D (t - t_ref) / 60 s: D in raw per minute";
  } else {
    doc["basis"] =
        "b(t) = b + D (B(t) - B(t_ref)), B the hat functions of the knots but the first: D in "
        "raw, the bias at each knot less the bias at the first";
    doc["knots"] = drift.basis.knots_s;
  }
  ordered_json D = ordered_json::array(), sd = ordered_json::array();
  const Eigen::Index J = drift.D.cols();
  const Eigen::Index P = drift.covariance.rows() - 3 * J;
  for (int i = 0; i < 3; ++i) {
    ordered_json row = ordered_json::array(), row_sd = ordered_json::array();
    for (Eigen::Index j = 0; j < J; ++j) {
      row.push_back(drift.D(i, j));
      if (drift.covariance.size() > 0) {
        const Eigen::Index index = P + i * J + j;
        row_sd.push_back(std::sqrt(std::max(0.0, drift.covariance(index, index))));
      }
    }
    D.push_back(row);
    sd.push_back(row_sd);
  }
  doc["D"] = D;
  if (drift.random_walk) {
    doc["random_walk"] = ToJson(*drift.random_walk);
    doc["random_walk_note"] =
        "the prior of the knots' increments: N(0, q^2 dt) per axis, q in raw per sqrt(s)";
  }
  if (drift.covariance.size() > 0) {
    doc["D_std"] = sd;
    doc["covariance"] = ToJson(drift.covariance);
  } else {
    doc["D_std"] = nullptr;
    doc["covariance"] = nullptr;
  }
  return doc;
}

// `thermal` (thermal.hpp): T_ref, the degrees, the flat vector's slots and coefficients (x-first),
// their σ and covariance, and the temperatures the fit spans.
ordered_json ThermalSection(const ThermalTerms& t, ModelKind model) {
  ordered_json doc;
  doc["basis"] =
      "theta(T) = sum over d of theta_d (T - t_ref)^d, each group to its degree: theta_d in the "
      "parameters' units per K^d, frame x-first";
  doc["frame"] = ToString(Frame::kXFirst);
  doc["t_ref"] = t.params.t_ref_c;
  doc["degrees"] = {
      {"K", t.params.degrees.K}, {"bias", t.params.degrees.bias}, {"k2", t.params.degrees.k2}};
  const auto [lo, hi] = std::minmax_element(t.temperatures_c.begin(), t.temperatures_c.end());
  if (lo != t.temperatures_c.end()) doc["temperature_range"] = {*lo, *hi};
  const std::vector<ThermalSlot> slots = ThermalSlots(model, t.params.degrees);
  const Eigen::VectorXd x = Pack(t.params, model);
  ordered_json names = ordered_json::array(), values = ordered_json::array(),
               sd = ordered_json::array();
  const bool have_std = t.covariance.rows() == x.size();
  for (std::size_t i = 0; i < slots.size(); ++i) {
    const auto idx = static_cast<Eigen::Index>(i);
    names.push_back(ThermalSlotName(slots[i]));
    values.push_back(x(idx));
    if (have_std) sd.push_back(std::sqrt(std::max(0.0, t.covariance(idx, idx))));
  }
  doc["order"] = names;
  doc["coefficients"] = values;
  doc["std"] = have_std ? sd : ordered_json(nullptr);
  doc["covariance"] = have_std ? ToJson(t.covariance) : ordered_json(nullptr);
  return doc;
}

// The accelerometer's section: every key of a version-1 file but `format` and `version`.
// The positions fitted, each with its reading, interval, direction, residual and errors.
ordered_json PositionsSection(const CalibrationResult& result, const CalibrationFileInfo& info,
                              const std::vector<double>& errors) {
  const std::vector<Vec3> offsets = result.DriftOffsets(info.positions.size());
  ordered_json positions = ordered_json::array();
  for (std::size_t k = 0; k < info.positions.size(); ++k) {
    const Position& p = info.positions[k];
    ordered_json entry;
    entry["mean"] = ToJson(p.mean);
    entry["samples"] = p.samples;
    if (p.std) entry["std"] = ToJson(*p.std);
    if (k < info.mean_sigmas.size()) entry["mean_sigma"] = ToJson(info.mean_sigmas[k]);
    if (p.interval) {
      entry["interval"] = {{"begin", p.interval->begin},
                           {"end", p.interval->end},
                           {"t_begin", p.interval->t_begin_s},
                           {"t_end", p.interval->t_end_s}};
    }
    if (p.temperature_c) entry["temperature"] = *p.temperature_c;
    if (result.drift) {
      entry["time"] = result.drift->times_s[k];
      entry["drift_offset"] = ToJson(offsets[k]);
    }
    entry["direction"] = ToJson(result.directions[k]);
    entry["residual"] = ToJson(result.residuals[k]);
    entry["gravity_norm_error"] = Nullable(errors[k]);
    if (result.crossval_rms) entry["crossval_error"] = result.crossval_errors[k];
    if (result.excluded(k)) entry["excluded"] = true;
    if (k < info.position_source.size()) entry["file"] = info.position_source[k];
    positions.push_back(entry);
  }
  return positions;
}

// How the linear and quadratic models were compared (model "auto", or "quadratic" with the
// linear fit as comparison).
ordered_json ModelSelectionSection(const CalibrationFileInfo& info) {
  const ModelSelection* s = info.model_selection;
  ordered_json selection;
  selection["requested"] = info.model_requested;
  selection["chosen"] = std::string(ToString(s->chosen));
  selection["reason"] = s->reason;
  selection["linear_crossval_rms"] = Nullable(s->linear.crossval_rms);
  selection["quadratic_crossval_rms"] =
      s->quadratic ? Nullable(s->quadratic->crossval_rms) : ordered_json(nullptr);
  selection["k2_t"] =
      s->quadratic && std::isfinite(s->k2_t.sum()) ? ToJson(s->k2_t) : ordered_json(nullptr);
  selection["k2_t_threshold"] = Nullable(s->k2_t_threshold);
  selection["improvement"] = Nullable(s->improvement);
  selection["improvement_se"] = Nullable(s->improvement_se);
  selection["improvement_threshold"] = Nullable(s->improvement_threshold);
  selection["screened_with"] = std::string(ToString(s->screened_with));
  selection["positions_compared"] = s->positions_used.size();
  if (!s->quadratic_error.empty()) selection["quadratic_error"] = s->quadratic_error;
  return selection;
}

// How the bias model was chosen (bias model "auto"): each step of the forward selection.
ordered_json BiasModelSelectionSection(const BiasModelSelection& s) {
  ordered_json steps = ordered_json::array();
  for (const BiasModelStep& step : s.steps) {
    ordered_json entry;
    entry["simpler"] = ToString(step.simpler);
    entry["richer"] = ToString(step.richer);
    if (!step.error.empty()) {
      entry["error"] = step.error;
    } else {
      entry["positions_compared"] = step.positions_used.size();
      entry["simpler_crossval_rms"] = Nullable(step.simpler_rms);
      entry["richer_crossval_rms"] = Nullable(step.richer_rms);
      entry["improvement"] = Nullable(step.improvement);
      entry["improvement_se"] = Nullable(step.improvement_se);
      entry["improvement_threshold"] = Nullable(step.improvement_threshold);
      entry["wald"] = Nullable(step.wald);
      entry["wald_degrees_of_freedom"] = step.wald_dof;
      entry["wald_threshold"] = Nullable(step.wald_threshold);
    }
    entry["accepted"] = step.accepted;
    steps.push_back(entry);
  }
  return {{"requested", "auto"},
          {"chosen", ToString(s.chosen)},
          {"reason", s.reason},
          {"steps", steps}};
}

// The diagnosis's findings, each with its code, severity, message and numbers.
ordered_json FindingsSection(const Diagnosis& diagnosis) {
  ordered_json findings = ordered_json::array();
  for (const Finding& f : diagnosis.findings) {
    ordered_json numbers = ordered_json::object();
    for (const auto& [name, value] : f.numbers) numbers[name] = Nullable(value);
    findings.push_back({{"code", f.code},
                        {"severity", std::string(ToString(f.severity))},
                        {"message", f.message},
                        {"numbers", numbers}});
  }
  return findings;
}

ordered_json AccelerometerSection(const CalibrationResult& result, const CalibrationFileInfo& info,
                                  const Diagnosis& diagnosis) {
  const std::vector<Vec3> means = Means(info.positions);
  ordered_json doc;
  doc["verdict"] = std::string(ToString(diagnosis.verdict()));
  doc["model"] = std::string(ToString(result.model));
  doc["gravity"] = result.gravity;
  doc["units"] = {{"raw", info.raw_unit}, {"specific_force", std::string(ToString(info.unit))}};
  doc["frame"] = std::string(ToString(result.frame));
  doc["equation"] = Equation(result.frame);
  doc["K"] = ToJson(result.params.K);
  doc["bias"] = ToJson(result.params.bias);
  doc["k2"] = ToJson(result.params.k2);

  const auto& slots = ParameterSlots(result.model, result.frame);
  ordered_json order = ordered_json::array();
  for (const auto& s : slots) order.push_back(std::string(s.name));
  doc["parameter_order"] = order;
  if (result.covariance.size() > 0) {
    const ordered_json cov = ToJson(result.covariance);
    const ModelParameters std_params =
        Unpack(result.covariance.diagonal().cwiseMax(0.0).cwiseSqrt(), slots);
    doc["std"] = {{"K", ToJson(std_params.K)},
                  {"bias", ToJson(std_params.bias)},
                  {"k2", ToJson(std_params.k2)}};
    doc["covariance"] = cov;
  } else {
    doc["std"] = nullptr;
    doc["covariance"] = nullptr;
  }
  // σ̂ where it was estimated: with degrees of freedom, by a method that gives a covariance (the
  // baselines estimate none; a 0 there would claim a noise-free sensor).
  const bool estimated = result.degrees_of_freedom > 0 && result.covariance.size() > 0;
  doc["noise"] = {
      {"source", result.noise_source},
      {"sigma_raw", estimated ? ordered_json(result.residual_sigma) : ordered_json(nullptr)},
      {"degrees_of_freedom", result.degrees_of_freedom}};
  if (result.noise_source == "samples") {
    doc["noise"]["scatter_ratio"] = Nullable(result.scatter_ratio);
    doc["noise"]["inflated"] = result.scatter_ratio > 1.0;
  }

  const EngineeringParameters eng = ToEngineering(result.params, result.gravity);
  const Misalignment tau = MisalignmentOf(result.params.K, result.frame);
  ordered_json tau_rad, tau_arcsec;
  for (std::size_t i = 0; i < tau.names.size(); ++i) {
    const auto index = static_cast<Eigen::Index>(i);
    tau_rad[std::string(tau.names[i])] = tau.rad(index);
    tau_arcsec[std::string(tau.names[i])] = tau.rad(index) * kArcsecPerRad;
  }
  doc["engineering"] = {{"scale_factor", ToJson(eng.scale_factor)},
                        {"misalignment_rad", tau_rad},
                        {"misalignment_arcsec", tau_arcsec},
                        {"bias_specific_force", ToJson(eng.bias_force)},
                        {"k2_g_per_g2", ToJson(eng.k2_g_per_g2)}};

  if (result.drift) doc["bias_drift"] = DriftSection(*result.drift);
  if (result.thermal) doc["thermal"] = ThermalSection(*result.thermal, result.model);
  const std::vector<double> errors = GravityNormErrors(result, means);
  doc["positions"] = PositionsSection(result, info, errors);
  doc["gravity_norm_rms_before"] = Nullable(GravityNormRmsUncalibrated(means, result.gravity));
  doc["gravity_norm_rms_after"] = Nullable(Rms(result.InFit(errors)));  // outliers excluded
  doc["crossval_rms"] = Nullable(result.crossval_rms);
  if (!result.crossval_note.empty()) doc["crossval_note"] = result.crossval_note;
  ordered_json outliers = ordered_json::array();
  for (const OutlierFinding& o : result.outliers) {
    outliers.push_back({{"position", o.position + 1},
                        {"excluded", o.excluded},
                        {"statistic", std::string(ToString(o.statistic))},
                        {"t", o.t},
                        {"threshold", o.threshold},
                        {"degrees_of_freedom", o.degrees_of_freedom},
                        {"normal_residual", o.normal_residual},
                        {"scatter", o.scatter}});
  }
  doc["outliers"] = outliers;
  if (!result.outlier_note.empty()) doc["outlier_note"] = result.outlier_note;
  if (info.model_selection) doc["model_selection"] = ModelSelectionSection(info);
  if (info.bias_model_selection) {
    doc["bias_model_selection"] = BiasModelSelectionSection(*info.bias_model_selection);
  }
  const Summary& s = result.summary;
  doc["solver"] = {{"method", std::string(ToString(s.method))},
                   {"estimator", std::string(ToString(s.estimator))},
                   {"initialization", std::string(ToString(s.initialization))},
                   {"initialization_note", s.initialization_note},
                   {"iterations", s.iterations},
                   {"correction_rounds", s.correction_rounds},
                   {"converged", s.converged()},
                   {"termination", std::string(ToString(s.termination))},
                   {"termination_message", s.termination_message},
                   {"initial_cost", s.initial_cost},
                   {"cost", s.final_cost}};
  doc["diagnostics"] = FindingsSection(diagnosis);
  doc["source"] = info.source;
  if (!info.sources.empty()) doc["sources"] = info.sources;
  return doc;
}

ordered_json ProvenanceSection(const Provenance& provenance) {
  ordered_json doc;
  doc["accelcal_version"] = std::string(Version());
  if (!provenance.command.empty()) doc["command"] = provenance.command;
  doc["options"] = provenance.options.is_object() ? provenance.options : ordered_json::object();
  ordered_json inputs = ordered_json::array();
  for (const InputRecord& input : provenance.inputs) {
    ordered_json entry = {{"name", input.name}, {"bytes", input.bytes}};
    if (!input.sha256.empty()) entry["sha256"] = input.sha256;
    if (const std::optional<SourceStream>& s = input.stream) {
      ordered_json parameters = ordered_json::object();
      for (const auto& [name, value] : s->calibration_in_force) parameters[name] = value;
      entry["stream"] = {{"format", s->format},
                         {"topic", s->topic},
                         {"type", s->type},
                         {"instance", s->instance},
                         {"device_id", s->device_id ? ordered_json(*s->device_id) : ordered_json()},
                         {"unit", s->unit},
                         {"corrected", s->corrected},
                         {"calibration_in_force", parameters}};
    }
    inputs.push_back(entry);
  }
  doc["inputs"] = inputs;
  if (!provenance.date.empty()) doc["date"] = provenance.date;
  return doc;
}

}  // namespace

std::string CalibrationToJson(const CalibrationResult& result, const CalibrationFileInfo& info) {
  if (!info.provenance.date.empty()) {
    if (const auto why = CheckProvenanceDate(info.provenance.date)) {
      throw std::invalid_argument("provenance date: " + *why);
    }
  }
  const Diagnosis computed = info.diagnosis ? Diagnosis{}
                                            : Diagnose({&result,
                                                        &info.positions,
                                                        OutlierOptions{}.max_excluded,
                                                        info.model_selection,
                                                        {},
                                                        info.unit});
  const Diagnosis& diagnosis = info.diagnosis ? *info.diagnosis : computed;
  ordered_json doc;
  doc["format"] = "accelcal-calibration";
  doc["version"] = kCalibrationFileVersion;
  // The unit's verdict: the worst of its sensors' (one sensor today).
  doc["verdict"] = std::string(ToString(diagnosis.verdict()));
  doc["sensors"] = {{"accelerometer", AccelerometerSection(result, info, diagnosis)}};
  if (info.gyroscope != nullptr)
    doc["sensors"]["gyroscope"] = internal::GyroscopeSection(*info.gyroscope, info.unit);
  doc["provenance"] = ProvenanceSection(info.provenance);
  // Labels and paths are bytes from a command line: one that is no UTF-8 (a Latin-1 file name)
  // becomes U+FFFD (JsonText), which JSON can hold, rather than no file at all.
  return JsonText(doc);
}

namespace {

// `count` digits of `text` at `at` as a number in [low, high]; false when they are not.
bool Digits(const std::string& text, std::size_t at, std::size_t count, int low, int high,
            int* value) {
  if (at + count > text.size()) return false;
  int v = 0;
  for (std::size_t i = at; i < at + count; ++i) {
    if (text[i] < '0' || text[i] > '9') return false;
    v = 10 * v + (text[i] - '0');
  }
  *value = v;
  return v >= low && v <= high;
}

}  // namespace

std::vector<InputRecord> InputRecords(const LoadedInput& input) {
  std::vector<InputRecord> records;
  for (const LoadedFile& f : input.files) {
    records.push_back({f.path, f.data.bytes, f.data.sha256, f.data.stream});
  }
  return records;
}

std::optional<std::string> CheckProvenanceDate(const std::string& date) {
  const std::string expected =
      "'" + date + "' is not a date YYYY-MM-DD, optionally followed by THH:MM[:SS] and Z or +HH:MM";
  int year = 0, month = 0, day = 0, unused = 0;
  if (!Digits(date, 0, 4, 1, 9999, &year) || date.size() < 10 || date[4] != '-' ||
      !Digits(date, 5, 2, 1, 12, &month) || date[7] != '-' || !Digits(date, 8, 2, 1, 31, &day)) {
    return expected;
  }
  const bool leap = (year % 4 == 0 && year % 100 != 0) || year % 400 == 0;
  const int days[12] = {31, leap ? 29 : 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  if (day > days[month - 1]) return "'" + date + "': that month has no day " + std::to_string(day);
  std::size_t at = 10;
  if (at == date.size()) return std::nullopt;
  if (date[at] != 'T' || !Digits(date, at + 1, 2, 0, 23, &unused) || date.size() < at + 6 ||
      date[at + 3] != ':' || !Digits(date, at + 4, 2, 0, 59, &unused)) {
    return expected;
  }
  at += 6;
  if (at < date.size() && date[at] == ':') {
    if (!Digits(date, at + 1, 2, 0, 60, &unused)) return expected;  // 60: a leap second
    at += 3;
  }
  if (at == date.size()) return std::nullopt;
  if (date[at] == 'Z' && at + 1 == date.size()) return std::nullopt;
  const bool offset = (date[at] == '+' || date[at] == '-') && date.size() == at + 6 &&
                      Digits(date, at + 1, 2, 0, 23, &unused) && date[at + 3] == ':' &&
                      Digits(date, at + 4, 2, 0, 59, &unused);
  return offset ? std::nullopt : std::optional<std::string>(expected);
}

}  // namespace accelcal
