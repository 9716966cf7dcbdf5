// The binding's shared conversions (py_common.hpp).
#include "py_common.hpp"

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

namespace accelcal::python {

std::string PathString(const py::handle& path, const char* what) {
  const py::module_ os = py::module_::import("os");
  py::object name;
  try {
    // The file system's bytes, as open() takes them (a name that is not UTF-8 included).
    name = os.attr("fsencode")(os.attr("fspath")(path));
  } catch (py::error_already_set& e) {
    if (!e.matches(PyExc_TypeError)) throw;
    throw py::type_error(std::string(what) + ": a file name (str, bytes or os.PathLike), not " +
                         py::str(py::type::handle_of(path).attr("__name__")).cast<std::string>());
  }
  std::string bytes = name.cast<std::string>();
  // As open(): a NUL would end the name the system sees, and another file would be read.
  if (bytes.find('\0') != std::string::npos) {
    throw py::value_error(std::string(what) + ": embedded null byte in the file name");
  }
  return bytes;
}

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
py::str FileNameStr(const std::string& name) {
  PyObject* text =
      PyUnicode_DecodeFSDefaultAndSize(name.data(), static_cast<Py_ssize_t>(name.size()));
  if (text == nullptr) throw py::error_already_set();
  return py::reinterpret_steal<py::str>(text);
}

std::vector<Position> PositionsOf(const Rows& rows) {
  std::vector<Position> positions;
  for (const Vec3& p : ToVectors(rows)) {
    if (!p.allFinite()) {  // a file of them could not be read back
      throw py::value_error("positions: row " + std::to_string(positions.size()) +
                            " is not finite");
    }
    positions.push_back(Position{p, 1, std::nullopt, std::nullopt, std::nullopt});
  }
  return positions;
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
  // Position numbers, from 1, as the file and the tool count them.
  std::vector<int> used;
  for (const int k : s.positions_used) used.push_back(k + 1);
  d["positions_used"] = used;
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

// A JSON value as the Python object json.loads makes of it.
py::object ToPython(const nlohmann::ordered_json& value) {
  return py::module_::import("json").attr("loads")(value.dump());
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

std::vector<std::string> ColumnList(const py::handle& columns) {
  std::vector<std::string> list;
  if (columns.is_none()) return list;
  if (py::isinstance<py::str>(columns)) {  // "t,x,y,z", as the command line takes it
    std::string text = columns.cast<std::string>();
    std::size_t start = 0;
    while (true) {
      const std::size_t comma = text.find(',', start);
      list.push_back(text.substr(start, comma - start));
      if (comma == std::string::npos) break;
      start = comma + 1;
    }
    return list;
  }
  for (const py::handle item : py::iter(columns)) {
    if (py::isinstance<py::str>(item)) {
      list.push_back(item.cast<std::string>());
    } else if (py::isinstance<py::int_>(item) && !py::isinstance<py::bool_>(item)) {
      list.push_back(py::str(item).cast<std::string>());  // a 1-based column number
    } else {
      throw py::type_error("columns: column numbers (from 1) or header names, not " +
                           py::str(py::type::handle_of(item).attr("__name__")).cast<std::string>());
    }
  }
  return list;
}

ReadOptions MakeReadOptions(const std::string& kind, std::vector<std::string> columns,
                            std::optional<double> rate_hz, const std::string& time_unit,
                            std::optional<double> instance, std::optional<std::string> topic,
                            std::optional<std::string> frame_id) {
  ReadOptions o;
  o.kind = Parse(InputKindFromString(kind), kind, "input kind");
  o.columns = std::move(columns);
  if (topic) {
    if (topic->empty()) throw py::value_error("topic: an empty name");
    o.topic = *topic;
  }
  if (frame_id) {
    if (frame_id->empty()) throw py::value_error("frame_id: an empty name");
    o.frame_id = *frame_id;
  }
  CheckRate(rate_hz);
  o.rate_hz = rate_hz;
  o.time_unit = Parse(TimeUnitFromString(time_unit), time_unit, "time unit");
  if (instance && !std::isfinite(*instance)) throw py::value_error("instance must be finite");
  o.instance = instance;
  return o;
}

}  // namespace accelcal::python
