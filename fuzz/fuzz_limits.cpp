// libFuzzer harness: batch's limits files (acceptance.hpp ParseLimits, on the YAML reader of
// io/yaml_document). Accepted failure: InputError. Whatever is accepted is a valid set of limits.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "accelcal/acceptance.hpp"
#include "accelcal/error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const accelcal::AcceptanceLimits limits = accelcal::ParseLimits(text, "fuzz.yaml");
    if (limits.limits.empty() && !limits.max_severity) std::abort();
    for (const accelcal::Limit& l : limits.limits) {
      if (!l.min && !l.max && !l.abs_max) std::abort();
      for (const auto& bound : {l.min, l.max, l.abs_max}) {
        if (bound && !std::isfinite(*bound)) std::abort();
      }
      if (l.min && l.max && *l.min > *l.max) std::abort();
      if (l.abs_max && *l.abs_max < 0) std::abort();
      bool named = false;
      for (const accelcal::QuantityName& q : accelcal::KnownQuantityNames()) {
        named = named || accelcal::QuantityMatches(l.pattern, q.name);
      }
      if (!named) std::abort();
    }
  } catch (const accelcal::InputError&) {
  }
  return 0;
}
