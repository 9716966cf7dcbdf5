#include "accelcal/sha256.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>

#include "core/cpu_features.hpp"
#include "core/sha256_blocks.hpp"

namespace accelcal {

namespace internal {

// FIPS 180-4 §4.2.2: the first 32 bits of the fractional parts of the cube roots of the first 64
// primes.
const std::uint32_t kSha256RoundConstants[64] = {
    0x428a2f98, 0x71374491, 0xb5c0fbcf, 0xe9b5dba5, 0x3956c25b, 0x59f111f1, 0x923f82a4, 0xab1c5ed5,
    0xd807aa98, 0x12835b01, 0x243185be, 0x550c7dc3, 0x72be5d74, 0x80deb1fe, 0x9bdc06a7, 0xc19bf174,
    0xe49b69c1, 0xefbe4786, 0x0fc19dc6, 0x240ca1cc, 0x2de92c6f, 0x4a7484aa, 0x5cb0a9dc, 0x76f988da,
    0x983e5152, 0xa831c66d, 0xb00327c8, 0xbf597fc7, 0xc6e00bf3, 0xd5a79147, 0x06ca6351, 0x14292967,
    0x27b70a85, 0x2e1b2138, 0x4d2c6dfc, 0x53380d13, 0x650a7354, 0x766a0abb, 0x81c2c92e, 0x92722c85,
    0xa2bfe8a1, 0xa81a664b, 0xc24b8b70, 0xc76c51a3, 0xd192e819, 0xd6990624, 0xf40e3585, 0x106aa070,
    0x19a4c116, 0x1e376c08, 0x2748774c, 0x34b0bcb5, 0x391c0cb3, 0x4ed8aa4a, 0x5b9cca4f, 0x682e6ff3,
    0x748f82ee, 0x78a5636f, 0x84c87814, 0x8cc70208, 0x90befffa, 0xa4506ceb, 0xbef9a3f7, 0xc67178f2};

namespace {

constexpr std::uint32_t Rotr(std::uint32_t x, int n) { return (x >> n) | (x << (32 - n)); }

std::uint32_t BigEndian32(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) |
         std::uint32_t{p[3]};
}

}  // namespace

void Sha256BlocksPortable(std::uint32_t state[8], const std::uint8_t* data, std::size_t blocks) {
  for (; blocks > 0; --blocks, data += 64) {
    std::uint32_t w[64];  // the message schedule, §6.2.2 step 1
    for (int t = 0; t < 16; ++t) w[t] = BigEndian32(data + 4 * t);
    for (int t = 16; t < 64; ++t) {
      const std::uint32_t s0 = Rotr(w[t - 15], 7) ^ Rotr(w[t - 15], 18) ^ (w[t - 15] >> 3);
      const std::uint32_t s1 = Rotr(w[t - 2], 17) ^ Rotr(w[t - 2], 19) ^ (w[t - 2] >> 10);
      w[t] = w[t - 16] + s0 + w[t - 7] + s1;
    }
    std::uint32_t a = state[0], b = state[1], c = state[2], d = state[3];
    std::uint32_t e = state[4], f = state[5], g = state[6], h = state[7];
    for (int t = 0; t < 64; ++t) {  // §6.2.2 step 3
      const std::uint32_t S1 = Rotr(e, 6) ^ Rotr(e, 11) ^ Rotr(e, 25);
      const std::uint32_t choose = (e & f) ^ (~e & g);
      const std::uint32_t t1 = h + S1 + choose + kSha256RoundConstants[t] + w[t];
      const std::uint32_t S0 = Rotr(a, 2) ^ Rotr(a, 13) ^ Rotr(a, 22);
      const std::uint32_t majority = (a & b) ^ (a & c) ^ (b & c);
      const std::uint32_t t2 = S0 + majority;
      h = g, g = f, f = e, e = d + t1, d = c, c = b, b = a, a = t1 + t2;
    }
    state[0] += a, state[1] += b, state[2] += c, state[3] += d;
    state[4] += e, state[5] += f, state[6] += g, state[7] += h;
  }
}

namespace {

using BlockFunction = void (*)(std::uint32_t*, const std::uint8_t*, std::size_t);

BlockFunction ChooseBlocks() {
#if defined(ACCELCAL_HAVE_SHA_EXTENSIONS)
  // What the extensions' block function is built with: SHA, SSSE3 and SSE4.1.
  const CpuFeatures& cpu = Cpu();
  if (cpu.sha && cpu.ssse3 && cpu.sse41) return Sha256BlocksShaExtensions;
#endif
  return Sha256BlocksPortable;
}

BlockFunction Blocks() {
  static const BlockFunction chosen = ChooseBlocks();
  return chosen;
}

}  // namespace

bool Sha256UsesShaExtensions() { return Blocks() != Sha256BlocksPortable; }

}  // namespace internal

namespace {

constexpr std::array<std::uint32_t, 8> kInitialState = {  // FIPS 180-4 §5.3.3
    0x6a09e667, 0xbb67ae85, 0x3c6ef372, 0xa54ff53a, 0x510e527f, 0x9b05688c, 0x1f83d9ab, 0x5be0cd19};

using BlockFunction = void (*)(std::uint32_t*, const std::uint8_t*, std::size_t);

// Update and Digest with a given block function (the portable one for the tests' comparison).
class Hasher {
 public:
  explicit Hasher(BlockFunction blocks) : blocks_(blocks) {}
  void Update(std::array<std::uint32_t, 8>& state, std::array<std::uint8_t, 64>& buffer,
              std::size_t& buffered, std::uint64_t& length, const std::uint8_t* p,
              std::size_t size) const {
    length += size;
    if (buffered > 0) {
      const std::size_t take = std::min(size, 64 - buffered);
      std::memcpy(buffer.data() + buffered, p, take);
      buffered += take, p += take, size -= take;
      if (buffered < 64) return;
      blocks_(state.data(), buffer.data(), 1);
      buffered = 0;
    }
    blocks_(state.data(), p, size / 64);
    p += size / 64 * 64, size %= 64;
    std::memcpy(buffer.data(), p, size);
    buffered = size;
  }
  std::array<std::uint8_t, 32> Digest(std::array<std::uint32_t, 8>& state,
                                      std::array<std::uint8_t, 64>& buffer, std::size_t buffered,
                                      std::uint64_t length) const {
    // §5.1.1: a 1 bit, zeros to 56 mod 64 bytes, the length in bits as 64-bit big-endian.
    buffer[buffered++] = 0x80;
    if (buffered > 56) {
      std::memset(buffer.data() + buffered, 0, 64 - buffered);
      blocks_(state.data(), buffer.data(), 1);
      buffered = 0;
    }
    std::memset(buffer.data() + buffered, 0, 56 - buffered);
    const std::uint64_t bits = length * 8;
    for (int i = 0; i < 8; ++i) buffer[56 + i] = static_cast<std::uint8_t>(bits >> (56 - 8 * i));
    blocks_(state.data(), buffer.data(), 1);
    std::array<std::uint8_t, 32> digest;
    for (int i = 0; i < 8; ++i) {
      for (int j = 0; j < 4; ++j)
        digest[4 * i + j] = static_cast<std::uint8_t>(state[i] >> (24 - 8 * j));
    }
    return digest;
  }

 private:
  BlockFunction blocks_;
};

std::string Hex(const std::array<std::uint8_t, 32>& digest) {
  static const char kDigits[] = "0123456789abcdef";
  std::string hex;
  for (const std::uint8_t byte : digest) {
    hex += kDigits[byte >> 4];
    hex += kDigits[byte & 15];
  }
  return hex;
}

std::string HexWith(BlockFunction blocks, std::string_view bytes) {
  std::array<std::uint32_t, 8> state = kInitialState;
  std::array<std::uint8_t, 64> buffer{};
  std::size_t buffered = 0;
  std::uint64_t length = 0;
  const Hasher hasher(blocks);
  hasher.Update(state, buffer, buffered, length,
                reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
  return Hex(hasher.Digest(state, buffer, buffered, length));
}

}  // namespace

Sha256::Sha256() : state_(kInitialState) {}

void Sha256::Update(const void* data, std::size_t size) {
  if (done_) throw std::logic_error("Sha256::Update after Digest");
  Hasher(internal::Blocks())
      .Update(state_, buffer_, buffered_, length_, static_cast<const std::uint8_t*>(data), size);
}

std::array<std::uint8_t, 32> Sha256::Digest() {
  if (done_) throw std::logic_error("Sha256::Digest called twice");
  done_ = true;
  return Hasher(internal::Blocks()).Digest(state_, buffer_, buffered_, length_);
}

std::string Sha256::HexDigest() { return Hex(Digest()); }

std::string Sha256Hex(std::string_view bytes) { return HexWith(internal::Blocks(), bytes); }

std::string internal::Sha256HexPortable(std::string_view bytes) {
  return HexWith(internal::Sha256BlocksPortable, bytes);
}

}  // namespace accelcal
