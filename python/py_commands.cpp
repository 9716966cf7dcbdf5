// The tool's commands in-process (accelcal.cli): the arguments as the command line takes them,
// its standard output and error captured, the GIL released while it runs.
#include <string>
#include <utility>
#include <vector>

#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "commands.hpp"
#include "py_common.hpp"

namespace accelcal::python {

void BindCommands(py::module_& m) {
  m.def(
      "_run_command",
      [](std::vector<std::string> args) {
        std::string out, err;
        int status = 0;
        args.insert(args.begin(), "accelcal");
        {
          py::gil_scoped_release release;
          status = cli::RunCommandLineCaptured(args, &out, &err);
        }
        return py::make_tuple(status, py::bytes(out), py::bytes(err));
      },
      py::arg("args"),
      "Runs `accelcal ARGS...` in this process: (exit status, stdout, stderr), both bytes. "
      "accelcal.cli builds ARGS from keyword arguments");
}

}  // namespace accelcal::python
