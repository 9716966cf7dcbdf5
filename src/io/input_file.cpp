#include "io/input_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <condition_variable>
#include <cstring>
#include <mutex>
#include <system_error>
#include <thread>

#include "accelcal/error.hpp"
#include "core/text_format.hpp"
#include "io/text_lines.hpp"

namespace accelcal::internal {

namespace {
// A block holds many lines: at least two of the longest line a reader accepts, so that a block
// without a line end is a line too long, never a line cut by the block. 256 KiB rather than more:
// the block stays in the core's second-level cache while it is parsed, and a larger buffer only
// costs page faults (each of its pages is touched once; 1 MiB took 0.6 ms of them).
constexpr std::size_t kBlockBytes = std::size_t{1} << 18;
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
    // A NUL would end the name the system sees: another file would be read.
    if (path.find('\0') != std::string::npos) {
      throw InputError(internal::VisibleLine(path), 0,
                       "the name holds a NUL character: the system would read another file");
    }
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
  // A file of /proc or /sys says it has 0 bytes but has content, made as it is read: read as a
  // pipe is, to its end (within max_stream_bytes), not as the empty file its size claims.
  regular_ = S_ISREG(st.st_mode) && st.st_size > 0;
  if (regular_) {
    const off_t at = ::lseek(fd_, 0, SEEK_CUR);  // standard input may have been read from
    start_ = at > 0 ? static_cast<std::size_t>(at) : 0;
    const auto size = static_cast<std::size_t>(st.st_size);
    size_ = size > start_ ? size - start_ : 0;
    mtime_s_ = st.st_mtim.tv_sec;
    mtime_ns_ = st.st_mtim.tv_nsec;
  }
}

std::optional<std::string> InputFile::Changed() const {
  if (!regular_) return std::nullopt;
  struct stat st;
  if (::fstat(fd_, &st) != 0) return std::string("cannot be checked: ") + std::strerror(errno);
  const auto size = static_cast<std::size_t>(st.st_size);
  const std::size_t was = start_ + size_;
  if (size != was) {
    return std::string(size > was ? "grew" : "shrank") + " from " + std::to_string(was) + " to " +
           std::to_string(size) + " bytes";
  }
  if (st.st_mtim.tv_sec != mtime_s_ || st.st_mtim.tv_nsec != mtime_ns_) {
    return std::string("was written to (its modification time moved)");
  }
  return std::nullopt;
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

// Hashes the blocks a TextBlocks read, in order, on a thread of its own: Add hands it bytes that
// stay unchanged until WaitPending says they are hashed. At most kQueue blocks are outstanding
// (TextBlocks reads the next block into its other buffer while the last is hashed). Where no thread
// can be started, Add hashes them at once. (Waits that spin before they sleep were measured: no
// faster, the spinning thread taking the time of the core the other runs on.)
class BackgroundHash {
 public:
  static constexpr std::size_t kQueue = 2;

  explicit BackgroundHash(Sha256* hash) : hash_(hash) {
    try {
      thread_ = std::thread([this] { Run(); });
    } catch (const std::system_error&) {  // no thread: hashed in Add
    }
  }
  ~BackgroundHash() {
    if (!thread_.joinable()) return;
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      stop_.store(true);
    }
    wake_.notify_all();
    thread_.join();
  }
  BackgroundHash(const BackgroundHash&) = delete;
  BackgroundHash& operator=(const BackgroundHash&) = delete;

  /// Hashes [data, data + size) after what came before (with fewer than kQueue blocks pending).
  void Add(const char* data, std::size_t size) {
    if (!thread_.joinable()) {
      hash_->Update(data, size);
      return;
    }
    const std::size_t added = added_.load(std::memory_order_relaxed);
    queue_[added % kQueue] = {data, size};
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      added_.store(added + 1, std::memory_order_release);
    }
    wake_.notify_all();
  }
  /// Until at most `n` of the blocks added are not yet hashed (the oldest go first).
  void WaitPending(std::size_t n) {
    const auto done = [&] {
      return added_.load(std::memory_order_relaxed) - hashed_.load(std::memory_order_acquire) <= n;
    };
    std::unique_lock<std::mutex> lock(mutex_);
    wake_.wait(lock, done);
  }

 private:
  struct Block {
    const char* data = nullptr;
    std::size_t size = 0;
  };
  void Run() {
    while (true) {
      const std::size_t hashed = hashed_.load(std::memory_order_relaxed);
      {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(
            lock, [&] { return added_.load(std::memory_order_acquire) != hashed || stop_.load(); });
      }
      if (added_.load(std::memory_order_acquire) == hashed) return;  // stopped, nothing left
      const Block block = queue_[hashed % kQueue];
      hash_->Update(block.data, block.size);  // the block stays unchanged until WaitPending
      {
        const std::lock_guard<std::mutex> lock(mutex_);
        hashed_.store(hashed + 1, std::memory_order_release);
      }
      wake_.notify_all();
    }
  }

  Sha256* hash_;
  Block queue_[kQueue];
  std::atomic<std::size_t> added_{0}, hashed_{0};
  std::mutex mutex_;
  std::condition_variable wake_;
  std::atomic<bool> stop_{false};  // set under mutex_
  std::thread thread_;             // last: started once the rest is ready
};

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

TextBlocks::TextBlocks(Source source, std::size_t total)
    : source_(std::move(source)), total_(total) {}

TextBlocks::~TextBlocks() = default;

void TextBlocks::Fingerprint(Sha256* hash) {
  hash->Update(buffer_.get(), end_);  // already_read
  hash_ = std::make_unique<BackgroundHash>(hash);
}

void TextBlocks::FinishFingerprint() {
  if (hash_) hash_->WaitPending(0);
}

void TextBlocks::Fill(std::size_t min_bytes) {
  if (file_ == nullptr && !source_) return;
  while (!eof_ && end_ - begin_ < min_bytes) {
    if (hash_) {
      // The next bytes go into the other buffer, after the unconsumed text, while this one's last
      // block may still be hashed; the other's block (two reads ago) must be hashed first.
      hash_->WaitPending(1);
      const std::size_t capacity = std::max(min_bytes, kBlockBytes);
      if (spare_capacity_ < capacity) {
        spare_.reset(new char[capacity]);
        spare_capacity_ = capacity;
      }
      if (end_ > begin_) std::memcpy(spare_.get(), buffer_.get() + begin_, end_ - begin_);
      base_ += begin_;
      end_ -= begin_;
      begin_ = 0;
      std::swap(buffer_, spare_);
      std::swap(capacity_, spare_capacity_);
    } else {
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
    }
    const std::size_t got = file_ != nullptr ? file_->Read(buffer_.get() + end_, capacity_ - end_)
                                             : source_(buffer_.get() + end_, capacity_ - end_);
    if (hash_ && got > 0) hash_->Add(buffer_.get() + end_, got);
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
