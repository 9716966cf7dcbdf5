// Python bindings (pybind11): the C++ API under the same names in snake_case, numpy arrays for
// readings and matrices, and the library's errors as Python exceptions with the CLI's messages.
// The package accelcal (python/accelcal/__init__.py) wraps calibrate and calibrate_log to turn the
// diagnosis (diagnosis.hpp) into Python warnings; everything else is used as bound here. The
// bindings are in py_calibration.cpp and py_files.cpp, what they share in py_common.
#include <exception>
#include <string>

#include <pybind11/pybind11.h>

#include "accelcal/error.hpp"
#include "accelcal/version.hpp"
#include "py_common.hpp"

namespace py = pybind11;
using namespace accelcal;

PYBIND11_MODULE(_accelcal, m) {
  m.doc() = "accelcal: calibration of triaxial accelerometers (C++ library bindings)";
  m.attr("__version__") = std::string(Version());
  static py::exception<InputError> input_error(m, "InputError", PyExc_ValueError);
  static py::exception<DataError> data_error(m, "DataError", PyExc_ValueError);
  input_error.attr("__doc__") =
      "A file or argument that cannot be read as what it should be (the message names the file, "
      "line and reason, as the command line's: exit status 3)";
  data_error.attr("__doc__") =
      "Data that were read but cannot give what was asked (no static interval, too few or "
      "degenerate positions), named as the command line names them";
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      input_error(e.what());
    } catch (const DataError& e) {
      data_error(e.what());
    }
  });

  python::BindCalibration(m);
  python::BindFilesAndLogs(m);
  python::BindCommands(m);
}
