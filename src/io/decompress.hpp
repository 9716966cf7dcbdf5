#pragma once
// The compressions binary logs use for their blocks (ROS 1 bag chunks: bz2, lz4; MCAP chunks:
// lz4, zstd), decompressed in one place, on the Debian libraries that are each format's standard
// (libbz2, liblz4's frame format, libzstd).

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace accelcal::internal {

enum class Compression { kNone, kBz2, kLz4Frame, kZstd };

/// The largest block decompressed: ROS 1 writes 768 kB chunks and MCAP 4 MiB ones by default; a
/// block that claims more is refused (memory stays bounded by what a log really holds).
inline constexpr std::size_t kMaxDecompressedBytes = std::size_t{256} << 20;

/// The most the compressed blocks of one file may inflate to in all, unless the file is large (64
/// times its bytes: noisy samples compress a few times, not 64). Each block is inflated to be read
/// or checked (bz2 about 0.25 GB/s, zlib 0.4, zstd 2), so without it a small file of many blocks,
/// each within the bound of one, took minutes: 300 zstd chunks of 255 MiB in a 3.4 MB MCAP, 39 s;
/// 40 bz2 chunks of 255 MiB in a 16 kB bag, 44 s.
inline constexpr std::uint64_t kMaxFileInflatedBytes = std::uint64_t{1} << 30;

/// What a file's compressed blocks inflate to in all, held to kMaxFileInflatedBytes (or 64 times
/// the file). Every reader of compressed blocks counts them here, before inflating each when its
/// size is known.
class InflatedTotal {
 public:
  /// Counts `bytes` more inflated from a file of `file_bytes` (a stream's: those read so far).
  /// The reason, for blocks named `what` ("variables", "chunks"), when the total passes the bound.
  std::optional<std::string> Add(std::uint64_t bytes, std::uint64_t file_bytes, const char* what);
  std::uint64_t total() const { return total_; }

 private:
  std::uint64_t total_ = 0;
};

/// Decompresses `n` bytes at `data`, which must be one whole compressed block (a bz2 stream, an
/// LZ4 frame, a zstd frame) of exactly `size` bytes once decompressed, into `*out` (resized to
/// `size`). Memory grows with the output actually produced, never past `size`. Returns the reason
/// when the block is not that: corrupt, shorter or longer than `size`, followed by other bytes.
std::optional<std::string> Decompress(Compression compression, const unsigned char* data,
                                      std::size_t n, std::size_t size,
                                      std::vector<unsigned char>* out);

}  // namespace accelcal::internal
