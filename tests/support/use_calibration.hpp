#pragma once
// A calibration the reader accepted, used as the tool uses one: every export format and the HTML
// report. Expected refusals are swallowed: DataError from a format that cannot hold the
// calibration. Anything else propagates
// (the test or fuzz harness that calls this reports it). Shared by fuzz/fuzz_calibration_file.cpp,
// fuzz/fuzz_calibration_keys.cpp and tests/test_calibration_keys.cpp.
#include <stdexcept>
#include <string>

#include "accelcal/calibration_file.hpp"
#include "accelcal/error.hpp"
#include "accelcal/export.hpp"
#include "accelcal/report.hpp"

namespace accelcal::test {

inline void UseCalibration(const LoadedCalibration& calibration, const std::string& text,
                           const std::string& source) {
  for (const ExportFormat format : AllExportFormats()) {
    try {
      ExportCalibration(calibration, text, format);
    } catch (const DataError&) {
    }
  }
  // The report's plots never draw at a coordinate that is not a number (a value near 1e308
  // overflowed a plot's span, and every point went to "-nan").
  const std::string html = RenderReport({calibration, source, nullptr, {}});
  for (const char* bad : {"=\"nan\"", "=\"-nan\"", "=\"inf\"", "=\"-inf\""}) {
    if (html.find(bad) != std::string::npos) {
      throw std::runtime_error(std::string("the report drew a coordinate ") + bad);
    }
  }
}

// A calibration file's text as the fuzzers feed it: read, and when the reader accepts it, used.
inline void ReadAndUseCalibration(const std::string& text, const std::string& source) {
  LoadedCalibration calibration;
  try {
    calibration = ParseCalibrationJson(text, source);
  } catch (const InputError&) {
    return;
  }
  UseCalibration(calibration, text, source);
}

}  // namespace accelcal::test
