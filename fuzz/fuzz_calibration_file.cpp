// libFuzzer harness: calibration files (calibration_file.hpp) and everything that reads them:
// every export format and the HTML report. Accepted failures: InputError (bad file), DataError
// (a format that cannot express the calibration).
#include <cstdint>
#include <string>

#include "accelcal/calibration_file.hpp"
#include "accelcal/error.hpp"
#include "accelcal/export.hpp"
#include "accelcal/report.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  accelcal::LoadedCalibration cal;
  try {
    cal = accelcal::ParseCalibrationJson(text, "fuzz.json");
  } catch (const accelcal::InputError&) {
    return 0;
  }
  for (const accelcal::ExportFormat format : accelcal::AllExportFormats()) {
    try {
      accelcal::ExportCalibration(cal, text, format);
    } catch (const accelcal::DataError&) {
    }
  }
  try {
    accelcal::RenderReport({text, "fuzz.json", nullptr, {}});
  } catch (const accelcal::InputError&) {
  }
  return 0;
}
