// libFuzzer harness: system-level series files (series_file.hpp), binary and text.
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "accelcal/error.hpp"
#include "accelcal/series_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    accelcal::ParseSeries(text, "fuzz.bin", [](const accelcal::SystemSample& s) {
      if (!std::isfinite(s.t) || !s.f.allFinite()) std::abort();  // refused, never passed on
    });
  } catch (const accelcal::InputError&) {
  }
  return 0;
}
