#include "io/binary_stream.hpp"

#include <algorithm>

#include "accelcal/error.hpp"
#include "core/text_format.hpp"

namespace accelcal::internal {

namespace {
// Read this much at a time: a record is far smaller (a ULog message at most 64 KiB), and the
// block stays in the core's second-level cache while its records are decoded.
constexpr std::size_t kBlockBytes = std::size_t{1} << 18;
}  // namespace

BinaryStream::BinaryStream(InputFile* file, std::string already_read)
    : file_(file),
      name_(file->name()),
      buffer_(already_read.begin(), already_read.end()),
      end_(already_read.size()) {}

BinaryStream::BinaryStream(std::string bytes, std::string name)
    : file_(nullptr), name_(std::move(name)), owned_(std::move(bytes)), eof_(true) {
  view_ = reinterpret_cast<const unsigned char*>(owned_.data());
  end_ = owned_.size();
}

BinaryStream::BinaryStream(std::string_view bytes, std::string name, Borrowed)
    : file_(nullptr),
      name_(std::move(name)),
      view_(reinterpret_cast<const unsigned char*>(bytes.data())),
      end_(bytes.size()),
      eof_(true) {}

void BinaryStream::Fill(std::size_t n) {
  if (file_ == nullptr) return;  // all the input is there already
  // Move what is left to the front, then read whole blocks until n bytes are there.
  if (begin_ > 0) {
    // The hash has seen every byte already in the buffer.
    std::memmove(buffer_.data(), buffer_.data() + begin_, end_ - begin_);
    end_ -= begin_;
    begin_ = 0;
  }
  while (end_ < n && !eof_) {
    // At most doubling what is there: a record's length (read from the file) that claims more
    // bytes than the file has makes the buffer no larger than twice the file.
    const std::size_t want = std::max(std::min(n - end_, std::max(end_, kBlockBytes)), kBlockBytes);
    if (buffer_.size() < end_ + want) buffer_.resize(end_ + want);
    const std::size_t got = file_->ReadFully(reinterpret_cast<char*>(buffer_.data() + end_), want);
    if (hash_ != nullptr) hash_->Update(buffer_.data() + end_, got);
    end_ += got;
    if (got < want) eof_ = true;
  }
}

bool BinaryStream::Need(std::size_t n) {
  if (end_ - begin_ < n) Fill(n);
  return end_ - begin_ >= n;
}

bool BinaryStream::ZerosToEnd(std::uint64_t* nonzero) {
  while (Need(1)) {
    const unsigned char* d = data();
    const std::size_t n = available();
    const unsigned char* hit = std::find_if(d, d + n, [](unsigned char c) { return c != 0; });
    Skip(static_cast<std::size_t>(hit - d));
    if (hit != d + n) {
      *nonzero = offset();
      return false;
    }
  }
  return true;
}

std::string BinaryStream::ZerosMessage(std::uint64_t at) {
  return "the log ends in zero bytes from byte " + std::to_string(at) +
         " (space the logger reserved but never wrote)";
}

void BinaryStream::Fail(std::uint64_t at, const std::string& why) const {
  throw InputError(name_, 0,
                   Format("byte %llu: ", static_cast<unsigned long long>(at)) + VisibleLine(why));
}

bool BinaryStream::SkipAhead(std::uint64_t n) {
  while (n > 0) {
    if (!Need(1)) return false;
    const std::size_t take = static_cast<std::size_t>(std::min<std::uint64_t>(n, available()));
    Skip(take);
    n -= take;
  }
  return true;
}

void BinaryStream::Drain() {
  while (true) {
    Skip(end_ - begin_);
    if (eof_) return;
    Fill(kBlockBytes);
  }
}

}  // namespace accelcal::internal
