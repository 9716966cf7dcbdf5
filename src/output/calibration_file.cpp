#include "accelcal/calibration_file.hpp"

#include <cmath>
#include <set>

#include <nlohmann/json.hpp>

#include "accelcal/engineering.hpp"
#include "accelcal/error.hpp"
#include "accelcal/frame.hpp"
#include "core/text_format.hpp"

namespace accelcal {

namespace {

using nlohmann::ordered_json;

ordered_json ToJson(const Vec3& v) { return ordered_json::array({v(0), v(1), v(2)}); }

ordered_json ToJson(const Mat33& m) {
  ordered_json rows = ordered_json::array();
  for (int i = 0; i < 3; ++i) rows.push_back(ordered_json::array({m(i, 0), m(i, 1), m(i, 2)}));
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

}  // namespace

std::string CalibrationToJson(const CalibrationResult& result, const CalibrationFileInfo& info) {
  const std::vector<Vec3> means = Means(info.positions);
  ordered_json doc;
  const Diagnosis computed = info.diagnosis ? Diagnosis{}
                                            : Diagnose({&result,
                                                        &info.positions,
                                                        OutlierOptions{}.max_excluded,
                                                        info.model_selection,
                                                        {},
                                                        info.unit});
  const Diagnosis& diagnosis = info.diagnosis ? *info.diagnosis : computed;
  doc["format"] = "accelcal-calibration";
  doc["version"] = 1;
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
    ordered_json cov = ordered_json::array();
    for (Eigen::Index i = 0; i < result.covariance.rows(); ++i) {
      ordered_json row = ordered_json::array();
      for (Eigen::Index j = 0; j < result.covariance.cols(); ++j)
        row.push_back(result.covariance(i, j));
      cov.push_back(row);
    }
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
  doc["noise"] = {{"source", result.noise_source},
                  {"sigma_raw", result.degrees_of_freedom > 0 ? ordered_json(result.residual_sigma)
                                                              : ordered_json(nullptr)},
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

  const std::vector<double> errors = GravityNormErrors(result.params, means, result.gravity);
  ordered_json positions = ordered_json::array();
  for (std::size_t k = 0; k < info.positions.size(); ++k) {
    const Position& p = info.positions[k];
    ordered_json entry;
    entry["mean"] = ToJson(p.mean);
    entry["samples"] = p.samples;
    if (p.std) entry["std"] = ToJson(*p.std);
    if (p.interval) {
      entry["interval"] = {{"begin", p.interval->begin},
                           {"end", p.interval->end},
                           {"t_begin", p.interval->t_begin_s},
                           {"t_end", p.interval->t_end_s}};
    }
    entry["direction"] = ToJson(result.directions[k]);
    entry["residual"] = ToJson(result.residuals[k]);
    entry["gravity_norm_error"] = Nullable(errors[k]);
    if (result.crossval_rms) entry["crossval_error"] = result.crossval_errors[k];
    if (result.excluded(k)) entry["excluded"] = true;
    if (k < info.position_source.size()) entry["file"] = info.position_source[k];
    positions.push_back(entry);
  }
  doc["positions"] = positions;
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
  if (const ModelSelection* s = info.model_selection) {
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
    doc["model_selection"] = selection;
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
  ordered_json findings = ordered_json::array();
  for (const Finding& f : diagnosis.findings) {
    ordered_json numbers = ordered_json::object();
    for (const auto& [name, value] : f.numbers) numbers[name] = Nullable(value);
    findings.push_back({{"code", f.code},
                        {"severity", std::string(ToString(f.severity))},
                        {"message", f.message},
                        {"numbers", numbers}});
  }
  doc["diagnostics"] = findings;
  doc["source"] = info.source;
  if (!info.sources.empty()) doc["sources"] = info.sources;
  // Labels and paths are bytes from a command line: one that is no UTF-8 (a Latin-1 file name)
  // becomes U+FFFD, which JSON can hold, rather than no file at all.
  return doc.dump(2, ' ', false, ordered_json::error_handler_t::replace) + "\n";
}

namespace {

double Number(const ordered_json& j, const std::string& what, const std::string& source) {
  if (!j.is_number()) throw InputError(source, 0, what + " must be a number");
  const double v = j.get<double>();
  if (!std::isfinite(v)) throw InputError(source, 0, what + " is not finite");
  return v;
}

Vec3 Vector3(const ordered_json& doc, const char* key, const std::string& source) {
  if (!doc.contains(key) || !doc[key].is_array() || doc[key].size() != 3) {
    throw InputError(source, 0, std::string("'") + key + "' must be an array of 3 numbers");
  }
  Vec3 v;
  for (int i = 0; i < 3; ++i)
    v(i) = Number(doc[key][i], std::string(key) + "[" + std::to_string(i) + "]", source);
  return v;
}

}  // namespace

namespace {

// Parses JSON refusing a key that appears twice in one object: the last one would silently win
// (a second identity "K" would turn `apply` into a no-op).
ordered_json ParseWithoutDuplicateKeys(const std::string& text, const std::string& source) {
  std::vector<std::set<std::string>> keys;  // of each object being read
  std::string duplicate;
  const auto check = [&](int, nlohmann::json::parse_event_t event, ordered_json& parsed) {
    using Event = nlohmann::json::parse_event_t;
    if (event == Event::object_start) keys.emplace_back();
    if (event == Event::object_end && !keys.empty()) keys.pop_back();
    if (event == Event::key && !keys.empty() &&
        !keys.back().insert(parsed.get<std::string>()).second && duplicate.empty()) {
      duplicate = parsed.get<std::string>();
    }
    return true;
  };
  ordered_json doc;
  // nlohmann's parser reads numbers with strtod, after putting the C locale's decimal point in
  // place of '.': right in any locale, but only while no other thread changes it in between.
  const internal::ClassicLocale c_locale;
  try {
    doc = ordered_json::parse(text, check);
  } catch (const nlohmann::json::exception& e) {  // syntax, or a number beyond double's range
    throw InputError(source, 0, std::string("not valid JSON: ") + e.what());
  }
  if (!duplicate.empty()) {
    throw InputError(source, 0, "the key '" + duplicate + "' appears twice in one object");
  }
  return doc;
}

}  // namespace

namespace {

// The checks of every key of a parsed calibration file (ParseCalibrationJson).
LoadedCalibration ParseCalibrationDocument(ordered_json doc, const std::string& source) {
  if (!doc.is_object() || !doc.contains("format") || doc["format"] != "accelcal-calibration") {
    throw InputError(
        source, 0, "not an accelcal calibration file (\"format\" is not \"accelcal-calibration\")");
  }
  if (!doc.contains("version") || !doc["version"].is_number_integer() || doc["version"] != 1) {
    throw InputError(source, 0, "unsupported calibration file version (expected 1)");
  }
  LoadedCalibration cal;
  const std::optional<ModelKind> model = doc.contains("model") && doc["model"].is_string()
                                             ? ModelKindFromString(doc["model"].get<std::string>())
                                             : std::nullopt;
  if (!model) throw InputError(source, 0, "'model' must be \"linear\" or \"quadratic\"");
  cal.model = *model;
  if (!doc.contains("gravity")) throw InputError(source, 0, "'gravity' is missing");
  cal.gravity = Number(doc["gravity"], "'gravity'", source);
  if (!(cal.gravity > 0)) throw InputError(source, 0, "'gravity' must be positive");
  const std::optional<ForceUnit> unit =
      doc.contains("units") && doc["units"].is_object() &&
              doc["units"].contains("specific_force") && doc["units"]["specific_force"].is_string()
          ? ForceUnitFromString(doc["units"]["specific_force"].get<std::string>())
          : std::nullopt;
  if (!unit) throw InputError(source, 0, "'units.specific_force' must be \"m/s2\" or \"g\"");
  cal.unit = *unit;
  if (!doc.contains("K") || !doc["K"].is_array() || doc["K"].size() != 3) {
    throw InputError(source, 0, "'K' must be a 3x3 array");
  }
  for (int i = 0; i < 3; ++i) {
    const auto& row = doc["K"][i];
    if (!row.is_array() || row.size() != 3) throw InputError(source, 0, "'K' must be a 3x3 array");
    for (int j = 0; j < 3; ++j) {
      cal.params.K(i, j) =
          Number(row[j], "K[" + std::to_string(i) + "][" + std::to_string(j) + "]", source);
    }
  }
  // "frame" was added after version 1 first shipped: absent means x-first.
  cal.frame = Frame::kXFirst;
  if (doc.contains("frame")) {
    const std::optional<Frame> frame =
        doc["frame"].is_string() ? FrameFromString(doc["frame"].get<std::string>()) : std::nullopt;
    if (!frame) {
      throw InputError(source, 0, "'frame' must be \"x-first\", \"z-first\" or \"platform\"");
    }
    cal.frame = *frame;
  }
  const Mat33& K = cal.params.K;
  if (cal.frame == Frame::kXFirst && (K(0, 1) != 0 || K(0, 2) != 0 || K(1, 2) != 0)) {
    throw InputError(source, 0, "'K' must be lower-triangular (frame x-first)");
  }
  if (cal.frame == Frame::kZFirst && (K(1, 0) != 0 || K(2, 0) != 0 || K(2, 1) != 0)) {
    throw InputError(source, 0, "'K' must be upper-triangular (frame z-first)");
  }
  if (cal.params.K(0, 0) == 0 || cal.params.K(1, 1) == 0 || cal.params.K(2, 2) == 0) {
    throw InputError(source, 0, "'K' has a zero diagonal entry");
  }
  cal.params.bias = Vector3(doc, "bias", source);
  cal.params.k2 = Vector3(doc, "k2", source);
  if (cal.model == ModelKind::kLinear && !cal.params.k2.isZero(0)) {
    throw InputError(source, 0, "a linear model must have k2 = [0, 0, 0]");
  }
  if (doc["units"].contains("raw")) {
    if (!doc["units"]["raw"].is_string()) throw InputError(source, 0, "'units.raw' must be text");
    cal.raw_unit = doc["units"]["raw"].get<std::string>();
  }
  if (doc.contains("verdict")) {
    if (!doc["verdict"].is_string() ||
        (doc["verdict"] != "ok" && doc["verdict"] != "warnings" && doc["verdict"] != "failed")) {
      throw InputError(source, 0, "'verdict' must be \"ok\", \"warnings\" or \"failed\"");
    }
    cal.verdict = doc["verdict"].get<std::string>();
  }
  if (doc.contains("source") && doc["source"].is_string()) {
    cal.source = doc["source"].get<std::string>();
  }
  if (doc.contains("covariance") && !doc["covariance"].is_null()) {
    const std::size_t P = ParameterSlots(cal.model, cal.frame).size();
    const ordered_json& cov = doc["covariance"];
    const std::string shape = "'covariance' must be null or a " + std::to_string(P) + "x" +
                              std::to_string(P) + " array (the " +
                              std::string(ToString(cal.model)) + " model in frame " +
                              std::string(ToString(cal.frame)) + ")";
    if (!cov.is_array() || cov.size() != P) throw InputError(source, 0, shape);
    cal.covariance.resize(static_cast<Eigen::Index>(P), static_cast<Eigen::Index>(P));
    for (std::size_t i = 0; i < P; ++i) {
      if (!cov[i].is_array() || cov[i].size() != P) throw InputError(source, 0, shape);
      for (std::size_t j = 0; j < P; ++j) {
        cal.covariance(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = Number(
            cov[i][j], "covariance[" + std::to_string(i) + "][" + std::to_string(j) + "]", source);
      }
    }
  }
  if (doc.contains("positions")) {
    if (!doc["positions"].is_array()) throw InputError(source, 0, "'positions' must be an array");
    for (std::size_t k = 0; k < doc["positions"].size(); ++k) {
      const ordered_json& position = doc["positions"][k];
      if (!position.is_object()) {
        throw InputError(source, 0, "'positions[" + std::to_string(k) + "]' must be an object");
      }
      cal.position_means.push_back(Vector3(position, "mean", source));
    }
  }
  return cal;
}

}  // namespace

LoadedCalibration ParseCalibrationJson(const std::string& text, const std::string& source) {
  ordered_json doc = ParseWithoutDuplicateKeys(text, source);
  // Every key's type is checked below; a JSON type error that escapes a check (a bug) still
  // names the file rather than ending as an internal error.
  try {
    return ParseCalibrationDocument(std::move(doc), source);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(source, 0, std::string("unexpected content: ") + e.what());
  }
}

}  // namespace accelcal
