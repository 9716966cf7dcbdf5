// Python's calibrate, calibrate_log and diagnose, and their result (CalibrationResult): the
// calibration as the command line does it, with its diagnosis and provenance.
#include "cli_common.hpp"
#include "commands.hpp"
#include "py_common.hpp"
#include "py_result.hpp"

#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "accelcal/calibrate.hpp"
#include "accelcal/calibrate_unit.hpp"
#include "accelcal/calibration_file.hpp"
#include "accelcal/diagnosis.hpp"
#include "accelcal/error.hpp"
#include "accelcal/export.hpp"
#include "accelcal/gyro_calibration.hpp"
#include "accelcal/model_selection.hpp"
#include "accelcal/report.hpp"
#include "accelcal/sensor_parameters.hpp"
#include "accelcal/static_detection.hpp"

namespace accelcal::python {

namespace {

// ---------------------------------------------------------------------------------------------
// Calibration as the command line does it, and its diagnosis.

struct FitSettings {
  std::string model = "linear";  // linear, quadratic or auto
  std::string method = "joint";
  std::string frame = "x-first";
  double gravity = kStandardGravity_ms2;
  std::string estimator = "ml";
  bool cross_validate = true;
  std::string outliers = "exclude";
  double outlier_probability = 1e-3;
  int max_outliers = 3;
  int max_iterations = 0;  // 0: the solvers' defaults
  std::optional<std::string> units;
};

// The fit's arguments as a calibration file's provenance records them: every one, as used.
nlohmann::ordered_json SettingsJson(const FitSettings& s) {
  nlohmann::ordered_json o;
  o["model"] = s.model;
  o["method"] = s.method;
  o["frame"] = s.frame;
  o["gravity"] = s.gravity;
  o["estimator"] = s.estimator;
  o["cross_validate"] = s.cross_validate;
  o["outliers"] = s.outliers;
  o["outlier_probability"] = s.outlier_probability;
  o["max_outliers"] = s.max_outliers;
  o["max_iterations"] = s.max_iterations;
  o["units"] = s.units ? nlohmann::ordered_json(*s.units) : nlohmann::ordered_json(nullptr);
  return o;
}

// The options as RunCalibrate (apps/accelcal/cmd_calibrate.cpp) builds them; ValueError when
// invalid.
CalibrationOptions MakeOptions(const FitSettings& s) {
  CalibrationOptions o;
  const bool auto_model = s.model == "auto";
  o.model = auto_model ? ModelKind::kLinear : Parse(ModelKindFromString(s.model), s.model, "model");
  o.method = Parse(SolverMethodFromString(s.method), s.method, "method");
  o.frame = Parse(FrameFromString(s.frame), s.frame, "frame");
  o.gravity = s.gravity;
  o.estimator = Parse(EstimatorFromString(s.estimator), s.estimator, "estimator");
  o.outliers.policy = Parse(OutlierPolicyFromString(s.outliers), s.outliers, "outliers");
  o.outliers.false_alarm_probability = s.outlier_probability;
  o.outliers.max_excluded = s.max_outliers;
  o.cross_validate = s.cross_validate;
  if (s.max_iterations < 0) throw py::value_error("max_iterations must be >= 0 (0: the default)");
  if (s.max_iterations > 0) {
    o.two_step.max_sweeps = s.max_iterations;
    o.joint.max_iterations = s.max_iterations;
    o.modulus.max_iterations = s.max_iterations;
    o.newton_lagrange.max_iterations = s.max_iterations;
  }
  if (auto why = o.Validate()) throw OptionError(*why);
  if (auto_model) {
    if (!s.cross_validate) {
      throw py::value_error("model 'auto' decides on held-out error: it needs cross_validate=True");
    }
    CalibrationOptions quadratic = o;
    quadratic.model = ModelKind::kQuadratic;
    if (auto why = quadratic.Validate()) throw OptionError("model 'auto': " + *why);
  }
  UnitOf(s.units, s.gravity);  // an unknown unit is an error before any work
  return o;
}

Diagnosis DiagnoseFit(const PyCalibration& c, const RawLog* log,
                      const StaticDetectionResult* detection);

// Fits as RunCalibrate does (a quadratic fit, asked for or a candidate of "auto", is compared
// with the linear fit) and diagnoses the result; `log` and `detection` add their findings.
PyCalibration Fit(std::vector<Position> positions, std::vector<Vec3> sigmas, const FitSettings& s,
                  CalibrationOptions options, const RawLog* log,
                  const StaticDetectionResult* detection, std::string source) {
  PyCalibration c;
  c.model_requested = s.model;
  c.unit = UnitOf(s.units, s.gravity);
  c.positions = std::move(positions);
  c.source = std::move(source);
  c.max_excluded = s.max_outliers;
  const std::vector<Vec3> means = Means(c.positions);
  options.reading_sigmas = std::move(sigmas);
  c.mean_sigmas = options.reading_sigmas;
  ModelChoice choice = CalibrateChoosingModel(means, options, s.model == "auto");
  c.result = std::move(choice.result);
  c.selection = std::move(choice.selection);
  c.diagnosis = DiagnoseFit(c, log, detection);
  return c;
}

// Python's result of a unit calibrated by the library (calibrate_log).
PyCalibration FromOutcome(const UnitOutcome& u, int max_excluded) {
  PyCalibration c;
  const CalibrationFileInfo info = u.FileInfo();
  c.result = u.accelerometer;
  c.selection = u.model_selection;
  c.model_requested = u.model_requested;
  c.unit = u.unit;
  c.positions = u.input.positions;
  c.mean_sigmas = u.mean_sigmas;
  c.source = info.source;
  c.raw_unit = u.raw_unit;
  c.sources = info.sources;
  c.position_source = info.position_source;
  c.bias_model_selection = u.bias_model_selection;
  c.max_excluded = max_excluded;
  c.diagnosis = u.diagnosis;
  c.provenance = u.provenance;
  if (u.gyroscope) {
    c.gyroscope = u.gyroscope->calibration;
    c.gyroscope->accelerometer.reset();  // the joint fit's accelerometer is c.result
  }
  return c;
}

// The diagnosis as RunCalibrate's: the fit, the log and its detection, the gyroscope.
Diagnosis DiagnoseFit(const PyCalibration& c, const RawLog* log,
                      const StaticDetectionResult* detection) {
  DiagnosisInput in;
  in.result = &c.result;
  in.positions = &c.positions;
  in.max_excluded = c.max_excluded;
  in.selection = c.selection ? &*c.selection : nullptr;
  // One log, so its findings are not prefixed with its name (the command line's for one file).
  if (log || detection) in.logs.push_back({c.source, log, detection});
  in.unit = c.unit;
  in.gyroscope = c.gyroscope ? &*c.gyroscope : nullptr;
  return Diagnose(in);
}

// A value the file writes as null when it is NaN (not computed): None.
py::object FloatOrNone(double v) { return std::isnan(v) ? py::object(py::none()) : py::float_(v); }

py::dict GyroDict(const GyroCalibration& g) {
  py::dict d;
  d["model"] = std::string(ToString(g.model));
  d["model_reason"] = g.model_reason;
  d["estimator"] = std::string(ToString(g.estimator));
  d["units"] = std::string(ToString(g.unit));
  d["K"] = Mat33(g.params.K);
  d["bias"] = Vec3(g.params.bias);
  d["G"] = Mat33(g.params.G);
  std::vector<std::string> names;
  for (const SensorParameter& p : ListParameters(g.params, g.model)) names.emplace_back(p.name);
  d["parameter_names"] = names;
  if (g.covariance.size() > 0) {
    d["covariance"] = g.covariance;
    d["std"] = Eigen::VectorXd(g.covariance.diagonal().cwiseSqrt());
  } else {
    d["covariance"] = py::none();
    d["std"] = py::none();
  }
  d["noise_sigma_raw"] = Vec3(g.noise_sigma_raw);
  d["still_scatter_ratio"] = g.still_scatter_ratio;
  d["rotation_scatter_ratio"] = g.rotation_scatter_ratio;
  d["accelerometer_scatter_ratio"] = g.accel_scatter_ratio;
  py::list stills;
  for (const GyroStillSpan& span : g.still_spans) {
    py::dict st;
    st["first_sample"] = span.first_sample;
    st["last_sample"] = span.last_sample;
    st["mean_raw"] = Vec3(span.mean_raw);
    st["turned_outside_deg"] = span.turned_outside_deg;
    st["still"] = span.still;
    stills.append(st);
  }
  d["stills"] = stills;
  if (g.time_offset) {
    py::dict lag;
    lag["lag_s"] = g.time_offset->lag_s;
    lag["std_s"] = g.time_offset->std_s;
    lag["turns"] = g.time_offset->turns;
    lag["at_limit"] = g.time_offset->at_limit;
    d["time_offset"] = lag;
  } else {
    d["time_offset"] = py::none();
  }
  py::list rotations;
  for (const GyroRotation& r : g.rotations) {
    py::dict t;
    t["from"] = r.from + 1;  // position numbers count from 1, as in the file and the tool
    t["to"] = r.to + 1;
    t["first_sample"] = r.first_sample;
    t["last_sample"] = r.last_sample;
    t["duration_s"] = r.duration_s;
    t["angle_deg"] = r.angle_deg;
    t["turned_deg"] = r.turned_deg;
    t["turned_std_deg"] = r.turned_std_deg;
    t["residual_deg"] = r.residual_deg;
    t["heldout_deg"] = r.heldout_deg;
    t["statistic"] = FloatOrNone(r.statistic);  // the screening's, None when not screened
    t["threshold"] = FloatOrNone(r.threshold);
    t["flagged"] = r.flagged;
    t["excluded"] = false;
    rotations.append(t);
  }
  d["rotations"] = rotations;
  d["rms_deg"] = g.rms_deg;
  d["heldout_rms_deg"] = g.heldout_rms_deg;
  return d;
}

// CalibrationResult's read-only attributes.
void BindResultAttributes(py::class_<PyCalibration>& cls) {
  cls.def_property_readonly(
         "model", [](const PyCalibration& c) { return std::string(ToString(c.result.model)); },
         "The model fitted: 'linear' or 'quadratic' (with model='auto', the one chosen)")
      .def_property_readonly(
          "frame", [](const PyCalibration& c) { return std::string(ToString(c.result.frame)); },
          "The body frame's convention: 'x-first' (K lower-triangular) or 'z-first' (upper)")
      .def_property_readonly(
          "gravity", [](const PyCalibration& c) { return c.result.gravity; },
          "The magnitude of gravity the fit took, in units")
      .def_property_readonly(
          "units", [](const PyCalibration& c) { return std::string(ToString(c.unit)); },
          "Unit of gravity and of the calibrated specific force: 'm/s2' or 'g'")
      .def_property_readonly(
          "K", [](const PyCalibration& c) { return Mat33(c.result.params.K); },
          "K (3 x 3) [raw per unit of specific force]: scale factors on the diagonal, "
          "misalignments off it")
      .def_property_readonly(
          "bias", [](const PyCalibration& c) { return Vec3(c.result.params.bias); },
          "b (3) [raw]: the reading at zero specific force")
      .def_property_readonly(
          "k2", [](const PyCalibration& c) { return Vec3(c.result.params.k2); },
          "k2 (3) [raw per unit squared]: the squared coefficients (zeros for the linear model)")
      .def_property_readonly(
          "covariance",
          [](const PyCalibration& c) -> std::optional<Eigen::MatrixXd> {
            if (c.result.covariance.size() == 0) return std::nullopt;
            return c.result.covariance;
          },
          "The parameters' covariance in parameter_names' order (maximum-likelihood methods; None "
          "otherwise or without degrees of freedom)")
      .def_property_readonly(
          "parameter_names",
          [](const PyCalibration& c) {
            std::vector<std::string> names;
            for (const SensorParameter& p :
                 ListParameters(c.result.params, c.result.model, c.result.frame))
              names.emplace_back(p.name);
            return names;
          },
          "The flat parameters' names in the covariance's order (K_xx, b_x, ...)")
      .def_property_readonly(
          "directions", [](const PyCalibration& c) { return ToRows(c.result.directions); },
          "The fitted unit gravity directions c_k in the body frame (m x 3, one row per position)")
      .def_property_readonly(
          "residuals", [](const PyCalibration& c) { return ToRows(c.result.residuals); },
          "p_k - mu(theta, g c_k) [raw] (m x 3, one row per position)")
      .def_property_readonly(
          "residual_sigma", [](const PyCalibration& c) { return c.result.residual_sigma; },
          "The residuals' sigma [raw] (0 without degrees of freedom)")
      .def_property_readonly(
          "scatter_ratio", [](const PyCalibration& c) { return c.result.scatter_ratio; },
          "With the samples' noise: sqrt(chi2 / dof), 1 when that noise explains the positions' "
          "scatter (the covariance is multiplied by its square above 1); NaN otherwise")
      .def_property_readonly(
          "degrees_of_freedom", [](const PyCalibration& c) { return c.result.degrees_of_freedom; },
          "m - P: positions in the fit less parameters")
      .def_property_readonly(
          "crossval_rms", [](const PyCalibration& c) { return c.result.crossval_rms; },
          "RMS of |f_k| - g with each position corrected by a fit without it [units]; None without "
          "cross-validation or when a fit without some position failed (crossval_note)")
      .def_property_readonly(
          "crossval_errors", [](const PyCalibration& c) { return c.result.crossval_errors; },
          "Each position's held-out |f_k| - g [units], in the positions' order")
      .def_property_readonly(
          "crossval_note", [](const PyCalibration& c) { return c.result.crossval_note; },
          "Why cross-validation did not run on every position ('' when it did)")
      .def_property_readonly(
          "outliers",
          [](const PyCalibration& c) {
            py::list list;
            for (const OutlierFinding& o : c.result.outliers) {
              py::dict d;
              d["position"] = o.position + 1;  // counts from 1, as the file and the tool
              d["excluded"] = o.excluded;
              d["statistic"] = std::string(ToString(o.statistic));
              d["t"] = o.t;
              d["threshold"] = o.threshold;
              d["degrees_of_freedom"] = o.degrees_of_freedom;
              d["normal_residual"] = o.normal_residual;
              d["scatter"] = o.scatter;
              list.append(d);
            }
            return list;
          },
          "Positions the screening found discordant: dicts whose 'position' is the position's "
          "number, counting from 1 as the calibration file, the diagnostics and the command line "
          "do (its row of the readings is position - 1)")
      .def_property_readonly(
          "outlier_note", [](const PyCalibration& c) { return c.result.outlier_note; },
          "Why the screening did not run or could not test some position ('' when it ran on all)")
      .def_property_readonly(
          "summary", [](const PyCalibration& c) { return SummaryDict(c.result.summary); },
          "How the solve went: method, initialization, iterations, termination (and its formula), "
          "costs, time_s, brief_report")
      .def_property_readonly(
          "verdict",
          [](const PyCalibration& c) { return std::string(ToString(c.diagnosis.verdict())); },
          "'ok' (notes at most), 'warnings' or 'failed' (the calibration failed its checks and "
          "must not be used as it is; the command line exits with status 6)")
      .def_property_readonly(
          "diagnostics", [](const PyCalibration& c) { return FindingsList(c.diagnosis); },
          "The diagnosis (diagnosis.hpp), failures first, then warnings, then notes: dicts with "
          "code, severity ('note', 'warning', 'failure'), message and numbers (a dict; position "
          "numbers in it count from 1, as in the messages)")
      .def_property_readonly(
          "model_selection",
          [](const PyCalibration& c) -> py::object {
            if (!c.selection) return py::none();
            return SelectionDict(*c.selection);
          },
          "With model 'auto' (or 'quadratic' with cross-validation): which model the held-out "
          "errors support and why (model_selection.hpp; positions_used are position numbers, from "
          "1); "
          "else None")
      .def_property_readonly(
          "gyroscope",
          [](const PyCalibration& c) -> py::object {
            if (!c.gyroscope) return py::none();
            py::dict d = GyroDict(*c.gyroscope);
            if (!c.gyroscope->source.empty()) d["source"] = FileNameStr(c.gyroscope->source);
            return d;
          },
          "The gyroscope calibrated from the same recording (calibrate_log's gyro options; "
          "gyro_calibration.hpp), else None: a dict with source (its log), model, estimator, K "
          "[raw per rad/s], "
          "bias [raw], G [raw per force unit, zeros for the linear model], covariance (in "
          "parameter_names' order) and std, noise_sigma_raw, scatter ratios, stills (per "
          "position: the samples where the gyro was still, its mean raw rate there, the angle "
          "it turned outside them), time_offset (the gyro's lag behind the accelerometer, "
          "lag_s and std_s), rotations (dicts with the file's keys; from and to are position "
          "numbers, from 1; statistic and threshold None when not screened), "
          "rms_deg and heldout_rms_deg")
      .def_property_readonly(
          "source", [](const PyCalibration& c) { return FileNameStr(c.source); },
          "The input file, or ''");
}

// CalibrationResult's methods: pickling, apply and to_json.
void BindResultMethods(py::class_<PyCalibration>& cls) {
  cls
      // Pickled as the call that restores it (every protocol, 0 included).
      .def("__reduce__",
           [](const PyCalibration& c) {
             return py::make_tuple(py::module_::import("accelcal").attr("_restore_result"),
                                   py::make_tuple(py::bytes(SaveState(c))));
           })
      .def(
          "apply",
          [](const PyCalibration& c, const Rows& readings) {
            return Apply(c.result.params, readings);
          },
          py::arg("readings"), "Corrected specific force (n x 3) of raw readings (n x 3)")
      .def(
          "to_json",
          [](const PyCalibration& c, std::optional<Rows> positions,
             std::optional<std::string> units, std::optional<std::string> raw_units,
             std::optional<std::string> source, std::optional<std::string> date) {
            CalibrationFileInfo info;
            info.unit = units ? Parse(ForceUnitFromString(*units), *units, "units") : c.unit;
            info.raw_unit = raw_units ? *raw_units : c.raw_unit;
            info.source = source ? *source : c.source;
            info.sources = c.sources;
            info.position_source = c.position_source;
            info.bias_model_selection = c.bias_model_selection ? &*c.bias_model_selection : nullptr;
            if (positions) {
              if (static_cast<std::size_t>(positions->rows()) != c.result.directions.size()) {
                throw py::value_error("to_json: " + std::to_string(positions->rows()) +
                                      " positions for a calibration of " +
                                      std::to_string(c.result.directions.size()));
              }
              info.positions = PositionsOf(*positions);
            } else {
              info.positions = c.positions;
              info.mean_sigmas = c.mean_sigmas;
            }
            info.model_selection = c.selection ? &*c.selection : nullptr;
            info.model_requested = c.model_requested;
            // The stored diagnosis is of the fitted positions in the stored unit.
            if (!positions && info.unit == c.unit) info.diagnosis = &c.diagnosis;
            info.provenance = c.provenance;
            // A raw gyroscope's counts are labelled as the accelerometer's when they are.
            std::optional<UnitGyroscope> relabelled;
            if (c.gyroscope && raw_units && c.gyroscope->unit == GyroUnit::kRaw) {
              relabelled = *c.gyroscope;
              relabelled->raw_unit = *raw_units;
            }
            info.gyroscope = relabelled ? &*relabelled : c.gyroscope ? &*c.gyroscope : nullptr;
            if (date) {
              if (const auto why = CheckProvenanceDate(*date))
                throw py::value_error("date: " + *why);
              info.provenance.date = *date;
            }
            return CalibrationToJson(c.result, info);
          },
          py::arg("positions") = std::nullopt, py::arg("units") = std::nullopt,
          py::arg("raw_units") = std::nullopt, py::arg("source") = std::nullopt,
          py::arg("date") = std::nullopt,
          "The calibration file (JSON text, docs/calibration-file.md). By default of the fitted "
          "positions (with their sample counts and noise) in the result's units, with its "
          "diagnosis and source: for calibrate_log the same text as `accelcal calibrate LOG "
          "--json` but its provenance (the Python function, its arguments and the file's "
          "SHA-256). Other positions (m x 3) or units are diagnosed anew, without the log. "
          "`date` (YYYY-MM-DD[THH:MM[:SS]Z]) is written as the provenance's date; none without "
          "it.");
}

// The functions that make a CalibrationResult, and diagnose.
void BindCalibrationFunctions(py::module_& m) {
  m.def(
      "calibrate",
      [](const Rows& readings, const std::string& model, const std::string& method,
         const std::string& frame, double gravity, const std::string& estimator,
         std::optional<Rows> reading_sigmas, bool cross_validate, const std::string& outliers,
         double outlier_probability, int max_outliers, std::optional<std::string> units,
         int max_iterations) {
        const FitSettings s{model,        method,         frame,           gravity,
                            estimator,    cross_validate, outliers,        outlier_probability,
                            max_outliers, max_iterations, std::move(units)};
        const CalibrationOptions options = MakeOptions(s);
        std::vector<Vec3> sigmas;
        if (reading_sigmas) sigmas = ToVectors(*reading_sigmas);
        std::vector<Position> positions = PositionsOf(readings);
        PyCalibration c;
        {
          py::gil_scoped_release release;
          c = Fit(std::move(positions), std::move(sigmas), s, options, nullptr, nullptr, "");
        }
        c.provenance.command = "accelcal Python calibrate";
        c.provenance.options = SettingsJson(s);
        c.provenance.options["reading_sigmas"] = reading_sigmas.has_value();
        return c;
      },
      py::arg("readings"), py::arg("model") = "linear", py::arg("method") = "joint",
      py::arg("frame") = "x-first", py::arg("gravity") = kStandardGravity_ms2,
      py::arg("estimator") = "ml", py::arg("reading_sigmas") = std::nullopt,
      py::arg("cross_validate") = true, py::arg("outliers") = "exclude", py::kw_only(),
      py::arg("outlier_probability") = 1e-3, py::arg("max_outliers") = 3,
      py::arg("units") = std::nullopt, py::arg("max_iterations") = 0,
      "Calibrates from averaged readings and diagnoses the result (no Python warnings: "
      "accelcal.calibrate adds them)");

  m.def(
      "_calibrate_unit",
      [](std::vector<std::string> args) {
        if (args.empty() || args.front() != "calibrate") {
          throw py::value_error("_calibrate_unit: the arguments of calibrate");
        }
        std::string out, err;
        std::optional<PyCalibration> c;
        bool data_error = false;  // DataError: too little in the data (the tool's status 3 too)
        int status = 0;
        {
          py::gil_scoped_release release;  // taken again to build the Python result
          args.insert(args.begin(), "accelcal");
          // The tool's own options, rules and messages, then the library's CalibrateUnit.
          status = cli::RunCommandLineCaptured(
              args, &out, &err, nullptr, [&c, &data_error](const cli::CalibrateArgs& a) {
                cli::Gravity g;
                UnitRequest request = cli::CalibrateRequest(a, &g);
                request.provenance.command = "accelcal Python calibrate_log";
                try {
                  c = FromOutcome(CalibrateUnit(request), request.outliers.max_excluded);
                } catch (const DataError&) {
                  data_error = true;
                  throw;  // the tool's message for it
                }
                return 0;
              });
        }
        if (!c) return py::make_tuple(status, py::none(), py::none(), py::bytes(err), data_error);
        Rows means = ToRows(Means(c->positions));
        return py::make_tuple(status, std::move(*c), std::move(means), py::bytes(err), false);
      },
      py::arg("args"),
      "accelcal.calibrate_log: `accelcal calibrate ARGS...`'s options parsed and checked by the "
      "tool, the unit calibrated by the library (CalibrateUnit): (exit status, result or None, "
      "positions or None, the tool's standard error as bytes, whether the error was a "
      "DataError)");

  m.def(
      "diagnose",
      [](const PyCalibration& c, std::optional<Rows> positions, std::optional<std::string> units,
         std::optional<Rows> samples, std::optional<Eigen::VectorXd> time,
         std::optional<double> rate_hz, const std::string& time_unit,
         std::optional<py::dict> detection, std::optional<int> max_outliers) {
        std::vector<Position> fitted = c.positions;
        if (positions) {
          if (static_cast<std::size_t>(positions->rows()) != c.result.directions.size()) {
            throw py::value_error("diagnose: " + std::to_string(positions->rows()) +
                                  " positions for a calibration of " +
                                  std::to_string(c.result.directions.size()));
          }
          fitted = PositionsOf(*positions);
        }
        std::optional<RawLog> log;
        if (samples) {
          log = LogFromArrays(time, *samples, rate_hz, time_unit);
        } else if (time) {
          throw py::value_error("diagnose: time needs the samples");
        }
        std::optional<StaticDetectionResult> found;
        if (detection) {
          found = DetectionFromDict(
              *detection, log ? std::optional<std::size_t>(log->samples.size()) : std::nullopt);
        }
        DiagnosisInput in;
        in.result = &c.result;
        in.positions = &fitted;
        in.max_excluded = max_outliers ? *max_outliers : c.max_excluded;
        in.selection = c.selection ? &*c.selection : nullptr;
        if (log || found) {
          in.logs.push_back({c.source, log ? &*log : nullptr, found ? &*found : nullptr});
        }
        in.unit = units ? Parse(ForceUnitFromString(*units), *units, "units") : c.unit;
        return DiagnosisDict(Diagnose(in));
      },
      py::arg("result"), py::arg("positions") = std::nullopt, py::arg("units") = std::nullopt,
      py::arg("samples") = std::nullopt, py::arg("time") = std::nullopt,
      py::arg("rate_hz") = std::nullopt, py::arg("time_unit") = "s",
      py::arg("detection") = std::nullopt, py::arg("max_outliers") = std::nullopt,
      "The diagnosis of a calibration (diagnosis.hpp): {'verdict': ..., 'diagnostics': [...]}");
}

}  // namespace

void BindCalibration(py::module_& m) {
  m.def(
      "_result_from_state", [](const py::bytes& state) { return LoadState(std::string(state)); },
      py::arg("state"), "A CalibrationResult from its pickled state (pickle calls it)");
  py::class_<PyCalibration> cls(
      m, "CalibrationResult",
      "A calibration: p = K f + b + k2 * f**2 (docs/model.md), with its diagnosis (verdict, "
      "diagnostics) and the positions it was fitted to");
  BindResultAttributes(cls);
  BindResultMethods(cls);
  BindCalibrationFunctions(m);
}

}  // namespace accelcal::python
