#pragma once
// What the text and the binary readers share (log_reader.cpp, native_log.cpp).

#include <optional>
#include <string>
#include <string_view>

#include "accelcal/log_reader.hpp"
#include "io/binary_stream.hpp"
#include "io/input_file.hpp"

namespace accelcal::internal {

/// The end of every raw log's reading, text or binary, once its samples, times (as read) and
/// lines are in: times must not go backwards (InputError at the sample's line), the time
/// column's unit is decided (`unit`, kAuto from `time_name` and the steps) and the times made
/// seconds from the first sample (MakeTimeAxis), and the rate set (`rate_hz` must agree with
/// the timestamps').
void FinishRawLog(RawLog* log, TimeUnit unit, const std::optional<double>& rate_hz,
                  std::string_view time_name);

/// Throws InputError when `file` changed while it was read (its digest would not describe what
/// was parsed).
void RequireUnchanged(const InputFile& file);

/// Reads a binary log (native_log.hpp) from `in`, as ReadInput reads a text log; `file` (may be
/// null: the log was in memory) is the file `in` reads, whose size and digest are the input's
/// fingerprint (ReadOptions::fingerprint), and `path` its path (a database is opened by it).
InputData ReadNativeLog(BinaryStream& in, InputFile* file, const ReadOptions& options,
                        const std::string* path = nullptr);

}  // namespace accelcal::internal
