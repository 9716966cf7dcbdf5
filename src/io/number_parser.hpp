#pragma once
// Decimal numbers of delimited text (log_reader, row_parser): correctly rounded, bit-identical to
// fast_float, with a fast path for the short decimals loggers write.

#include <cstdint>
#include <cstring>
#include <string_view>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace accelcal::internal {

/// Exact powers of ten representable in a double (10^22 is the largest).
inline constexpr double kExactPow10[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                         1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                         1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

/// mantissa · 10^exponent, correctly rounded (exact operands: Clinger's fast path).
inline double ExactDecimal(std::uint64_t mantissa, int exponent, bool negative) {
  // Through a signed integer: mantissa <= 2^53, and the unsigned conversion costs a branch.
  double v = static_cast<double>(static_cast<std::int64_t>(mantissa));
  v = exponent < 0 ? v / kExactPow10[-exponent] : v * kExactPow10[exponent];
  return negative ? -v : v;
}

inline bool IsDigit(char c) { return static_cast<unsigned char>(c - '0') < 10; }

/// The number whose 8 decimal digits (values 0 to 9, the first in the lowest byte) make `v`.
inline std::uint64_t CombineDigits(std::uint64_t v) {
  v = v * 10 + (v >> 8);  // pairs of digits in every other byte
  v = (((v & 0x000000FF000000FF) * 0x000F424000000064) +
       (((v >> 16) & 0x000000FF000000FF) * 0x0000271000000001)) >>
      32;
  return v & 0xFFFFFFFF;
}

/// How many of the 8 bytes at `p` are decimal digits before the first that is not (0 to 8), and
/// the value of those digits in `*value`: one test and three multiplications instead of a step per
/// digit (the bytes read as one little-endian word; other byte orders take the digit loop: -1).
inline int LeadingDigits(const char* p, std::uint64_t* value) {
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  std::uint64_t v;
  std::memcpy(&v, p, sizeof v);
  // A byte of `t` is 0 when the byte is 0x30..0x39 (its high nibble 3, and adding 6 leaves it 3);
  // a carry from adding 6 to a byte >= 0xFA only changes the bytes after that non-digit.
  const std::uint64_t t =
      ((v & 0xF0F0F0F0F0F0F0F0) | (((v + 0x0606060606060606) & 0xF0F0F0F0F0F0F0F0) >> 4)) ^
      0x3333333333333333;
  const int n = t == 0 ? 8 : __builtin_ctzll(t) >> 3;
  if (n == 0) {
    *value = 0;
    return 0;
  }
  // The digits moved to the end of the word, zeros (leading zeros) before them; the borrows of
  // the bytes after them go out of the word.
  *value = CombineDigits((v - 0x3030303030303030) << (8 * (8 - n)));
  return n;
#else
  (void)p;
  (void)value;
  return -1;
#endif
}

inline constexpr std::uint64_t kPow10Integer[] = {1,      10,      100,      1000,     10000,
                                                  100000, 1000000, 10000000, 100000000};

/// Parses a decimal number at the start of [p, last) on the fast path (Clinger): at most 15
/// significant digits and a decimal exponent within ±22 make the mantissa and the power of ten
/// exact, so one multiplication or division rounds correctly, bit-identical to fast_float. Returns
/// the position after the number, or nullptr when the text is not such a number (long mantissas,
/// large exponents, nan/inf spellings, no digits): the caller then uses ParseNumber on the whole
/// field.
inline const char* ParseShortDecimal(const char* p, const char* last, double* value) {
  bool negative = false;
  if (p != last && (*p == '+' || *p == '-')) negative = *p++ == '-';
  std::uint64_t mantissa = 0;
  int exponent = 0;
  const char* digits_begin = p;
  while (p != last && *p == '0') ++p;  // leading zeros are not significant
  const char* significant_begin = p;
  while (p != last && IsDigit(*p)) {
    mantissa = mantissa * 10 + static_cast<unsigned>(*p - '0');
    ++p;
  }
  int digits = static_cast<int>(p - significant_begin);
  bool any_digit = p != digits_begin;
  if (p != last && *p == '.') {
    ++p;
    const char* fraction_begin = p;
    if (mantissa == 0) {
      while (p != last && *p == '0') ++p;
      exponent -= static_cast<int>(p - fraction_begin);
    }
    const char* fraction_digits_begin = p;
    // More than 15 digits fail below; the wrap-around of longer mantissas does not matter.
    for (int n = 8; n == 8 && last - p >= 8;) {
      std::uint64_t part;
      n = LeadingDigits(p, &part);
      if (n < 0) break;
      mantissa = mantissa * kPow10Integer[n] + part;
      p += n;
    }
    while (p != last && IsDigit(*p)) {
      mantissa = mantissa * 10 + static_cast<unsigned>(*p - '0');
      ++p;
    }
    const int fraction_digits = static_cast<int>(p - fraction_digits_begin);
    digits += fraction_digits;
    exponent -= fraction_digits;
    any_digit = any_digit || p != fraction_begin;
  }
  if (!any_digit || digits > 15) return nullptr;
  if (p != last && (*p == 'e' || *p == 'E')) {
    ++p;
    bool exp_negative = false;
    if (p != last && (*p == '+' || *p == '-')) exp_negative = *p++ == '-';
    int e = 0;
    const char* exp_begin = p;
    while (p != last && IsDigit(*p) && e < 10000) {
      e = e * 10 + (*p - '0');
      ++p;
    }
    if (p == exp_begin) return nullptr;
    exponent += exp_negative ? -e : e;
  }
  if (exponent < -22 || exponent > 22) return nullptr;
  *value = ExactDecimal(mantissa, exponent, negative);
  return p;
}

/// Where the parts of a number lie, counted from its first byte after the sign: what
/// ParseDecimal16 found, kept per column of a log so that the next row's number, written by the
/// same printf format, is read by checking that its bytes have the same layout (ParseShaped)
/// instead of finding the parts again.
struct NumberShape {
  std::uint32_t mask = 0;    // bits 0 to `length` (0: no shape yet)
  std::uint32_t digits = 0;  // within `mask`: the digits' bytes (the byte after the number is not)
  std::uint8_t length = 0;   // bytes after the sign, at most 15
  std::uint8_t int_len = 0, frac_begin = 0, frac_len = 0;
  bool point = false;       // a '.' at int_len
  std::uint8_t exp_at = 0;  // the 'e' or 'E'; 0: no exponent
  bool exp_signed = false;  // a sign after it
  std::uint8_t exp_begin = 0, exp_len = 0;
};

#if defined(__SSE2__)
/// Bit i set when byte i of `c` is a decimal digit.
inline unsigned DigitMask(__m128i c) {
  const __m128i at_least_0 = _mm_cmpgt_epi8(c, _mm_set1_epi8('0' - 1));
  const __m128i at_most_9 = _mm_cmplt_epi8(c, _mm_set1_epi8('9' + 1));
  return static_cast<unsigned>(_mm_movemask_epi8(_mm_and_si128(at_least_0, at_most_9)));
}

/// Bit i set when byte i of `c` is blank (IsBlank: space, tab, carriage return).
inline unsigned BlankMask(__m128i c) {
  const __m128i blank = _mm_or_si128(
      _mm_or_si128(_mm_cmpeq_epi8(c, _mm_set1_epi8(' ')), _mm_cmpeq_epi8(c, _mm_set1_epi8('\t'))),
      _mm_cmpeq_epi8(c, _mm_set1_epi8('\r')));
  return static_cast<unsigned>(_mm_movemask_epi8(blank));
}

/// The value of the `n` (0 to 8) digits at `p`, whose 8 bytes must be readable.
inline std::uint64_t DigitsValue(const char* p, unsigned n) {
  if (n == 0) return 0;
  std::uint64_t v;
  std::memcpy(&v, p, sizeof v);
  return CombineDigits((v - 0x3030303030303030) << (8 * (8 - n)));  // as LeadingDigits
}

/// The value of a decimal mantissa of `int_len` digits at `int_digits` and `frac_len` at
/// `frac_digits` (15 in all at most, 8 readable bytes at each), or false when its parts are
/// longer than this reads (ParseShortDecimal decides those).
inline bool DecimalMantissa(const char* int_digits, unsigned int_len, const char* frac_digits,
                            unsigned frac_len, std::uint64_t* mantissa) {
  const unsigned n = int_len + frac_len;
  if (n <= 8 && int_len < 8) {
    // Both parts in one word: the integer digits, then the fraction's after them.
    std::uint64_t a, b;
    std::memcpy(&a, int_digits, sizeof a);
    std::memcpy(&b, frac_digits, sizeof b);
    const unsigned shift = 8 * int_len;
    a = (a - 0x3030303030303030) & ((std::uint64_t{1} << shift) - 1);
    b = (b - 0x3030303030303030) << shift;
    *mantissa = CombineDigits((a | b) << (8 * (8 - n)));
    return true;
  }
  if (int_len <= 8 && frac_len <= 8) {
    *mantissa = DigitsValue(int_digits, int_len) * kPow10Integer[frac_len] +
                DigitsValue(frac_digits, frac_len);
    return true;
  }
  return false;
}

/// The value of the `length` (1 to 4) exponent digits at `digits`.
inline int ExponentDigits(const char* d, unsigned length) {
  switch (length) {  // unrolled: two digits, as printf's %e writes, take no loop
    case 1:
      return d[0] - '0';
    case 2:
      return 10 * (d[0] - '0') + (d[1] - '0');
    case 3:
      return 100 * (d[0] - '0') + 10 * (d[1] - '0') + (d[2] - '0');
    default:
      return 1000 * (d[0] - '0') + 100 * (d[1] - '0') + 10 * (d[2] - '0') + (d[3] - '0');
  }
}

/// ParseShortDecimal for a number that lies within the 16 bytes at `p`, with at least 32 bytes
/// readable there: its parts found from one mask of the digits instead of byte by byte. The same
/// mantissa and exponent as ParseShortDecimal, so the same value, for the numbers it takes (at
/// most 8 digits before the point and 8 after, 15 in all, an exponent of at most 4 digits);
/// nullptr for others (ParseShortDecimal decides). The number may continue past the position
/// returned when that is byte 16 or beyond: the caller checks the byte there. When `shape` is
/// given, the number's layout goes there when the number and the byte after it lie within 16
/// bytes after its sign (else its mask becomes 0).
inline const char* ParseDecimal16(const char* p, double* value, NumberShape* shape = nullptr) {
  const bool negative = p[0] == '-';
  const unsigned sign = (negative || p[0] == '+') ? 1 : 0;
  const char* const q = p + sign;
  const unsigned digit =
      DigitMask(_mm_loadu_si128(reinterpret_cast<const __m128i*>(q)));  // bits 0-15
  const unsigned int_len = static_cast<unsigned>(__builtin_ctz(~digit));
  unsigned pos = int_len;
  unsigned frac_begin = pos, frac_len = 0;
  const bool point = q[pos] == '.';
  if (point) {
    frac_begin = ++pos;
    frac_len = static_cast<unsigned>(__builtin_ctz(~(digit >> pos)));
    pos += frac_len;
  }
  const unsigned n = int_len + frac_len;  // all the digits (leading zeros too)
  if (n - 1 > 14) return nullptr;         // none, or more than 15
  int exponent = -static_cast<int>(frac_len);
  unsigned exp_at = 0, exp_begin = 0, exp_len = 0;
  bool exp_signed = false;
  if ((q[pos] | 0x20) == 'e') {
    exp_at = pos++;
    const bool exp_negative = q[pos] == '-';
    exp_signed = exp_negative || q[pos] == '+';
    pos += exp_signed;
    exp_begin = pos;
    exp_len = static_cast<unsigned>(__builtin_ctz(~(digit >> pos)));
    if (exp_len == 0 || exp_len > 4) return nullptr;
    const int e = ExponentDigits(q + pos, exp_len);
    pos += exp_len;
    exponent += exp_negative ? -e : e;
  }
  if (exponent < -22 || exponent > 22) return nullptr;
  std::uint64_t mantissa;
  if (!DecimalMantissa(q, int_len, q + frac_begin, frac_len, &mantissa)) return nullptr;
  *value = ExactDecimal(mantissa, exponent, negative);
  if (shape != nullptr) shape->mask = 0;  // none, unless the number fits
  if (shape != nullptr && pos < 16) {
    shape->mask = (2u << pos) - 1;
    shape->digits = digit & ((1u << pos) - 1);
    shape->length = static_cast<std::uint8_t>(pos);
    shape->int_len = static_cast<std::uint8_t>(int_len);
    shape->frac_begin = static_cast<std::uint8_t>(frac_begin);
    shape->frac_len = static_cast<std::uint8_t>(frac_len);
    shape->point = point;
    shape->exp_at = static_cast<std::uint8_t>(exp_at);
    shape->exp_signed = exp_signed;
    shape->exp_begin = static_cast<std::uint8_t>(exp_begin);
    shape->exp_len = static_cast<std::uint8_t>(exp_len);
  }
  return q + pos;
}

/// ParseDecimal16 for a number laid out as `shape` says (a sign before it allowed), with at least
/// 32 bytes readable at `p`: its digits where the shape has them and nowhere else up to the byte
/// after it, its point, exponent letter and exponent sign checked, and the same arithmetic, so
/// the same value. nullptr when the number is laid out otherwise (ParseDecimal16 decides). The
/// caller checks the byte at the position returned, as for ParseDecimal16.
inline const char* ParseShaped(const char* p, const NumberShape& shape, double* value) {
  const bool negative = p[0] == '-';
  const char* const q = p + ((negative || p[0] == '+') ? 1 : 0);
  const unsigned digit = DigitMask(_mm_loadu_si128(reinterpret_cast<const __m128i*>(q)));
  if ((digit & shape.mask) != shape.digits) return nullptr;
  if (shape.point && q[shape.int_len] != '.') return nullptr;
  int exponent = -static_cast<int>(shape.frac_len);
  if (shape.exp_at != 0) {
    if ((q[shape.exp_at] | 0x20) != 'e') return nullptr;
    bool exp_negative = false;
    if (shape.exp_signed) {
      const char c = q[shape.exp_at + 1];
      exp_negative = c == '-';
      if (!exp_negative && c != '+') return nullptr;
    }
    const int e = ExponentDigits(q + shape.exp_begin, shape.exp_len);
    exponent += exp_negative ? -e : e;
    if (exponent < -22 || exponent > 22) return nullptr;
  }
  std::uint64_t mantissa = 0;  // the shape's lengths are ones DecimalMantissa reads
  DecimalMantissa(q, shape.int_len, q + shape.frac_begin, shape.frac_len, &mantissa);
  *value = ExactDecimal(mantissa, exponent, negative);
  return q + shape.length;
}
#endif

/// Parses the whole of [first, last) as a number (a leading '+' allowed), correctly rounded;
/// false when it is not one. nan and inf spellings parse (the callers refuse them).
bool ParseNumber(const char* first, const char* last, double* value);
inline bool ParseNumber(std::string_view field, double* value) {
  return ParseNumber(field.data(), field.data() + field.size(), value);
}

}  // namespace accelcal::internal
