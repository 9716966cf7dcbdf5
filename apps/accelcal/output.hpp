#pragma once
// Output helpers of the command-line tool.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <initializer_list>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/text_format.hpp"

namespace accelcal::cli {

/// Where this thread's standard output and error go: the process's (default), or strings, when
/// the Python package runs a command in-process (RunCommandLineCaptured). The tool writes both
/// through WriteOut and WriteErr only.
struct Console {
  std::string* out = nullptr;  ///< nullptr: the process's stdout
  std::string* err = nullptr;  ///< nullptr: the process's stderr
};
/// Sets this thread's console; returns the one it replaces.
Console SetConsole(Console console);
/// Whether this thread's output is captured (no terminal, no signal handlers of its own).
bool Captured();
void WriteOut(std::string_view text);
void WriteErr(std::string_view text);

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

/// One output file of a command. A regular file (or a new one) is written to a hidden temporary
/// file beside it (".NAME.XXXXXXXXXX.tmp": created with O_CREAT|O_EXCL|O_NOFOLLOW under an
/// unpredictable name, so a link planted there cannot redirect it) and renamed over it by
/// Commit, so that a failure or an interruption (SIGINT, SIGTERM: InstallCleanupHandlers) never
/// leaves a partial file. The new file has the mode of the file it replaces (without set-id
/// bits; and, run as root, its owner), else 0666 less the umask. A symbolic link is followed:
/// its target is replaced, the link kept. "-" is stdout. A target that exists and is not a
/// regular file (a device such as /dev/null, a FIFO, a terminal) is written directly, never
/// replaced; a read-only file (no write permission for the user, or none for anyone) is not
/// replaced. Throws OutputError naming the path.
class OutputFile {
 public:
  explicit OutputFile(const std::string& path);
  /// Removes the temporary file unless committed.
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;
  void Write(std::string_view text);
  /// Everything written reaches the disk (flushed, synced, closed); Commit then only renames.
  void Finish();
  /// Finish, then the temporary file replaces the target.
  void Commit();
  const std::string& path() const { return path_; }
  /// `bytes` written again at byte `offset` (a header completed at the end, as a ROS bag's index
  /// position). Only a file being replaced can be; OutputError for stdout, a device or a FIFO.
  void Rewrite(std::uint64_t offset, std::string_view bytes);
  /// The temporary file that will replace the target, for a library that writes a file by its
  /// name (SQLite): empty for stdout, a device or a FIFO, which are written as they are.
  const std::string& temporary() const { return temp_; }
  /// The file replaced: the path given, or the file a symbolic link given names.
  const std::string& target() const { return target_; }

 private:
  void Flush();
  std::string path_;    // as given, for messages
  std::string target_;  // the file replaced (a link's target)
  std::string temp_;    // empty: written directly
  int fd_ = -1;
  int slot_ = -1;  // the cleanup handlers' record of temp_
  bool to_stdout_ = false;
  bool finished_ = false, committed_ = false;
  std::string buffer_;
};

/// Several outputs as one: all finished before any is renamed, so an error in one (a full disk,
/// a bad directory) leaves none of them written.
void CommitAll(std::initializer_list<OutputFile*> outputs);

/// `content` to `path` as one OutputFile.
void WriteFileAtomically(const std::string& path, const std::string& content);

/// Refuses (UsageError) an output that is one of the inputs (it would destroy it) or the same
/// file as another output. `outputs`: option and path ("" or "-" are skipped).
void CheckOutputs(const std::vector<std::pair<std::string, std::string>>& outputs,
                  const std::vector<std::string>& inputs);

/// SIGINT, SIGTERM, SIGHUP, SIGPIPE, SIGQUIT and SIGXFSZ remove the temporary files being
/// written, then end the process as the signal would have.
void InstallCleanupHandlers();

/// stdout flushed and checked (a summary to a full disk is an error too): OutputError.
void FinishStdout();

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

/// printf into a std::string, in the "C" locale: the library's own (core/text_format.hpp).
using internal::Format;

}  // namespace accelcal::cli
