#pragma once
// Output helpers of the command-line tool.

#include <cstddef>
#include <functional>
#include <string>
#include <utility>

namespace accelcal::cli {

/// How much the tool says besides its results (`--quiet`, `--verbose`). Results (files, and
/// stdout when it is the requested output) are never affected; errors always go to stderr.
enum class Verbosity { kQuiet, kNormal, kVerbose };
void SetVerbosity(Verbosity verbosity);
Verbosity CurrentVerbosity();

/// An informational line on stdout (summaries, "wrote FILE"); nothing when quiet.
void Say(const char* format, ...) __attribute__((format(printf, 1, 2)));
/// "accelcal: warning: ..." on stderr (something the user must know about a result that was still
/// written); nothing when quiet.
void Warn(const char* format, ...) __attribute__((format(printf, 1, 2)));
/// A diagnostic line on stderr (detection thresholds, timings); only when verbose.
void Detail(const char* format, ...) __attribute__((format(printf, 1, 2)));

/// Writes `content` to `path` through a temporary file in the same directory and a rename, so a
/// failure never leaves a partial file. "-" writes to stdout. Throws OutputError.
void WriteFileAtomically(const std::string& path, const std::string& content);

/// A progress bar on stderr, drawn only when stderr is a terminal and the tool is not quiet, at
/// most every 0.1 s; erased by Finish() (and the destructor) so that it never mixes with the
/// output.
class ProgressBar {
 public:
  explicit ProgressBar(std::string label);
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;
  void Update(long done, long total);
  /// Update as a callback for the library's byte-count progress hooks (ReadOptions::progress,
  /// ReadSeries); the bar must outlive it.
  std::function<void(std::size_t, std::size_t)> ByteCallback();
  void Finish();

 private:
  std::string label_;
  bool active_;
  bool drawn_ = false;
  double last_draw_s_ = -1.0;
};

/// printf into a std::string.
std::string Format(const char* format, ...) __attribute__((format(printf, 1, 2)));

}  // namespace accelcal::cli
