// libFuzzer harness: orientation files (orientation_file.hpp). Accepted failure: InputError.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "accelcal/error.hpp"
#include "accelcal/orientation_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const accelcal::OrientationFile f = accelcal::ParseOrientations(text, "fuzz.csv");
    for (const accelcal::Vec3& c : f.directions) {
      // Directions are unit vectors, or the file was refused.
      if (!c.allFinite() || std::abs(c.norm() - 1.0) > 1e-9) std::abort();
    }
  } catch (const accelcal::InputError&) {
  }
  return 0;
}
