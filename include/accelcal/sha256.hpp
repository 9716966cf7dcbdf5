#pragma once
/// @file sha256.hpp
/// SHA-256 (FIPS 180-4) of a file's bytes, for the calibration file's `provenance`: which input,
/// exactly, a calibration came from. Written from the standard; on x86-64 CPUs with the SHA
/// extensions the block function runs on them (chosen at run time, as the solver's AVX kernel
/// is), about 15 times fewer instructions than the portable one, with the same digest.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace accelcal {

/// Incremental SHA-256: Update with the bytes in order, then Digest once.
class Sha256 {
 public:
  Sha256();
  void Update(const void* data, std::size_t size);
  /// The 32-byte digest; the object is spent afterwards (Update and Digest throw std::logic_error).
  std::array<std::uint8_t, 32> Digest();
  /// Digest() as 64 lowercase hexadecimal digits.
  std::string HexDigest();

 private:
  std::array<std::uint32_t, 8> state_;
  std::array<std::uint8_t, 64> buffer_{};
  std::size_t buffered_ = 0;
  std::uint64_t length_ = 0;  ///< bytes so far
  bool done_ = false;
};

/// The digest of `bytes` as 64 lowercase hexadecimal digits.
std::string Sha256Hex(std::string_view bytes);

namespace internal {
/// Whether the SHA extensions' block function is in use (the CPU has them and they were built).
bool Sha256UsesShaExtensions();
/// The portable digest, whatever the CPU: for tests comparing both block functions.
std::string Sha256HexPortable(std::string_view bytes);
}  // namespace internal

}  // namespace accelcal
