// The log writers' block compression (compress.hpp).
#include "output/compress.hpp"

#include <bzlib.h>
#include <lz4frame.h>
#include <zstd.h>

#include <stdexcept>

namespace accelcal::internal {

std::string Compress(Compression compression, std::string_view in) {
  switch (compression) {
    case Compression::kNone:
      return std::string(in);
    case Compression::kBz2: {
      // bzip2's bound: 1 % more than the input, and 600 bytes.
      std::string out(in.size() + in.size() / 100 + 600, '\0');
      unsigned int n = static_cast<unsigned int>(out.size());
      if (in.size() > 0x7fffffffu ||
          BZ2_bzBuffToBuffCompress(out.data(), &n, const_cast<char*>(in.data()),
                                   static_cast<unsigned int>(in.size()), 9, 0, 0) != BZ_OK) {
        throw std::runtime_error("bzip2 could not compress a block");
      }
      out.resize(n);
      return out;
    }
    case Compression::kLz4Frame: {
      std::string out(LZ4F_compressFrameBound(in.size(), nullptr), '\0');
      const std::size_t n =
          LZ4F_compressFrame(out.data(), out.size(), in.data(), in.size(), nullptr);
      if (LZ4F_isError(n)) throw std::runtime_error("lz4 could not compress a block");
      out.resize(n);
      return out;
    }
    case Compression::kZstd: {
      std::string out(ZSTD_compressBound(in.size()), '\0');
      const std::size_t n = ZSTD_compress(out.data(), out.size(), in.data(), in.size(), 3);
      if (ZSTD_isError(n)) throw std::runtime_error("zstd could not compress a block");
      out.resize(n);
      return out;
    }
  }
  throw std::logic_error("Compress: an unknown compression");
}

}  // namespace accelcal::internal
