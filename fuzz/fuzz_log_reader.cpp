// libFuzzer harness: raw logs and positions files (log_reader.hpp), read as every input kind.
// The only accepted failure is InputError (file, line, reason); anything else is a finding. And
// a differential oracle for the fast paths: lines ending in '\r' alone are read by the general
// path only (LineReader and ParseFields), lines ending in '\n' by the fast ones (the row
// template, the column layouts, FastRow); a text without '\r' must read the same both ways, bit
// for bit, or fail with the same message.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>
#include <string_view>

#include "accelcal/error.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/native_log.hpp"

namespace {

struct Outcome {
  accelcal::InputData data;
  std::string error;
};

Outcome Read(std::string_view text, accelcal::InputKind kind) {
  accelcal::ReadOptions options;
  options.kind = kind;
  Outcome out;
  try {
    out.data = accelcal::ParseInput(text, "fuzz.csv", options);
  } catch (const accelcal::InputError& e) {
    out.error = e.what();
  }
  return out;
}

bool SameBits(const accelcal::Vec3& a, const accelcal::Vec3& b) {
  return std::memcmp(a.data(), b.data(), 3 * sizeof(double)) == 0;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  // A binary log (its magic found by the fuzzer) is read as bytes, not lines: no line-end
  // differential for it (fuzz_native_log fuzzes it).
  const bool differential =
      text.find('\r') == std::string_view::npos &&
      accelcal::DetectLogFormat(text.substr(0, 16)) == accelcal::LogFormat::kText;
  std::string mac;
  if (differential) {
    mac.assign(text);
    std::replace(mac.begin(), mac.end(), '\n', '\r');
  }
  for (const accelcal::InputKind kind :
       {accelcal::InputKind::kAuto, accelcal::InputKind::kRaw, accelcal::InputKind::kPositions}) {
    const Outcome fast = Read(text, kind);
    if (fast.error.empty()) {
      // What was read is finite and consistent, or it would have been refused.
      const accelcal::InputData& d = fast.data;
      for (const accelcal::Vec3& s : d.raw.samples) {
        if (!s.allFinite()) std::abort();
      }
      if (!d.raw.time_s.empty() && d.raw.time_s.size() != d.raw.samples.size()) std::abort();
      for (const accelcal::Position& p : d.positions) {
        if (!p.mean.allFinite()) std::abort();
      }
    }
    if (!differential) continue;
    const Outcome general = Read(mac, kind);
    if (fast.error != general.error) std::abort();
    if (!fast.error.empty()) continue;
    const accelcal::InputData &a = fast.data, &b = general.data;
    if (a.kind != b.kind || a.raw.samples.size() != b.raw.samples.size() ||
        a.raw.line != b.raw.line || a.raw.time_s.size() != b.raw.time_s.size() ||
        a.positions.size() != b.positions.size()) {
      std::abort();
    }
    for (std::size_t i = 0; i < a.raw.samples.size(); ++i) {
      if (!SameBits(a.raw.samples[i], b.raw.samples[i])) std::abort();
    }
    if (!a.raw.time_s.empty() && std::memcmp(a.raw.time_s.data(), b.raw.time_s.data(),
                                             a.raw.time_s.size() * sizeof(double)) != 0) {
      std::abort();
    }
    for (std::size_t i = 0; i < a.positions.size(); ++i) {
      if (!SameBits(a.positions[i].mean, b.positions[i].mean)) std::abort();
    }
  }
  return 0;
}
