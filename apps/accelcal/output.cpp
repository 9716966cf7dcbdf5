#include "output.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <climits>
#include <csignal>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <optional>
#include <string>

#include "accelcal/error.hpp"
#include "commands.hpp"

namespace accelcal::cli {

namespace {
double NowSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
}  // namespace

namespace {
// Per thread: the Python package runs commands in several threads at once.
thread_local Verbosity g_verbosity = Verbosity::kNormal;
thread_local Console g_console;
}  // namespace

Console SetConsole(Console console) {
  const Console old = g_console;
  g_console = console;
  return old;
}
bool Captured() { return g_console.out != nullptr || g_console.err != nullptr; }

void WriteOut(std::string_view text) {
  if (g_console.out != nullptr) {
    g_console.out->append(text);
  } else if (std::fwrite(text.data(), 1, text.size(), stdout) != text.size()) {
    throw OutputError(std::string("cannot write to stdout: ") + std::strerror(errno));
  }
}

void WriteErr(std::string_view text) {
  if (g_console.err != nullptr) {
    g_console.err->append(text);
  } else {
    std::fwrite(text.data(), 1, text.size(), stderr);
  }
}

void WriteErrLine(std::string_view text) {
  const bool ends = !text.empty() && text.back() == '\n';
  WriteErr(internal::VisibleLine(ends ? text.substr(0, text.size() - 1) : text) +
           (ends ? "\n" : ""));
}

std::string Shown(std::string_view name) { return internal::VisibleLine(name); }

void SetVerbosity(Verbosity verbosity) { g_verbosity = verbosity; }
Verbosity CurrentVerbosity() { return g_verbosity; }

void Say(const char* format, ...) {
  if (g_verbosity == Verbosity::kQuiet) return;
  va_list args;
  va_start(args, format);
  const std::string text = internal::VFormat(format, args);
  va_end(args);
  WriteOut(text);
}

void Warn(const char* format, ...) {
  if (g_verbosity == Verbosity::kQuiet) return;
  va_list args;
  va_start(args, format);
  const std::string text = internal::VFormat(format, args);
  va_end(args);
  WriteErrLine("accelcal: warning: " + text);
}

void Detail(const char* format, ...) {
  if (g_verbosity != Verbosity::kVerbose) return;
  va_list args;
  va_start(args, format);
  const std::string text = internal::VFormat(format, args);
  va_end(args);
  WriteErrLine(text);
}

ProgressBar::ProgressBar(std::string label)
    : label_(std::move(label)),
      active_(!Captured() && isatty(STDERR_FILENO) == 1 && g_verbosity != Verbosity::kQuiet) {}

ProgressBar::~ProgressBar() { Finish(); }

void ProgressBar::Update(long done, long total) {
  if (!active_ || total <= 0) return;
  const double now = NowSeconds();
  if (done < total && now - last_draw_s_ < 0.1) return;
  last_draw_s_ = now;
  constexpr int kWidth = 30;
  const long filled = kWidth * done / total;
  WriteErr(Format("\r%s [%s%s] %ld/%ld", label_.c_str(), std::string(filled, '#').c_str(),
                  std::string(kWidth - filled, '.').c_str(), done, total));
  std::fflush(stderr);
  drawn_ = true;
}

std::function<void(std::size_t, std::size_t)> ProgressBar::ByteCallback() {
  return [this](std::size_t done, std::size_t total) {
    Update(static_cast<long>(done), static_cast<long>(total));
  };
}

void ProgressBar::Finish() {
  if (!drawn_) return;
  WriteErr(Format("\r\033[K"));  // erase the line
  std::fflush(stderr);
  drawn_ = false;
}

namespace {

// The temporary files being written, for the signal handlers: fixed storage (a handler may not
// allocate), each slot's path complete before its flag is set.
constexpr int kCleanupSlots = 8;
struct CleanupSlot {
  volatile std::sig_atomic_t used = 0;
  int dir_fd = AT_FDCWD;  // what path is relative to (a Directory's file)
  char path[PATH_MAX];
};
CleanupSlot g_cleanup[kCleanupSlots];
std::mutex g_cleanup_mutex;  // threads of the Python package take slots at once; handlers only read

int RegisterTemporary(int dir_fd, const std::string& path) {
  if (path.size() >= PATH_MAX) return -1;
  const std::lock_guard<std::mutex> lock(g_cleanup_mutex);
  for (int i = 0; i < kCleanupSlots; ++i) {
    if (g_cleanup[i].used == 0) {
      g_cleanup[i].dir_fd = dir_fd;
      std::memcpy(g_cleanup[i].path, path.c_str(), path.size() + 1);
      g_cleanup[i].used = 1;
      return i;
    }
  }
  return -1;
}

void UnregisterTemporary(int slot) {
  const std::lock_guard<std::mutex> lock(g_cleanup_mutex);
  if (slot >= 0) g_cleanup[slot].used = 0;
}

extern "C" void RemoveTemporariesAndDie(int sig) {
  for (CleanupSlot& slot : g_cleanup) {
    if (slot.used != 0) ::unlinkat(slot.dir_fd, slot.path, 0);
  }
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

// An unpredictable name part: 10 characters of [a-z0-9] from the kernel's generator.
std::string RandomPart() {
  unsigned char bytes[10];
  std::size_t got = 0;
  while (got < sizeof bytes) {
    const ssize_t n = ::getrandom(bytes + got, sizeof bytes - got, 0);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw OutputError(std::string("no random numbers: ") + std::strerror(errno));
    got += static_cast<std::size_t>(n);
  }
  static const char kAlphabet[] = "abcdefghijklmnopqrstuvwxyz0123456789";
  std::string out;
  for (unsigned char b : bytes) out += kAlphabet[b % 36];
  return out;
}

std::string Why(const std::string& path, const char* what) {
  return path + ": " + what + ": " + std::strerror(errno);
}

}  // namespace

void InstallCleanupHandlers() {
  if (Captured()) return;  // in the Python package, whose signals are Python's
  // SIGXFSZ: a file-size limit (ulimit -f) reached while writing.
  for (int sig : {SIGINT, SIGTERM, SIGHUP, SIGPIPE, SIGQUIT, SIGXFSZ}) {
    struct sigaction action {};
    action.sa_handler = RemoveTemporariesAndDie;
    sigemptyset(&action.sa_mask);
    ::sigaction(sig, &action, nullptr);
  }
}

void CheckNoNul(const std::string& path) {
  if (path.find('\0') != std::string::npos) {
    throw OutputError(internal::VisibleLine(path) +
                      ": the name holds a NUL character: the system would see a shorter name, "
                      "another file");
  }
}

namespace {

// One component of a path: never a way up, across or out of the directory it is in.
void CheckComponent(const std::string& parent, const std::string& name) {
  CheckNoNul(name);
  if (name.empty() || name == "." || name == ".." || name.find('/') != std::string::npos) {
    throw OutputError(parent + "/" + internal::VisibleLine(name) + ": not a name of one file in " +
                      parent);
  }
}

// An error about `path`: an OutputError when the tool is about to write there, else an
// InputError (it only reads).
[[noreturn]] void Refuse(bool writing, const std::string& path, const std::string& why) {
  if (writing) throw OutputError(path + ": " + why);
  throw InputError(path, 0, why);
}

std::string OpenFailure(int error, const char* what) {
  if (error == ELOOP) {
    return std::string("is a symbolic link: not followed (below the directory named, ") + what +
           " are the tool's own, never links: nothing is written or read outside it)";
  }
  if (error == ENOTDIR) return "is not a directory";
  return std::string("cannot be opened: ") + std::strerror(error);
}

}  // namespace

Directory Directory::Open(const std::string& path, bool create) {
  if (path.empty()) Refuse(create, "''", "a directory's name is empty");
  CheckNoNul(path);
  if (create && ::mkdir(path.c_str(), 0777) != 0 && errno != EEXIST) {
    Refuse(create, path, std::string("cannot create the directory: ") + std::strerror(errno));
  }
  // Followed when a link: the name is the user's own.
  const int fd = ::open(path.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) {
    const int e = errno;
    struct stat st {};
    if (e == ENOTDIR || (::stat(path.c_str(), &st) == 0 && !S_ISDIR(st.st_mode))) {
      Refuse(create, path, "exists and is not a directory");
    }
    Refuse(create, path, e == ENOENT ? "no such directory" : OpenFailure(e, "the directories"));
  }
  return Directory(path, fd);
}

Directory Directory::Sub(const std::string& name, bool create) const {
  CheckComponent(path_, name);
  const std::string shown = Shown(name);
  if (create && ::mkdirat(fd_, name.c_str(), 0777) != 0 && errno != EEXIST) {
    Refuse(create, shown, std::string("cannot create the directory: ") + std::strerror(errno));
  }
  const int fd = ::openat(fd_, name.c_str(), O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
  if (fd < 0) {
    const int e = errno;
    struct stat st {};
    // O_NOFOLLOW|O_DIRECTORY on a link gives ENOTDIR on some kernels: said as a link.
    if (::fstatat(fd_, name.c_str(), &st, AT_SYMLINK_NOFOLLOW) == 0 && S_ISLNK(st.st_mode)) {
      Refuse(create, shown, OpenFailure(ELOOP, "the directories"));
    }
    Refuse(create, shown, e == ENOENT ? "no such directory" : OpenFailure(e, "the directories"));
  }
  return Directory(shown, fd);
}

bool Directory::Has(const std::string& name, struct stat* st) const {
  CheckComponent(path_, name);
  struct stat own {};
  return ::fstatat(fd_, name.c_str(), st != nullptr ? st : &own, AT_SYMLINK_NOFOLLOW) == 0;
}

std::string Directory::Read(const std::string& name, std::size_t max_bytes) const {
  CheckComponent(path_, name);
  const std::string shown = Shown(name);
  // O_NONBLOCK: a FIFO planted there is refused below, not waited on.
  const int fd = ::openat(fd_, name.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) Refuse(false, shown, OpenFailure(errno, "the files"));
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    Refuse(false, shown, "not a regular file");
  }
  if (static_cast<std::size_t>(st.st_size) > max_bytes) {
    ::close(fd);
    Refuse(false, shown, "larger than " + std::to_string(max_bytes >> 20) + " MiB");
  }
  std::string data;
  char buffer[1 << 16];
  for (;;) {
    const ssize_t n = ::read(fd, buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int e = errno;
      ::close(fd);
      Refuse(false, shown, std::string("cannot be read: ") + std::strerror(e));
    }
    if (n == 0) break;
    data.append(buffer, static_cast<std::size_t>(n));
    if (data.size() > max_bytes) {
      ::close(fd);
      Refuse(false, shown, "larger than " + std::to_string(max_bytes >> 20) + " MiB");
    }
  }
  ::close(fd);
  return data;
}

void Directory::Remove(const std::string& name) const {
  struct stat st {};
  if (!Has(name, &st)) return;
  if (!S_ISREG(st.st_mode)) throw OutputError(Shown(name) + ": is not a regular file: not removed");
  if (::unlinkat(fd_, name.c_str(), 0) != 0 && errno != ENOENT) {
    throw OutputError(Shown(name) + ": cannot be removed: " + std::strerror(errno));
  }
}

void Directory::RemoveEmpty(const std::string& name) const {
  CheckComponent(path_, name);
  ::unlinkat(fd_, name.c_str(), AT_REMOVEDIR);  // not empty, or gone: left as it is
}

std::string Directory::Shown(const std::string& name) const {
  return path_ + (!path_.empty() && path_.back() == '/' ? "" : "/") + name;
}

Directory& Directory::operator=(Directory&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    path_ = std::move(other.path_);
    fd_ = other.fd_;
    other.fd_ = -1;
  }
  return *this;
}

Directory::~Directory() {
  if (fd_ >= 0) ::close(fd_);
}

DirectoryLock::DirectoryLock(const Directory& dir, const std::string& name, bool exclusive,
                             bool wait, bool create) {
  CheckComponent(dir.path(), name);
  const std::string shown = dir.Shown(name);
  fd_ =
      ::openat(dir.fd(), name.c_str(),
               (create ? O_RDWR | O_CREAT : O_RDONLY) | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC, 0666);
  if (fd_ < 0 && !create && errno == ENOENT) return;  // none: no one holds it
  if (fd_ < 0) Refuse(create, shown, "cannot lock: " + OpenFailure(errno, "the files"));
  struct stat st {};
  if (::fstat(fd_, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd_);
    fd_ = -1;
    Refuse(create, shown, "cannot lock: not a regular file");
  }
  int op = exclusive ? LOCK_EX : LOCK_SH;
  if (!wait) op |= LOCK_NB;
  while (::flock(fd_, op) != 0) {
    if (errno == EINTR) continue;
    if (!wait && errno == EWOULDBLOCK) {
      busy_ = true;
      return;
    }
    const int e = errno;
    ::close(fd_);
    fd_ = -1;
    Refuse(create, shown, std::string("cannot lock: ") + std::strerror(e));
  }
}

DirectoryLock::~DirectoryLock() {
  if (fd_ >= 0) ::close(fd_);
}

OutputFile::OutputFile(const std::string& path) : path_(path), target_(path), dir_fd_(AT_FDCWD) {
  if (path == "-") {
    to_stdout_ = true;
    return;
  }
  if (path.empty()) throw OutputError("an output file name is empty");
  CheckNoNul(path);
  if (g_console.files != nullptr) {
    for (CapturedFile& f : *g_console.files) {
      if (f.path == path) {
        captured_ = &f;
        return;
      }
    }
  }
  struct stat st;
  if (::lstat(path.c_str(), &st) == 0 && S_ISLNK(st.st_mode)) {
    struct stat to;
    if (::stat(path.c_str(), &to) == 0 && !S_ISREG(to.st_mode) && !S_ISDIR(to.st_mode) &&
        !S_ISSOCK(to.st_mode)) {
      // A link to a pipe, a FIFO or a device (/dev/stdout when it is a pipe, whose target
      // "pipe:[n]" has no path): written through the link, as it is.
      fd_ = ::open(path.c_str(), O_WRONLY | O_NOCTTY | O_CLOEXEC);
      if (fd_ < 0) throw OutputError(Why(path, "cannot open"));
      return;
    }
    char* real = ::realpath(path.c_str(), nullptr);
    if (real == nullptr) throw OutputError(Why(path, "a symbolic link that does not resolve"));
    target_ = real;
    std::free(real);
  }
  bool exists = false;
  if (::stat(target_.c_str(), &st) == 0) {
    exists = true;
    if (S_ISDIR(st.st_mode)) throw OutputError(path + ": is a directory");
    if (S_ISSOCK(st.st_mode)) throw OutputError(path + ": is a socket, not a file to write");
    if (!S_ISREG(st.st_mode)) {  // a device, a FIFO: written to, never replaced
      fd_ = ::open(target_.c_str(), O_WRONLY | O_NOCTTY | O_CLOEXEC);
      if (fd_ < 0) throw OutputError(Why(path, "cannot open"));
      return;
    }
    // A file made read-only is protected, as a shell's `>` would respect it (root included).
    if ((st.st_mode & 0222) == 0 || ::access(target_.c_str(), W_OK) != 0) {
      throw OutputError(path + ": is read-only: not replaced");
    }
  } else if (errno != ENOENT) {
    throw OutputError(Why(path, "cannot write"));
  }
  const std::size_t slash = target_.rfind('/');
  const std::string dir = slash == std::string::npos ? "."
                          : slash == 0               ? "/"
                                                     : target_.substr(0, slash);
  const std::string base = slash == std::string::npos ? target_ : target_.substr(slash + 1);
  CreateTemporary(dir, (dir == "/" ? "" : dir) + "/", base, exists ? &st : nullptr);
}

void OutputFile::CreateTemporary(const std::string& dir, const std::string& prefix,
                                 const std::string& base, const struct stat* replaced) {
  // ".NAME.XXXXXXXXXX.tmp": hidden from globs, NAME cut so the whole stays within NAME_MAX.
  for (int attempt = 0; fd_ < 0; ++attempt) {
    temp_ = prefix + "." + base.substr(0, 200) + "." + RandomPart() + ".tmp";
    fd_ = ::openat(dir_fd_, temp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC,
                   0666);
    if (fd_ < 0 && (errno != EEXIST || attempt == 100)) {
      const std::string why = Why(path_, ("cannot create a file in " + dir).c_str());
      temp_.clear();
      throw OutputError(why);
    }
  }
  slot_ = RegisterTemporary(dir_fd_, temp_);
  if (replaced != nullptr) {  // the file replaced keeps its permissions (and, for root, its owner)
    ::fchmod(fd_, replaced->st_mode & 0777);
    if (::geteuid() == 0) (void)!::fchown(fd_, replaced->st_uid, replaced->st_gid);
  }
}

OutputFile::OutputFile(const Directory& dir, const std::string& name)
    : path_(dir.Shown(name)), target_(path_), dir_fd_(dir.fd()), name_(name) {
  CheckComponent(dir.path(), name);
  struct stat st {};
  const bool exists = dir.Has(name, &st);
  if (exists) {
    if (S_ISLNK(st.st_mode)) {
      throw OutputError(path_ +
                        " is a symbolic link: not written through (a file here is the tool's "
                        "own; a link could send it elsewhere)");
    }
    if (!S_ISREG(st.st_mode)) throw OutputError(path_ + " is not a regular file: not replaced");
    if ((st.st_mode & 0222) == 0 || ::faccessat(dir_fd_, name.c_str(), W_OK, 0) != 0) {
      throw OutputError(path_ + ": is read-only: not replaced");
    }
  }
  CreateTemporary(dir.path(), "", name, exists ? &st : nullptr);
}

OutputFile::~OutputFile() {
  if (fd_ >= 0) ::close(fd_);
  if (!committed_ && !temp_.empty()) ::unlinkat(dir_fd_, temp_.c_str(), 0);
  UnregisterTemporary(slot_);
}

void OutputFile::Write(std::string_view text) {
  if (to_stdout_) {
    WriteOut(text);
    return;
  }
  buffer_.append(text);
  if (captured_ == nullptr && buffer_.size() >= (std::size_t{1} << 20)) Flush();
}

void OutputFile::Flush() {
  std::size_t done = 0;
  while (done < buffer_.size()) {
    const ssize_t n = ::write(fd_, buffer_.data() + done, buffer_.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw OutputError(Why(path_, "cannot write"));
    done += static_cast<std::size_t>(n);
  }
  buffer_.clear();
}

void OutputFile::Rewrite(std::uint64_t offset, std::string_view bytes) {
  if (captured_ != nullptr && !finished_ && offset + bytes.size() <= buffer_.size()) {
    buffer_.replace(static_cast<std::size_t>(offset), bytes.size(), bytes);
    return;
  }
  if (temp_.empty() || finished_) {
    throw OutputError(path_ + ": cannot be written back into (not a regular file)");
  }
  Flush();
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n =
        ::pwrite(fd_, bytes.data() + done, bytes.size() - done, static_cast<off_t>(offset + done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw OutputError(Why(path_, "cannot write"));
    done += static_cast<std::size_t>(n);
  }
}

void OutputFile::Finish() {
  if (finished_) return;
  if (to_stdout_) {
    FinishStdout();
  } else if (captured_ != nullptr) {
    // kept in buffer_ until Commit
  } else {
    Flush();
    if (!temp_.empty() && ::fsync(fd_) != 0) throw OutputError(Why(path_, "cannot write"));
    const int fd = fd_;
    fd_ = -1;
    if (::close(fd) != 0) throw OutputError(Why(path_, "cannot write"));
  }
  finished_ = true;
}

void OutputFile::Commit() {
  Finish();
  if (captured_ != nullptr && !committed_) {
    captured_->bytes = std::move(buffer_);
    captured_->written = true;
  }
  if (!temp_.empty() && !committed_) {
    const std::string& to = name_.empty() ? target_ : name_;
    if (::renameat(dir_fd_, temp_.c_str(), dir_fd_, to.c_str()) != 0) {
      throw OutputError(Why(path_, "cannot replace it"));
    }
    UnregisterTemporary(slot_);
    slot_ = -1;
  }
  committed_ = true;
}

void CommitAll(std::initializer_list<OutputFile*> outputs) {
  for (OutputFile* o : outputs) {
    if (o) o->Finish();
  }
  for (OutputFile* o : outputs) {
    if (o) o->Commit();
  }
}

void WriteFileAtomically(const std::string& path, const std::string& content) {
  OutputFile file(path);
  file.Write(content);
  file.Commit();
}

void FinishStdout() {
  if (g_console.out != nullptr) return;
  if (std::fflush(stdout) != 0 || std::ferror(stdout)) {
    const int e = errno;
    std::clearerr(stdout);
    throw OutputError(std::string("cannot write to stdout: ") + std::strerror(e));
  }
}

void CheckOutputs(const std::vector<std::pair<std::string, std::string>>& outputs,
                  const std::vector<std::string>& inputs) {
  // A file is known by its device and inode when it exists, else by its resolved directory and
  // name; only regular files (and files to be created) can be destroyed by a rename.
  struct Identity {
    bool exists = false;
    dev_t dev = 0;
    ino_t ino = 0;
    std::string path;
    bool operator==(const Identity& o) const {
      return exists == o.exists && (exists ? dev == o.dev && ino == o.ino : path == o.path);
    }
  };
  const auto identify = [](const std::string& path) -> std::optional<Identity> {
    if (path.empty() || path == "-") return std::nullopt;
    Identity id;
    struct stat st;
    if (::stat(path.c_str(), &st) == 0) {
      if (!S_ISREG(st.st_mode)) return std::nullopt;
      id.exists = true;
      id.dev = st.st_dev;
      id.ino = st.st_ino;
      return id;
    }
    const std::size_t slash = path.rfind('/');
    const std::string dir = slash == std::string::npos ? "." : path.substr(0, slash + 1);
    char* real = ::realpath(dir.c_str(), nullptr);
    id.path = (real ? std::string(real) : dir) + "/" +
              (slash == std::string::npos ? path : path.substr(slash + 1));
    std::free(real);
    return id;
  };
  std::vector<std::pair<std::string, Identity>> seen;
  for (const auto& [option, path] : outputs) {
    const std::optional<Identity> id = identify(path);
    if (!id) continue;
    for (const std::string& input : inputs) {
      const std::optional<Identity> in = identify(input);
      if (in && in->exists && *in == *id) {
        throw UsageError(option + " " + path + " is the input " + input +
                         ": writing it would destroy the input; choose another output file");
      }
    }
    for (const auto& [other, other_id] : seen) {
      if (other_id == *id) {
        throw UsageError(option + " and " + other + " name the same file (" + path +
                         "): give each output its own");
      }
    }
    seen.emplace_back(option, *id);
  }
}

}  // namespace accelcal::cli
