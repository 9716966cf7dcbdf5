#pragma once
// The log writers' block compression (ROS 1 bag chunks: bz2, lz4; MCAP chunks: lz4, zstd), the
// inverse of io/decompress.hpp, on the same Debian libraries.

#include <string>
#include <string_view>

#include "io/decompress.hpp"

namespace accelcal::internal {

/// `in` compressed as one whole block (a bz2 stream at level 9 as rosbag writes it, one LZ4
/// frame, one zstd frame at level 3); `in` itself for kNone. Throws std::runtime_error when the
/// library fails (out of memory).
std::string Compress(Compression compression, std::string_view in);

}  // namespace accelcal::internal
