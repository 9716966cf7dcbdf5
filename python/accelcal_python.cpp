// Python bindings (pybind11): the C++ API under the same names in snake_case, numpy arrays for
// readings and matrices, and the library's errors as Python exceptions with the CLI's messages.
#include <optional>
#include <string>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "accelcal/calibrate.hpp"
#include "accelcal/calibration_file.hpp"
#include "accelcal/error.hpp"
#include "accelcal/export.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/report.hpp"
#include "accelcal/static_detection.hpp"

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

template <typename T>
T Parse(std::optional<T> value, const std::string& text, const char* what) {
  if (!value) throw py::value_error(std::string("unknown ") + what + " '" + text + "'");
  return *value;
}

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

CalibrationOptions Options(const std::string& model, const std::string& method,
                           const std::string& frame, double gravity, const std::string& estimator) {
  CalibrationOptions o;
  o.model = Parse(ModelKindFromString(model), model, "model");
  o.method = Parse(SolverMethodFromString(method), method, "method");
  o.frame = Parse(FrameFromString(frame), frame, "frame");
  o.gravity = gravity;
  o.estimator = Parse(EstimatorFromString(estimator), estimator, "estimator");
  if (auto why = o.Validate()) throw py::value_error(*why);
  return o;
}

py::dict IntervalDict(const StaticInterval& i) {
  py::dict d;
  d["begin"] = i.begin;
  d["end"] = i.end;
  d["t_begin"] = i.t_begin_s;
  d["t_end"] = i.t_end_s;
  d["mean"] = Eigen::Vector3d(i.mean);
  d["std"] = Eigen::Vector3d(i.std);
  return d;
}

RawLog LogFromArrays(const std::optional<Eigen::VectorXd>& time, const Rows& samples,
                     std::optional<double> rate_hz) {
  RawLog log;
  log.source = "<array>";
  log.samples = ToVectors(samples);
  if (time) {
    if (time->size() != samples.rows()) throw py::value_error("time and samples differ in length");
    log.time_s.assign(time->data(), time->data() + time->size());
  }
  log.line.resize(log.samples.size(), 0);
  log.rate_hz = rate_hz;
  if (!log.rate_hz && log.time_s.size() >= 2) {
    log.rate_hz =
        static_cast<double>(log.time_s.size() - 1) / (log.time_s.back() - log.time_s.front());
  }
  return log;
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

  py::class_<CalibrationResult>(m, "CalibrationResult",
                                "A calibration: p = K f + b + k2 * f**2 (docs/model.md)")
      .def_property_readonly(
          "model", [](const CalibrationResult& r) { return std::string(ToString(r.model)); })
      .def_property_readonly(
          "frame", [](const CalibrationResult& r) { return std::string(ToString(r.frame)); })
      .def_readonly("gravity", &CalibrationResult::gravity)
      .def_property_readonly("K", [](const CalibrationResult& r) { return Mat33(r.params.K); })
      .def_property_readonly("bias", [](const CalibrationResult& r) { return Vec3(r.params.bias); })
      .def_property_readonly("k2", [](const CalibrationResult& r) { return Vec3(r.params.k2); })
      .def_property_readonly("covariance",
                             [](const CalibrationResult& r) -> std::optional<Eigen::MatrixXd> {
                               if (r.covariance.size() == 0) return std::nullopt;
                               return r.covariance;
                             })
      .def_property_readonly("parameter_names",
                             [](const CalibrationResult& r) {
                               std::vector<std::string> names;
                               for (const ParameterSlot& s : ParameterSlots(r.model, r.frame))
                                 names.emplace_back(s.name);
                               return names;
                             })
      .def_property_readonly("directions",
                             [](const CalibrationResult& r) { return ToRows(r.directions); })
      .def_property_readonly("residuals",
                             [](const CalibrationResult& r) { return ToRows(r.residuals); })
      .def_readonly("residual_sigma", &CalibrationResult::residual_sigma)
      .def_readonly("degrees_of_freedom", &CalibrationResult::degrees_of_freedom)
      .def_readonly("crossval_rms", &CalibrationResult::crossval_rms)
      .def_readonly("crossval_errors", &CalibrationResult::crossval_errors)
      .def_readonly("crossval_note", &CalibrationResult::crossval_note)
      .def_property_readonly("outliers",
                             [](const CalibrationResult& r) {
                               py::list list;
                               for (const OutlierFinding& o : r.outliers) {
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
                             })
      .def_readonly("outlier_note", &CalibrationResult::outlier_note)
      .def_property_readonly("summary",
                             [](const CalibrationResult& r) { return SummaryDict(r.summary); })
      .def(
          "apply",
          [](const CalibrationResult& r, const Rows& readings) {
            return Apply(r.params, readings);
          },
          py::arg("readings"), "Corrected specific force (n x 3) of raw readings (n x 3)")
      .def(
          "to_json",
          [](const CalibrationResult& r, const Rows& positions, const std::string& units,
             const std::string& raw_units, const std::string& source) {
            CalibrationFileInfo info;
            info.unit = Parse(ForceUnitFromString(units), units, "units");
            info.raw_unit = raw_units;
            info.source = source;
            for (const Vec3& p : ToVectors(positions))
              info.positions.push_back(Position{p, 1, std::nullopt, std::nullopt});
            return CalibrationToJson(r, info);
          },
          py::arg("positions"), py::arg("units") = "m/s2", py::arg("raw_units") = "raw",
          py::arg("source") = "", "The calibration file (JSON text) for the fitted positions");

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
         std::optional<Rows> reading_sigmas, bool cross_validate, const std::string& outliers) {
        CalibrationOptions o = Options(model, method, frame, gravity, estimator);
        o.outliers.policy = Parse(OutlierPolicyFromString(outliers), outliers, "outliers");
        if (reading_sigmas) o.reading_sigmas = ToVectors(*reading_sigmas);
        const std::vector<Vec3> r = ToVectors(readings);
        CalibrationResult result = Calibrate(r, o);
        if (cross_validate) CrossValidate(r, o, &result);
        return result;
      },
      py::arg("readings"), py::arg("model") = "linear", py::arg("method") = "joint",
      py::arg("frame") = "x-first", py::arg("gravity") = kStandardGravity_ms2,
      py::arg("estimator") = "ml", py::arg("reading_sigmas") = std::nullopt,
      py::arg("cross_validate") = true, py::arg("outliers") = "exclude",
      "Calibrates from averaged readings (m x 3), one per static position; outliers: exclude, "
      "flag or off (positions that disagree with the others, calibrate.hpp OutlierPolicy)");

  m.def(
      "read_input",
      [](const std::string& path, const std::string& kind, std::vector<std::string> columns,
         std::optional<double> rate_hz) {
        ReadOptions o;
        o.kind = Parse(InputKindFromString(kind), kind, "input kind");
        o.columns = std::move(columns);
        o.rate_hz = rate_hz;
        const InputData data = ReadInput(path, o);
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
          d["samples"] = ToRows(data.raw.samples);
          d["rate_hz"] = data.raw.rate_hz;
        } else {
          d["positions"] = ToRows(Means(data.positions));
        }
        return d;
      },
      py::arg("path"), py::arg("kind") = "auto", py::arg("columns") = std::vector<std::string>{},
      py::arg("rate_hz") = std::nullopt, "Reads a raw log or a positions file");

  m.def(
      "detect_static_intervals",
      [](const Rows& samples, std::optional<Eigen::VectorXd> time, std::optional<double> rate_hz,
         double window_s, double min_static_s, double threshold_factor, double init_rest_s) {
        const RawLog log = LogFromArrays(time, samples, rate_hz);
        StaticDetectionOptions o;
        o.window_s = window_s;
        o.min_duration_s = min_static_s;
        o.threshold_factor = threshold_factor;
        o.init_rest_s = init_rest_s;
        if (auto why = o.Validate()) throw py::value_error(*why);
        const StaticDetectionResult r = DetectStaticIntervals(log, o);
        py::list intervals, rejected;
        for (const StaticInterval& i : r.intervals) intervals.append(IntervalDict(i));
        for (const RejectedInterval& x : r.rejected) {
          py::dict d;
          d["t_begin"] = x.t_begin_s;
          d["t_end"] = x.t_end_s;
          d["reason"] = x.reason;
          rejected.append(d);
        }
        py::dict d;
        d["intervals"] = intervals;
        d["rejected"] = rejected;
        d["threshold"] = r.threshold;
        d["rate_hz"] = r.rate_hz;
        return d;
      },
      py::arg("samples"), py::arg("time") = std::nullopt, py::arg("rate_hz") = std::nullopt,
      py::arg("window_s") = 0.5, py::arg("min_static_s") = 1.0, py::arg("threshold_factor") = 10.0,
      py::arg("init_rest_s") = 0.0, "Static intervals of a raw log (static_detection.hpp)");

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
         std::optional<Eigen::VectorXd> time, std::optional<double> rate_hz) {
        ReportInput input;
        input.calibration_json = json_text;
        input.calibration_name = "<calibration>";
        RawLog log;
        if (samples) {
          log = LogFromArrays(time, *samples, rate_hz);
          input.log = &log;
        }
        return RenderReport(input);
      },
      py::arg("json_text"), py::arg("samples") = std::nullopt, py::arg("time") = std::nullopt,
      py::arg("rate_hz") = std::nullopt, "The HTML report (report.hpp)");
}
