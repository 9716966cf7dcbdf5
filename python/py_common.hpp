#pragma once
// What the binding's files share (py_common.cpp): numpy rows and the library's vectors, enum
// names, logs and static detections from arrays and dicts, diagnoses and model selections as
// dicts. Each py_*.cpp binds one part of the API (accelcal_python.cpp assembles the module).
#include <optional>
#include <string>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <nlohmann/json.hpp>

#include "accelcal/calibration_types.hpp"
#include "accelcal/diagnosis.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/model_selection.hpp"
#include "accelcal/positions.hpp"
#include "accelcal/static_detection.hpp"
#include "accelcal/time_axis.hpp"

namespace accelcal::python {

namespace py = pybind11;

using Rows = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

std::vector<Vec3> ToVectors(const Rows& rows);
Rows ToRows(const std::vector<Vec3>& v);
/// Averaged readings without sample counts or deviations.
std::vector<Position> PositionsOf(const Rows& rows);

/// The value of an enum named `text`, else ValueError "unknown WHAT 'TEXT'".
template <typename T>
T Parse(std::optional<T> value, const std::string& text, const char* what) {
  if (!value) throw py::value_error(std::string("unknown ") + what + " '" + text + "'");
  return *value;
}

/// A file name given as str, bytes or os.PathLike (pathlib.Path), as the library takes it;
/// TypeError naming `what` for anything else.
std::string PathString(const py::handle& path, const char* what);
/// A file name as Python's os names it: its bytes decoded as os.fsdecode does (a name that is not
/// UTF-8 keeps its bytes as surrogate escapes, so that it opens the same file).
py::str FileNameStr(const std::string& name);

/// A number as Python prints it.
std::string Number(double v);
/// Corrected specific force of every row (the quadratic model's failures name the row).
Rows Apply(const ModelParameters& params, const Rows& readings);
py::dict SummaryDict(const Summary& s);
/// The unit of gravity and of the result: given, or "g" when gravity is below 2.
ForceUnit UnitOf(const std::optional<std::string>& units, double gravity);
void CheckRate(std::optional<double> rate_hz);
/// A RawLog from arrays, every array checked first (InputError naming the argument).
RawLog LogFromArrays(const std::optional<Eigen::VectorXd>& time, const Rows& samples,
                     std::optional<double> rate_hz, const std::string& time_unit);
py::dict TimeAxisDict(const TimeAxis& a);
py::dict IntervalDict(const StaticInterval& i);
py::dict DetectionDict(const StaticDetectionResult& r, const RawLog& log);
/// The inverse of DetectionDict, its sample indices checked against a log of `samples` samples.
StaticDetectionResult DetectionFromDict(const py::dict& d, std::optional<std::size_t> samples);
py::list FindingsList(const Diagnosis& diagnosis);
py::dict DiagnosisDict(const Diagnosis& diagnosis);
py::dict SelectionDict(const ModelSelection& s);
/// A JSON value as the Python object json.loads makes of it.
py::object ToPython(const nlohmann::ordered_json& value);
StaticDetectionOptions DetectionOptions(double window_s, double min_static_s,
                                        double threshold_factor, double init_rest_s);
/// Column numbers (from 1) or header names: a list of str or int, or one comma-separated str.
std::vector<std::string> ColumnList(const py::handle& columns);
ReadOptions MakeReadOptions(const std::string& kind, std::vector<std::string> columns,
                            std::optional<double> rate_hz, const std::string& time_unit,
                            std::optional<double> instance, std::optional<std::string> topic,
                            std::optional<std::string> frame_id = std::nullopt);

/// The parts of the module (py_calibration.cpp, py_files.cpp, py_commands.cpp).
void BindCalibration(py::module_& m);
void BindFilesAndLogs(py::module_& m);
void BindCommands(py::module_& m);

}  // namespace accelcal::python
