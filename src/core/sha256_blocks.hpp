#pragma once
// The block functions of SHA-256 (sha256.cpp): `blocks` 64-byte blocks of `data` folded into
// `state` (FIPS 180-4 §6.2.2).
#include <cstddef>
#include <cstdint>

namespace accelcal::internal {

extern const std::uint32_t kSha256RoundConstants[64];  // K of FIPS 180-4 §4.2.2

void Sha256BlocksPortable(std::uint32_t state[8], const std::uint8_t* data, std::size_t blocks);
#if defined(ACCELCAL_HAVE_SHA_EXTENSIONS)
void Sha256BlocksShaExtensions(std::uint32_t state[8], const std::uint8_t* data,
                               std::size_t blocks);
#endif

}  // namespace accelcal::internal
