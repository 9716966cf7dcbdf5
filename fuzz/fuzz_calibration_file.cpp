// libFuzzer harness: calibration files (calibration_file.hpp) and everything that reads them:
// every export format and the HTML report. Accepted failures: InputError (bad file), DataError
// (a format that cannot express the calibration).
#include <cstdint>
#include <string>

#include "accelcal/calibration_file.hpp"
#include "accelcal/error.hpp"
#include "support/use_calibration.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  accelcal::test::ReadAndUseCalibration(text, "fuzz.json");
  return 0;
}
