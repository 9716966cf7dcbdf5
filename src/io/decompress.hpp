#pragma once
// The compressions binary logs use for their blocks (ROS 1 bag chunks: bz2, lz4; MCAP chunks:
// lz4, zstd), decompressed in one place, on the Debian libraries that are each format's standard
// (libbz2, liblz4's frame format, libzstd).

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace accelcal::internal {

enum class Compression { kNone, kBz2, kLz4Frame, kZstd };

/// The largest block decompressed: ROS 1 writes 768 kB chunks and MCAP 4 MiB ones by default; a
/// block that claims more is refused (memory stays bounded by what a log really holds).
inline constexpr std::size_t kMaxDecompressedBytes = std::size_t{256} << 20;

/// Decompresses `n` bytes at `data`, which must be one whole compressed block (a bz2 stream, an
/// LZ4 frame, a zstd frame) of exactly `size` bytes once decompressed, into `*out` (resized to
/// `size`). Memory grows with the output actually produced, never past `size`. Returns the reason
/// when the block is not that: corrupt, shorter or longer than `size`, followed by other bytes.
std::optional<std::string> Decompress(Compression compression, const unsigned char* data,
                                      std::size_t n, std::size_t size,
                                      std::vector<unsigned char>* out);

}  // namespace accelcal::internal
