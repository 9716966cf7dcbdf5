#include "output.hpp"

#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdarg>
#include <cstdio>
#include <cstring>

#include "commands.hpp"

namespace accelcal::cli {

namespace {
double NowSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
}  // namespace

namespace {
Verbosity g_verbosity = Verbosity::kNormal;
}  // namespace

void SetVerbosity(Verbosity verbosity) { g_verbosity = verbosity; }
Verbosity CurrentVerbosity() { return g_verbosity; }

void Say(const char* format, ...) {
  if (g_verbosity == Verbosity::kQuiet) return;
  va_list args;
  va_start(args, format);
  std::vprintf(format, args);
  va_end(args);
}

void Warn(const char* format, ...) {
  if (g_verbosity == Verbosity::kQuiet) return;
  std::fputs("accelcal: warning: ", stderr);
  va_list args;
  va_start(args, format);
  std::vfprintf(stderr, format, args);
  va_end(args);
}

void Detail(const char* format, ...) {
  if (g_verbosity != Verbosity::kVerbose) return;
  va_list args;
  va_start(args, format);
  std::vfprintf(stderr, format, args);
  va_end(args);
}

ProgressBar::ProgressBar(std::string label)
    : label_(std::move(label)),
      active_(isatty(STDERR_FILENO) == 1 && g_verbosity != Verbosity::kQuiet) {}

ProgressBar::~ProgressBar() { Finish(); }

void ProgressBar::Update(long done, long total) {
  if (!active_ || total <= 0) return;
  const double now = NowSeconds();
  if (done < total && now - last_draw_s_ < 0.1) return;
  last_draw_s_ = now;
  constexpr int kWidth = 30;
  const long filled = kWidth * done / total;
  std::fprintf(stderr, "\r%s [%s%s] %ld/%ld", label_.c_str(), std::string(filled, '#').c_str(),
               std::string(kWidth - filled, '.').c_str(), done, total);
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
  std::fprintf(stderr, "\r\033[K");  // erase the line
  std::fflush(stderr);
  drawn_ = false;
}

std::string Format(const char* format, ...) {
  va_list args;
  va_start(args, format);
  char stack[512];
  va_list copy;
  va_copy(copy, args);
  const int n = std::vsnprintf(stack, sizeof stack, format, copy);
  va_end(copy);
  std::string out;
  if (n < static_cast<int>(sizeof stack)) {
    out.assign(stack, static_cast<std::size_t>(std::max(n, 0)));
  } else {
    out.resize(static_cast<std::size_t>(n) + 1);
    std::vsnprintf(out.data(), out.size(), format, args);
    out.resize(static_cast<std::size_t>(n));
  }
  va_end(args);
  return out;
}

void WriteFileAtomically(const std::string& path, const std::string& content) {
  if (path == "-") {
    if (std::fwrite(content.data(), 1, content.size(), stdout) != content.size() ||
        std::fflush(stdout) != 0) {
      throw OutputError("cannot write to stdout");
    }
    return;
  }
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  std::FILE* file = std::fopen(tmp.c_str(), "wb");
  if (file == nullptr) {
    throw OutputError(path + ": cannot create: " + std::strerror(errno));
  }
  const bool written = std::fwrite(content.data(), 1, content.size(), file) == content.size();
  const bool flushed = std::fflush(file) == 0 && ::fsync(::fileno(file)) == 0;
  const int saved_errno = errno;
  const bool closed = std::fclose(file) == 0;
  if (!written || !flushed || !closed) {
    std::remove(tmp.c_str());
    throw OutputError(path + ": cannot write: " + std::strerror(saved_errno));
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int e = errno;
    std::remove(tmp.c_str());
    throw OutputError(path + ": cannot rename the temporary file: " + std::strerror(e));
  }
}

}  // namespace accelcal::cli
