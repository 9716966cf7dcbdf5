#include "accelcal/log_reader.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>

#include <fast_float/fast_float.h>

#include "accelcal/error.hpp"

namespace accelcal {

std::string_view ToString(InputKind kind) {
  switch (kind) {
    case InputKind::kAuto:
      return "auto";
    case InputKind::kRaw:
      return "raw";
    case InputKind::kPositions:
      break;
  }
  return "positions";
}

std::optional<InputKind> InputKindFromString(std::string_view text) {
  if (text == "auto") return InputKind::kAuto;
  if (text == "raw") return InputKind::kRaw;
  if (text == "positions") return InputKind::kPositions;
  return std::nullopt;
}

std::string ReadFileToString(const std::string& path) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"),
                                                       &std::fclose);
  if (!file) throw InputError(path, 0, std::string("cannot open: ") + std::strerror(errno));
  std::string data;
  char buffer[1 << 16];
  std::size_t n;
  while ((n = std::fread(buffer, 1, sizeof buffer, file.get())) > 0) data.append(buffer, n);
  if (std::ferror(file.get())) {
    throw InputError(path, 0, std::string("cannot read: ") + std::strerror(errno));
  }
  return data;
}

namespace {

enum class Delimiter { kComma, kWhitespace };

struct Line {
  std::string_view text;  // comment stripped, trimmed
  std::uint32_t number;   // 1-based
};

bool IsBlank(char c) { return c == ' ' || c == '\t' || c == '\r'; }

std::string_view Trim(std::string_view s) {
  while (!s.empty() && IsBlank(s.front())) s.remove_prefix(1);
  while (!s.empty() && IsBlank(s.back())) s.remove_suffix(1);
  return s;
}

// Walks the text line by line, skipping blank lines and comments.
class LineReader {
 public:
  explicit LineReader(std::string_view text) : text_(text) {}
  bool Next(Line* line) {
    while (pos_ < text_.size()) {
      const char* begin = text_.data() + pos_;
      const void* nl = std::memchr(begin, '\n', text_.size() - pos_);
      const std::size_t len =
          nl ? static_cast<std::size_t>(static_cast<const char*>(nl) - begin) : text_.size() - pos_;
      pos_ += len + 1;
      ++number_;
      std::string_view s(begin, len);
      const std::size_t hash = s.find('#');
      if (hash != std::string_view::npos) s = s.substr(0, hash);
      s = Trim(s);
      if (!s.empty()) {
        *line = {s, number_};
        return true;
      }
    }
    return false;
  }

 private:
  std::string_view text_;
  std::size_t pos_ = 0;
  std::uint32_t number_ = 0;
};

// Splits a trimmed line into fields; returns the count (fields beyond `max` are counted only).
std::size_t Split(std::string_view s, Delimiter delim, std::string_view* fields, std::size_t max) {
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

bool ParseNumber(std::string_view field, double* value) {
  const char* first = field.data();
  const char* last = field.data() + field.size();
  if (first != last && *first == '+') ++first;
  const auto result = fast_float::from_chars(first, last, *value);
  return result.ec == std::errc() && result.ptr == last;
}

std::string Normalise(std::string_view name) {
  std::string s;
  for (char c : name) s.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(c))));
  // Drop a unit suffix such as "_g", "_ms2", "_mps2", "_counts".
  static const char* const kUnits[] = {"_g", "_ms2", "_mps2", "_m/s2", "_counts", "_raw", "_lsb"};
  for (const char* unit : kUnits) {
    const std::size_t n = std::strlen(unit);
    if (s.size() > n && s.compare(s.size() - n, n, unit) == 0) {
      s.resize(s.size() - n);
      break;
    }
  }
  return s;
}

int FindColumn(const std::vector<std::string>& header, std::initializer_list<const char*> names) {
  for (std::size_t i = 0; i < header.size(); ++i) {
    for (const char* n : names) {
      if (header[i] == n) return static_cast<int>(i);
    }
  }
  return -1;
}

// Column roles: time, x, y, z, count, sx, sy, sz. -1 = absent.
enum Role { kTime, kX, kY, kZ, kCount, kSx, kSy, kSz, kRoles };

struct Layout {
  int column[kRoles];
};

Layout NamedLayout(const std::vector<std::string>& h) {
  Layout l;
  l.column[kTime] = FindColumn(h, {"t", "time", "timestamp", "time_s", "t_s", "timestamp_s"});
  l.column[kX] = FindColumn(h, {"x", "ax", "a_x", "acc_x", "accel_x", "accx"});
  l.column[kY] = FindColumn(h, {"y", "ay", "a_y", "acc_y", "accel_y", "accy"});
  l.column[kZ] = FindColumn(h, {"z", "az", "a_z", "acc_z", "accel_z", "accz"});
  l.column[kCount] = FindColumn(h, {"n", "samples", "n_samples", "count"});
  l.column[kSx] = FindColumn(h, {"sx", "std_x", "ax_std", "sigma_x"});
  l.column[kSy] = FindColumn(h, {"sy", "std_y", "ay_std", "sigma_y"});
  l.column[kSz] = FindColumn(h, {"sz", "std_z", "az_std", "sigma_z"});
  return l;
}

int ResolveColumn(const std::string& spec, const std::vector<std::string>& header,
                  std::size_t columns, const std::string& source) {
  double number = 0;
  if (ParseNumber(spec, &number)) {
    if (number < 1 || number > static_cast<double>(columns) || number != std::floor(number)) {
      throw InputError(source, 0,
                       "--columns entry '" + spec + "' is not a column number between 1 and " +
                           std::to_string(columns));
    }
    return static_cast<int>(number) - 1;
  }
  const std::string want = Normalise(spec);
  for (std::size_t i = 0; i < header.size(); ++i) {
    if (header[i] == want) return static_cast<int>(i);
  }
  throw InputError(source, 0,
                   "--columns entry '" + spec + "' names no column" +
                       (header.empty() ? std::string(" (the file has no header)") : std::string()));
}

}  // namespace

InputData ParseInput(std::string_view text, const std::string& source, const ReadOptions& options) {
  if (options.rate_hz && !(*options.rate_hz > 0 && std::isfinite(*options.rate_hz))) {
    throw InputError(source, 0, "the rate must be a positive number of Hz");
  }
  LineReader reader(text);
  Line first;
  if (!reader.Next(&first))
    throw InputError(source, 0, "no data (the file is empty or all comments)");
  const Delimiter delim =
      first.text.find(',') != std::string_view::npos ? Delimiter::kComma : Delimiter::kWhitespace;

  constexpr std::size_t kMaxFields = 256;
  std::string_view fields[kMaxFields];
  const std::size_t ncols = Split(first.text, delim, fields, kMaxFields);
  if (ncols > kMaxFields) {
    throw InputError(source, first.number, "more than 256 columns");
  }
  // A first line with a field that is not a number is a header.
  bool has_header = false;
  std::vector<std::string> header;
  for (std::size_t i = 0; i < ncols; ++i) {
    double v;
    if (!ParseNumber(fields[i], &v)) has_header = true;
  }
  if (has_header) {
    for (std::size_t i = 0; i < ncols; ++i) header.push_back(Normalise(fields[i]));
  }

  // Count the data rows (for auto-detection and to reserve memory).
  std::size_t rows = has_header ? 0 : 1;
  {
    LineReader counter(text);
    Line l;
    counter.Next(&l);
    while (counter.Next(&l)) ++rows;
  }
  if (rows == 0) throw InputError(source, first.number, "a header but no data rows");

  const Layout named = NamedLayout(header);
  InputData data;
  if (options.kind != InputKind::kAuto) {
    data.kind = options.kind;
    data.kind_reason = "given";
  } else if (named.column[kTime] >= 0) {
    data.kind = InputKind::kRaw;
    data.kind_reason = "auto: the header names a time column";
  } else if (rows <= options.max_rows_of_positions_file) {
    data.kind = InputKind::kPositions;
    data.kind_reason = "auto: " + std::to_string(rows) +
                       " rows <= " + std::to_string(options.max_rows_of_positions_file) +
                       " is a positions file (--input-kind raw to override)";
  } else {
    data.kind = InputKind::kRaw;
    data.kind_reason = "auto: " + std::to_string(rows) + " rows is a raw log";
  }
  const bool raw = data.kind == InputKind::kRaw;

  Layout layout;
  std::fill(std::begin(layout.column), std::end(layout.column), -1);
  if (!options.columns.empty()) {
    const std::size_t n = options.columns.size();
    if (raw ? (n != 3 && n != 4) : n != 3) {
      throw InputError(source, 0,
                       raw ? "--columns takes 3 entries (x,y,z) or 4 (time,x,y,z)"
                           : "--columns takes 3 entries (x,y,z) for a positions file");
    }
    const int offset = n == 4 ? 1 : 0;
    if (n == 4) layout.column[kTime] = ResolveColumn(options.columns[0], header, ncols, source);
    for (int a = 0; a < 3; ++a) {
      layout.column[kX + a] = ResolveColumn(options.columns[a + offset], header, ncols, source);
    }
    if (!raw) {
      for (int r = kCount; r < kRoles; ++r) layout.column[r] = named.column[r];
    }
  } else if (named.column[kX] >= 0 && named.column[kY] >= 0 && named.column[kZ] >= 0) {
    layout = named;
    if (raw) {
      for (int r = kCount; r < kRoles; ++r) layout.column[r] = -1;
    } else {
      layout.column[kTime] = -1;
    }
  } else if (raw && ncols == 4) {
    layout.column[kTime] = 0;
    layout.column[kX] = 1, layout.column[kY] = 2, layout.column[kZ] = 3;
  } else if (ncols == 3 || (!raw && (ncols == 4 || ncols == 7))) {
    layout.column[kX] = 0, layout.column[kY] = 1, layout.column[kZ] = 2;
    if (!raw && ncols >= 4) layout.column[kCount] = 3;
    if (!raw && ncols == 7) layout.column[kSx] = 4, layout.column[kSy] = 5, layout.column[kSz] = 6;
  } else {
    throw InputError(source, first.number,
                     std::to_string(ncols) + " columns" +
                         (raw ? ": use --columns to choose time,x,y,z or x,y,z"
                              : ": a positions file has x,y,z [,n [,sx,sy,sz]]"));
  }
  // Parse every data row.
  LineReader rows_reader(text);
  Line line;
  if (has_header) rows_reader.Next(&line);
  if (raw) {
    data.raw.source = source;
    data.raw.samples.reserve(rows);
    data.raw.line.reserve(rows);
    if (layout.column[kTime] >= 0) data.raw.time_s.reserve(rows);
  }
  double values[kRoles];
  while (rows_reader.Next(&line)) {
    const std::size_t n = Split(line.text, delim, fields, kMaxFields);
    if (n != ncols) {
      if (delim == Delimiter::kWhitespace && line.text.find(',') != std::string_view::npos) {
        throw InputError(source, line.number,
                         "mixed delimiters: a comma in a whitespace-separated file");
      }
      throw InputError(
          source, line.number,
          "expected " + std::to_string(ncols) + " columns, found " + std::to_string(n));
    }
    for (int r = 0; r < kRoles; ++r) {
      const int c = layout.column[r];
      if (c < 0) continue;
      if (!ParseNumber(fields[c], &values[r])) {
        throw InputError(source, line.number,
                         "column " + std::to_string(c + 1) + ": '" + std::string(fields[c]) +
                             "' is not a number");
      }
      if (!std::isfinite(values[r])) {
        throw InputError(source, line.number,
                         "column " + std::to_string(c + 1) + ": '" + std::string(fields[c]) +
                             "' is not a finite number");
      }
    }
    const Vec3 xyz(values[kX], values[kY], values[kZ]);
    if (raw) {
      if (layout.column[kTime] >= 0) {
        if (!data.raw.time_s.empty() && values[kTime] < data.raw.time_s.back()) {
          char buf[128];
          std::snprintf(buf, sizeof buf, "time goes backwards (%.9g after %.9g)", values[kTime],
                        data.raw.time_s.back());
          throw InputError(source, line.number, buf);
        }
        data.raw.time_s.push_back(values[kTime]);
      }
      data.raw.samples.push_back(xyz);
      data.raw.line.push_back(line.number);
    } else {
      Position p;
      p.mean = xyz;
      if (layout.column[kCount] >= 0) {
        if (!(values[kCount] >= 1) || values[kCount] != std::floor(values[kCount])) {
          throw InputError(source, line.number, "the sample count must be a whole number >= 1");
        }
        p.samples = static_cast<std::size_t>(values[kCount]);
      }
      if (layout.column[kSx] >= 0 && layout.column[kSy] >= 0 && layout.column[kSz] >= 0) {
        p.std = Vec3(values[kSx], values[kSy], values[kSz]);
        if ((p.std->array() < 0).any()) {
          throw InputError(source, line.number, "a standard deviation is negative");
        }
      }
      data.positions.push_back(p);
    }
  }
  if (raw) {
    if (options.rate_hz) {
      data.raw.rate_hz = options.rate_hz;
    } else if (data.raw.time_s.size() >= 2) {
      const double span = data.raw.time_s.back() - data.raw.time_s.front();
      if (!(span > 0)) throw InputError(source, 0, "the timestamps do not advance");
      data.raw.rate_hz = static_cast<double>(data.raw.time_s.size() - 1) / span;
    }
  }
  return data;
}

InputData ReadInput(const std::string& path, const ReadOptions& options) {
  const std::string text = ReadFileToString(path);
  return ParseInput(text, path, options);
}

}  // namespace accelcal
