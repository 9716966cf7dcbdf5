#pragma once
// Output helpers of the command-line tool.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <sys/stat.h>

#include "core/text_format.hpp"

namespace accelcal::cli {

/// An output file a command run in-process writes into memory instead of the disk (Console).
struct CapturedFile {
  std::string path;      ///< as the command is given it
  bool written = false;  ///< committed by the command
  std::string bytes;
};

/// Where this thread's standard output and error go: the process's (default), or strings, when
/// the Python package runs a command in-process (RunCommandLineCaptured). The tool writes both
/// through WriteOut and WriteErr only. `files`: output files (OutputFile) kept in memory by their
/// path, for a caller that writes them itself where it alone decides (batch, into directories
/// it opened without following links).
struct Console {
  std::string* out = nullptr;  ///< nullptr: the process's stdout
  std::string* err = nullptr;  ///< nullptr: the process's stderr
  std::vector<CapturedFile>* files = nullptr;
};
/// Sets this thread's console; returns the one it replaces.
Console SetConsole(Console console);
/// Whether this thread's output is captured (no terminal, no signal handlers of its own).
bool Captured();
void WriteOut(std::string_view text);
void WriteErr(std::string_view text);
/// A message of one line on stderr: every character of `text` but a final line feed made visible
/// (internal::VisibleLine), so that a file name holding a line feed or a terminal's control
/// sequence cannot make a line of its own ("verdict   ok") or rewrite the screen.
void WriteErrLine(std::string_view text);

/// How much the tool says besides its results (`--quiet`, `--verbose`). Results (files, and
/// stdout when it is the requested output) are never affected; errors always go to stderr.
enum class Verbosity { kQuiet, kNormal, kVerbose };
void SetVerbosity(Verbosity verbosity);
Verbosity CurrentVerbosity();

/// A name the user gave (a file's, a topic's) as a line of the summary can show it: control and
/// direction characters escaped (internal::VisibleLine).
std::string Shown(std::string_view name);

/// An informational line on stdout (summaries, "wrote FILE"); nothing when quiet.
void Say(const char* format, ...) __attribute__((format(printf, 1, 2)));
/// "accelcal: warning: ..." on stderr (something the user must know about a result that was still
/// written), one line (WriteErrLine); nothing when quiet.
void Warn(const char* format, ...) __attribute__((format(printf, 1, 2)));
/// A diagnostic line on stderr (detection thresholds, timings), as WriteErrLine; only when verbose.
void Detail(const char* format, ...) __attribute__((format(printf, 1, 2)));

/// A directory opened once and then used through its descriptor, so that what is made, read or
/// replaced in it stays in it whatever is renamed or linked meanwhile (batch's and the store's
/// trees). The root the user names is opened as named: a link there is the user's own choice,
/// followed as every tool follows it. Below it nothing is followed: a subdirectory is opened with
/// O_NOFOLLOW|O_DIRECTORY relative to its parent, a file is read with O_NOFOLLOW, and files are
/// created and replaced relative to it (OutputFile's directory form: openat, renameat). A
/// symbolic link, or something else than a directory or a regular file, where one is expected is
/// refused, naming its path: an OutputError when `create` (the tool is about to write there), an
/// InputError otherwise (it only reads). A name is one component: empty, ".", "..", a '/' or a
/// NUL are refused (a NUL would end the name the system sees, and another file would be used).
class Directory {
 public:
  /// `path`, made when missing and `create`.
  static Directory Open(const std::string& path, bool create);
  /// The subdirectory `name`, made when missing and `create`.
  Directory Sub(const std::string& name, bool create) const;
  /// Whether `name` exists in it, of any kind (a link not followed); `st` its lstat.
  bool Has(const std::string& name, struct stat* st = nullptr) const;
  /// The regular file `name`, at most `max_bytes` (InputError naming it otherwise).
  std::string Read(const std::string& name, std::size_t max_bytes) const;
  /// Removes the file `name` (a regular file only; absent: nothing).
  void Remove(const std::string& name) const;
  /// Removes the subdirectory `name` if it is empty (else leaves it, silently).
  void RemoveEmpty(const std::string& name) const;
  /// `name` in it, as messages show it: path() + "/" + name.
  std::string Shown(const std::string& name) const;
  const std::string& path() const { return path_; }
  int fd() const { return fd_; }

  Directory(Directory&& other) noexcept : path_(std::move(other.path_)), fd_(other.fd_) {
    other.fd_ = -1;
  }
  Directory& operator=(Directory&& other) noexcept;
  Directory(const Directory&) = delete;
  Directory& operator=(const Directory&) = delete;
  ~Directory();

 private:
  Directory(std::string path, int fd) : path_(std::move(path)), fd_(fd) {}
  std::string path_;
  int fd_ = -1;
};

/// A lock (flock) on the file `name` of `dir`, held while the object lives; the kernel releases
/// it when the process ends however it ends (kill -9 included), so a lock is never left stale.
/// `exclusive`: a writer's, else a reader's (shared); `wait`: wait for another holder, else
/// busy() says one holds it. `create`: make the file when missing (a writer's), else a missing
/// file is no holder (a reader does not write into what it reads). An error naming the file when
/// it cannot be opened (a link, not a regular file): OutputError for a writer (`create`), else
/// InputError.
class DirectoryLock {
 public:
  DirectoryLock(const Directory& dir, const std::string& name, bool exclusive, bool wait,
                bool create);
  ~DirectoryLock();
  DirectoryLock(const DirectoryLock&) = delete;
  DirectoryLock& operator=(const DirectoryLock&) = delete;
  bool busy() const { return busy_; }

 private:
  int fd_ = -1;
  bool busy_ = false;
};

/// Refuses (OutputError) a name with a NUL: the system would see a shorter one, another file.
void CheckNoNul(const std::string& path);

/// One output file of a command. A regular file (or a new one) is written to a hidden temporary
/// file beside it (".NAME.XXXXXXXXXX.tmp": created with O_CREAT|O_EXCL|O_NOFOLLOW under an
/// unpredictable name, so a link planted there cannot redirect it) and renamed over it by
/// Commit, so that a failure or an interruption (SIGINT, SIGTERM: InstallCleanupHandlers) never
/// leaves a partial file. The new file has the mode of the file it replaces (without set-id
/// bits; and, run as root, its owner), else 0666 less the umask. A symbolic link is followed:
/// its target is replaced, the link kept. "-" is stdout. A target that exists and is not a
/// regular file (a device such as /dev/null, a FIFO, a terminal) is written directly, never
/// replaced; a read-only file (no write permission for the user, or none for anyone) is not
/// replaced. Throws OutputError naming the path. A path the thread's Console captures is written
/// into memory instead.
class OutputFile {
 public:
  explicit OutputFile(const std::string& path);
  /// The file `name` of `dir`, created and replaced relative to it (openat, renameat), never
  /// through a link: a symbolic link, a FIFO, a device or a directory at `name` is refused
  /// (OutputError naming dir.Shown(name)), and a read-only file is not replaced. `dir` must
  /// outlive the object.
  OutputFile(const Directory& dir, const std::string& name);
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
  /// name (SQLite): empty for stdout, a device or a FIFO, which are written as they are (and for
  /// a captured file; a Directory's file gives its name in that directory).
  const std::string& temporary() const { return temp_; }
  /// The file replaced: the path given, or the file a symbolic link given names.
  const std::string& target() const { return target_; }

 private:
  void Flush();
  // The hidden temporary file beside the target (in `dir`, as messages name it), relative to
  // dir_fd_ with `prefix`; `replaced`: the file it will replace, whose mode it keeps.
  void CreateTemporary(const std::string& dir, const std::string& prefix, const std::string& base,
                       const struct stat* replaced);
  std::string path_;    // as given, for messages
  std::string target_;  // the file replaced (a link's target)
  std::string temp_;    // empty: written directly
  int dir_fd_;          // what temp_ and target_ are relative to (a Directory's, or AT_FDCWD)
  std::string name_;    // a Directory's file: its name there
  CapturedFile* captured_ = nullptr;  // written into memory (Console::files)
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
