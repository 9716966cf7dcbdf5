#pragma once
// Walking delimited text line by line, shared by every text reader (logs, series, orientations):
// comments and blank lines skipped, line numbers kept, and hostile input refused on the line
// where it appears (InputError) instead of being scanned or held whole.

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>

#include "accelcal/error.hpp"

namespace accelcal::internal {

/// No delimited row of at most 256 numbers comes near this; a longer line is not such a file (and
/// must not make the reader scan, or hold, gigabytes looking for its end).
inline constexpr std::size_t kMaxLineBytes = 65536;

struct Line {
  std::string_view text;  ///< comment stripped, trimmed
  std::uint32_t number;   ///< 1-based
};

inline bool IsBlank(char c) { return c == ' ' || c == '\t' || c == '\r'; }

inline std::string_view Trim(std::string_view s) {
  while (!s.empty() && IsBlank(s.front())) s.remove_prefix(1);
  while (!s.empty() && IsBlank(s.back())) s.remove_suffix(1);
  return s;
}

/// Walks the text line by line, skipping blank lines and `#` comments. Throws InputError for a
/// line longer than kMaxLineBytes or holding a NUL byte (binary data).
class LineReader {
 public:
  /// `lines_before`: how many lines of the file precede `text` (for 1-based line numbers).
  /// A UTF-8 byte-order mark at the start (spreadsheets write one) is skipped; UTF-16 text is
  /// refused by name; lines end at '\n' (a '\r' before it is trimmed) or, in a text with no '\n'
  /// in its first kMaxLineBytes, at '\r' (classic Mac line ends).
  LineReader(std::string_view text, const std::string& source, std::uint32_t lines_before = 0)
      : text_(text), source_(source), number_(lines_before) {
    if (text_.substr(0, 3) == "\xEF\xBB\xBF") pos_ = 3;
    if (text_.substr(0, 2) == "\xFF\xFE" || text_.substr(0, 2) == "\xFE\xFF") {
      throw InputError(source_, lines_before + 1,
                       "UTF-16 text (it starts with a byte-order mark): save it as UTF-8");
    }
    const std::string_view head = text_.substr(0, kMaxLineBytes + 1);
    if (head.find('\n') == std::string_view::npos && head.find('\r') != std::string_view::npos) {
      eol_ = '\r';
    }
  }
  /// The text not yet read.
  std::string_view rest() const {
    return pos_ < text_.size() ? text_.substr(pos_) : std::string_view();
  }
  std::size_t offset() const { return std::min(pos_, text_.size()); }
  std::uint32_t lines_read() const { return number_; }
  /// The text of the last whole-line comment before the line Next returned last (blank lines
  /// between them allowed), without its `#`; empty when there is none. A `# t ax ay az` line
  /// above the first row names the columns in many loggers' files.
  std::string_view preceding_comment() const { return preceding_comment_; }
  bool Next(Line* line) {
    while (pos_ < text_.size()) {
      const char* begin = text_.data() + pos_;
      const std::size_t remaining = text_.size() - pos_;
      const void* nl = std::memchr(begin, eol_, std::min(remaining, kMaxLineBytes + 1));
      ++number_;
      if (!nl && remaining > kMaxLineBytes) {
        throw InputError(
            source_, number_,
            "longer than " + std::to_string(kMaxLineBytes) + " bytes: not a delimited text file");
      }
      const std::size_t len =
          nl ? static_cast<std::size_t>(static_cast<const char*>(nl) - begin) : remaining;
      if (const void* nul = std::memchr(begin, '\0', len)) {
        throw InputError(source_, number_,
                         "a NUL byte at column " +
                             std::to_string(static_cast<const char*>(nul) - begin + 1) +
                             ": binary data, not a delimited text file");
      }
      pos_ += len + 1;
      std::string_view s(begin, len);
      const std::size_t hash = s.find('#');
      std::string_view comment;
      if (hash != std::string_view::npos) {
        comment = Trim(s.substr(hash + 1));
        s = s.substr(0, hash);
      }
      s = Trim(s);
      if (!s.empty()) {
        *line = {s, number_};
        preceding_comment_ = comment_;
        comment_ = {};
        return true;
      }
      if (!comment.empty()) comment_ = comment;
    }
    return false;
  }

 private:
  std::string_view text_;
  const std::string& source_;
  std::size_t pos_ = 0;
  std::uint32_t number_;
  std::string_view comment_, preceding_comment_;
  char eol_ = '\n';
};

}  // namespace accelcal::internal
