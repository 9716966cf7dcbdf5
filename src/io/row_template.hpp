#pragma once
// A whole row read at once (row_parser): a logger's printf writes every row of a log alike, so
// the layout of the last row the field-by-field path read is kept as a template of byte classes
// (digits where its digits were, its other bytes as they were, and the signs that may change),
// and the next rows are checked against it 16 bytes at a time (32 with AVX2) and their numbers
// read from the positions it gives (the mantissas two a vector with SSSE3). A row it accepts is a
// row exactly like the template's but for digits and signs, which the field-by-field path reads as
// the same numbers (the same mantissa and exponent through the same arithmetic, DecimalMantissa and
// ExactDecimal); any other row is left to it.

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "io/number_parser.hpp"
#include "io/text_lines.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#include <immintrin.h>
#include <tmmintrin.h>
#endif

#include <algorithm>

namespace accelcal::internal {

/// Where a field's number lay in the row the field-by-field path read: its first byte (a sign
/// or a digit) from the line's start, and its layout after the sign.
struct FieldSeen {
  std::uint32_t start = 0;
  NumberShape shape;
};

class RowTemplate {
 public:
  /// Rows longer than this (with the line end) are read field by field.
  static constexpr std::size_t kMaxBytes = 128;

  bool empty() const { return length_ == 0; }

#if defined(__SSE2__)
  /// The template of the row of `length` bytes at `line` (up to and with its '\n'), whose
  /// `count` fields are all numbers read into the roles `role` with the layouts `fields`;
  /// `comma`: the file's delimiter. Rows too long for a template leave it empty.
  void Build(const char* line, std::size_t length, const FieldSeen* fields, const int* role,
             std::size_t count, bool comma) {
    length_ = 0;
    if (length > kMaxBytes || count > kMaxNumbers) return;
    for (std::size_t f = 0; f < count; ++f) {
      if (fields[f].shape.mask == 0) return;  // a number not read by its layout
    }
    std::memset(digit_, 0, sizeof digit_);
    std::memset(sign_, 0, sizeof sign_);
    std::memset(exp_sign_, 0, sizeof exp_sign_);
    std::memcpy(bytes_, line, length);
    std::memset(bytes_ + length, 0, sizeof bytes_ - length);
    const auto separator = [&](std::size_t at) {
      return IsBlank(line[at]) || (comma && line[at] == ',');
    };
    for (std::size_t f = 0; f < count; ++f) {
      const NumberShape& s = fields[f].shape;
      Number& n = numbers_[f];
      n.role = static_cast<std::uint8_t>(role[f]);
      std::size_t at = fields[f].start;
      // The sign's place: where the sign is, or the blank before the number, when the number
      // still begins a field with a sign there (a separator or the line's start before it).
      const char first = line[at];
      n.sign_at = kNone;
      if (first == '-' || first == '+') {
        n.sign_at = static_cast<std::uint8_t>(at);
        ++at;
      } else if (at > 0 && IsBlank(line[at - 1]) && (at == 1 || separator(at - 2))) {
        n.sign_at = static_cast<std::uint8_t>(at - 1);
      }
      if (n.sign_at != kNone) sign_[n.sign_at] = 0xFF;
      n.digits_at = static_cast<std::uint8_t>(at);
      for (unsigned i = 0; i < s.length; ++i) {
        if ((s.digits >> i) & 1u) digit_[at + i] = 0xFF;
      }
      n.int_len = s.int_len;
      n.frac_at = static_cast<std::uint8_t>(at + s.frac_begin);
      n.frac_len = s.frac_len;
      n.exp_at = s.exp_at == 0 ? kNone : static_cast<std::uint8_t>(at + s.exp_begin);
      n.exp_len = s.exp_len;
      n.exp_sign_at = kNone;
      if (s.exp_at != 0 && s.exp_signed) {
        n.exp_sign_at = static_cast<std::uint8_t>(at + s.exp_at + 1);
        exp_sign_[n.exp_sign_at] = 0xFF;
      }
    }
    count_ = count;
    length_ = length;
    // 32 bytes at a time where the CPU has AVX2 (3 blocks for a 65-byte row instead of 5).
    wide_ = Cpu().avx2;
    const std::size_t block = wide_ ? 32 : 16;
    chunks_ = (length + block - 1) / block;
    readable_ = block * chunks_;
    // The mantissas' digits for the vector path: number 2i's at bytes 0-7 of pair i's vector and
    // number 2i + 1's at bytes 8-15, each right-aligned (zeros before it), gathered from 16 bytes
    // loaded at its first digit. Mantissas of more than 8 digits take the scalar path.
    vector_ = Cpu().ssse3;
    for (std::size_t f = 0; f < count; ++f) {
      const Number& n = numbers_[f];
      const unsigned digits = n.int_len + n.frac_len;
      if (digits > 8) vector_ = false;
      readable_ = std::max<std::size_t>(readable_, n.digits_at + std::size_t{16});
      unsigned char* shuffle = shuffle_[f / 2] + 8 * (f % 2);
      std::memset(shuffle, 0x80, 8);  // 0x80: a zero byte
      for (unsigned j = 0; j < digits && digits <= 8; ++j) {
        const unsigned from = j < n.int_len ? j : n.frac_at - n.digits_at + (j - n.int_len);
        shuffle[8 - digits + j] = static_cast<unsigned char>(from);
      }
    }
    if (count % 2 == 1) std::memset(shuffle_[count / 2] + 8, 0x80, 8);
    // Bytes past the line end are not checked.
    const unsigned all = wide_ ? 0xFFFFFFFFu : 0xFFFFu;
    tail_ = length % block == 0 ? 0u : (all << (length % block)) & all;
  }

  /// The row at `p` read into `values` when it is laid out as the template (and the text at `p`,
  /// up to `last`, holds the blocks it loads): the position after its '\n'; nullptr otherwise.
  const char* Read(const char* p, const char* last, double* values) const {
    if (static_cast<std::size_t>(last - p) < readable_) return nullptr;
    if (!(wide_ ? MatchesWide(p) : Matches(p))) return nullptr;
    std::uint64_t mantissa[kMaxNumbers];
    if (vector_) {
      VectorMantissas(p, mantissa);
    } else {
      for (std::size_t f = 0; f < count_; ++f) {
        const Number& n = numbers_[f];
        mantissa[f] = 0;  // the template's lengths are ones DecimalMantissa reads
        DecimalMantissa(p + n.digits_at, n.int_len, p + n.frac_at, n.frac_len, &mantissa[f]);
      }
    }
    for (std::size_t f = 0; f < count_; ++f) {
      const Number& n = numbers_[f];
      int exponent = -static_cast<int>(n.frac_len);
      if (n.exp_at != kNone) {
        const int e = ExponentDigits(p + n.exp_at, n.exp_len);
        exponent += (n.exp_sign_at != kNone && p[n.exp_sign_at] == '-') ? -e : e;
        if (exponent < -22 || exponent > 22) return nullptr;
      }
      values[n.role] =
          ExactDecimal(mantissa[f], exponent, n.sign_at != kNone && p[n.sign_at] == '-');
    }
    return p + length_;
  }
#endif

 private:
  static constexpr std::uint8_t kNone = 0xFF;
  static constexpr std::size_t kMaxNumbers = 16;
  struct Number {
    std::uint8_t role = 0;
    std::uint8_t sign_at = kNone;  // '+', '-' or ' ' may be there
    std::uint8_t digits_at = 0, int_len = 0, frac_at = 0, frac_len = 0;
    std::uint8_t exp_at = kNone, exp_len = 0;  // the exponent's digits
    std::uint8_t exp_sign_at = kNone;          // '+' or '-' may be there
  };
#if defined(__SSE2__)
  // Whether the row at `p` is laid out as the template, 16 bytes at a time.
  bool Matches(const char* p) const {
    const __m128i zero_below = _mm_set1_epi8('0' - 1), nine_above = _mm_set1_epi8('9' + 1);
    const __m128i space = _mm_set1_epi8(' '), plus = _mm_set1_epi8('+'), minus = _mm_set1_epi8('-');
    for (std::size_t c = 0; c < chunks_; ++c) {
      const __m128i text = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + 16 * c));
      const __m128i digit = Load(digit_, c);
      const __m128i is_digit =
          _mm_and_si128(_mm_cmpgt_epi8(text, zero_below), _mm_cmplt_epi8(text, nine_above));
      const __m128i is_sign = _mm_or_si128(_mm_cmpeq_epi8(text, plus), _mm_cmpeq_epi8(text, minus));
      // A digit exactly where the template has one; elsewhere the template's byte, or a sign (or
      // a blank) in a sign's place, or either sign in an exponent sign's place.
      const __m128i other = _mm_or_si128(
          _mm_or_si128(digit, _mm_cmpeq_epi8(text, Load(bytes_, c))),
          _mm_or_si128(
              _mm_and_si128(Load(sign_, c), _mm_or_si128(is_sign, _mm_cmpeq_epi8(text, space))),
              _mm_and_si128(Load(exp_sign_, c), is_sign)));
      const __m128i ok = _mm_and_si128(_mm_cmpeq_epi8(is_digit, digit), other);
      unsigned mask = static_cast<unsigned>(_mm_movemask_epi8(ok));
      if (c + 1 == chunks_) mask |= tail_;
      if (mask != 0xFFFFu) return false;
    }
    return true;
  }

#if defined(__x86_64__)
  // Matches, 32 bytes at a time (AVX2).
  __attribute__((target("avx2"))) bool MatchesWide(const char* p) const {
    const __m256i zero_below = _mm256_set1_epi8('0' - 1), nine_above = _mm256_set1_epi8('9' + 1);
    const __m256i space = _mm256_set1_epi8(' '), plus = _mm256_set1_epi8('+'),
                  minus = _mm256_set1_epi8('-');
    for (std::size_t c = 0; c < chunks_; ++c) {
      const __m256i text = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p + 32 * c));
      const __m256i digit = _mm256_load_si256(reinterpret_cast<const __m256i*>(digit_ + 32 * c));
      const __m256i is_digit = _mm256_and_si256(_mm256_cmpgt_epi8(text, zero_below),
                                                _mm256_cmpgt_epi8(nine_above, text));
      const __m256i is_sign =
          _mm256_or_si256(_mm256_cmpeq_epi8(text, plus), _mm256_cmpeq_epi8(text, minus));
      const __m256i other = _mm256_or_si256(
          _mm256_or_si256(
              digit, _mm256_cmpeq_epi8(text, _mm256_load_si256(reinterpret_cast<const __m256i*>(
                                                 bytes_ + 32 * c)))),
          _mm256_or_si256(
              _mm256_and_si256(_mm256_load_si256(reinterpret_cast<const __m256i*>(sign_ + 32 * c)),
                               _mm256_or_si256(is_sign, _mm256_cmpeq_epi8(text, space))),
              _mm256_and_si256(
                  _mm256_load_si256(reinterpret_cast<const __m256i*>(exp_sign_ + 32 * c)),
                  is_sign)));
      const __m256i ok = _mm256_and_si256(_mm256_cmpeq_epi8(is_digit, digit), other);
      unsigned mask = static_cast<unsigned>(_mm256_movemask_epi8(ok));
      if (c + 1 == chunks_) mask |= tail_;
      if (mask != 0xFFFFFFFFu) return false;
    }
    return true;
  }
#else
  bool MatchesWide(const char*) const { return false; }       // never chosen (Cpu)
#endif

#if defined(__x86_64__)

  // The mantissas (at most 8 digits each), two numbers a vector: the digits gathered by the
  // template's shuffles, then combined by multiply-adds, pairs, fours, eights (SSSE3).
  __attribute__((target("ssse3"))) void VectorMantissas(const char* p,
                                                        std::uint64_t* mantissa) const {
    const __m128i zero = _mm_set1_epi8('0');
    const __m128i tens = _mm_set_epi8(1, 10, 1, 10, 1, 10, 1, 10, 1, 10, 1, 10, 1, 10, 1, 10);
    const __m128i hundreds = _mm_set_epi16(1, 100, 1, 100, 1, 100, 1, 100);
    const __m128i ten_thousands = _mm_set_epi16(1, 10000, 1, 10000, 1, 10000, 1, 10000);
    for (std::size_t f = 0; f < count_; f += 2) {
      const std::size_t g = f + 1 < count_ ? f + 1 : f;
      const __m128i a = _mm_sub_epi8(
          _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + numbers_[f].digits_at)), zero);
      const __m128i b = _mm_sub_epi8(
          _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + numbers_[g].digits_at)), zero);
      // Number f's digits from a into bytes 0-7, number g's from b into bytes 8-15.
      const __m128i shuffle = Load(shuffle_[f / 2], 0);
      const __m128i low = _mm_shuffle_epi8(a, _mm_or_si128(shuffle, kHighHalfZero()));
      const __m128i high = _mm_shuffle_epi8(b, _mm_or_si128(shuffle, kLowHalfZero()));
      const __m128i digits = _mm_or_si128(low, high);
      const __m128i pairs = _mm_maddubs_epi16(digits, tens);
      const __m128i fours = _mm_madd_epi16(pairs, hundreds);
      const __m128i eights = _mm_madd_epi16(_mm_packs_epi32(fours, fours), ten_thousands);
      const auto both = static_cast<std::uint64_t>(_mm_cvtsi128_si64(eights));
      mantissa[f] = both & 0xFFFFFFFFu;
      if (g != f) mantissa[g] = both >> 32;
    }
  }
#else
  void VectorMantissas(const char*, std::uint64_t*) const {}  // never chosen (Cpu)
#endif
  // Shuffle masks that zero one half of the result (the index's top bit set).
  static __m128i kHighHalfZero() {
    return _mm_set_epi8(-128, -128, -128, -128, -128, -128, -128, -128, 0, 0, 0, 0, 0, 0, 0, 0);
  }
  static __m128i kLowHalfZero() {
    return _mm_set_epi8(0, 0, 0, 0, 0, 0, 0, 0, -128, -128, -128, -128, -128, -128, -128, -128);
  }
  // What the CPU offers beyond SSE2, asked once.
  struct Extensions {
    bool ssse3 = false, avx2 = false;
  };
  static const Extensions& Cpu() {
    static const Extensions cpu = [] {
      Extensions e;
#if defined(__GNUC__) && defined(__x86_64__)
      e.ssse3 = __builtin_cpu_supports("ssse3") != 0;
      e.avx2 = __builtin_cpu_supports("avx2") != 0;
#endif
      return e;
    }();
    return cpu;
  }

  static __m128i Load(const unsigned char* bytes, std::size_t chunk) {
    return _mm_load_si128(reinterpret_cast<const __m128i*>(bytes + 16 * chunk));
  }
  static __m128i Load(const char* bytes, std::size_t chunk) {
    return _mm_load_si128(reinterpret_cast<const __m128i*>(bytes + 16 * chunk));
  }
#endif

  alignas(32) char bytes_[kMaxBytes] = {};                       // the row (zeros after it)
  alignas(32) unsigned char digit_[kMaxBytes] = {};              // 0xFF where a digit must be
  alignas(32) unsigned char sign_[kMaxBytes] = {};               // 0xFF: '+', '-' or ' '
  alignas(32) unsigned char exp_sign_[kMaxBytes] = {};           // 0xFF: '+' or '-'
  alignas(16) unsigned char shuffle_[kMaxNumbers / 2][16] = {};  // VectorMantissas' gathers
  Number numbers_[kMaxNumbers];
  std::size_t count_ = 0, length_ = 0, chunks_ = 0;
  std::size_t readable_ = 0;  // bytes Read needs at the row
  unsigned tail_ = 0;
  bool vector_ = false;
  bool wide_ = false;  // blocks of 32 bytes (MatchesWide), else 16
};

}  // namespace accelcal::internal
