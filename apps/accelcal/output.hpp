#pragma once
// Output helpers of the command-line tool.

#include <string>

namespace accelcal::cli {

/// Writes `content` to `path` through a temporary file in the same directory and a rename, so a
/// failure never leaves a partial file. "-" writes to stdout. Throws OutputError.
void WriteFileAtomically(const std::string& path, const std::string& content);

/// printf into a std::string.
std::string Format(const char* format, ...) __attribute__((format(printf, 1, 2)));

}  // namespace accelcal::cli
