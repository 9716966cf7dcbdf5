// Reading a calibration file (calibration_file.hpp), version 1 or 2: every key a reader uses is
// checked here once, so that apply, export, report, compare and Python get typed values and never
// read the JSON themselves.
#include <algorithm>
#include <cmath>
#include <set>

#include <Eigen/SVD>
#include <nlohmann/json.hpp>

#include "accelcal/calibration_file.hpp"
#include "accelcal/error.hpp"
#include "accelcal/frame.hpp"
#include "accelcal/log_reader.hpp"
#include "core/text_format.hpp"
#include "output/calibration_file_sections.hpp"
#include "output/json_reader.hpp"
#include "output/section_io.hpp"

namespace accelcal {

namespace {

using internal::ParseWithoutDuplicateKeys;
using internal::QuotedChoices;
using internal::ReadDiagnostics;
using internal::Reader;
using internal::ReadGyroscope;
using internal::ReadSquareCovariance;
using internal::ReadTemperatureRange;
using nlohmann::ordered_json;

int VerdictRank(const std::string& verdict) {
  return static_cast<int>(FromName<Verdict>(verdict).value_or(Verdict::kOk));
}

std::string CheckedVerdict(const Reader& r, const ordered_json& doc) {
  if (!doc["verdict"].is_string() || !FromName<Verdict>(doc["verdict"].get<std::string>())) {
    r.Fail(r.Key("verdict") + " must be " + QuotedChoices(NameList<Verdict>()));
  }
  return doc["verdict"].get<std::string>();
}

void ReadModel(const Reader& r, const ordered_json& doc, LoadedCalibration& cal) {
  const std::optional<ModelKind> model = doc.contains("model") && doc["model"].is_string()
                                             ? ModelKindFromString(doc["model"].get<std::string>())
                                             : std::nullopt;
  if (!model) r.Fail(r.Key("model") + " must be \"linear\" or \"quadratic\"");
  cal.model = *model;
  if (!doc.contains("gravity")) r.Fail(r.Key("gravity") + " is missing");
  cal.gravity = r.Number(doc["gravity"], r.Key("gravity"));
  if (!(cal.gravity > 0)) r.Fail(r.Key("gravity") + " must be positive");
  const std::optional<ForceUnit> unit =
      doc.contains("units") && doc["units"].is_object() &&
              doc["units"].contains("specific_force") && doc["units"]["specific_force"].is_string()
          ? ForceUnitFromString(doc["units"]["specific_force"].get<std::string>())
          : std::nullopt;
  if (!unit) r.Fail(r.Key("units.specific_force") + " must be \"m/s2\" or \"g\"");
  cal.unit = *unit;
  if (doc["units"].contains("raw")) cal.raw_unit = r.Inside("units").Text(doc["units"], "raw");
  if (!doc.contains("K") || !doc["K"].is_array() || doc["K"].size() != 3) {
    r.Fail(r.Key("K") + " must be a 3x3 array");
  }
  for (int i = 0; i < 3; ++i) {
    const auto& row = doc["K"][i];
    if (!row.is_array() || row.size() != 3) r.Fail(r.Key("K") + " must be a 3x3 array");
    for (int j = 0; j < 3; ++j) {
      cal.params.K(i, j) =
          r.Number(row[j], "K[" + std::to_string(i) + "][" + std::to_string(j) + "]");
    }
  }
  // "frame" was added after version 1 first shipped: absent means x-first.
  cal.frame = Frame::kXFirst;
  if (doc.contains("frame")) {
    const std::optional<Frame> frame =
        doc["frame"].is_string() ? FrameFromString(doc["frame"].get<std::string>()) : std::nullopt;
    if (!frame) r.Fail(r.Key("frame") + " must be \"x-first\", \"z-first\" or \"platform\"");
    cal.frame = *frame;
  }
  const Mat33& K = cal.params.K;
  if (cal.frame == Frame::kXFirst && (K(0, 1) != 0 || K(0, 2) != 0 || K(1, 2) != 0)) {
    r.Fail(r.Key("K") + " must be lower-triangular (frame x-first)");
  }
  if (cal.frame == Frame::kZFirst && (K(1, 0) != 0 || K(2, 0) != 0 || K(2, 1) != 0)) {
    r.Fail(r.Key("K") + " must be upper-triangular (frame z-first)");
  }
  if (K(0, 0) == 0 || K(1, 1) == 0 || K(2, 2) == 0)
    r.Fail(r.Key("K") + " has a zero diagonal entry");
  CheckInvertible(r, K, "K");

  cal.params.bias = r.Vector3(doc, "bias");
  cal.params.k2 = r.Vector3(doc, "k2");
  if (cal.model == ModelKind::kLinear && !cal.params.k2.isZero(0)) {
    r.Fail("a linear model must have " + r.Key("k2") + " = [0, 0, 0]");
  }
}

// A covariance is symmetric with a diagonal >= 0: symmetric to 1e-6 of √(c_ii c_jj), far above
// the round-off of the inverse it came from (which writes it a few ulps apart) and far below an
// edit that means something.
void CheckCovariance(const Reader& r, const Eigen::MatrixXd& c) {
  for (Eigen::Index i = 0; i < c.rows(); ++i) {
    if (!(c(i, i) >= 0)) {
      r.Fail(r.Key("covariance") + internal::Format("[%d][%d]", int(i), int(i)) +
             " is a variance and may not be negative");
    }
    for (Eigen::Index j = 0; j < i; ++j) {
      if (std::abs(c(i, j) - c(j, i)) > 1e-6 * std::sqrt(c(i, i) * c(j, j))) {
        r.Fail(r.Key("covariance") + " is not symmetric" +
               internal::Format(" ([%d][%d] against [%d][%d])", int(i), int(j), int(j), int(i)));
      }
    }
  }
}

}  // namespace

namespace internal {

Eigen::MatrixXd ReadSquareCovariance(const Reader& r, const ordered_json& doc, std::size_t n,
                                     const std::string& what) {
  const ordered_json& cov = doc["covariance"];
  const std::string shape = r.Key("covariance") + " must be null or a " + std::to_string(n) + "x" +
                            std::to_string(n) + " array (" + what + ")";
  if (!cov.is_array() || cov.size() != n) r.Fail(shape);
  Eigen::MatrixXd c(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i) {
    if (!cov[i].is_array() || cov[i].size() != n) r.Fail(shape);
    for (std::size_t j = 0; j < n; ++j) {
      c(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) =
          r.Number(cov[i][j], "covariance[" + std::to_string(i) + "][" + std::to_string(j) + "]");
    }
  }
  CheckCovariance(r, c);
  return c;
}

void SectionReader::Covariance(Eigen::MatrixXd& v, std::size_t n, const std::string& what) {
  v = IsNull("covariance") ? Eigen::MatrixXd() : ReadSquareCovariance(r_, doc_, n, what);
}

}  // namespace internal

namespace {

void ReadCovariance(const Reader& r, const ordered_json& doc, LoadedCalibration& cal) {
  if (!doc.contains("covariance") || doc["covariance"].is_null()) return;
  cal.covariance = ReadSquareCovariance(r, doc, ParameterSlots(cal.model, cal.frame).size(),
                                        "the " + std::string(ToString(cal.model)) +
                                            " model in frame " + std::string(ToString(cal.frame)));
}

FilePosition ReadPosition(const Reader& r, const ordered_json& p) {
  FilePosition position;
  position.mean = r.Vector3(p, "mean");
  if (p.contains("samples")) {
    if (!p["samples"].is_number_unsigned()) r.Fail(r.Key("samples") + " must be a count");
    position.samples = p["samples"].get<std::size_t>();
  }
  position.std = r.OptionalVector3(p, "std");
  position.mean_sigma = r.OptionalVector3(p, "mean_sigma");
  if (position.mean_sigma && !(position.mean_sigma->minCoeff() >= 0)) {
    r.Fail(r.Key("mean_sigma") + " must not be negative");
  }
  if (p.contains("interval")) {
    const ordered_json& i = r.Object(p, "interval");
    const Reader in = r.Inside("interval");
    FilePosition::Interval interval;
    for (const auto& [key, value] :
         {std::pair("begin", &interval.begin), std::pair("end", &interval.end),
          std::pair("t_begin", &interval.t_begin), std::pair("t_end", &interval.t_end)}) {
      if (!i.contains(key)) in.Fail(in.Key(key) + " is missing");
      *value = in.Number(i[key], in.Key(key));
    }
    position.interval = interval;
  }
  position.direction = r.OptionalVector3(p, "direction");
  position.residual = r.OptionalVector3(p, "residual");
  position.gravity_norm_error = r.Nullable(p, "gravity_norm_error");
  position.crossval_error = r.Nullable(p, "crossval_error");
  position.time = r.Nullable(p, "time");
  position.drift_offset = r.OptionalVector3(p, "drift_offset");
  position.temperature = r.Nullable(p, "temperature");
  if (position.temperature && !InTemperatureRange(*position.temperature)) {
    r.Fail(r.Key("temperature") + internal::Format(" must be from %g to %g degC",
                                                   kTemperatureRange_C[0], kTemperatureRange_C[1]));
  }
  if (p.contains("excluded")) {
    if (!p["excluded"].is_boolean()) r.Fail(r.Key("excluded") + " must be true or false");
    position.excluded = p["excluded"].get<bool>();
  }
  if (p.contains("file")) {
    if (!p["file"].is_number_unsigned() || p["file"].get<std::uint64_t>() > 1000000) {
      r.Fail(r.Key("file") + " must be an index into 'sources'");
    }
    position.file = p["file"].get<int>();
  }
  return position;
}

void ReadPositions(const Reader& r, const ordered_json& doc, LoadedCalibration& cal) {
  if (!doc.contains("positions")) return;
  if (!doc["positions"].is_array()) r.Fail(r.Key("positions") + " must be an array");
  for (std::size_t k = 0; k < doc["positions"].size(); ++k) {
    const ordered_json& p = doc["positions"][k];
    const std::string name = "positions[" + std::to_string(k) + "]";
    if (!p.is_object()) r.Fail(r.Key(name) + " must be an object");
    cal.positions.push_back(ReadPosition(r.Inside(name), p));
    cal.position_means.push_back(cal.positions.back().mean);
  }
}

// `bias_drift` (bias_drift.hpp), checked against the model and the positions' times.
void ReadDrift(const Reader& r, const ordered_json& doc, LoadedCalibration& cal) {
  if (!doc.contains("bias_drift")) return;
  const ordered_json& d = r.Object(doc, "bias_drift");
  const Reader in = r.Inside("bias_drift");
  const std::string name = in.Text(d, "model");
  const std::optional<BiasModel> model = BiasModelFromString(name);
  if (!model || model->constant()) {
    in.Fail(in.Key("model") + " must be linear or spline:K, not '" + name + "'");
  }
  BiasDrift drift;
  drift.basis.model = *model;
  if (!d.contains("t_ref")) in.Fail(in.Key("t_ref") + " is missing");
  drift.basis.t_ref_s = in.Number(d["t_ref"], in.Key("t_ref"));
  const auto J = static_cast<std::size_t>(model->functions());
  if (model->kind == BiasModelKind::kSpline) {
    const std::string shape =
        in.Key("knots") + " must be " + std::to_string(J + 1) + " increasing times";
    if (!d.contains("knots") || !d["knots"].is_array() || d["knots"].size() != J + 1) {
      in.Fail(shape);
    }
    for (std::size_t j = 0; j <= J; ++j) {
      drift.basis.knots_s.push_back(in.Number(d["knots"][j], in.Key("knots")));
      if (j > 0 && !(drift.basis.knots_s[j] > drift.basis.knots_s[j - 1])) in.Fail(shape);
    }
  }
  const std::string shape = in.Key("D") + " must be 3 arrays of " + std::to_string(J) +
                            " numbers (the " + name + " bias)";
  if (!d.contains("D") || !d["D"].is_array() || d["D"].size() != 3) in.Fail(shape);
  drift.D.resize(3, static_cast<Eigen::Index>(J));
  for (std::size_t i = 0; i < 3; ++i) {
    if (!d["D"][i].is_array() || d["D"][i].size() != J) in.Fail(shape);
    for (std::size_t j = 0; j < J; ++j) {
      drift.D(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) =
          in.Number(d["D"][i][j], in.Key("D"));
    }
  }
  drift.random_walk = in.OptionalVector3(d, "random_walk");
  if (drift.random_walk && !(drift.random_walk->minCoeff() > 0)) {
    in.Fail(in.Key("random_walk") + " must be positive, one q per axis");
  }
  if (drift.random_walk && model->kind != BiasModelKind::kSpline) {
    in.Fail(in.Key("random_walk") + " is the prior of a spline bias, not of a " + name + " one");
  }
  if (d.contains("covariance") && !d["covariance"].is_null()) {
    drift.covariance = ReadSquareCovariance(
        in, d, ParameterSlots(cal.model, cal.frame).size() + 3 * J, "the model's parameters and D");
  }
  for (std::size_t k = 0; k < cal.positions.size(); ++k) {
    if (!cal.positions[k].time) {
      r.Fail(r.Key("positions") + "[" + std::to_string(k) +
             "] has no 'time', which a drifting bias needs");
    }
    drift.times_s.push_back(*cal.positions[k].time);
    // The drift must be one the model can take from its own positions' readings.
    const std::optional<Vec3> f =
        SpecificForce(cal.params, Vec3(cal.positions[k].mean - drift.Offset(drift.times_s[k])));
    if (!f || !std::isfinite(f->norm())) {
      r.Fail(r.Key("bias_drift") + " at the time of positions[" + std::to_string(k) +
             "] leaves a reading the model cannot invert: its 'D' and 't_ref' are not a drift "
             "of this session");
    }
  }
  cal.drift = std::move(drift);
}

void ReadSolver(const Reader& r, const ordered_json& doc, LoadedCalibration& cal) {
  if (!doc.contains("solver")) return;
  const ordered_json& solver = r.Object(doc, "solver");
  const Reader s = r.Inside("solver");
  if (solver.contains("method")) cal.solver.method = s.Text(solver, "method");
  if (solver.contains("estimator")) cal.solver.estimator = s.Text(solver, "estimator");
  // A count as written, or none: a file's number need not fit an integer (1e308).
  if (solver.contains("iterations") && solver["iterations"].is_number_integer()) {
    cal.solver.iterations = solver["iterations"].get<long long>();
  }
  if (solver.contains("converged")) {
    if (!solver["converged"].is_boolean()) s.Fail(s.Key("converged") + " must be true or false");
    cal.solver.converged = solver["converged"].get<bool>();
  }
}

}  // namespace

namespace internal {

void ReadDiagnostics(const Reader& r, const ordered_json& doc, LoadedCalibration& cal) {
  if (!doc.contains("diagnostics")) return;
  if (!doc["diagnostics"].is_array()) r.Fail(r.Key("diagnostics") + " must be an array");
  std::vector<Finding> findings;
  for (std::size_t k = 0; k < doc["diagnostics"].size(); ++k) {
    const ordered_json& f = doc["diagnostics"][k];
    const Reader d = r.Inside("diagnostics[" + std::to_string(k) + "]");
    if (!f.is_object())
      r.Fail(r.Key("diagnostics[" + std::to_string(k) + "]") + " must be an object");
    Finding finding;
    finding.code = f.contains("code") ? d.Text(f, "code") : std::string();
    finding.message = f.contains("message") ? d.Text(f, "message") : std::string();
    const std::optional<Severity> severity =
        f.contains("severity") && f["severity"].is_string()
            ? FromName<Severity>(f["severity"].get<std::string>())
            : std::nullopt;
    if (!severity) {
      d.Fail(d.Key("severity") + " must be " + QuotedChoices(NameList<Severity>()));
    }
    finding.severity = *severity;
    if (f.contains("numbers")) {
      for (const auto& [name, value] : d.Object(f, "numbers").items()) {
        if (!value.is_null() && !value.is_number())
          d.Fail(d.Key("numbers." + name) + " must be a number");
        finding.numbers.emplace_back(name, value.is_null() ? std::nan("") : value.get<double>());
      }
    }
    findings.push_back(std::move(finding));
  }
  cal.diagnostics = std::move(findings);
}

}  // namespace internal

namespace {}  // namespace

namespace internal {

void CheckTemperatureRange(const Reader& in, std::pair<double, double> range, double t_ref_c) {
  const auto [lo, hi] = range;
  if (!(lo <= hi && InTemperatureRange(lo) && InTemperatureRange(hi))) {
    in.Fail(in.Key("temperature_range") + internal::Format(" must be from %g to %g degC, low first",
                                                           kTemperatureRange_C[0],
                                                           kTemperatureRange_C[1]));
  }
  if (!(t_ref_c >= lo && t_ref_c <= hi)) {
    in.Fail(in.Key("t_ref") + " must be within " + in.Key("temperature_range"));
  }
}

void CheckInvertible(const Reader& r, const Mat33& K, const char* key) {
  const Vec3 sv = Eigen::JacobiSVD<Mat33>(K).singularValues();
  if (!(sv(2) > 1e-12 * sv(0)) || !(sv(2) >= 1e-12)) {
    r.Fail(r.Key(key) + internal::Format(" is singular (its smallest singular value %.3g, its "
                                         "largest %.3g)",
                                         sv(2), sv(0)));
  }
}

std::pair<double, double> ReadTemperatureRange(const Reader& in, const ordered_json& t,
                                               double t_ref_c) {
  if (!t.contains("temperature_range")) {
    in.Fail(in.Key("temperature_range") +
            " is missing: the temperatures the fit spans, to which its polynomials are held");
  }
  const ordered_json& range = t["temperature_range"];
  if (!range.is_array() || range.size() != 2) {
    in.Fail(in.Key("temperature_range") + " must be 2 temperatures");
  }
  const std::pair<double, double> lo_hi{in.Number(range[0], in.Key("temperature_range")),
                                        in.Number(range[1], in.Key("temperature_range"))};
  CheckTemperatureRange(in, lo_hi, t_ref_c);
  return lo_hi;
}

}  // namespace internal

namespace {

// `thermal` (thermal.hpp), checked against the model, its parameters and the positions.
void ReadThermal(const Reader& r, const ordered_json& doc, LoadedCalibration& cal) {
  if (!doc.contains("thermal")) return;
  const ordered_json& t = r.Object(doc, "thermal");
  const Reader in = r.Inside("thermal");
  if (cal.drift) in.Fail("a bias that drifts in time and parameters that follow temperature");
  if (cal.frame != Frame::kXFirst || in.Text(t, "frame") != ToString(Frame::kXFirst)) {
    in.Fail(in.Key("frame") + " and the parameters' frame must be x-first");
  }
  ThermalTerms terms;
  if (!t.contains("t_ref")) in.Fail(in.Key("t_ref") + " is missing");
  terms.params.t_ref_c = in.Number(t["t_ref"], in.Key("t_ref"));
  if (!InTemperatureRange(terms.params.t_ref_c)) {
    in.Fail(in.Key("t_ref") + internal::Format(" must be from %g to %g degC",
                                               kTemperatureRange_C[0], kTemperatureRange_C[1]));
  }
  const ordered_json& d = in.Object(t, "degrees");
  const Reader din = in.Inside("degrees");
  for (const auto& [key, value] :
       {std::pair("K", &terms.params.degrees.K), std::pair("bias", &terms.params.degrees.bias),
        std::pair("k2", &terms.params.degrees.k2)}) {
    if (!d.contains(key)) continue;
    if (!d[key].is_number_unsigned() || d[key].get<std::uint64_t>() > kMaxThermalDegree) {
      din.Fail(din.Key(key) + " must be a whole number from 0 to " +
               std::to_string(kMaxThermalDegree));
    }
    *value = d[key].get<int>();
  }
  std::vector<ThermalSlot> slots;
  try {
    slots = ThermalSlots(cal.model, terms.params.degrees);
  } catch (const std::invalid_argument& e) {
    din.Fail(e.what());
  }
  if (terms.params.degrees.Max() == 0) din.Fail("no degree above 0: not a thermal model");
  const std::size_t n = slots.size();
  const std::string shape = " must be an array of " + std::to_string(n) + " (degrees " +
                            terms.params.degrees.ToString() + ")";
  for (const char* key : {"order", "coefficients"}) {
    if (!t.contains(key) || !t[key].is_array() || t[key].size() != n) in.Fail(in.Key(key) + shape);
  }
  Eigen::VectorXd x(static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i) {
    if (t["order"][i] != ThermalSlotName(slots[i])) {
      in.Fail(in.Key("order") + " must be the slots of degrees " + terms.params.degrees.ToString() +
              " in order");
    }
    x(static_cast<Eigen::Index>(i)) = in.Number(t["coefficients"][i], in.Key("coefficients"));
  }
  terms.params = UnpackThermal(x, cal.model, terms.params.degrees, terms.params.t_ref_c);
  // θ_0 is the file's parameters.
  const Eigen::VectorXd at_ref = Pack(cal.params, ParameterSlots(cal.model, cal.frame));
  if ((x.head(at_ref.size()) - at_ref).norm() > 1e-9 * (1 + at_ref.norm())) {
    in.Fail(in.Key("coefficients") +
            " of degree 0 differ from the parameters: they must be the "
            "parameters at t_ref");
  }
  if (t.contains("covariance") && !t["covariance"].is_null()) {
    terms.covariance = ReadSquareCovariance(in, t, n, "the thermal coefficients");
  }
  cal.thermal_range_c = ReadTemperatureRange(in, t, terms.params.t_ref_c);
  if (t.contains("std") && !t["std"].is_null()) {
    if (!t["std"].is_array() || t["std"].size() != n) in.Fail(in.Key("std") + shape);
    for (std::size_t i = 0; i < n; ++i) {
      if (!(in.Number(t["std"][i], in.Key("std")) >= 0)) {
        in.Fail(in.Key("std") + " must not be negative");
      }
    }
  }
  for (std::size_t k = 0; k < cal.positions.size(); ++k) {
    if (!cal.positions[k].temperature) {
      r.Fail(r.Key("positions[" + std::to_string(k) + "]") +
             " has no 'temperature', which parameters that follow temperature need");
    }
    terms.temperatures_c.push_back(*cal.positions[k].temperature);
    // The range is the positions' (a few ulps of a mean aside).
    const double slack = 1e-9 * (1 + std::abs(*cal.positions[k].temperature));
    if (*cal.positions[k].temperature < cal.thermal_range_c->first - slack ||
        *cal.positions[k].temperature > cal.thermal_range_c->second + slack) {
      r.Fail(r.Key("positions[" + std::to_string(k) + "].temperature") + " is outside " +
             in.Key("temperature_range"));
    }
  }
  cal.thermal = std::move(terms);
}

// The accelerometer's keys: a version-1 document's top level, a version-2 document's
// `sensors.accelerometer`.
void ReadAccelerometer(const Reader& r, const ordered_json& doc, LoadedCalibration& cal) {
  ReadModel(r, doc, cal);
  if (doc.contains("verdict")) cal.verdict = CheckedVerdict(r, doc);
  if (doc.contains("source") && doc["source"].is_string()) {
    cal.source = doc["source"].get<std::string>();
  }
  ReadCovariance(r, doc, cal);
  ReadPositions(r, doc, cal);
  ReadDrift(r, doc, cal);
  ReadThermal(r, doc, cal);
  cal.gravity_norm_rms_before = r.Nullable(doc, "gravity_norm_rms_before");
  cal.gravity_norm_rms_after = r.Nullable(doc, "gravity_norm_rms_after");
  cal.crossval_rms = r.Nullable(doc, "crossval_rms");
  if (doc.contains("noise") && !doc["noise"].is_null()) {
    const Reader rn = r.Inside("noise");
    cal.noise_sigma_raw = rn.Nullable(r.Object(doc, "noise"), "sigma_raw");
    if (cal.noise_sigma_raw && !(*cal.noise_sigma_raw >= 0)) {
      rn.Fail(rn.Key("sigma_raw") + " must not be negative");
    }
    const ordered_json& noise = r.Object(doc, "noise");
    const std::optional<double> dof = rn.Nullable(noise, "degrees_of_freedom");
    const bool from_samples = noise.contains("source") && noise["source"] == "samples" &&
                              !(noise.contains("inflated") && noise["inflated"] == true);
    if (dof && *dof > 0 && !from_samples) cal.covariance_dof = *dof;
  }
  ReadSolver(r, doc, cal);
  ReadDiagnostics(r, doc, cal);
}

// A binary log's stream (InputRecord::stream).
SourceStream ReadSourceStream(const ordered_json& s, const Reader& r) {
  if (!s.is_object()) r.Fail(r.Key("") + " must be an object");
  const auto text = [&](const char* key) {
    if (!s.contains(key)) r.Fail(r.Key(key) + " is missing");
    return r.Text(s, key);
  };
  SourceStream stream;
  stream.format = text("format");
  stream.topic = text("topic");
  stream.type = text("type");
  if (!s.contains("instance") || !s["instance"].is_number_integer()) {
    r.Fail(r.Key("instance") + " must be an integer");
  }
  stream.instance = s["instance"].get<int>();
  if (s.contains("device_id") && !s["device_id"].is_null()) {
    if (!s["device_id"].is_number_unsigned()) r.Fail(r.Key("device_id") + " must be a count");
    stream.device_id = s["device_id"].get<std::uint64_t>();
  }
  if (!s.contains("corrected") || !s["corrected"].is_boolean()) {
    r.Fail(r.Key("corrected") + " must be true or false");
  }
  stream.corrected = s["corrected"].get<bool>();
  if (s.contains("unit")) stream.unit = r.Text(s, "unit");
  if (s.contains("calibration_in_force")) {
    const ordered_json& parameters = s["calibration_in_force"];
    if (!parameters.is_object()) r.Fail(r.Key("calibration_in_force") + " must be an object");
    for (const auto& [parameter, value] : parameters.items()) {
      stream.calibration_in_force[parameter] =
          r.Number(value, r.Key("calibration_in_force." + parameter));
    }
  }
  return stream;
}

void ReadProvenance(const Reader& r, const ordered_json& doc, Provenance& provenance) {
  if (!doc.contains("provenance")) return;
  const ordered_json& p = r.Object(doc, "provenance");
  const Reader in = r.Inside("provenance");
  if (p.contains("accelcal_version")) provenance.accelcal_version = in.Text(p, "accelcal_version");
  if (p.contains("command")) provenance.command = in.Text(p, "command");
  if (p.contains("options")) provenance.options = in.Object(p, "options");
  if (p.contains("date")) {
    provenance.date = in.Text(p, "date");
    if (const auto why = CheckProvenanceDate(provenance.date))
      in.Fail(in.Key("date") + ": " + *why);
  }
  if (!p.contains("inputs")) return;
  if (!p["inputs"].is_array()) in.Fail(in.Key("inputs") + " must be an array");
  for (std::size_t k = 0; k < p["inputs"].size(); ++k) {
    const std::string name = "inputs[" + std::to_string(k) + "]";
    if (!p["inputs"][k].is_object()) in.Fail(in.Key(name) + " must be an object");
    const ordered_json& i = p["inputs"][k];
    const Reader f = in.Inside(name);
    InputRecord input;
    if (!i.contains("name")) f.Fail(f.Key("name") + " is missing");
    input.name = f.Text(i, "name");
    if (i.contains("bytes")) {
      if (!i["bytes"].is_number_unsigned()) f.Fail(f.Key("bytes") + " must be a count");
      input.bytes = i["bytes"].get<std::uint64_t>();
    }
    if (i.contains("sha256")) {
      input.sha256 = f.Text(i, "sha256");
      const bool hex = input.sha256.size() == 64 &&
                       input.sha256.find_first_not_of("0123456789abcdef") == std::string::npos;
      if (!hex) f.Fail(f.Key("sha256") + " must be 64 lowercase hexadecimal digits");
    }
    if (i.contains("stream")) input.stream = ReadSourceStream(i["stream"], f.Inside("stream"));
    provenance.inputs.push_back(std::move(input));
  }
}

LoadedCalibration ParseCalibrationDocument(const ordered_json& doc, const std::string& source) {
  const Reader top(source, "");
  if (!doc.is_object() || !doc.contains("format") || doc["format"] != "accelcal-calibration") {
    top.Fail("not an accelcal calibration file (\"format\" is not \"accelcal-calibration\")");
  }
  const bool known_version = doc.contains("version") && doc["version"].is_number_integer() &&
                             (doc["version"] == 1 || doc["version"] == 2);
  if (!known_version) {
    top.Fail("unsupported calibration file version " +
             (doc.contains("version") ? doc["version"].dump() : std::string("(none)")) +
             " (this accelcal reads versions 1 and " + std::to_string(kCalibrationFileVersion) +
             ")");
  }
  LoadedCalibration cal;
  cal.version = doc["version"].get<int>();
  if (cal.version == 1) {
    ReadAccelerometer(top, doc, cal);
    return cal;
  }
  const ordered_json& sensors = top.Object(doc, "sensors");
  if (!sensors.contains("accelerometer")) {
    top.Fail("holds no accelerometer calibration ('sensors' has no 'accelerometer')");
  }
  ReadAccelerometer(top.Inside("sensors").Inside("accelerometer"),
                    top.Inside("sensors").Object(sensors, "accelerometer"), cal);
  if (!doc.contains("verdict")) top.Fail("'verdict' is missing");
  const std::string unit_verdict = CheckedVerdict(top, doc);
  if (VerdictRank(unit_verdict) > VerdictRank(cal.verdict)) cal.verdict = unit_verdict;
  ReadProvenance(top, doc, cal.provenance);
  if (sensors.contains("gyroscope")) {
    cal.gyroscope = ReadGyroscope(top.Inside("sensors").Inside("gyroscope"),
                                  top.Inside("sensors").Object(sensors, "gyroscope"));
  }
  return cal;
}

}  // namespace

LoadedCalibration ParseCalibrationJson(const std::string& text, const std::string& source) {
  const ordered_json doc = ParseWithoutDuplicateKeys(text, source);
  // Every key's type is checked above; a JSON type error that escapes a check (a bug) still
  // names the file rather than ending as an internal error.
  try {
    return ParseCalibrationDocument(doc, source);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(source, 0, std::string("unexpected content: ") + e.what());
  }
}

}  // namespace accelcal
