// libFuzzer harness: raw logs and positions files (log_reader.hpp), read as every input kind.
// The only accepted failure is InputError (file, line, reason); anything else is a finding.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "accelcal/error.hpp"
#include "accelcal/log_reader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  for (const accelcal::InputKind kind :
       {accelcal::InputKind::kAuto, accelcal::InputKind::kRaw, accelcal::InputKind::kPositions}) {
    accelcal::ReadOptions options;
    options.kind = kind;
    try {
      const accelcal::InputData d = accelcal::ParseInput(text, "fuzz.csv", options);
      // What was read is finite and consistent, or it would have been refused.
      for (const accelcal::Vec3& s : d.raw.samples) {
        if (!s.allFinite()) std::abort();
      }
      if (!d.raw.time_s.empty() && d.raw.time_s.size() != d.raw.samples.size()) std::abort();
      for (const accelcal::Position& p : d.positions) {
        if (!p.mean.allFinite()) std::abort();
      }
    } catch (const accelcal::InputError&) {
    }
  }
  return 0;
}
