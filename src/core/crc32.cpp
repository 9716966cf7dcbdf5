// CRC-32 (crc32.hpp).
#include "core/crc32.hpp"

#include <array>
#include <cstring>

namespace accelcal::internal {

namespace {

// table[k][b]: the CRC of byte b followed by k zero bytes, so that sixteen bytes are folded in at
// once (each through its own table) instead of one at a time.
struct Tables {
  std::array<std::array<std::uint32_t, 256>, 16> t{};
  Tables() {
    for (std::uint32_t b = 0; b < 256; ++b) {
      std::uint32_t c = b;
      for (int bit = 0; bit < 8; ++bit) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[0][b] = c;
    }
    for (std::size_t k = 1; k < 16; ++k) {
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
  for (; n >= 16; n -= 16, data += 16) {
    std::uint32_t w[4];
    std::memcpy(w, data, 16);  // little-endian, as the tables assume
    w[0] ^= crc;
    crc = t[15][w[0] & 0xFF] ^ t[14][(w[0] >> 8) & 0xFF] ^ t[13][(w[0] >> 16) & 0xFF] ^
          t[12][w[0] >> 24] ^ t[11][w[1] & 0xFF] ^ t[10][(w[1] >> 8) & 0xFF] ^
          t[9][(w[1] >> 16) & 0xFF] ^ t[8][w[1] >> 24] ^ t[7][w[2] & 0xFF] ^
          t[6][(w[2] >> 8) & 0xFF] ^ t[5][(w[2] >> 16) & 0xFF] ^ t[4][w[2] >> 24] ^
          t[3][w[3] & 0xFF] ^ t[2][(w[3] >> 8) & 0xFF] ^ t[1][(w[3] >> 16) & 0xFF] ^
          t[0][w[3] >> 24];
  }
  for (; n > 0; --n, ++data) crc = t[0][(crc ^ *data) & 0xFFu] ^ (crc >> 8);
  return ~crc;
}

}  // namespace accelcal::internal
