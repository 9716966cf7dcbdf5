#pragma once
// What every harness that reads a log checks of what was read (fuzz_native_log, fuzz_file_log):
// a raw log's promise (finite samples and times, as many lines as samples, times from the first
// that never go back), or, where the format can hold one (a MAT-file's matrix), a positions
// file's (finite means). Anything else aborts: a finding.
#include <cmath>
#include <cstdlib>

#include "accelcal/log_reader.hpp"

namespace accelcal::fuzz {

inline void CheckInput(const InputData& data, bool positions_allowed = false) {
  if (positions_allowed && data.kind == InputKind::kPositions) {
    for (const Position& p : data.positions) {
      if (!p.mean.allFinite()) std::abort();
    }
    return;
  }
  const RawLog& log = data.raw;
  if (data.kind != InputKind::kRaw || log.samples.size() != log.line.size() ||
      (!log.time_s.empty() && log.time_s.size() != log.samples.size())) {
    std::abort();
  }
  for (std::size_t i = 0; i < log.samples.size(); ++i) {
    if (!log.samples[i].allFinite()) std::abort();
    if (!log.time_s.empty() &&
        (!std::isfinite(log.time_s[i]) || (i > 0 && log.time_s[i] < log.time_s[i - 1]))) {
      std::abort();
    }
  }
}

}  // namespace accelcal::fuzz
