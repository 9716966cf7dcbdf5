// Python bindings (pybind11): the C++ API under the same names in snake_case, numpy arrays for
// readings and matrices, and the library's errors as Python exceptions with the CLI's messages.
// The package accelcal (python/accelcal/__init__.py) wraps calibrate and calibrate_log to turn the
// diagnosis (diagnosis.hpp) into Python warnings; everything else is used as bound here.
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
#include "accelcal/calibration_file.hpp"
#include "accelcal/diagnosis.hpp"
#include "accelcal/error.hpp"
#include "accelcal/export.hpp"
#include "accelcal/load_positions.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/model_selection.hpp"
#include "accelcal/report.hpp"
#include "accelcal/static_detection.hpp"
#include "accelcal/time_axis.hpp"

namespace py = pybind11;
using namespace accelcal;

namespace {

using Rows = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

std::vector<Vec3> ToVectors(const Rows& rows) {
  std::vector<Vec3> v(static_cast<std::size_t>(rows.rows()));
  for (Eigen::Index k = 0; k < rows.rows(); ++k)
    v[static_cast<std::size_t>(k)] = rows.row(k).transpose();
  return v;
}
Rows ToRows(const std::vector<Vec3>& v) {
  Rows rows(static_cast<Eigen::Index>(v.size()), 3);
  for (std::size_t k = 0; k < v.size(); ++k)
    rows.row(static_cast<Eigen::Index>(k)) = v[k].transpose();
  return rows;
}
// Positions known only by their averaged reading (one sample, no standard deviation).
std::vector<Position> PositionsOf(const Rows& rows) {
  std::vector<Position> positions;
  for (const Vec3& p : ToVectors(rows))
    positions.push_back(Position{p, 1, std::nullopt, std::nullopt});
  return positions;
}

template <typename T>
T Parse(std::optional<T> value, const std::string& text, const char* what) {
  if (!value) throw py::value_error(std::string("unknown ") + what + " '" + text + "'");
  return *value;
}

std::string Number(double v) { return py::str(py::float_(v)).cast<std::string>(); }

// Corrected specific force of every row; a reading the quadratic model cannot invert is an error
// naming its row, as `accelcal apply` names its line.
Rows Apply(const ModelParameters& params, const Rows& readings) {
  Rows f(readings.rows(), 3);
  for (Eigen::Index k = 0; k < readings.rows(); ++k) {
    const std::optional<Vec3> v = SpecificForce(params, Vec3(readings.row(k).transpose()));
    if (!v) {
      throw DataError("row " + std::to_string(k) +
                      ": the reading lies outside the range the quadratic model can invert");
    }
    f.row(k) = v->transpose();
  }
  return f;
}

py::dict SummaryDict(const Summary& s) {
  py::dict d;
  d["method"] = std::string(ToString(s.method));
  d["estimator"] = std::string(ToString(s.estimator));
  d["initialization"] = std::string(ToString(s.initialization));
  d["initialization_note"] = s.initialization_note;
  d["iterations"] = s.iterations;
  d["converged"] = s.converged();
  d["termination"] = std::string(ToString(s.termination));
  d["termination_message"] = s.termination_message;
  d["initial_cost"] = s.initial_cost;
  d["final_cost"] = s.final_cost;
  d["time_s"] = s.time_s;
  d["brief_report"] = s.BriefReport();
  return d;
}

// ---------------------------------------------------------------------------------------------
// Raw logs from arrays: validated here so that any array gives a result or a clean exception.

// The unit of gravity and of the result: given, or "g" when gravity is below 2 (a gravity in g is
// about 1, one in m/s² about 9.8), else "m/s2".
ForceUnit UnitOf(const std::optional<std::string>& units, double gravity) {
  if (units) return Parse(ForceUnitFromString(*units), *units, "units");
  return gravity < 2.0 ? ForceUnit::kStandardGravity : ForceUnit::kMetersPerSecond2;
}

void CheckRate(std::optional<double> rate_hz) {
  if (rate_hz && !(std::isfinite(*rate_hz) && *rate_hz > 0)) {
    throw InputError(
        "rate_hz", 0,
        "the sample rate must be a positive, finite number of Hz, got " + Number(*rate_hz));
  }
}

// A RawLog as ReadInput makes one from a file: the time axis by MakeTimeAxis (unit, rate per
// segment, gaps), a given rate checked against it. Every array is checked first: samples finite,
// time finite and non-decreasing and as long as the samples, rate positive and finite; the errors
// (InputError) name the argument and the first bad index.
RawLog LogFromArrays(const std::optional<Eigen::VectorXd>& time, const Rows& samples,
                     std::optional<double> rate_hz, const std::string& time_unit) {
  const TimeUnit unit = Parse(TimeUnitFromString(time_unit), time_unit, "time unit");
  CheckRate(rate_hz);
  for (Eigen::Index i = 0; i < samples.rows(); ++i) {
    if (!samples.row(i).allFinite()) {
      throw InputError("samples", 0,
                       "row " + std::to_string(i) + " is not finite (" + Number(samples(i, 0)) +
                           ", " + Number(samples(i, 1)) + ", " + Number(samples(i, 2)) + ")");
    }
  }
  RawLog log;
  log.source = "<array>";
  log.samples = ToVectors(samples);
  log.line.resize(log.samples.size(), 0);
  log.rate_hz = rate_hz;
  if (!time) return log;
  const Eigen::VectorXd& t = *time;
  if (t.size() != samples.rows()) {
    throw InputError("time", 0,
                     std::to_string(t.size()) + " timestamps for " +
                         std::to_string(samples.rows()) + " samples: they must match");
  }
  for (Eigen::Index i = 0; i < t.size(); ++i) {
    if (!std::isfinite(t(i))) {
      throw InputError("time", 0,
                       "time[" + std::to_string(i) + "] is not finite (" + Number(t(i)) + ")");
    }
    if (i > 0 && t(i) < t(i - 1)) {
      throw InputError("time", 0,
                       "time[" + std::to_string(i) + "] = " + Number(t(i)) + " is before time[" +
                           std::to_string(i - 1) + "] = " + Number(t(i - 1)) +
                           ": timestamps must not decrease");
    }
  }
  log.time_s.assign(t.data(), t.data() + t.size());
  try {
    log.time = MakeTimeAxis(&log.time_s, unit, "");
  } catch (const DataError& e) {
    throw InputError("time", 0, e.what());
  }
  log.rate_hz = log.time->rate_hz;
  if (rate_hz) {
    if (std::abs(*rate_hz / log.time->rate_hz - 1) > kRateTolerance) {
      throw InputError("rate_hz", 0,
                       "the given rate " + Number(*rate_hz) +
                           " Hz contradicts the time array, whose timestamps come at " +
                           Number(log.time->rate_hz) + " Hz");
    }
    log.rate_hz = rate_hz;
  }
  return log;
}

py::dict TimeAxisDict(const TimeAxis& a) {
  py::dict d;
  d["unit"] = std::string(ToString(a.unit));
  d["unit_reason"] = a.unit_reason;
  d["origin_s"] = a.origin_s;
  d["typical_step_s"] = a.typical_step_s;
  d["rate_hz"] = a.rate_hz;
  py::list gaps;
  for (const TimeGap& g : a.gaps) gaps.append(py::make_tuple(g.index, g.t_before_s, g.t_after_s));
  d["gaps"] = gaps;
  d["resolution_s"] = a.resolution_s;
  d["repeated_fraction"] = a.repeated_fraction;
  d["irregular_fraction"] = a.irregular_fraction;
  return d;
}

const char* CauseName(RejectedInterval::Cause cause) {
  switch (cause) {
    case RejectedInterval::Cause::kTooShort:
      return "too_short";
    case RejectedInterval::Cause::kClipped:
      return "clipped";
    case RejectedInterval::Cause::kMoving:
      break;
  }
  return "moving";
}
RejectedInterval::Cause CauseFromName(const std::string& name) {
  for (RejectedInterval::Cause c :
       {RejectedInterval::Cause::kTooShort, RejectedInterval::Cause::kClipped,
        RejectedInterval::Cause::kMoving}) {
    if (name == CauseName(c)) return c;
  }
  throw py::value_error("unknown rejected-period cause '" + name +
                        "' (too_short, clipped, moving)");
}

py::dict IntervalDict(const StaticInterval& i) {
  py::dict d;
  d["begin"] = i.begin;
  d["end"] = i.end;
  d["samples"] = i.count();
  d["t_begin"] = i.t_begin_s;
  d["t_end"] = i.t_end_s;
  d["mean"] = Eigen::Vector3d(i.mean);
  d["std"] = Eigen::Vector3d(i.std);
  return d;
}

py::dict DetectionDict(const StaticDetectionResult& r, const RawLog& log) {
  py::list intervals, rejected;
  for (const StaticInterval& i : r.intervals) intervals.append(IntervalDict(i));
  for (const RejectedInterval& x : r.rejected) {
    py::dict d;
    d["begin"] = x.begin;
    d["end"] = x.end;
    d["t_begin"] = x.t_begin_s;
    d["t_end"] = x.t_end_s;
    d["cause"] = CauseName(x.cause);
    d["reason"] = x.reason;
    rejected.append(d);
  }
  py::dict d;
  d["intervals"] = intervals;
  d["rejected"] = rejected;
  d["threshold"] = r.threshold;
  d["noise_reference"] = r.noise_reference;
  d["rate_hz"] = r.rate_hz;
  d["window_samples"] = r.window_samples;
  d["quantisation_step"] = Eigen::Vector3d(r.quantisation_step);
  d["segments"] = r.segments;
  d["joined"] = r.joined;
  d["time_axis"] = log.time ? py::object(TimeAxisDict(*log.time)) : py::none();
  return d;
}

StaticDetectionResult DetectionFromDictUnchecked(const py::dict& d,
                                                 std::optional<std::size_t> samples);

// The inverse of DetectionDict (what Diagnose reads of it), its sample indices checked against a
// log of `samples` samples. A dict that is not such a result (a key missing, a value of another
// type) is a ValueError naming what is wrong, not a KeyError or a RuntimeError from a cast.
StaticDetectionResult DetectionFromDict(const py::dict& d, std::optional<std::size_t> samples) {
  try {
    return DetectionFromDictUnchecked(d, samples);
  } catch (const py::error_already_set& e) {
    if (!e.matches(PyExc_KeyError) && !e.matches(PyExc_TypeError) && !e.matches(PyExc_IndexError)) {
      throw;
    }
    throw py::value_error(std::string("detection: not a result of detect_static_intervals (") +
                          e.what() + ")");
  } catch (const py::cast_error& e) {
    throw py::value_error(std::string("detection: not a result of detect_static_intervals (") +
                          e.what() + ")");
  }
}

StaticDetectionResult DetectionFromDictUnchecked(const py::dict& d,
                                                 std::optional<std::size_t> samples) {
  StaticDetectionResult r;
  const auto index = [&](const py::handle& item, const char* key) {
    const long long v = item[key].cast<long long>();
    if (v < 0 || (samples && static_cast<std::size_t>(v) > *samples)) {
      throw py::value_error(std::string("detection: interval ") + key + " " + std::to_string(v) +
                            " lies outside the " +
                            (samples ? std::to_string(*samples) + " samples" : "log"));
    }
    return static_cast<std::size_t>(v);
  };
  for (const py::handle& item : d["intervals"].cast<py::list>()) {
    StaticInterval s;
    s.begin = index(item, "begin");
    s.end = index(item, "end");
    if (s.end < s.begin) throw py::value_error("detection: an interval ends before it begins");
    s.t_begin_s = item["t_begin"].cast<double>();
    s.t_end_s = item["t_end"].cast<double>();
    s.mean = item["mean"].cast<Eigen::Vector3d>();
    s.std = item["std"].cast<Eigen::Vector3d>();
    const std::size_t count = item["samples"].cast<std::size_t>();
    s.averaged = count == s.end - s.begin ? 0 : count;
    r.intervals.push_back(s);
  }
  for (const py::handle& item : d["rejected"].cast<py::list>()) {
    RejectedInterval x;
    x.begin = index(item, "begin");
    x.end = index(item, "end");
    x.t_begin_s = item["t_begin"].cast<double>();
    x.t_end_s = item["t_end"].cast<double>();
    x.cause = CauseFromName(item["cause"].cast<std::string>());
    x.reason = item["reason"].cast<std::string>();
    r.rejected.push_back(x);
  }
  if (d.contains("joined")) r.joined = d["joined"].cast<std::size_t>();
  return r;
}

// ---------------------------------------------------------------------------------------------
// Calibration as the command line does it, and its diagnosis.

// A calibration with what it was fitted to and its diagnosis: Python's CalibrationResult.
struct PyCalibration {
  CalibrationResult result;
  std::optional<ModelSelection> selection;  // model "auto", or "quadratic" with held-out errors
  std::string model_requested;
  ForceUnit unit = ForceUnit::kMetersPerSecond2;
  std::vector<Position> positions;  // the fitted positions, in the result's order
  std::string source;               // the input file, "" from arrays
  int max_excluded = OutlierOptions{}.max_excluded;
  Diagnosis diagnosis;
  Provenance provenance;  // the function and its arguments, the file read (to_json writes it)
};

py::list FindingsList(const Diagnosis& diagnosis) {
  py::list list;
  for (const Finding& f : diagnosis.findings) {
    py::dict numbers;
    for (const auto& [name, value] : f.numbers) numbers[py::str(name)] = value;
    py::dict d;
    d["code"] = f.code;
    d["severity"] = std::string(ToString(f.severity));
    d["message"] = f.message;
    d["numbers"] = numbers;
    list.append(d);
  }
  return list;
}

py::dict DiagnosisDict(const Diagnosis& diagnosis) {
  py::dict d;
  d["verdict"] = std::string(ToString(diagnosis.verdict()));
  d["diagnostics"] = FindingsList(diagnosis);
  return d;
}

py::dict SelectionDict(const ModelSelection& s) {
  py::dict d;
  d["chosen"] = std::string(ToString(s.chosen));
  d["reason"] = s.reason;
  d["screened_with"] = std::string(ToString(s.screened_with));
  d["positions_used"] = s.positions_used;  // 0-based
  d["linear_crossval_rms"] = s.linear.crossval_rms;
  d["quadratic_crossval_rms"] =
      s.quadratic ? py::object(py::cast(s.quadratic->crossval_rms)) : py::none();
  d["quadratic_error"] = s.quadratic_error;
  d["k2_t"] = Eigen::Vector3d(s.k2_t);
  d["k2_t_threshold"] = s.k2_t_threshold;
  d["improvement"] = s.improvement;
  d["improvement_se"] = s.improvement_se;
  d["improvement_threshold"] = s.improvement_threshold;
  return d;
}

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

// A JSON value as the Python object json.loads makes of it.
py::object ToPython(const nlohmann::ordered_json& value) {
  return py::module_::import("json").attr("loads")(value.dump());
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
  if (auto why = o.Validate()) throw py::value_error(*why);
  if (auto_model) {
    if (!s.cross_validate) {
      throw py::value_error("model 'auto' decides on held-out error: it needs cross_validate=True");
    }
    CalibrationOptions quadratic = o;
    quadratic.model = ModelKind::kQuadratic;
    if (auto why = quadratic.Validate()) throw py::value_error("model 'auto': " + *why);
  }
  UnitOf(s.units, s.gravity);  // an unknown unit is an error before any work
  return o;
}

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
  ModelChoice choice = CalibrateChoosingModel(means, options, s.model == "auto");
  c.result = std::move(choice.result);
  c.selection = std::move(choice.selection);
  DiagnosisInput in;
  in.result = &c.result;
  in.positions = &c.positions;
  in.max_excluded = c.max_excluded;
  in.selection = c.selection ? &*c.selection : nullptr;
  // One log, so its findings are not prefixed with its name (the command line's for one file).
  if (log || detection) in.logs.push_back({c.source, log, detection});
  in.unit = c.unit;
  c.diagnosis = Diagnose(in);
  return c;
}

StaticDetectionOptions DetectionOptions(double window_s, double min_static_s,
                                        double threshold_factor, double init_rest_s) {
  StaticDetectionOptions o;
  o.window_s = window_s;
  o.min_duration_s = min_static_s;
  o.threshold_factor = threshold_factor;
  o.init_rest_s = init_rest_s;
  if (auto why = o.Validate()) throw py::value_error(*why);
  return o;
}

ReadOptions MakeReadOptions(const std::string& kind, std::vector<std::string> columns,
                            std::optional<double> rate_hz, const std::string& time_unit,
                            std::optional<double> instance) {
  ReadOptions o;
  o.kind = Parse(InputKindFromString(kind), kind, "input kind");
  o.columns = std::move(columns);
  CheckRate(rate_hz);
  o.rate_hz = rate_hz;
  o.time_unit = Parse(TimeUnitFromString(time_unit), time_unit, "time unit");
  if (instance && !std::isfinite(*instance)) throw py::value_error("instance must be finite");
  o.instance = instance;
  return o;
}

}  // namespace

PYBIND11_MODULE(_accelcal, m) {
  m.doc() = "accelcal: calibration of triaxial accelerometers (C++ library bindings)";
  static py::exception<InputError> input_error(m, "InputError", PyExc_ValueError);
  static py::exception<DataError> data_error(m, "DataError", PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      input_error(e.what());
    } catch (const DataError& e) {
      data_error(e.what());
    }
  });

  py::class_<PyCalibration>(
      m, "CalibrationResult",
      "A calibration: p = K f + b + k2 * f**2 (docs/model.md), with its diagnosis (verdict, "
      "diagnostics) and the positions it was fitted to")
      .def_property_readonly(
          "model", [](const PyCalibration& c) { return std::string(ToString(c.result.model)); })
      .def_property_readonly(
          "frame", [](const PyCalibration& c) { return std::string(ToString(c.result.frame)); })
      .def_property_readonly("gravity", [](const PyCalibration& c) { return c.result.gravity; })
      .def_property_readonly(
          "units", [](const PyCalibration& c) { return std::string(ToString(c.unit)); },
          "Unit of gravity and of the calibrated specific force: 'm/s2' or 'g'")
      .def_property_readonly("K", [](const PyCalibration& c) { return Mat33(c.result.params.K); })
      .def_property_readonly("bias",
                             [](const PyCalibration& c) { return Vec3(c.result.params.bias); })
      .def_property_readonly("k2", [](const PyCalibration& c) { return Vec3(c.result.params.k2); })
      .def_property_readonly("covariance",
                             [](const PyCalibration& c) -> std::optional<Eigen::MatrixXd> {
                               if (c.result.covariance.size() == 0) return std::nullopt;
                               return c.result.covariance;
                             })
      .def_property_readonly(
          "parameter_names",
          [](const PyCalibration& c) {
            std::vector<std::string> names;
            for (const ParameterSlot& s : ParameterSlots(c.result.model, c.result.frame))
              names.emplace_back(s.name);
            return names;
          })
      .def_property_readonly("directions",
                             [](const PyCalibration& c) { return ToRows(c.result.directions); })
      .def_property_readonly("residuals",
                             [](const PyCalibration& c) { return ToRows(c.result.residuals); })
      .def_property_readonly("residual_sigma",
                             [](const PyCalibration& c) { return c.result.residual_sigma; })
      .def_property_readonly("scatter_ratio",
                             [](const PyCalibration& c) { return c.result.scatter_ratio; })
      .def_property_readonly("degrees_of_freedom",
                             [](const PyCalibration& c) { return c.result.degrees_of_freedom; })
      .def_property_readonly("crossval_rms",
                             [](const PyCalibration& c) { return c.result.crossval_rms; })
      .def_property_readonly("crossval_errors",
                             [](const PyCalibration& c) { return c.result.crossval_errors; })
      .def_property_readonly("crossval_note",
                             [](const PyCalibration& c) { return c.result.crossval_note; })
      .def_property_readonly(
          "outliers",
          [](const PyCalibration& c) {
            py::list list;
            for (const OutlierFinding& o : c.result.outliers) {
              py::dict d;
              d["position"] = o.position;  // 0-based, as the readings' rows
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
          "Positions the screening found discordant: dicts whose 'position' is the 0-based row "
          "of the readings (the calibration file and the diagnostics count from 1)")
      .def_property_readonly("outlier_note",
                             [](const PyCalibration& c) { return c.result.outlier_note; })
      .def_property_readonly("summary",
                             [](const PyCalibration& c) { return SummaryDict(c.result.summary); })
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
          "errors support and why (model_selection.hpp; positions_used 0-based); else None")
      .def_property_readonly(
          "source", [](const PyCalibration& c) { return c.source; }, "The input file, or ''")
      .def(
          "apply",
          [](const PyCalibration& c, const Rows& readings) {
            return Apply(c.result.params, readings);
          },
          py::arg("readings"), "Corrected specific force (n x 3) of raw readings (n x 3)")
      .def(
          "to_json",
          [](const PyCalibration& c, std::optional<Rows> positions,
             std::optional<std::string> units, const std::string& raw_units,
             std::optional<std::string> source, std::optional<std::string> date) {
            CalibrationFileInfo info;
            info.unit = units ? Parse(ForceUnitFromString(*units), *units, "units") : c.unit;
            info.raw_unit = raw_units;
            info.source = source ? *source : c.source;
            if (positions) {
              if (static_cast<std::size_t>(positions->rows()) != c.result.directions.size()) {
                throw py::value_error("to_json: " + std::to_string(positions->rows()) +
                                      " positions for a calibration of " +
                                      std::to_string(c.result.directions.size()));
              }
              info.positions = PositionsOf(*positions);
            } else {
              info.positions = c.positions;
            }
            info.model_selection = c.selection ? &*c.selection : nullptr;
            info.model_requested = c.model_requested;
            // The stored diagnosis is of the fitted positions in the stored unit.
            if (!positions && info.unit == c.unit) info.diagnosis = &c.diagnosis;
            info.provenance = c.provenance;
            if (date) {
              if (const auto why = CheckProvenanceDate(*date))
                throw py::value_error("date: " + *why);
              info.provenance.date = *date;
            }
            return CalibrationToJson(c.result, info);
          },
          py::arg("positions") = std::nullopt, py::arg("units") = std::nullopt,
          py::arg("raw_units") = "raw", py::arg("source") = std::nullopt,
          py::arg("date") = std::nullopt,
          "The calibration file (JSON text, docs/calibration-file.md). By default of the fitted "
          "positions (with their sample counts and noise) in the result's units, with its "
          "diagnosis and source: for calibrate_log the same text as `accelcal calibrate LOG "
          "--json` but its provenance (the Python function, its arguments and the file's "
          "SHA-256). Other positions (m x 3) or units are diagnosed anew, without the log. "
          "`date` (YYYY-MM-DD[THH:MM[:SS]Z]) is written as the provenance's date; none without "
          "it.");

  py::class_<LoadedCalibration>(m, "Calibration", "A calibration read from its file")
      .def_property_readonly(
          "model", [](const LoadedCalibration& c) { return std::string(ToString(c.model)); })
      .def_property_readonly(
          "frame", [](const LoadedCalibration& c) { return std::string(ToString(c.frame)); })
      .def_readonly("gravity", &LoadedCalibration::gravity)
      .def_property_readonly(
          "units", [](const LoadedCalibration& c) { return std::string(ToString(c.unit)); })
      .def_readonly("raw_units", &LoadedCalibration::raw_unit)
      .def_property_readonly("K", [](const LoadedCalibration& c) { return Mat33(c.params.K); })
      .def_property_readonly("bias", [](const LoadedCalibration& c) { return Vec3(c.params.bias); })
      .def_property_readonly("k2", [](const LoadedCalibration& c) { return Vec3(c.params.k2); })
      .def_readonly("version", &LoadedCalibration::version, "The file's format version (1 or 2)")
      .def_readonly("verdict", &LoadedCalibration::verdict,
                    "\"ok\", \"warnings\" or \"failed\" ('' in files older than diagnoses)")
      .def_readonly("source", &LoadedCalibration::source, "The calibrated input's name")
      .def_property_readonly(
          "provenance",
          [](const LoadedCalibration& c) -> py::object {
            if (c.version < 2) return py::none();
            const Provenance& p = c.provenance;
            py::dict d;
            d["accelcal_version"] = p.accelcal_version;
            d["command"] = p.command;
            d["options"] = ToPython(p.options);
            py::list inputs;
            for (const InputRecord& i : p.inputs) {
              py::dict input;
              input["name"] = i.name;
              input["bytes"] = i.bytes;
              input["sha256"] = i.sha256;
              inputs.append(input);
            }
            d["inputs"] = inputs;
            d["date"] = p.date.empty() ? py::object(py::none()) : py::object(py::str(p.date));
            return d;
          },
          "What made the file (version 2; None for version 1): accelcal_version, command, "
          "options, inputs (name, bytes, sha256), date (None when none was given)")
      .def(
          "apply",
          [](const LoadedCalibration& c, const Rows& readings) {
            return Apply(c.params, readings);
          },
          py::arg("readings"));

  m.def("parse_calibration_json", &ParseCalibrationJson, py::arg("text"),
        py::arg("source") = "<string>", "Reads a calibration file's text (accelcal calibrate -o)");
  m.def(
      "load_calibration",
      [](const std::string& path) {
        return ParseCalibrationJson(ReadFileToString(path, kMaxSmallFileBytes), path);
      },
      py::arg("path"));

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
        PyCalibration c =
            Fit(PositionsOf(readings), std::move(sigmas), s, options, nullptr, nullptr, "");
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
      "calibrate_log",
      [](const std::string& path, const std::string& model, const std::string& method,
         const std::string& frame, double gravity, const std::string& estimator,
         std::vector<std::string> columns, std::optional<double> rate_hz, double window_s,
         double min_static_s, double threshold_factor, double init_rest_s, bool cross_validate,
         const std::string& outliers, double outlier_probability, int max_outliers,
         std::optional<std::string> units, const std::string& time_unit,
         std::optional<double> instance, const std::string& input_kind, int max_iterations) {
        const FitSettings s{model,        method,         frame,           gravity,
                            estimator,    cross_validate, outliers,        outlier_probability,
                            max_outliers, max_iterations, std::move(units)};
        // Every option is checked before the file is read, as the command line does.
        const StaticDetectionOptions detection_options =
            DetectionOptions(window_s, min_static_s, threshold_factor, init_rest_s);
        const CalibrationOptions options = MakeOptions(s);
        const ReadOptions read =
            MakeReadOptions(input_kind, std::move(columns), rate_hz, time_unit, instance);
        LoadOptions load;
        load.read = read;
        load.detection = detection_options;
        try {
          const LoadedInput in = LoadPositions({path}, load);
          const LoadedFile& file = in.files.front();
          const std::vector<Position>& positions = in.positions;
          const InputData& data = file.data;
          const std::optional<StaticDetectionResult>& detection = file.detection;
          std::vector<Vec3> sigmas = SigmasOfMeans(positions);  // empty: from the residuals
          PyCalibration c = Fit(positions, std::move(sigmas), s, options,
                                data.kind == InputKind::kRaw ? &data.raw : nullptr,
                                detection ? &*detection : nullptr, path);
          c.provenance.command = "accelcal Python calibrate_log";
          c.provenance.options = SettingsJson(s);
          nlohmann::ordered_json& o = c.provenance.options;
          o["columns"] = read.columns;
          o["rate_hz"] = rate_hz ? nlohmann::ordered_json(*rate_hz) : nlohmann::ordered_json();
          o["window_s"] = window_s;
          o["min_static_s"] = min_static_s;
          o["threshold_factor"] = threshold_factor;
          o["init_rest_s"] = init_rest_s;
          o["time_unit"] = time_unit;
          o["instance"] = instance ? nlohmann::ordered_json(*instance) : nlohmann::ordered_json();
          o["input_kind"] = input_kind;
          c.provenance.inputs = InputRecords(in);
          return py::make_tuple(std::move(c), ToRows(Means(positions)));
        } catch (const DataError& e) {
          throw DataError(path + ": " + e.what());  // as the command line names the input
        }
      },
      py::arg("path"), py::arg("model") = "linear", py::arg("method") = "joint",
      py::arg("frame") = "x-first", py::arg("gravity") = kStandardGravity_ms2,
      py::arg("estimator") = "ml", py::arg("columns") = std::vector<std::string>{},
      py::arg("rate_hz") = std::nullopt, py::arg("window_s") = 0.5, py::arg("min_static_s") = 1.0,
      py::arg("threshold_factor") = 10.0, py::arg("init_rest_s") = 0.0,
      py::arg("cross_validate") = true, py::kw_only(), py::arg("outliers") = "exclude",
      py::arg("outlier_probability") = 1e-3, py::arg("max_outliers") = 3,
      py::arg("units") = std::nullopt, py::arg("time_unit") = "auto",
      py::arg("instance") = std::nullopt, py::arg("input_kind") = "raw",
      py::arg("max_iterations") = 0,
      "What `accelcal calibrate INPUT` does, diagnosis included; returns (result, positions) "
      "(no Python warnings: accelcal.calibrate_log adds them)");

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

  m.def(
      "read_input",
      [](const std::string& path, const std::string& kind, std::vector<std::string> columns,
         std::optional<double> rate_hz, const std::string& time_unit,
         std::optional<double> instance) {
        const InputData data = ReadInput(
            path, MakeReadOptions(kind, std::move(columns), rate_hz, time_unit, instance));
        py::dict d;
        d["kind"] = data.kind == InputKind::kRaw ? "raw" : "positions";
        d["kind_reason"] = data.kind_reason;
        if (data.kind == InputKind::kRaw) {
          if (data.raw.time_s.empty()) {
            d["time"] = py::none();
          } else {
            d["time"] = Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(
                data.raw.time_s.data(), static_cast<Eigen::Index>(data.raw.time_s.size())));
          }
          d["time_axis"] = data.raw.time ? py::object(TimeAxisDict(*data.raw.time)) : py::none();
          d["samples"] = ToRows(data.raw.samples);
          d["rate_hz"] = data.raw.rate_hz;
        } else {
          d["positions"] = ToRows(Means(data.positions));
          std::vector<std::size_t> counts;
          bool have_std = true;
          Rows stds(static_cast<Eigen::Index>(data.positions.size()), 3);
          for (std::size_t k = 0; k < data.positions.size(); ++k) {
            counts.push_back(data.positions[k].samples);
            if (data.positions[k].std) {
              stds.row(static_cast<Eigen::Index>(k)) = data.positions[k].std->transpose();
            } else {
              have_std = false;
            }
          }
          d["counts"] = counts;
          d["stds"] = have_std ? py::object(py::cast(stds)) : py::none();
        }
        return d;
      },
      py::arg("path"), py::arg("kind") = "auto", py::arg("columns") = std::vector<std::string>{},
      py::arg("rate_hz") = std::nullopt, py::kw_only(), py::arg("time_unit") = "auto",
      py::arg("instance") = std::nullopt,
      "Reads a raw log or a positions file (log_reader.hpp) as `accelcal calibrate` reads it.\n"
      "kind: 'auto', 'raw' or 'positions'; columns: 3 or 4 column numbers or header names; "
      "rate_hz: for logs without a time column (with one it must agree within 5 %); "
      "time_unit: 'auto', 's', 'ms', 'us' or 'ns' (time_axis.hpp); instance: the sensor to keep "
      "of a file whose instance column holds several.\n"
      "A raw log gives {'kind', 'kind_reason', 'samples' (n x 3), 'time' (seconds from the first "
      "sample, or None), 'time_axis', 'rate_hz'}; time_axis is None without a time column, else "
      "{'unit', 'unit_reason', 'origin_s' (the first timestamp in s, as written), "
      "'typical_step_s', 'rate_hz', 'gaps' (a list of (index, t_before, t_after): index the "
      "0-based first sample after the gap, times in s from the first sample), 'resolution_s', "
      "'repeated_fraction', 'irregular_fraction'}. A positions file gives {'kind', "
      "'kind_reason', 'positions' (m x 3), 'counts' (samples per position, 1 when unknown), "
      "'stds' (m x 3 per-axis sample standard deviations, or None)}.");

  m.def(
      "detect_static_intervals",
      [](const Rows& samples, std::optional<Eigen::VectorXd> time, std::optional<double> rate_hz,
         double window_s, double min_static_s, double threshold_factor, double init_rest_s,
         const std::string& time_unit) {
        const StaticDetectionOptions o =
            DetectionOptions(window_s, min_static_s, threshold_factor, init_rest_s);
        const RawLog log = LogFromArrays(time, samples, rate_hz, time_unit);
        return DetectionDict(DetectStaticIntervals(log, o), log);
      },
      py::arg("samples"), py::arg("time") = std::nullopt, py::arg("rate_hz") = std::nullopt,
      py::arg("window_s") = 0.5, py::arg("min_static_s") = 1.0, py::arg("threshold_factor") = 10.0,
      py::arg("init_rest_s") = 0.0, py::kw_only(), py::arg("time_unit") = "s",
      "Static intervals of a raw log (static_detection.hpp), as for a file: the time array "
      "(in time_unit: 's', 'ms', 'us', 'ns' or 'auto') is read by the library's time axis, so a "
      "gap in it splits the detection and the rate is taken per segment; without time, rate_hz "
      "is required (with time, it must agree within 5 %). The arrays are checked first: samples "
      "finite, time finite, non-decreasing and as long as samples, rate_hz positive and finite "
      "(InputError naming the first bad index).\n"
      "Returns {'intervals': [{'begin', 'end' (0-based sample indices, end one past the last), "
      "'samples' (averaged), 't_begin', 't_end' [s], 'mean', 'std'}], 'rejected': [{'begin', "
      "'end', 't_begin', 't_end', 'cause' ('too_short', 'clipped' or 'moving'), 'reason'}], "
      "'threshold', 'noise_reference' [raw^2], 'rate_hz', 'window_samples', "
      "'quantisation_step', 'segments', 'joined', 'time_axis' (as read_input's, None without "
      "time)}.");

  m.def(
      "export_calibration",
      [](const std::string& json_text, const std::string& format, const std::string& raw_unit,
         int instance, const std::string& c_prefix) {
        const LoadedCalibration cal = ParseCalibrationJson(json_text, "<calibration>");
        ExportOptions o;
        o.raw_unit = raw_unit;
        o.instance = instance;
        o.c_prefix = c_prefix;
        const ExportResult e = ExportCalibration(
            cal, json_text, Parse(ExportFormatFromString(format), format, "export format"), o);
        py::dict loss;
        loss["dropped"] = e.loss.dropped;
        loss["positions"] = e.loss.positions;
        loss["max_error"] = e.loss.max_error;
        loss["rms_error"] = e.loss.rms_error;
        py::dict d;
        d["text"] = e.text;
        d["convention"] = e.convention;
        d["loss"] = loss;
        return d;
      },
      py::arg("json_text"), py::arg("format"), py::arg("raw_unit") = "", py::arg("instance") = 0,
      py::arg("c_prefix") = "accelcal", "A calibration in another tool's format (export.hpp)");

  m.def(
      "render_report",
      [](const std::string& json_text, std::optional<Rows> samples,
         std::optional<Eigen::VectorXd> time, std::optional<double> rate_hz,
         const std::string& time_unit) {
        ReportInput input;
        input.calibration_name = "<calibration>";
        RawLog log;
        if (samples) {
          log = LogFromArrays(time, *samples, rate_hz, time_unit);
          input.log = &log;
        }
        input.calibration = ParseCalibrationJson(json_text, input.calibration_name);
        return RenderReport(input);
      },
      py::arg("json_text"), py::arg("samples") = std::nullopt, py::arg("time") = std::nullopt,
      py::arg("rate_hz") = std::nullopt, py::kw_only(), py::arg("time_unit") = "s",
      "The HTML report (report.hpp) of a calibration file's text, with the raw signal when "
      "samples (and time or rate_hz, checked as for detect_static_intervals) are given");
}
