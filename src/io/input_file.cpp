#include "io/input_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "accelcal/error.hpp"
#include "core/text_format.hpp"
#include "io/text_lines.hpp"

namespace accelcal::internal {

namespace {
// A block holds many lines: at least two of the longest line a reader accepts, so that a block
// without a line end is a line too long, never a line cut by the block.
constexpr std::size_t kBlockBytes = std::size_t{1} << 20;
static_assert(kBlockBytes > 2 * kMaxLineBytes, "a block must hold the longest line");

std::string MiB(std::size_t bytes) {
  return Format("%.0f MiB", static_cast<double>(bytes) / (1 << 20));
}
}  // namespace

InputFile::InputFile(const std::string& path, std::size_t max_stream_bytes)
    : name_(path == "-" ? "<stdin>" : path), max_stream_bytes_(max_stream_bytes) {
  if (path == "-") {
    fd_ = STDIN_FILENO;
  } else {
    fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd_ < 0) throw InputError(name_, 0, std::string("cannot open: ") + std::strerror(errno));
    owned_ = true;
  }
  struct stat st;
  if (::fstat(fd_, &st) != 0) {
    const int e = errno;
    if (owned_) ::close(fd_);
    throw InputError(name_, 0, std::string("cannot read: ") + std::strerror(e));
  }
  if (S_ISDIR(st.st_mode)) {
    if (owned_) ::close(fd_);
    throw InputError(name_, 0, "is a directory, not a file");
  }
  regular_ = S_ISREG(st.st_mode);
  if (regular_) size_ = static_cast<std::size_t>(st.st_size);
}

InputFile::~InputFile() {
  if (owned_) ::close(fd_);
}

std::size_t InputFile::Read(char* out, std::size_t n) {
  if (regular_) n = std::min(n, size_ - done_);  // the file as it was when opened
  if (n == 0) return 0;
  ssize_t got;
  do {
    got = ::read(fd_, out, n);
  } while (got < 0 && errno == EINTR);
  if (got < 0) throw InputError(name_, 0, std::string("cannot read: ") + std::strerror(errno));
  done_ += static_cast<std::size_t>(got);
  if (hash_ != nullptr) hash_->Update(out, static_cast<std::size_t>(got));
  if (got == 0 && regular_ && done_ < size_) {
    throw InputError(name_, 0,
                     "the file shrank while it was read (" + std::to_string(size_) +
                         " bytes when " + "opened, " + std::to_string(done_) +
                         " when its end came): is a logger truncating or rotating it?");
  }
  if (!regular_ && done_ > max_stream_bytes_) {
    throw InputError(name_, 0,
                     "more than " + MiB(max_stream_bytes_) +
                         " from something that is not a regular file (a pipe or a device): "
                         "the limit for such inputs; save it to a file first");
  }
  return static_cast<std::size_t>(got);
}

TextBlocks::TextBlocks(InputFile* file, std::string already_read)
    : file_(file),
      buffer_(new char[already_read.size()]),
      capacity_(already_read.size()),
      data_(buffer_.get()),
      end_(already_read.size()),
      total_(file->size()) {
  std::memcpy(buffer_.get(), already_read.data(), already_read.size());
}

TextBlocks::TextBlocks(std::string_view text)
    : data_(text.data()), end_(text.size()), total_(text.size()), eof_(true) {
  eol_ = DetectLineEnd(text);
  started_ = true;
}

void TextBlocks::Fill(std::size_t min_bytes) {
  if (file_ == nullptr) return;
  while (!eof_ && end_ - begin_ < min_bytes) {
    if (begin_ > 0) {  // the consumed text goes; the rest moves to the front
      std::memmove(buffer_.get(), buffer_.get() + begin_, end_ - begin_);
      base_ += begin_;
      end_ -= begin_;
      begin_ = 0;
    }
    if (capacity_ < min_bytes) {
      const std::size_t capacity = std::max(min_bytes, kBlockBytes);
      std::unique_ptr<char[]> larger(new char[capacity]);
      if (end_ > 0) std::memcpy(larger.get(), buffer_.get(), end_);
      buffer_ = std::move(larger);
      capacity_ = capacity;
    }
    const std::size_t got = file_->Read(buffer_.get() + end_, capacity_ - end_);
    if (got == 0) eof_ = true;
    end_ += got;
    data_ = buffer_.get();
  }
  if (!started_) {
    started_ = true;
    eol_ = DetectLineEnd(std::string_view(data_ + begin_, end_ - begin_));
  }
}

std::string_view TextBlocks::WholeLines() const {
  const std::string_view all(data_ + begin_, end_ - begin_);
  if (eof_) return all;
  const std::size_t last = all.rfind(eol_);
  // No line end at all in more than the longest line: the reader refuses it as too long.
  return last == std::string_view::npos ? all : all.substr(0, last + 1);
}

std::string_view TextBlocks::Peek(std::size_t min_bytes) {
  Fill(std::max(min_bytes, 2 * kMaxLineBytes + 2));
  const std::string_view lines = WholeLines();
  peeked_ = lines.size();
  return lines;
}

bool TextBlocks::Next(std::string_view* block) {
  Fill(kBlockBytes);
  const std::string_view lines = WholeLines();
  peeked_ = 0;
  if (lines.empty()) return false;
  block_offset_ = base_ + begin_;
  begin_ += lines.size();
  *block = lines;
  return true;
}

}  // namespace accelcal::internal
