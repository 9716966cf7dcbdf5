// The sizes a Level 5 MAT-file claims, checked (mat_structure.hpp).
#include "io/mat_structure.hpp"

#include <zlib.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <memory>
#include <vector>

#include "core/text_format.hpp"
#include "io/decompress.hpp"

namespace accelcal::internal {

namespace {

// Data types and array classes (the specification's tables 1-1 and 1-3).
constexpr std::uint32_t kMiInt8 = 1, kMiUint8 = 2, kMiInt16 = 3, kMiUint16 = 4, kMiInt32 = 5,
                        kMiUint32 = 6, kMiSingle = 7, kMiDouble = 9, kMiInt64 = 12, kMiUint64 = 13,
                        kMiMatrix = 14, kMiCompressed = 15, kMiUtf8 = 16, kMiUtf16 = 17,
                        kMiUtf32 = 18;
constexpr std::uint32_t kCellClass = 1, kStructClass = 2, kObjectClass = 3, kCharClass = 4,
                        kSparseClass = 5;
constexpr int kMaxDepth = 64;

std::uint64_t TypeSize(std::uint32_t type) {
  switch (type) {
    case kMiInt8:
    case kMiUint8:
    case kMiUtf8:
      return 1;
    case kMiInt16:
    case kMiUint16:
    case kMiUtf16:
      return 2;
    case kMiInt32:
    case kMiUint32:
    case kMiSingle:
    case kMiUtf32:
      return 4;
    case kMiDouble:
    case kMiInt64:
    case kMiUint64:
      return 8;
    default:
      return 1;
  }
}

// Bytes read forward: the file's, or a compressed variable's once inflated.
class Source {
 public:
  virtual ~Source() = default;
  // Exactly `n` bytes into `out` (nullptr: skipped); false when the source ends first.
  virtual bool Read(unsigned char* out, std::uint64_t n) = 0;
  // Where the next byte is, for messages.
  virtual std::string Where() const = 0;
};

class FileSource : public Source {
 public:
  FileSource(std::FILE* f, std::uint64_t size) : f_(f), size_(size), left_(size - 128) {}
  std::uint64_t offset() const { return size_ - left_; }
  std::string Where() const override {
    return Format("at byte %llu", static_cast<unsigned long long>(offset()));
  }
  bool Read(unsigned char* out, std::uint64_t n) override {
    if (n > left_) return false;
    left_ -= n;
    if (out == nullptr) return std::fseek(f_, static_cast<long>(n), SEEK_CUR) == 0;
    return std::fread(out, 1, static_cast<std::size_t>(n), f_) == n;
  }

 private:
  std::FILE* f_;
  std::uint64_t size_, left_;  // the file's bytes, and those after the position
};

// A zlib stream of `compressed` bytes from `file`, inflated as it is read.
class InflateSource : public Source {
 public:
  InflateSource(Source* file, std::uint64_t compressed)
      : file_(file), left_(compressed), where_(file->Where()) {
    std::memset(&z_, 0, sizeof z_);
    ok_ = inflateInit(&z_) == Z_OK;
  }
  ~InflateSource() override { inflateEnd(&z_); }
  InflateSource(const InflateSource&) = delete;
  InflateSource& operator=(const InflateSource&) = delete;

  bool Read(unsigned char* out, std::uint64_t n) override {
    while (n > 0) {
      if (have_ == used_) {
        if (!Fill()) return false;
        continue;
      }
      const std::uint64_t step = std::min<std::uint64_t>(n, have_ - used_);
      if (out != nullptr) {
        std::memcpy(out, buffer_ + used_, static_cast<std::size_t>(step));
        out += step;
      }
      used_ += static_cast<std::size_t>(step);
      n -= step;
    }
    return true;
  }
  std::uint64_t inflated() const { return z_.total_out; }
  std::string Where() const override {
    return Format("%llu bytes into the compressed variable %s, inflated",
                  static_cast<unsigned long long>(z_.total_out - (have_ - used_)), where_.c_str());
  }
  const std::string& error() const { return error_; }
  // The whole stream consumed: what the variable holds past its elements, inflated to its end.
  bool Drain() {
    while (Fill()) used_ = have_;
    return error_.empty();
  }

 private:
  bool Fill() {
    if (!ok_ || ended_) return false;
    have_ = used_ = 0;
    while (have_ == 0) {
      if (z_.avail_in == 0) {
        if (left_ == 0) {
          error_ = "zlib stream is cut short";
          return false;
        }
        const std::size_t step =
            static_cast<std::size_t>(std::min<std::uint64_t>(left_, sizeof in_));
        if (!file_->Read(in_, step)) {
          error_ = "zlib stream runs past the end of the file";
          return false;
        }
        left_ -= step;
        z_.next_in = in_;
        z_.avail_in = static_cast<uInt>(step);
      }
      z_.next_out = buffer_;
      z_.avail_out = sizeof buffer_;
      const int r = inflate(&z_, Z_NO_FLUSH);
      have_ = sizeof buffer_ - z_.avail_out;
      if (r == Z_STREAM_END) {
        ended_ = true;
        return have_ > 0;
      }
      if (r != Z_OK && !(r == Z_BUF_ERROR && have_ > 0)) {
        error_ = std::string("zlib stream is corrupt (") + (z_.msg != nullptr ? z_.msg : "") + ")";
        return false;
      }
      if (z_.total_out > kMaxMatInflatedBytes) {
        error_ = Format("data inflate past %llu MiB",
                        static_cast<unsigned long long>(kMaxMatInflatedBytes >> 20));
        return false;
      }
    }
    return true;
  }

  Source* file_;
  std::uint64_t left_;
  std::string where_;  // the compressed element's, in the file
  z_stream z_;
  bool ok_ = false, ended_ = false;
  std::string error_;
  unsigned char in_[16384];
  unsigned char buffer_[65536];
  std::size_t have_ = 0, used_ = 0;
};

class Walker {
 public:
  Walker(bool swap, std::uint64_t file_bytes) : swap_(swap), file_bytes_(file_bytes) {}

  // The elements of a container of `size` bytes from `in` (`top`: the file's, ended by its end).
  void Elements(Source* in, std::uint64_t size, int depth, bool top) {
    if (depth > kMaxDepth) Fail(Format("elements nested more than %d deep", kMaxDepth));
    std::uint64_t left = size;
    std::uint32_t matrix_class = 0;
    std::uint64_t values = 0;  // the matrix's dims multiplied (saturating)
    std::uint32_t nzmax = 0;
    for (int index = 0;; ++index) {
      if (!top && left < 8) break;
      unsigned char tag[8];
      where_ = in->Where();
      if (top) {
        if (!in->Read(tag, 8)) break;  // the file's end (a few bytes of padding are let be)
      } else if (!in->Read(tag, 8)) {
        Fail("an element is cut short");
      }
      std::uint32_t type = U32(tag), bytes = U32(tag + 4);
      if (!top) left -= 8;
      if ((type >> 16) != 0) {  // the small format: up to 4 bytes in the tag itself
        bytes = type >> 16;
        type &= 0xffff;
        if (bytes > 4) Fail(Format("a small element of %u bytes (at most 4)", bytes));
        if (index == 3 && matrix_class == kStructClass) field_name_length_ = U32(tag + 4);
        // A matrix's data in the small format: as many values as a large element's (found by
        // fuzz_file_schema: 3.7 G values claimed by one byte, libmatio asked for 30 GB).
        if (!top) CheckValues(index, matrix_class, values, bytes, type);
        continue;
      }
      if (!top && bytes > left) {
        Fail(Format("an element of %u bytes where its matrix holds %llu more", bytes,
                    static_cast<unsigned long long>(left)));
      }
      const std::uint64_t padded = top && type == kMiCompressed ? bytes : (bytes + 7u) / 8u * 8u;
      if (type == kMiMatrix) {
        Elements(in, bytes, depth + 1, false);
        // Its padding; at a file's or stream's end it may be missing.
        if (!in->Read(nullptr, Pad(bytes) - bytes) && !top) Fail("an element is cut short");
      } else if (type == kMiCompressed) {
        if (depth != 0) Fail("a compressed element inside a matrix");
        InflateSource inflated(in, bytes);
        try {
          Elements(&inflated, kMaxMatInflatedBytes, depth + 1, true);
        } catch (const Refused&) {
          // An element cut short by the stream's own failure (corrupt, or past the bound): that.
          if (!inflated.error().empty()) Fail("a compressed variable whose " + inflated.error());
          throw;
        }
        if (!inflated.Drain()) Fail("a compressed variable whose " + inflated.error());
        // In all, what a real file's variables inflate to (decompress.hpp).
        if (const std::optional<std::string> why =
                inflated_.Add(inflated.inflated(), file_bytes_, "variables")) {
          Fail(*why);
        }
        if (!inflated.error().empty() && inflated.inflated() == 0) {
          Fail("a compressed variable whose " + inflated.error());
        }
      } else if (!top && index <= 1 && bytes <= 64) {
        unsigned char data[64];
        if (!in->Read(data, bytes)) Fail("an element is cut short");
        if (index == 0 && bytes >= 8) {  // the array flags: the class, and a sparse's nzmax
          matrix_class = U32(data) & 0xff;
          nzmax = U32(data + 4);
        } else if (index == 1) {  // the dimensions
          values = 1;
          for (std::uint32_t d = 0; d + 4 <= bytes; d += 4) {
            const std::uint64_t n = U32(data + d);
            values = n == 0 ? 0 : values > (~std::uint64_t{0}) / n ? ~std::uint64_t{0} : values * n;
          }
          // A cell or struct holds a matrix element (8 bytes at least) per value.
          if ((matrix_class == kCellClass || matrix_class == kStructClass ||
               matrix_class == kObjectClass) &&
              values > Less(left, Pad(bytes)) / 8) {
            Fail(Format("a cell or struct of %llu elements in %llu bytes",
                        static_cast<unsigned long long>(values),
                        static_cast<unsigned long long>(left)));
          }
          if (matrix_class == kSparseClass && nzmax > left) {
            Fail(Format("a sparse matrix of %u values in %llu bytes", nzmax,
                        static_cast<unsigned long long>(left)));
          }
        }
        if (!in->Read(nullptr, Pad(bytes) - bytes)) Fail("an element is cut short");
      } else {
        if (!top) CheckValues(index, matrix_class, values, bytes, type);
        if (!top && index == 4 && matrix_class == kStructClass && field_name_length_ > 0 &&
            values > 0 && bytes / field_name_length_ > Less(left, Pad(bytes)) / 8 / values) {
          Fail("a struct whose fields claim more elements than it holds");
        }
        if (!in->Read(nullptr, bytes)) {
          Fail(top ? Format("a variable of %u bytes past the end", bytes)
                   : std::string("an element is cut short"));
        }
        if (!in->Read(nullptr, padded - bytes) && !top) Fail("an element is cut short");
      }
      if (!top) left -= std::min<std::uint64_t>(Pad(bytes), left);
    }
  }

  // The real part of a numeric or char matrix (its element 3) holds each value in `type`'s size.
  void CheckValues(int index, std::uint32_t matrix_class, std::uint64_t values, std::uint32_t bytes,
                   std::uint32_t type) const {
    if (index == 3 && matrix_class >= kCharClass && matrix_class != kSparseClass &&
        values > bytes / TypeSize(type)) {
      Fail(Format("a matrix of %llu values whose data holds %u bytes of type %u",
                  static_cast<unsigned long long>(values), bytes, type));
    }
  }

  struct Refused {
    std::string why;
  };
  // The element whose tag was read last, and where it is.
  [[noreturn]] void Fail(const std::string& why) const { throw Refused{why + " (" + where_ + ")"}; }

 private:
  static std::uint64_t Pad(std::uint64_t n) { return (n + 7) / 8 * 8; }
  static std::uint64_t Less(std::uint64_t a, std::uint64_t b) { return a > b ? a - b : 0; }
  std::uint32_t U32(const unsigned char* p) const {
    std::uint32_t v;
    std::memcpy(&v, p, 4);
    return swap_ ? __builtin_bswap32(v) : v;
  }

  bool swap_;
  std::uint64_t file_bytes_;
  InflatedTotal inflated_;  // by the compressed variables so far
  std::uint32_t field_name_length_ = 0;
  std::string where_;
};

}  // namespace

std::optional<std::string> CheckMatStructure(const std::string& path) {
  const std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"),
                                                          &std::fclose);
  if (!f) return std::string("a MAT-file that cannot be opened");
  unsigned char header[128];
  if (std::fread(header, 1, sizeof header, f.get()) != sizeof header) {
    return std::string("a MAT-file shorter than its 128-byte header");
  }
  const bool little = header[126] == 'I' && header[127] == 'M';
  if (!little && !(header[126] == 'M' && header[127] == 'I')) {
    return std::string("a MAT-file whose header has no endian indicator (IM or MI at byte 126)");
  }
  // libmatio reads the file as its version field says, whatever its text: 0x0200 is HDF5 (7.3,
  // its own library's to check), 0x0100 Level 5 (walked here). A "MATLAB 7.3" text over a
  // Level 5 version had let libmatio size an allocation from unchecked dimensions (8 TB).
  const unsigned version =
      little ? header[124] | (header[125] << 8) : (header[124] << 8) | header[125];
  if (version == 0x0200) return std::nullopt;
  if (version != 0x0100) {
    return Format("a MAT-file of version 0x%04x (0x0100: Level 5; 0x0200: 7.3)", version);
  }
  if (std::fseek(f.get(), 0, SEEK_END) != 0) return std::string("a MAT-file that cannot be read");
  const long size = std::ftell(f.get());
  if (size < 128 || std::fseek(f.get(), 128, SEEK_SET) != 0) {
    return std::string("a MAT-file that cannot be read");
  }
  FileSource file(f.get(), static_cast<std::uint64_t>(size));
  try {
    Walker(!little, static_cast<std::uint64_t>(size)).Elements(&file, 0, 0, true);
  } catch (const Walker::Refused& refused) {
    return refused.why;
  }
  return std::nullopt;
}

}  // namespace accelcal::internal
