#pragma once
// CRC-32 as zlib, PNG and MCAP define it (ISO-HDLC: polynomial 0x04C11DB7, reflected, initial
// value and final XOR 0xFFFFFFFF; "123456789" gives 0xCBF43926), sixteen bytes a step (the
// slicing-by-16 tables): an MCAP chunk is checked at memory speed.

#include <cstddef>
#include <cstdint>

namespace accelcal::internal {

/// The CRC-32 of `n` bytes at `data`, continuing from `crc` (0 to start).
std::uint32_t Crc32(const unsigned char* data, std::size_t n, std::uint32_t crc = 0);

}  // namespace accelcal::internal
