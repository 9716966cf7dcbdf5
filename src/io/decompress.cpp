// Block decompression for the binary log readers (decompress.hpp).
#include "io/decompress.hpp"

#include <bzlib.h>
#include <lz4frame.h>
#include <zstd.h>

#include <algorithm>
#include <climits>
#include <cstring>
#include <memory>

#include "core/text_format.hpp"

namespace accelcal::internal {

namespace {

// The output buffer grows as the output arrives, doubling up to `size`: a block that claims a
// large size but holds little asks for little memory.
class Output {
 public:
  Output(std::vector<unsigned char>* out, std::size_t size) : out_(out), size_(size) {
    out_->clear();
    out_->resize(std::min<std::size_t>(size_, std::size_t{1} << 20));
  }
  // Room after `written` bytes: more than none while fewer than `size` are written.
  unsigned char* At(std::size_t written) { return out_->data() + written; }
  std::size_t RoomAfter(std::size_t written) {
    if (written == out_->size() && out_->size() < size_) {
      out_->resize(std::min(size_, std::max<std::size_t>(2 * out_->size(), 1)));
    }
    return out_->size() - written;
  }

 private:
  std::vector<unsigned char>* out_;
  std::size_t size_;
};

std::optional<std::string> Bz2(const unsigned char* data, std::size_t n, std::size_t size,
                               std::vector<unsigned char>* out) {
  if (n > UINT_MAX) return std::string("a bz2 block larger than 4 GiB");
  bz_stream z{};
  if (BZ2_bzDecompressInit(&z, 0, 0) != BZ_OK) return std::string("bz2 could not start");
  const std::unique_ptr<bz_stream, int (*)(bz_stream*)> end(&z, BZ2_bzDecompressEnd);
  z.next_in = const_cast<char*>(reinterpret_cast<const char*>(data));
  z.avail_in = static_cast<unsigned>(n);
  Output o(out, size);
  std::size_t written = 0;
  while (true) {
    const std::size_t room = std::min<std::size_t>(o.RoomAfter(written), UINT_MAX);
    // A byte of room past `size` tells a block that holds more than it says.
    unsigned char extra = 0;
    z.next_out = reinterpret_cast<char*>(room > 0 ? o.At(written) : &extra);
    z.avail_out = room > 0 ? static_cast<unsigned>(room) : 1;
    const int rc = BZ2_bzDecompress(&z);
    written += (room > 0 ? room : 1) - z.avail_out;
    if (written > size) return Format("the bz2 block holds more than the %zu bytes it says", size);
    if (rc == BZ_STREAM_END) break;
    if (rc != BZ_OK) return Format("the bz2 block is corrupt (bzlib error %d)", rc);
    if (z.avail_in == 0 && z.avail_out > 0) {
      return Format("the bz2 block ends after %zu of the %zu bytes it says", written, size);
    }
  }
  if (written != size) {
    return Format("the bz2 block holds %zu bytes, not the %zu it says", written, size);
  }
  if (z.avail_in != 0) return Format("%u bytes follow the bz2 block's end", z.avail_in);
  return std::nullopt;
}

std::optional<std::string> Lz4Frame(const unsigned char* data, std::size_t n, std::size_t size,
                                    std::vector<unsigned char>* out) {
  LZ4F_dctx* context = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&context, LZ4F_VERSION))) {
    return std::string("lz4 could not start");
  }
  const std::unique_ptr<LZ4F_dctx, LZ4F_errorCode_t (*)(LZ4F_dctx*)> free(
      context, LZ4F_freeDecompressionContext);
  Output o(out, size);
  std::size_t written = 0, read = 0;
  while (true) {
    std::size_t room = o.RoomAfter(written);
    unsigned char extra = 0;
    std::size_t in = n - read, out_room = room > 0 ? room : 1;
    const std::size_t hint = LZ4F_decompress(context, room > 0 ? o.At(written) : &extra, &out_room,
                                             data + read, &in, nullptr);
    if (LZ4F_isError(hint)) {
      return Format("the lz4 frame is corrupt (%s)", LZ4F_getErrorName(hint));
    }
    read += in;
    written += out_room;
    if (written > size) return Format("the lz4 frame holds more than the %zu bytes it says", size);
    if (hint == 0) break;  // the frame's end
    if (read == n && out_room == 0 && in == 0) {
      return Format("the lz4 frame ends after %zu of the %zu bytes it says", written, size);
    }
  }
  if (written != size) {
    return Format("the lz4 frame holds %zu bytes, not the %zu it says", written, size);
  }
  if (read != n) return Format("%zu bytes follow the lz4 frame's end", n - read);
  return std::nullopt;
}

std::optional<std::string> Zstd(const unsigned char* data, std::size_t n, std::size_t size,
                                std::vector<unsigned char>* out) {
  const std::unique_ptr<ZSTD_DStream, std::size_t (*)(ZSTD_DStream*)> stream(ZSTD_createDStream(),
                                                                             ZSTD_freeDStream);
  if (!stream || ZSTD_isError(ZSTD_initDStream(stream.get()))) {
    return std::string("zstd could not start");
  }
  Output o(out, size);
  ZSTD_inBuffer in{data, n, 0};
  std::size_t written = 0;
  while (true) {
    const std::size_t room = o.RoomAfter(written);
    unsigned char extra = 0;
    ZSTD_outBuffer to{room > 0 ? o.At(written) : &extra, room > 0 ? room : 1, 0};
    const std::size_t left = ZSTD_decompressStream(stream.get(), &to, &in);
    if (ZSTD_isError(left)) {
      return Format("the zstd frame is corrupt (%s)", ZSTD_getErrorName(left));
    }
    written += to.pos;
    if (written > size) return Format("the zstd frame holds more than the %zu bytes it says", size);
    if (left == 0) break;  // the frame's end, all of it out
    if (in.pos == in.size && to.pos < to.size) {
      return Format("the zstd frame ends after %zu of the %zu bytes it says", written, size);
    }
  }
  if (written != size) {
    return Format("the zstd frame holds %zu bytes, not the %zu it says", written, size);
  }
  if (in.pos != n) return Format("%zu bytes follow the zstd frame's end", n - in.pos);
  return std::nullopt;
}

}  // namespace

std::optional<std::string> InflatedTotal::Add(std::uint64_t bytes, std::uint64_t file_bytes,
                                              const char* what) {
  total_ += bytes;
  const std::uint64_t bound = std::max(kMaxFileInflatedBytes, 64 * file_bytes);
  if (total_ <= bound) return std::nullopt;
  return Format(
      "compressed %s that inflate past %llu MiB in all (64 times the file, and at least "
      "%llu MiB)",
      what, static_cast<unsigned long long>(bound >> 20),
      static_cast<unsigned long long>(kMaxFileInflatedBytes >> 20));
}

std::optional<std::string> Decompress(Compression compression, const unsigned char* data,
                                      std::size_t n, std::size_t size,
                                      std::vector<unsigned char>* out) {
  if (size > kMaxDecompressedBytes) {
    return Format(
        "a block of %zu bytes once decompressed, more than the %zu MiB accelcal reads "
        "in one",
        size, kMaxDecompressedBytes >> 20);
  }
  switch (compression) {
    case Compression::kNone:
      if (n != size) return Format("an uncompressed block of %zu bytes that says %zu", n, size);
      out->assign(data, data + n);
      return std::nullopt;
    case Compression::kBz2:
      return Bz2(data, n, size, out);
    case Compression::kLz4Frame:
      return Lz4Frame(data, n, size, out);
    case Compression::kZstd:
      return Zstd(data, n, size, out);
  }
  return std::string("an unknown compression");
}

}  // namespace accelcal::internal
