#pragma once
// A whole row read at once (row_parser): a logger's printf writes every row of a log alike, so
// the layout of the last row the field-by-field path read is kept as a template of byte classes
// (digits where its digits were, its other bytes as they were, and the signs that may change),
// and the next rows are checked against it 16 bytes at a time (32 with AVX2) and their numbers
// read from the positions it gives (the mantissas two a vector with SSSE3). A row it accepts is a
// row exactly like the template's but for digits and signs, which the field-by-field path reads as
// the same numbers (the same mantissa and exponent through the same arithmetic, DecimalMantissa and
// ExactDecimal); any other row is left to it. The exponents of the last row read are kept with its
// bytes: a row whose exponents are those bytes (most rows: a logger's values change in their
// digits) is checked in one pass that also finds its signs, and its exponents are not read again.

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "core/cpu_features.hpp"
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
    std::memset(mantissa_digit_, 0, sizeof mantissa_digit_);
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
        if ((s.digits >> i) & 1u) digit_[at + i] = mantissa_digit_[at + i] = 0xFF;
      }
      n.int_len = s.int_len;
      n.frac_at = static_cast<std::uint8_t>(at + s.frac_begin);
      n.frac_len = s.frac_len;
      n.exp_at = s.exp_at == 0 ? kNone : static_cast<std::uint8_t>(at + s.exp_begin);
      n.exp_len = s.exp_len;
      for (unsigned i = 0; s.exp_at != 0 && i < s.exp_len; ++i) mantissa_digit_[n.exp_at + i] = 0;
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
    // The vector path (VectorValues) reads numbers two at a time from 16 bytes loaded at each one's
    // sign place (or first digit, without one): number 2i's digits right-aligned in bytes 0-7 of
    // pair i's vector and its sign in byte 0 of another, number 2i + 1's in bytes 8-15. Mantissas
    // of more than 8 digits take the scalar path.
    vector_ = Cpu().ssse3;
    std::memset(gather_, 0x80, sizeof gather_);  // 0x80: a zero byte
    for (std::size_t f = 0; f < count; ++f) {
      Number& n = numbers_[f];
      n.load_at = n.sign_at != kNone ? n.sign_at : n.digits_at;  // the sign is just before
      const unsigned digits = n.int_len + n.frac_len;
      const unsigned last_digit =
          n.frac_len > 0 ? n.frac_at + n.frac_len - 1u : n.digits_at + n.int_len - 1u;
      if (digits > 8 || last_digit - n.load_at > 15) vector_ = false;
      readable_ = std::max<std::size_t>(readable_, n.load_at + std::size_t{16});
      unsigned char(&gather)[4][16] = gather_[f / 2];
      const unsigned half = 8 * (f % 2);
      for (unsigned j = 0; j < digits && vector_; ++j) {
        const unsigned from = j < n.int_len ? n.digits_at + j : n.frac_at + (j - n.int_len);
        gather[f % 2][half + 8 - digits + j] = static_cast<unsigned char>(from - n.load_at);
      }
      if (n.sign_at != kNone) gather[2 + f % 2][half] = 0;
    }
    // Bytes past the line end are not checked.
    for (std::size_t c = 0; c < chunks_; ++c) {
      const std::size_t end = std::min(length, block * (c + 1)) - block * c;
      past_end_[c] = static_cast<unsigned>(((std::uint64_t{1} << block) - 1) &
                                           ~((std::uint64_t{1} << end) - 1));
    }
    if (!Refer(line)) length_ = 0;  // an exponent beyond ExactDecimal's
  }

  /// Reads the rows from `p` on that are laid out as the template, at most `max_rows`, while the
  /// text up to `last` holds the blocks a row loads: each row's values go to `values` (by role)
  /// and then `row(values, next)` is called, `next` being the position after the row's '\n'.
  /// Returns the position after the last row read (`p` when none is).
  template <typename Row>
  const char* ReadRows(const char* p, const char* last, std::size_t max_rows, double* values,
                       Row& row) {
#if defined(__x86_64__)
    if (wide_) return ReadRowsWide(p, last, max_rows, values, row);
#endif
    for (std::size_t n = 0; n < max_rows && Holds(p, last); ++n) {
      // Most rows have the exponents of the last row read; another row is checked against the
      // whole layout, and its exponents read and kept.
      if (!Check<false>(p) && !(Check<true>(p) && Refer(p))) break;
      if (vector_) {
        VectorValues(p, values);
      } else {
        ScalarValues(p, values);
      }
      p += length_;
      row(values, p);
    }
    return p;
  }
#endif

 private:
#if defined(__SSE2__)
  bool Holds(const char* p, const char* last) const {
    return static_cast<std::size_t>(last - p) >= readable_;
  }
#if defined(__x86_64__)
  // ReadRows, 32 bytes at a time, with the checks and the vector path compiled into the loop.
  template <typename Row>
  __attribute__((target("avx2"))) const char* ReadRowsWide(const char* p, const char* last,
                                                           std::size_t max_rows, double* values,
                                                           Row& row) {
    for (std::size_t n = 0; n < max_rows && Holds(p, last); ++n) {
      if (!CheckWide<false>(p) && !(CheckWide<true>(p) && Refer(p))) break;
      if (vector_) {
        VectorValues(p, values);
      } else {
        ScalarValues(p, values);
      }
      p += length_;
      row(values, p);
    }
    return p;
  }
#endif
  // The numbers one by one (mantissas of more than 8 digits, or no SSSE3).
  void ScalarValues(const char* p, double* values) const {
    for (std::size_t f = 0; f < count_; ++f) {
      const Number& n = numbers_[f];
      std::uint64_t mantissa = 0;  // the template's lengths are ones DecimalMantissa reads
      DecimalMantissa(p + n.digits_at, n.int_len, p + n.frac_at, n.frac_len, &mantissa);
      values[n.role] =
          ExactDecimal(mantissa, exponent_[f], n.sign_at != kNone && p[n.sign_at] == '-');
    }
  }
#endif
  static constexpr std::uint8_t kNone = 0xFF;
  static constexpr std::size_t kMaxNumbers = 16;
  struct Number {
    std::uint8_t role = 0;
    std::uint8_t sign_at = kNone;  // '+', '-' or ' ' may be there
    std::uint8_t digits_at = 0, int_len = 0, frac_at = 0, frac_len = 0;
    std::uint8_t exp_at = kNone, exp_len = 0;  // the exponent's digits
    std::uint8_t exp_sign_at = kNone;          // '+' or '-' may be there
    std::uint8_t load_at = 0;                  // VectorValues' 16 bytes
  };
#if defined(__SSE2__)
  // Whether the row at `p` is laid out as the template. kAnyExponent: its exponents' digits and
  // signs may be any; else they must be the reference's (bytes_).
  template <bool kAnyExponent>
  bool Check(const char* p) const {
    const unsigned char* const digit = kAnyExponent ? digit_ : mantissa_digit_;
    unsigned wrong = 0;
    for (std::size_t c = 0; c < chunks_; ++c) {
      const __m128i text = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + 16 * c));
      const __m128i d = _mm_sub_epi8(text, _mm_set1_epi8('0'));
      const __m128i is_digit = _mm_cmpeq_epi8(_mm_min_epu8(d, _mm_set1_epi8(9)), d);
      const __m128i is_sign = _mm_or_si128(_mm_cmpeq_epi8(text, _mm_set1_epi8('-')),
                                           _mm_cmpeq_epi8(text, _mm_set1_epi8('+')));
      // A digit where the template's digits are; elsewhere the reference's byte, or a sign (or a
      // blank) in a sign's place, or either sign in an exponent sign's place.
      const __m128i at_digit = Load(digit, c);
      __m128i ok = _mm_or_si128(_mm_and_si128(at_digit, is_digit),
                                _mm_andnot_si128(at_digit, _mm_cmpeq_epi8(text, Load(bytes_, c))));
      ok = _mm_or_si128(
          ok, _mm_and_si128(Load(sign_, c),
                            _mm_or_si128(is_sign, _mm_cmpeq_epi8(text, _mm_set1_epi8(' ')))));
      if (kAnyExponent) ok = _mm_or_si128(ok, _mm_and_si128(Load(exp_sign_, c), is_sign));
      wrong |= ~(static_cast<unsigned>(_mm_movemask_epi8(ok)) | past_end_[c]) & 0xFFFFu;
    }
    return wrong == 0;
  }

#if defined(__x86_64__)
  // Check, 32 bytes at a time (AVX2).
  template <bool kAnyExponent>
  __attribute__((target("avx2"), always_inline)) bool CheckWide(const char* p) const {
    const unsigned char* const digit = kAnyExponent ? digit_ : mantissa_digit_;
    unsigned wrong = 0;
    for (std::size_t c = 0; c < chunks_; ++c) {
      const __m256i text = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p + 32 * c));
      const __m256i d = _mm256_sub_epi8(text, _mm256_set1_epi8('0'));
      const __m256i is_digit = _mm256_cmpeq_epi8(_mm256_min_epu8(d, _mm256_set1_epi8(9)), d);
      const __m256i is_sign = _mm256_or_si256(_mm256_cmpeq_epi8(text, _mm256_set1_epi8('-')),
                                              _mm256_cmpeq_epi8(text, _mm256_set1_epi8('+')));
      __m256i ok = _mm256_blendv_epi8(_mm256_cmpeq_epi8(text, Load32(bytes_, c)), is_digit,
                                      Load32(digit, c));
      ok = _mm256_or_si256(
          ok, _mm256_and_si256(
                  Load32(sign_, c),
                  _mm256_or_si256(is_sign, _mm256_cmpeq_epi8(text, _mm256_set1_epi8(' ')))));
      if (kAnyExponent) ok = _mm256_or_si256(ok, _mm256_and_si256(Load32(exp_sign_, c), is_sign));
      wrong |= ~(static_cast<unsigned>(_mm256_movemask_epi8(ok)) | past_end_[c]);
    }
    return wrong == 0;
  }
  template <typename Byte>
  __attribute__((target("avx2"), always_inline)) static __m256i Load32(const Byte* bytes,
                                                                       std::size_t chunk) {
    return _mm256_load_si256(reinterpret_cast<const __m256i*>(bytes + 32 * chunk));
  }
#endif

  // The exponents of the row at `p` (laid out as the template) kept, with its bytes as the
  // reference; false, keeping the last, when one is beyond ExactDecimal's exact range.
  bool Refer(const char* p) {
    int exponent[kMaxNumbers];
    for (std::size_t f = 0; f < count_; ++f) {
      const Number& n = numbers_[f];
      exponent[f] = -static_cast<int>(n.frac_len);
      if (n.exp_at != kNone) {
        const int e = ExponentDigits(p + n.exp_at, n.exp_len);
        exponent[f] += (n.exp_sign_at != kNone && p[n.exp_sign_at] == '-') ? -e : e;
        if (exponent[f] < -22 || exponent[f] > 22) return false;
      }
    }
    for (std::size_t f = 0; f < count_; ++f) {
      exponent_[f] = exponent[f];
      // ExactDecimal's one rounding as v · multiply / divide, one of the two being 1.
      multiply_[f] = exponent[f] < 0 ? 1.0 : kExactPow10[exponent[f]];
      divide_[f] = exponent[f] < 0 ? kExactPow10[-exponent[f]] : 1.0;
    }
    if (count_ < kMaxNumbers) multiply_[count_] = divide_[count_] = 1.0;  // an odd count's pair
    std::memcpy(bytes_, p, length_);
    return true;
  }

#if defined(__x86_64__)
  // The row's numbers (mantissas of at most 8 digits), two a vector: digits and signs gathered by
  // the template's shuffles, the digits combined by multiply-adds (pairs, fours, eights), then
  // ExactDecimal's arithmetic on both lanes (SSSE3).
  __attribute__((target("ssse3"))) void VectorValues(const char* p, double* values) const {
    const __m128i zero = _mm_set1_epi8('0'), minus = _mm_set1_epi8('-');
    const __m128i tens = _mm_set_epi8(1, 10, 1, 10, 1, 10, 1, 10, 1, 10, 1, 10, 1, 10, 1, 10);
    const __m128i hundreds = _mm_set_epi16(1, 100, 1, 100, 1, 100, 1, 100);
    const __m128i ten_thousands = _mm_set_epi16(1, 10000, 1, 10000, 1, 10000, 1, 10000);
    for (std::size_t f = 0; f < count_; f += 2) {
      const std::size_t g = f + 1 < count_ ? f + 1 : f;
      const __m128i a = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + numbers_[f].load_at));
      const __m128i b = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + numbers_[g].load_at));
      const unsigned char(&gather)[4][16] = gather_[f / 2];
      // The digits' bytes, then their values: a zero byte stays 0 ('0' subtracted, saturated).
      const __m128i digits = _mm_subs_epu8(_mm_or_si128(_mm_shuffle_epi8(a, Load(gather[0], 0)),
                                                        _mm_shuffle_epi8(b, Load(gather[1], 0))),
                                           zero);
      const __m128i pairs = _mm_maddubs_epi16(digits, tens);
      const __m128i fours = _mm_madd_epi16(pairs, hundreds);
      const __m128i eights = _mm_madd_epi16(_mm_packs_epi32(fours, fours), ten_thousands);
      // The signs' bytes at bytes 0 and 8: a '-' sets the lane's sign bit.
      const __m128i signs =
          _mm_slli_epi64(_mm_cmpeq_epi8(_mm_or_si128(_mm_shuffle_epi8(a, Load(gather[2], 0)),
                                                     _mm_shuffle_epi8(b, Load(gather[3], 0))),
                                        minus),
                         63);
      __m128d v = _mm_cvtepi32_pd(eights);
      v = _mm_div_pd(_mm_mul_pd(v, _mm_load_pd(multiply_ + f)), _mm_load_pd(divide_ + f));
      v = _mm_xor_pd(v, _mm_castsi128_pd(signs));
      _mm_storeh_pd(values + numbers_[g].role, v);  // when g is f, overwritten next
      _mm_storel_pd(values + numbers_[f].role, v);
    }
  }
#else
  void VectorValues(const char*, double*) const {}  // never chosen (Cpu)
#endif
  static __m128i Load(const unsigned char* bytes, std::size_t chunk) {
    return _mm_load_si128(reinterpret_cast<const __m128i*>(bytes + 16 * chunk));
  }
  static __m128i Load(const char* bytes, std::size_t chunk) {
    return _mm_load_si128(reinterpret_cast<const __m128i*>(bytes + 16 * chunk));
  }
#endif

  alignas(32) char bytes_[kMaxBytes] = {};                    // the reference row (zeros after it)
  alignas(32) unsigned char digit_[kMaxBytes] = {};           // 0xFF where a digit must be
  alignas(32) unsigned char mantissa_digit_[kMaxBytes] = {};  // digit_ but the exponents'
  alignas(32) unsigned char sign_[kMaxBytes] = {};            // 0xFF: '+', '-' or ' '
  alignas(32) unsigned char exp_sign_[kMaxBytes] = {};        // 0xFF: '+' or '-'
  // VectorValues' shuffles per pair: the digits of its first and second numbers, their signs.
  alignas(16) unsigned char gather_[kMaxNumbers / 2][4][16] = {};
  Number numbers_[kMaxNumbers];
  // Of the reference row's numbers: ExactDecimal's exponent, and as factors (one of them 1).
  int exponent_[kMaxNumbers] = {};
  alignas(16) double multiply_[kMaxNumbers] = {}, divide_[kMaxNumbers] = {};
  unsigned past_end_[kMaxBytes / 16] = {};  // per block, bits for the bytes past the line's end
  std::size_t count_ = 0, length_ = 0, chunks_ = 0;
  std::size_t readable_ = 0;  // bytes Read needs at the row
  bool vector_ = false;
  bool wide_ = false;  // blocks of 32 bytes (CheckWide), else 16
};

}  // namespace accelcal::internal
