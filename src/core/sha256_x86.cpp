// SHA-256's block function on the x86 SHA extensions (sha256_blocks.hpp), built with -msha
// -msse4.1 and called only when the CPU has them (sha256.cpp). Four rounds per step: the message
// words W[4g..4g+3] plus the round constants feed two SHA256RNDS2, each two rounds; the state is
// kept as the halves (A, B, E, F) and (C, D, G, H) those instructions take (Intel SDM,
// SHA256RNDS2).
#include <immintrin.h>

#include "core/sha256_blocks.hpp"

namespace accelcal::internal {

void Sha256BlocksShaExtensions(std::uint32_t state[8], const std::uint8_t* data,
                               std::size_t blocks) {
  // state[0..3] = A B C D and state[4..7] = E F G H, lowest lane first, to ABEF and CDGH (highest
  // lane first, as the instructions number them).
  const __m128i abcd = _mm_shuffle_epi32(_mm_loadu_si128(reinterpret_cast<__m128i*>(state)), 0xB1);
  const __m128i efgh =
      _mm_shuffle_epi32(_mm_loadu_si128(reinterpret_cast<__m128i*>(state + 4)), 0x1B);
  __m128i abef = _mm_alignr_epi8(abcd, efgh, 8);
  __m128i cdgh = _mm_blend_epi16(efgh, abcd, 0xF0);
  // The message is big-endian 32-bit words.
  const __m128i byte_swap = _mm_set_epi64x(0x0c0d0e0f08090a0bLL, 0x0405060700010203LL);
  for (; blocks > 0; --blocks, data += 64) {
    const __m128i abef_before = abef, cdgh_before = cdgh;
    __m128i w[4];  // the last four groups of four message words, group g in w[g % 4]
    for (int g = 0; g < 16; ++g) {
      __m128i& words = w[g % 4];
      if (g < 4) {
        words = _mm_shuffle_epi8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(data + 16 * g)),
                                 byte_swap);
      } else {
        // W[t] = σ1(W[t-2]) + W[t-7] + σ0(W[t-15]) + W[t-16] for the group t = 4g..4g+3 (FIPS
        // 180-4 §6.2.2): MSG1 adds σ0, the aligned pair supplies W[t-7], MSG2 adds σ1.
        const __m128i previous = w[(g + 3) % 4], before_previous = w[(g + 2) % 4];
        __m128i next = _mm_sha256msg1_epu32(words, w[(g + 1) % 4]);
        next = _mm_add_epi32(next, _mm_alignr_epi8(previous, before_previous, 4));
        words = _mm_sha256msg2_epu32(next, previous);
      }
      __m128i message = _mm_add_epi32(
          words, _mm_loadu_si128(reinterpret_cast<const __m128i*>(kSha256RoundConstants + 4 * g)));
      cdgh = _mm_sha256rnds2_epu32(cdgh, abef, message);  // rounds 4g, 4g+1: cdgh is now ABEF
      message = _mm_shuffle_epi32(message, 0x0E);
      abef = _mm_sha256rnds2_epu32(abef, cdgh, message);  // rounds 4g+2, 4g+3
    }
    abef = _mm_add_epi32(abef, abef_before);
    cdgh = _mm_add_epi32(cdgh, cdgh_before);
  }
  const __m128i feba = _mm_shuffle_epi32(abef, 0x1B);
  const __m128i dchg = _mm_shuffle_epi32(cdgh, 0xB1);
  _mm_storeu_si128(reinterpret_cast<__m128i*>(state), _mm_blend_epi16(feba, dchg, 0xF0));
  _mm_storeu_si128(reinterpret_cast<__m128i*>(state + 4), _mm_alignr_epi8(dchg, feba, 8));
}

}  // namespace accelcal::internal
