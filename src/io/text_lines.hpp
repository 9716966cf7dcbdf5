#pragma once
// Walking delimited text line by line, shared by every text reader (logs, series, orientations):
// comments and blank lines skipped, line numbers kept, and hostile input refused on the line
// where it appears (InputError) instead of being scanned or held whole.

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

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

enum class Delimiter { kComma, kWhitespace };

inline constexpr std::size_t kMaxFields = 256;

/// Splits a trimmed line (Line::text) into fields: at commas, each field trimmed, or at runs of
/// blanks. Returns the count (fields beyond `max` are counted only). The one tokenizer of every
/// text format: logs (one delimiter for the file), orientation files and tables (SplitLine).
inline std::size_t Split(std::string_view s, Delimiter delim, std::string_view* fields,
                         std::size_t max) {
  std::size_t count = 0;
  if (delim == Delimiter::kComma) {
    std::size_t start = 0;
    while (true) {
      const std::size_t comma = s.find(',', start);
      const std::string_view field = Trim(s.substr(
          start, comma == std::string_view::npos ? std::string_view::npos : comma - start));
      if (count < max) fields[count] = field;
      ++count;
      if (comma == std::string_view::npos) break;
      start = comma + 1;
    }
  } else {
    std::size_t i = 0;
    while (i < s.size()) {
      while (i < s.size() && IsBlank(s[i])) ++i;
      if (i >= s.size()) break;
      const std::size_t start = i;
      while (i < s.size() && !IsBlank(s[i])) ++i;
      if (count < max) fields[count] = s.substr(start, i - start);
      ++count;
    }
  }
  return count;
}

/// The fields of one line of a small file (orientation files, tables): at commas when the line
/// has one, else at blanks.
inline std::vector<std::string_view> SplitLine(std::string_view line) {
  const Delimiter delim =
      line.find(',') != std::string_view::npos ? Delimiter::kComma : Delimiter::kWhitespace;
  std::vector<std::string_view> fields(Split(line, delim, nullptr, 0));
  Split(line, delim, fields.data(), fields.size());
  return fields;
}

/// How lines end: '\n' (a '\r' before it is trimmed as blank), or '\r' alone in a text with no
/// '\n' among its first kMaxLineBytes + 1 bytes (classic Mac line ends).
inline char DetectLineEnd(std::string_view head) {
  head = head.substr(0, kMaxLineBytes + 1);
  return head.find('\n') == std::string_view::npos && head.find('\r') != std::string_view::npos
             ? '\r'
             : '\n';
}

/// Walks the text line by line, skipping blank lines and `#` comments. Throws InputError for a
/// line longer than kMaxLineBytes or holding a NUL byte (binary data), and beyond 2^32 - 1 lines
/// (line numbers are 32-bit).
class LineReader {
 public:
  /// `lines_before`: how many lines of the file precede `text` (for 1-based line numbers).
  /// At the start of a file (no lines before), a UTF-8 byte-order mark (spreadsheets write one)
  /// is skipped and UTF-16 text is refused by name. `eol`: the line end (DetectLineEnd of the
  /// file's start); 0 detects it from `text`.
  LineReader(std::string_view text, const std::string& source, std::uint32_t lines_before = 0,
             char eol = 0)
      : text_(text), source_(source), number_(lines_before) {
    if (lines_before == 0) {
      if (text_.substr(0, 3) == "\xEF\xBB\xBF") pos_ = 3;
      if (text_.substr(0, 2) == "\xFF\xFE" || text_.substr(0, 2) == "\xFE\xFF") {
        throw InputError(source_, 1,
                         "UTF-16 text (it starts with a byte-order mark): save it as UTF-8");
      }
    }
    eol_ = eol != 0 ? eol : DetectLineEnd(text_);
  }
  /// The text not yet read.
  std::string_view rest() const {
    return pos_ < text_.size() ? text_.substr(pos_) : std::string_view();
  }
  std::size_t offset() const { return std::min(pos_, text_.size()); }
  /// The first byte not yet read (a caller's own scan of the next line, then AcceptLine).
  const char* cursor() const { return text_.data() + offset(); }
  /// Consumes the next line, `bytes` long with its line end, as Next would have returned it: the
  /// caller has read it as a data line (not blank, no comment, no NUL byte, at most
  /// kMaxLineBytes before its line end; lines_read() below 2^32 − 1). Returns its number.
  std::uint32_t AcceptLine(std::size_t bytes) {
    pos_ += bytes;
    preceding_comment_ = comment_;
    comment_ = {};
    return ++number_;
  }
  /// AcceptLine for `count` data lines, `bytes` long in all.
  void AcceptLines(std::size_t bytes, std::uint32_t count) {
    if (count == 0) return;
    pos_ += bytes;
    preceding_comment_ = count == 1 ? comment_ : std::string_view();
    comment_ = {};
    number_ += count;
  }
  std::uint32_t lines_read() const { return number_; }
  /// The text of the last whole-line comment before the line Next returned last (blank lines
  /// between them allowed), without its `#`; empty when there is none. A `# t ax ay az` line
  /// above the first row names the columns in many loggers' files.
  std::string_view preceding_comment() const { return preceding_comment_; }
  bool Next(Line* line) {
    while (pos_ < text_.size()) {
      const char* begin = text_.data() + pos_;
      const std::size_t remaining = text_.size() - pos_;
      const std::size_t scan = std::min(remaining, kMaxLineBytes + 1);
      const void* nl = std::memchr(begin, eol_, scan);
      if (number_ == UINT32_MAX) {
        throw InputError(source_, number_, "more than 4294967295 lines: not a file accelcal reads");
      }
      ++number_;
      const std::size_t len =
          nl ? static_cast<std::size_t>(static_cast<const char*>(nl) - begin) : remaining;
      // NUL first: a binary file (or /dev/zero) is named as such, not as a long line.
      if (const void* nul = std::memchr(begin, '\0', std::min(len, scan))) {
        throw InputError(source_, number_,
                         "a NUL byte at column " +
                             std::to_string(static_cast<const char*>(nul) - begin + 1) +
                             ": binary data, not a delimited text file");
      }
      if (!nl && remaining > kMaxLineBytes) {
        throw InputError(
            source_, number_,
            "longer than " + std::to_string(kMaxLineBytes) + " bytes: not a delimited text file");
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
