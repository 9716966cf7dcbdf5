#pragma once
// Text the library writes, the same whatever the host program's locale (internal).
//
// printf and strtod follow the C locale, which a host program may change: a Python GUI calling
// setlocale(LC_NUMERIC, "de_DE.UTF-8") (or a C++ program calling std::locale::global with a named
// locale, which sets the C locale too) makes "%.9g" write "0,000208474897". Every number the
// library writes goes through Format, which runs printf in the "C" locale; code that must call a
// locale-dependent C function itself holds a ClassicLocale while it does. Integers written with
// std::to_string and doubles written by nlohmann::json's dump (its own shortest round-trip
// conversion) or std::to_chars are locale-independent already. The library writes no text through
// iostreams (which would follow std::locale::global).
//
// Labels and paths that reach a line-based file (a comment line, a header) go through VisibleLine
// first: one line, every character visible.

#include <locale.h>

#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <initializer_list>
#include <string>
#include <string_view>
#include <utility>

namespace accelcal::internal {

// The "C" locale for the calling thread while it lives (uselocale: the host's other threads keep
// theirs), then the thread's previous locale again. Nests.
class ClassicLocale {
 public:
  ClassicLocale() : previous_(::uselocale(Locale())) {}
  ~ClassicLocale() {
    if (previous_ != locale_t{}) ::uselocale(previous_);
  }
  ClassicLocale(const ClassicLocale&) = delete;
  ClassicLocale& operator=(const ClassicLocale&) = delete;

 private:
  static locale_t Locale() {
    // Made once, shared by all threads (uselocale only reads it), never freed. Should it fail
    // (memory), uselocale(0) only queries, and the text is the host locale's.
    static const locale_t c = ::newlocale(LC_ALL_MASK, "C", locale_t{});
    return c;
  }
  locale_t previous_;
};

// Format with a va_list (the tool's Say and Warn take their arguments so).
__attribute__((format(printf, 1, 0))) inline std::string VFormat(const char* format, va_list args) {
  const ClassicLocale c_locale;
  va_list copy;
  va_copy(copy, args);
  char stack[256];
  const int n = std::vsnprintf(stack, sizeof stack, format, copy);
  va_end(copy);
  std::string text;
  if (n > 0 && static_cast<std::size_t>(n) < sizeof stack) {
    text.assign(stack, static_cast<std::size_t>(n));
  } else if (n > 0) {
    text.resize(static_cast<std::size_t>(n));
    std::vsnprintf(text.data(), text.size() + 1, format, args);
  }
  return text;
}

// printf into a std::string, in the "C" locale: "%.9g" of 0.5 is "0.5" everywhere.
__attribute__((format(printf, 1, 2))) inline std::string Format(const char* format, ...) {
  va_list args;
  va_start(args, format);
  std::string text = VFormat(format, args);
  va_end(args);
  return text;
}

// A-Z to a-z, nothing else (std::tolower follows the locale: a Turkish one maps 'I' to 'ı').
inline char AsciiLower(char c) {
  return c >= 'A' && c <= 'Z' ? static_cast<char>(c - 'A' + 'a') : c;
}

// snprintf in the "C" locale, for code that formats into a fixed buffer.
__attribute__((format(printf, 3, 4))) inline int FormatTo(char* buffer, std::size_t size,
                                                          const char* format, ...) {
  const ClassicLocale c_locale;
  va_list args;
  va_start(args, format);
  const int n = std::vsnprintf(buffer, size, format, args);
  va_end(args);
  return n;
}

// One UTF-8 character of `text` from `i`: its code point and length, or -1 and length 1 for a byte
// that starts no well-formed sequence (overlong forms, surrogates and values beyond U+10FFFF are
// not well-formed).
struct CodePoint {
  long value;
  std::size_t length;
};
inline CodePoint DecodeUtf8(std::string_view text, std::size_t i) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char b0 = byte(i);
  if (b0 < 0x80) return {b0, 1};
  std::size_t length = 0;
  long value = 0, minimum = 0;
  if (b0 >= 0xC2 && b0 <= 0xDF) {
    length = 2, value = b0 & 0x1F, minimum = 0x80;
  } else if (b0 >= 0xE0 && b0 <= 0xEF) {
    length = 3, value = b0 & 0x0F, minimum = 0x800;
  } else if (b0 >= 0xF0 && b0 <= 0xF4) {
    length = 4, value = b0 & 0x07, minimum = 0x10000;
  } else {
    return {-1, 1};
  }
  if (i + length > text.size()) return {-1, 1};
  for (std::size_t k = 1; k < length; ++k) {
    if ((byte(i + k) & 0xC0) != 0x80) return {-1, 1};
    value = (value << 6) | (byte(i + k) & 0x3F);
  }
  if (value < minimum || value > 0x10FFFF || (value >= 0xD800 && value <= 0xDFFF)) return {-1, 1};
  return {value, length};
}

// Whether a code point is a control character or a line or paragraph separator by some reader:
// C0 and DEL, C1 (U+0085 is YAML 1.1's and Python's "next line"), U+2028 and U+2029, the
// byte-order mark U+FEFF and the non-characters U+FFFE, U+FFFF (YAML readers refuse them); and
// the bidirectional controls (Unicode's Bidi_Control: U+061C, U+200E, U+200F, U+202A to U+202E,
// U+2066 to U+2069), which reorder what a terminal shows after them (a topic named with U+202E
// shows its name, and the rest of the line, reversed).
inline bool IsInvisible(long c) {
  return c < 0x20 || (c >= 0x7F && c <= 0x9F) || c == 0x2028 || c == 0x2029 || c == 0xFEFF ||
         c == 0xFFFE || c == 0xFFFF || c == 0x061C || c == 0x200E || c == 0x200F ||
         (c >= 0x202A && c <= 0x202E) || (c >= 0x2066 && c <= 0x2069);
}

// What EscapeText writes for what a line (or a quoted string) cannot hold.
enum class Escaping {
  /// VisibleLine: backslashes and quotes kept; a byte that is not UTF-8 as "\xHH".
  kVisibleLine,
  /// The inside of a YAML double-quoted scalar: '"' and '\\' escaped too; a byte that is not
  /// UTF-8 (a JSON document holds none) as U+FFFD.
  kYamlDoubleQuoted,
};

// Tab, line feed and carriage return as "\t", "\n", "\r", the other characters of IsInvisible
// as "\xHH" (below U+0100) or "\uHHHH"; printable Unicode as it is; the rest per `style`.
inline std::string EscapeText(std::string_view text, Escaping style) {
  const bool yaml = style == Escaping::kYamlDoubleQuoted;
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size();) {
    const CodePoint c = DecodeUtf8(text, i);
    if (yaml && (c.value == '"' || c.value == '\\')) {
      out += '\\';
      out += static_cast<char>(c.value);
    } else if (c.value == '\t') {
      out += "\\t";
    } else if (c.value == '\n') {
      out += "\\n";
    } else if (c.value == '\r') {
      out += "\\r";
    } else if (c.value < 0) {
      out += yaml ? std::string("\\uFFFD")
                  : Format("\\x%02X", static_cast<unsigned>(static_cast<unsigned char>(text[i])));
    } else if (IsInvisible(c.value)) {
      out += Format(c.value < 0x100 ? "\\x%02lX" : "\\u%04lX", c.value);
    } else {
      out.append(text, i, c.length);
    }
    i += c.length;
  }
  return out;
}

// `text` as one line of visible characters, for a comment or header line of a file: tab, line
// feed and carriage return become "\t", "\n", "\r", the other characters of IsInvisible "\xHH"
// (below U+0100) or "\uHHHH", a byte that is not UTF-8 "\xHH"; everything else (backslashes,
// quotes, printable Unicode) is kept as it is.
inline std::string VisibleLine(std::string_view text) {
  return EscapeText(text, Escaping::kVisibleLine);
}

// `message` with each phrase of `pairs` (first: the phrase, second: its replacement) replaced where
// it stands as words of its own (not inside a longer word of letters, digits and '_'), in order:
// a message of the library's readers with the options it names put as an edge names them.
inline std::string ReplaceWords(std::string message,
                                std::initializer_list<std::pair<const char*, const char*>> pairs) {
  const auto word = [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
  };
  for (const auto& [phrase, replacement] : pairs) {
    const std::string_view name = phrase;
    for (std::size_t at = message.find(name); at != std::string::npos;
         at = message.find(name, at + 1)) {
      const std::size_t end = at + name.size();
      if ((at > 0 && word(message[at - 1])) || (end < message.size() && word(message[end]))) {
        continue;  // part of a longer word
      }
      message.replace(at, name.size(), replacement);
      at += std::string_view(replacement).size() - 1;
    }
  }
  return message;
}

}  // namespace accelcal::internal
