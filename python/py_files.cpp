// Python's calibration files (Calibration, parse/load, export, report) and logs (read_input,
// detect_static_intervals).
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
#include "accelcal/sensor_parameters.hpp"
#include "accelcal/static_detection.hpp"
#include "accelcal/time_axis.hpp"

namespace accelcal::python {

namespace {

// Python's Calibration: a file read, with its text (what it pickles as) and name.
struct PyLoadedCalibration : LoadedCalibration {
  std::string text, name;
};

PyLoadedCalibration LoadCalibrationText(std::string text, std::string name) {
  PyLoadedCalibration c;
  static_cast<LoadedCalibration&>(c) = ParseCalibrationJson(text, name);
  c.text = std::move(text);
  c.name = std::move(name);
  return c;
}

// Calibration, a calibration file as read, and the functions that read one.
void BindCalibrationFiles(py::module_& m) {
  py::class_<PyLoadedCalibration>(
      m, "Calibration",
      "A calibration read from its file (load_calibration, parse_calibration_json): the "
      "accelerometer's model and parameters, what made it, and the file's text (pickled as that "
      "text)")
      .def_property_readonly(
          "model", [](const PyLoadedCalibration& c) { return std::string(ToString(c.model)); },
          "'linear' or 'quadratic'")
      .def_property_readonly(
          "frame", [](const PyLoadedCalibration& c) { return std::string(ToString(c.frame)); },
          "'x-first', 'z-first' or 'platform'")
      .def_readonly("gravity", &LoadedCalibration::gravity,
                    "The magnitude of gravity of the fit, in units")
      .def_property_readonly(
          "units", [](const PyLoadedCalibration& c) { return std::string(ToString(c.unit)); },
          "The unit of gravity and of the calibrated specific force: 'm/s2' or 'g'")
      .def_readonly("raw_units", &LoadedCalibration::raw_unit,
                    "The label of the raw readings' unit (units.raw)")
      .def_property_readonly(
          "K", [](const PyLoadedCalibration& c) { return Mat33(c.params.K); },
          "K (3 x 3) [raw per unit of specific force]")
      .def_property_readonly(
          "bias", [](const PyLoadedCalibration& c) { return Vec3(c.params.bias); }, "b (3) [raw]")
      .def_property_readonly(
          "k2", [](const PyLoadedCalibration& c) { return Vec3(c.params.k2); },
          "k2 (3) [raw per unit squared] (zeros for the linear model)")
      .def_property_readonly(
          "covariance",
          [](const PyLoadedCalibration& c) -> std::optional<Eigen::MatrixXd> {
            if (c.covariance.size() == 0) return std::nullopt;
            return c.covariance;
          },
          "The parameters' covariance in parameter_names' order, or None (a file without one)")
      .def_property_readonly(
          "parameter_names",
          [](const PyLoadedCalibration& c) {
            std::vector<std::string> names;
            for (const SensorParameter& p : ListParameters(c.params, c.model, c.frame))
              names.emplace_back(p.name);
            return names;
          },
          "The names of the covariance's rows (K_xx, b_x, ...)")
      .def_property_readonly(
          "has_gyroscope", [](const PyLoadedCalibration& c) { return c.has_gyroscope(); },
          "Whether the file holds a gyroscope's calibration (sensors.gyroscope)")
      .def_readonly("version", &LoadedCalibration::version, "The file's format version (1 or 2)")
      .def_readonly("verdict", &LoadedCalibration::verdict,
                    "\"ok\", \"warnings\" or \"failed\" ('' in files older than diagnoses)")
      .def_readonly("source", &LoadedCalibration::source, "The calibrated input's name")
      .def_property_readonly(
          "provenance",
          [](const PyLoadedCalibration& c) -> py::object {
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
          [](const PyLoadedCalibration& c, const Rows& readings) {
            return Apply(c.params, readings);
          },
          py::arg("readings"),
          "Corrected specific force (n x 3) of raw readings (n x 3), in the file's units")
      .def_property_readonly(
          "text", [](const PyLoadedCalibration& c) { return c.text; },
          "The calibration file's text, as read")
      // Pickled as the call that reads its text again (every protocol, 0 included).
      .def("__reduce__", [](const PyLoadedCalibration& c) {
        return py::make_tuple(py::module_::import("accelcal").attr("_restore_calibration"),
                              py::make_tuple(c.text, c.name));
      });

  m.def(
      "parse_calibration_json",
      [](const std::string& text, const std::string& source) {
        return LoadCalibrationText(text, source);
      },
      py::arg("text"), py::arg("source") = "<string>",
      "Reads a calibration file's text (accelcal calibrate -o); `source` names it in errors");
  m.def(
      "load_calibration",
      [](const py::object& path) {
        const std::string name = PathString(path, "load_calibration");
        std::string text;
        {
          py::gil_scoped_release release;
          text = ReadFileToString(name, kMaxSmallFileBytes);
        }
        return LoadCalibrationText(std::move(text), name);
      },
      py::arg("path"), "Reads a calibration file (accelcal calibrate -o FILE)");
}

// Logs read and cut into still intervals as the tool does.
void BindLogs(py::module_& m) {
  m.def(
      "read_input",
      [](const py::object& path_arg, const std::string& kind, const py::object& columns,
         std::optional<double> rate_hz, const std::string& time_unit,
         std::optional<double> instance, std::optional<std::string> topic,
         std::optional<std::string> frame_id) {
        const std::string path = PathString(path_arg, "read_input");
        const ReadOptions options =
            MakeReadOptions(kind, ColumnList(columns), rate_hz, time_unit, instance,
                            std::move(topic), std::move(frame_id));
        InputData data;
        {
          py::gil_scoped_release release;
          data = ReadInput(path, options);
        }
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
      py::arg("path"), py::arg("kind") = "auto", py::arg("columns") = py::tuple(),
      py::arg("rate_hz") = std::nullopt, py::kw_only(), py::arg("time_unit") = "auto",
      py::arg("instance") = std::nullopt, py::arg("topic") = std::nullopt,
      py::arg("frame_id") = std::nullopt,
      "Reads a raw log or a positions file (log_reader.hpp) as `accelcal calibrate` reads it.\n"
      "kind: 'auto', 'raw' or 'positions'; columns: 3 or 4 column numbers or header names; "
      "rate_hz: for logs without a time column (with one it must agree within 5 %); "
      "time_unit: 'auto', 's', 'ms', 'us' or 'ns' (time_axis.hpp); instance: the sensor to keep "
      "of a file whose instance column holds several (a ULog topic's multi id); topic: the "
      "stream of a binary log (a ULog topic, a DataFlash message, a bag's topic) or a "
      "MAT-file's variable; frame_id: of a ROS topic on which several sensors publish, the "
      "header.frame_id whose messages to read. path '-' reads this process's standard input.\n"
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
        StaticDetectionResult found;
        {
          py::gil_scoped_release release;
          found = DetectStaticIntervals(log, o);
        }
        return DetectionDict(found, log);
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
}

// A calibration written in other formats, and its report.
void BindOutputs(py::module_& m) {
  m.def(
      "export_calibration",
      [](const std::string& json_text, const std::string& format,
         std::optional<std::string> raw_unit, std::optional<int> instance,
         std::optional<std::string> c_prefix) {
        const ExportFormat to = Parse(ExportFormatFromString(format), format, "export format");
        ExportOptions o;
        std::vector<std::string> given;  // an option the format has no use for is refused
        if (raw_unit) o.raw_unit = *raw_unit, given.push_back("raw_unit");
        if (instance) o.instance = instance, given.push_back("instance");
        if (c_prefix) o.c_prefix = *c_prefix, given.push_back("c_prefix");
        if (auto why = o.Validate(to, given)) throw OptionError(*why);
        const LoadedCalibration cal = ParseCalibrationJson(json_text, "<calibration>");
        const ExportResult e = ExportCalibration(cal, json_text, to, o);
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
      py::arg("json_text"), py::arg("format"), py::arg("raw_unit") = std::nullopt,
      py::arg("instance") = std::nullopt, py::arg("c_prefix") = std::nullopt,
      "A calibration in another tool's format (export.hpp)");

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
        py::gil_scoped_release release;
        return RenderReport(input);
      },
      py::arg("json_text"), py::arg("samples") = std::nullopt, py::arg("time") = std::nullopt,
      py::arg("rate_hz") = std::nullopt, py::kw_only(), py::arg("time_unit") = "s",
      "The HTML report (report.hpp) of a calibration file's text, with the raw signal when "
      "samples (and time or rate_hz, checked as for detect_static_intervals) are given");
}

}  // namespace

void BindFilesAndLogs(py::module_& m) {
  BindCalibrationFiles(m);
  BindLogs(m);
  BindOutputs(m);
}

}  // namespace accelcal::python
