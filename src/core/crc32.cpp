// CRC-32 (crc32.hpp).
#include "core/crc32.hpp"

#include <array>
#include <cstring>

namespace accelcal::internal {

namespace {

// table[k][b]: the CRC of byte b followed by k zero bytes, so that eight bytes are folded in at
// once (each through its own table) instead of one at a time.
struct Tables {
  std::array<std::array<std::uint32_t, 256>, 8> t{};
  Tables() {
    for (std::uint32_t b = 0; b < 256; ++b) {
      std::uint32_t c = b;
      for (int bit = 0; bit < 8; ++bit) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[0][b] = c;
    }
    for (std::size_t k = 1; k < 8; ++k) {
      for (std::size_t b = 0; b < 256; ++b)
        t[k][b] = (t[k - 1][b] >> 8) ^ t[0][t[k - 1][b] & 0xFFu];
    }
  }
};

const Tables& TheTables() {
  static const Tables tables;
  return tables;
}

}  // namespace

std::uint32_t Crc32(const unsigned char* data, std::size_t n, std::uint32_t crc) {
  const auto& t = TheTables().t;
  crc = ~crc;
  for (; n >= 8; n -= 8, data += 8) {
    std::uint32_t lo, hi;
    std::memcpy(&lo, data, 4);  // little-endian, as the tables assume
    std::memcpy(&hi, data + 4, 4);
    lo ^= crc;
    crc = t[7][lo & 0xFF] ^ t[6][(lo >> 8) & 0xFF] ^ t[5][(lo >> 16) & 0xFF] ^ t[4][lo >> 24] ^
          t[3][hi & 0xFF] ^ t[2][(hi >> 8) & 0xFF] ^ t[1][(hi >> 16) & 0xFF] ^ t[0][hi >> 24];
  }
  for (; n > 0; --n, ++data) crc = t[0][(crc ^ *data) & 0xFFu] ^ (crc >> 8);
  return ~crc;
}

}  // namespace accelcal::internal
