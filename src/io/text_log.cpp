// Reading a text log's table in blocks (text_log.hpp).
#include "io/text_log.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <optional>

#include "accelcal/error.hpp"
#include "accelcal/native_log.hpp"
#include "core/text_format.hpp"
#include "io/input_file.hpp"
#include "io/mat_file.hpp"
#include "io/native_input.hpp"
#include "io/number_parser.hpp"
#include "io/row_parser.hpp"
#include "io/text_lines.hpp"

namespace accelcal::internal {

namespace {

// The header of a positions file with counts and standard deviations, as accelcal simulate writes
// it: columns named n, sx, sy and sz. ("samples" alone is not enough: raw logs carry sample
// indices under that name.)
bool NamesPositionsColumns(const std::vector<std::string>& header) {
  const auto has = [&](const char* name) {
    return std::find(header.begin(), header.end(), name) != header.end();
  };
  return has("n") && has("sx") && has("sy") && has("sz");
}

std::string Normalise(std::string_view name) {
  std::string s;
  for (char c : name) s.push_back(static_cast<char>(internal::AsciiLower(c)));
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

Layout NamedLayout(const std::vector<std::string>& h) {
  Layout l;
  l.column[kTime] = FindColumn(h, {"t",
                                   "time",
                                   "timestamp",
                                   "time_s",
                                   "t_s",
                                   "timestamp_s",
                                   "time_ms",
                                   "t_ms",
                                   "timestamp_ms",
                                   "timems",
                                   "time_us",
                                   "t_us",
                                   "timestamp_us",
                                   "timeus",
                                   "time_usec",
                                   "timestamp_sample",
                                   "time_ns",
                                   "t_ns",
                                   "timestamp_ns",
                                   "%time",
                                   "header.stamp",
                                   "field.header.stamp",
                                   "t[s]",
                                   "time[s]",
                                   "t[ms]",
                                   "time[ms]",
                                   "t[us]",
                                   "time[us]",
                                   "t[ns]",
                                   "time[ns]",
                                   "t(s)",
                                   "time(s)",
                                   "t(ms)",
                                   "time(ms)",
                                   "t(us)",
                                   "time(us)",
                                   "t(ns)",
                                   "time(ns)"});
  l.column[kX] = FindColumn(h, {"x", "ax", "a_x", "acc_x", "accel_x", "accx"});
  l.column[kY] = FindColumn(h, {"y", "ay", "a_y", "acc_y", "accel_y", "accy"});
  l.column[kZ] = FindColumn(h, {"z", "az", "a_z", "acc_z", "accel_z", "accz"});
  l.column[kCount] = FindColumn(h, {"n", "samples", "n_samples", "count"});
  l.column[kSx] = FindColumn(h, {"sx", "std_x", "ax_std", "sigma_x"});
  l.column[kSy] = FindColumn(h, {"sy", "std_y", "ay_std", "sigma_y"});
  l.column[kSz] = FindColumn(h, {"sz", "std_z", "az_std", "sigma_z"});
  // A column naming the sensor of each row: ArduPilot's I, PX4's device_id and multi_id, ...
  l.column[kInstance] =
      FindColumn(h, {"i", "instance", "multi_id", "device_id", "imu", "imu_id", "sensor_id", "id"});
  l.column[kTemperature] = -1;
  for (std::size_t i = 0; i < h.size() && l.column[kTemperature] < 0; ++i) {
    for (const char* n : kTemperatureColumnNames) {
      if (h[i] == n) l.column[kTemperature] = static_cast<int>(i);
    }
  }
  return l;
}

int ResolveColumn(const std::string& spec, const std::vector<std::string>& header,
                  std::size_t columns, const std::string& source,
                  const char* what = "the columns option's entry") {
  double number = 0;
  if (ParseNumber(spec, &number)) {
    if (number < 1 || number > static_cast<double>(columns) || number != std::floor(number)) {
      throw InputError(source, 0,
                       std::string(what) + " '" + spec + "' is not a column number between 1 and " +
                           std::to_string(columns));
    }
    return static_cast<int>(number) - 1;
  }
  const std::string want = Normalise(spec);
  for (std::size_t i = 0; i < header.size(); ++i) {
    if (header[i] == want) return static_cast<int>(i);
  }
  throw InputError(source, 0,
                   std::string(what) + " '" + spec + "' names no column" +
                       (header.empty() ? std::string(" (the file has no header)") : std::string()));
}

// Several sensors in one file (ArduPilot's IMU instances, PX4's device ids): the rows of one, by
// `chosen`, or an error listing those found. A column with more than 16 distinct values is not
// an instance column (a sample counter, say) and is left alone.
void SelectInstance(const std::vector<double>& instances, const std::string& column,
                    const std::optional<double>& chosen, const std::string& source,
                    InputData* data) {
  std::vector<std::pair<double, std::size_t>> found;  // value, rows
  for (double v : instances) {
    auto it = std::find_if(found.begin(), found.end(), [&](const auto& f) { return f.first == v; });
    if (it == found.end()) {
      if (found.size() == 16) {
        if (chosen) {
          throw InputError(
              source, 0,
              "column '" + column + "' has more than 16 distinct values: not an instance column");
        }
        return;
      }
      found.push_back({v, 1});
    } else {
      ++it->second;
    }
  }
  std::sort(found.begin(), found.end());
  std::string list;
  for (const auto& [value, rows] : found) {
    list +=
        (list.empty() ? "" : ", ") + ShortNumber(value) + " (" + std::to_string(rows) + " rows)";
  }
  if (!chosen) {
    if (found.size() <= 1) return;
    throw InputError(source, 0,
                     "the rows belong to " + std::to_string(found.size()) +
                         " sensors (instance column '" + column + "': " + list +
                         "): choose one instance");
  }
  if (std::none_of(found.begin(), found.end(), [&](const auto& f) { return f.first == *chosen; })) {
    throw InputError(source, 0,
                     "no rows of instance " + ShortNumber(*chosen) + " (column '" + column +
                         "' has " + list + ")");
  }
  std::size_t kept = 0;
  for (std::size_t i = 0; i < instances.size(); ++i) {
    if (instances[i] != *chosen) continue;
    if (data->kind == InputKind::kRaw) {
      RawLog& log = data->raw;
      if (!log.time_s.empty()) log.time_s[kept] = log.time_s[i];
      if (!log.temperature_c.empty()) log.temperature_c[kept] = log.temperature_c[i];
      log.samples[kept] = log.samples[i];
      log.line[kept] = log.line[i];
    } else {
      data->positions[kept] = data->positions[i];
    }
    ++kept;
  }
  if (data->kind == InputKind::kRaw) {
    RawLog& log = data->raw;
    if (!log.time_s.empty()) log.time_s.resize(kept);
    if (!log.temperature_c.empty()) log.temperature_c.resize(kept);
    log.samples.resize(kept);
    log.line.resize(kept);
  } else {
    data->positions.resize(kept);
  }
}

// The text before the first data row, and the first rows, are read into memory to tell the
// header and the kind; beyond this they are not a log (blank lines, a binary file's padding).
constexpr std::size_t kMaxHeadBytes = std::size_t{64} << 20;

// The first `want_rows` data rows (fewer at the end of the input) of `blocks`, peeked, not
// consumed. Throws InputError when they are spread over more than kMaxHeadBytes.
std::string_view PeekRows(internal::TextBlocks& blocks, std::size_t want_rows,
                          const std::string& source, std::size_t* rows_found) {
  for (std::size_t want = std::size_t{256} << 10;; want *= 4) {
    const std::string_view head = blocks.Peek(want);
    LineReader counter(head, source, 0, blocks.line_end());
    Line l;
    std::size_t rows = 0;
    while (rows < want_rows && counter.Next(&l)) ++rows;
    if (rows >= want_rows || blocks.AtEnd()) {
      *rows_found = rows;
      return head;
    }
    if (want >= kMaxHeadBytes) {
      throw InputError(source, counter.lines_read(),
                       "only " + std::to_string(rows) + " data rows in the first " +
                           std::to_string(kMaxHeadBytes >> 20) +
                           " MiB (blank lines or comments): not a log accelcal reads");
    }
  }
}

// " ('name')" of column `c` (0-based) when the file has a header, for messages.
std::string ColumnName(const std::vector<std::string>& header, int c) {
  if (c < 0 || static_cast<std::size_t>(c) >= header.size()) return "";
  return " ('" + header[static_cast<std::size_t>(c)] + "')";
}

// Which column holds what: the columns option's (time,x,y,z or x,y,z, each a number or a
// header name, no column twice), else the header's names, else the column count's layout.
Layout ChooseLayout(const std::vector<std::string>& chosen, const std::vector<std::string>& header,
                    const Layout& named, std::size_t ncols, bool raw, const std::string& source,
                    std::uint32_t first_line) {
  Layout layout;
  std::fill(std::begin(layout.column), std::end(layout.column), -1);
  if (!chosen.empty()) {
    const std::size_t n = chosen.size();
    if (raw ? (n != 3 && n != 4) : n != 3) {
      throw InputError(source, 0,
                       raw ? "the columns option takes 3 entries (x,y,z) or 4 (time,x,y,z)"
                           : "the columns option takes 3 entries (x,y,z) for a positions file");
    }
    const int offset = n == 4 ? 1 : 0;
    if (n == 4) layout.column[kTime] = ResolveColumn(chosen[0], header, ncols, source);
    for (int a = 0; a < 3; ++a) {
      layout.column[kX + a] = ResolveColumn(chosen[a + offset], header, ncols, source);
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
    throw InputError(source, first_line,
                     std::to_string(ncols) + " columns" +
                         (raw ? ": use the columns option to choose time,x,y,z or x,y,z"
                              : ": a positions file has x,y,z [,n [,sx,sy,sz]]"));
  }
  if (!chosen.empty()) {
    static constexpr const char* kRole[] = {"time", "x", "y", "z"};
    for (int a = kTime; a <= kZ; ++a) {
      for (int b = kTime; b < a; ++b) {
        if (layout.column[a] >= 0 && layout.column[a] == layout.column[b]) {
          throw InputError(source, 0,
                           "the columns option names column " +
                               std::to_string(layout.column[a] + 1) +
                               ColumnName(header, layout.column[a]) + " twice (as " + kRole[b] +
                               " and " + kRole[a] + "): each needs its own column");
        }
      }
    }
  }
  return layout;
}

// The temperature column (ReadOptions::temperature): the one named, else the header's (when no
// other role reads it), else none (-1).
int TemperatureColumn(const std::string& given, const std::vector<std::string>& header,
                      const Layout& named, const Layout& layout, std::size_t ncols,
                      const std::string& source) {
  if (given == "none") return -1;
  const int c = given.empty()
                    ? named.column[kTemperature]
                    : ResolveColumn(given, header, ncols, source, "the temperature column");
  if (c < 0) return -1;
  for (int r = 0; r < kTemperature; ++r) {
    if (layout.column[r] != c) continue;
    if (given.empty()) return -1;
    static constexpr const char* kRole[] = {"time", "x",  "y",  "z",       "sample count",
                                            "sx",   "sy", "sz", "instance"};
    throw InputError(source, 0,
                     "the temperature column " + std::to_string(c + 1) + ColumnName(header, c) +
                         " is read as the " + kRole[r] + ": each needs its own column");
  }
  return c;
}

// A raw log's last block (`block`, after `lines_before` lines) whose last line has no line end,
// and holds data: a logger writes a row, then its line end, so the recording stopped while that
// row was written, and its last field may be a number cut short ("34" of "34799"), read as
// wrong as any. The line is left out of `block` and said (read_warning), as a binary log's
// record cut short is. The first data line (`first_line`, perhaps the header) is kept: a file
// of one line is not a recording cut short. A positions file is never passed here: each of its
// rows is a position, typed by hand as often as not, and a last line without its end is whole.
void LeaveOutCutLine(std::string_view* block, std::uint32_t lines_before, std::uint32_t first_line,
                     char eol, InputData* data) {
  if (block->empty() || block->back() == eol) return;
  const std::size_t end = block->rfind(eol);
  const std::size_t start = end == std::string_view::npos ? 0 : end + 1;
  std::string_view tail = block->substr(start);
  tail = internal::Trim(tail.substr(0, tail.find('#')));
  if (tail.empty()) return;  // a comment or blanks: nothing cut that was read
  const auto number = static_cast<std::uint32_t>(
      lines_before + std::count(block->begin(), block->begin() + start, eol) + 1);
  if (number <= first_line) return;
  *block = block->substr(0, start);
  data->raw.read_warning = internal::Format(
      "the file ends inside line %u, which has no line end (the recording was cut while it was "
      "written; its last value may be cut short), left out: the rows before it were read",
      number);
}

// The header: a first line with a field that is not a number (`has_header`), or a comment just
// above the first row; empty when there is none.
std::vector<std::string> HeaderOf(const std::string_view* fields, std::size_t ncols,
                                  std::string_view preceding_comment, bool* has_header) {
  std::vector<std::string> header;
  for (std::size_t i = 0; i < ncols; ++i) {
    double v;
    if (!ParseNumber(fields[i], &v)) *has_header = true;
  }
  if (*has_header) {
    for (std::size_t i = 0; i < ncols; ++i) header.push_back(Normalise(fields[i]));
  } else if (!preceding_comment.empty()) {
    // A comment line just above the first row that names as many columns as it has, none a
    // number, is the header ("# time tx ty tz").
    std::string_view names[kMaxFields];
    const std::string_view comment = preceding_comment;
    const Delimiter comment_delim =
        comment.find(',') != std::string_view::npos ? Delimiter::kComma : Delimiter::kWhitespace;
    if (Split(comment, comment_delim, names, kMaxFields) == ncols &&
        std::none_of(names, names + ncols, [](std::string_view f) {
          double v;
          return f.empty() || ParseNumber(f, &v);
        })) {
      for (std::size_t i = 0; i < ncols; ++i) header.push_back(Normalise(names[i]));
    }
  }
  return header;
}

// The input's kind: the one given, else what the header names, else a raw log when a rate was
// given or the file has more rows (`count_rows`) than a positions file.
void ChooseKind(const ReadOptions& options, const Layout& named,
                const std::vector<std::string>& header,
                const std::function<std::size_t()>& count_rows, InputData* data) {
  std::size_t rows = 0;
  if (options.kind != InputKind::kAuto) {
    data->kind = options.kind;
    data->kind_reason = "given";
  } else if (named.column[kTime] >= 0) {
    data->kind = InputKind::kRaw;
    data->kind_reason = "auto: the header names a time column";
  } else if (NamesPositionsColumns(header)) {
    // Only averaged readings carry a sample count and standard deviations, however many rows.
    data->kind = InputKind::kPositions;
    data->kind_reason = "auto: the header is a positions file's (n, sx, sy, sz)";
  } else if (options.rate_hz) {  // a sample rate belongs to a raw log, however short
    data->kind = InputKind::kRaw;
    data->kind_reason = "auto: a sample rate was given: a raw log";
  } else if ((rows = count_rows()) <= options.max_rows_of_positions_file) {
    data->kind = InputKind::kPositions;
    data->kind_from_row_count = true;
    data->kind_reason = "auto: " + std::to_string(rows) +
                        " rows <= " + std::to_string(options.max_rows_of_positions_file) +
                        " is a positions file (input kind \"raw\" to override)";
  } else {
    data->kind = InputKind::kRaw;
    data->kind_reason = "auto: more than " + std::to_string(options.max_rows_of_positions_file) +
                        " rows is a raw log";
  }
}

// Another stream of this file (the accelerometer's beside the gyroscope's, `other_columns`): no
// column both.
void RefuseSharedColumns(const std::vector<std::string>& other_columns,
                         const std::vector<std::string>& header, const Layout& named,
                         std::size_t ncols, const std::string& source, std::uint32_t first_line,
                         const Layout& layout) {
  const Layout other = ChooseLayout(other_columns, header, named, ncols, true, source, first_line);
  for (int a = kX; a <= kZ; ++a) {
    for (int b = kX; b <= kZ; ++b) {
      if (layout.column[a] == other.column[b]) {
        throw InputError(source, 0,
                         "the columns option reads column " + std::to_string(layout.column[a] + 1) +
                             ColumnName(header, layout.column[a]) + " as its " +
                             std::string(1, "xyz"[a - kX]) +
                             ", which the other stream of this file reads as its " +
                             std::string(1, "xyz"[b - kX]) + ": each needs its own columns");
      }
    }
  }
}

}  // namespace

std::string ShortNumber(double v) {
  char buf[32];
  if (v == std::floor(v) && std::abs(v) < 1e15) {
    internal::FormatTo(buf, sizeof buf, "%.0f", v);
  } else {
    internal::FormatTo(buf, sizeof buf, "%.6g", v);
  }
  return buf;
}

InputData ParseBlocks(TextBlocks& blocks, const std::string& source, const ReadOptions& options,
                      const BlockSink* sink, BlockColumns* columns) {
  if (options.rate_hz && !(*options.rate_hz > 0 && std::isfinite(*options.rate_hz))) {
    throw InputError(source, 0, "the rate must be a positive number of Hz");
  }
  std::size_t head_rows = 0;
  const std::string_view head = PeekRows(blocks, 1, source, &head_rows);
  LineReader reader(head, source, 0, blocks.line_end());
  Line first;
  if (!reader.Next(&first))
    throw InputError(source, 0, "no data (the file is empty or all comments)");
  const Delimiter delim =
      first.text.find(',') != std::string_view::npos ? Delimiter::kComma : Delimiter::kWhitespace;

  std::string_view fields[kMaxFields];
  const std::size_t ncols = Split(first.text, delim, fields, kMaxFields);
  if (ncols > kMaxFields) {
    throw InputError(source, first.number, "more than 256 columns");
  }
  if (first.text.find(';') != std::string_view::npos) {
    throw InputError(source, first.number,
                     "semicolons separate the fields (a spreadsheet's export with decimal "
                     "commas?); accelcal reads commas, tabs or spaces between fields and points "
                     "in numbers");
  }
  bool has_header = false;
  const std::vector<std::string> header =
      HeaderOf(fields, ncols, reader.preceding_comment(), &has_header);
  const std::uint32_t first_line = first.number;
  // A guess for reserving; capped, so that a huge file with a short first line cannot make the
  // reader ask for memory its rows will never fill (the vectors grow past it as needed).
  const std::size_t expected_rows =
      std::min<std::size_t>(blocks.total() / (first.text.size() + 1) + 1, std::size_t{1} << 22);

  const Layout named = NamedLayout(header);
  // Auto-detection needs to know only whether there are more rows than a positions file has.
  const auto CountRows = [&] {
    std::size_t found = 0;
    PeekRows(blocks, options.max_rows_of_positions_file + 2, source, &found);
    return has_header ? found - 1 : found;
  };
  InputData data;
  ChooseKind(options, named, header, CountRows, &data);
  const bool raw = data.kind == InputKind::kRaw;
  if (!raw && options.rate_hz) {
    throw InputError(source, 0,
                     "a sample rate was given, but this is a positions file (" + data.kind_reason +
                         "): a rate belongs to a raw log");
  }

  Layout layout = ChooseLayout(options.columns, header, named, ncols, raw, source, first_line);
  if (options.other_columns) {
    RefuseSharedColumns(*options.other_columns, header, named, ncols, source, first_line, layout);
  }
  if (sink != nullptr && !raw) {
    throw InputError(source, 0, "a positions file, not a raw log (" + data.kind_reason + ")");
  }
  // Parse every data row, block by block.
  if (raw && sink == nullptr) {
    data.raw.samples.reserve(expected_rows);
    data.raw.line.reserve(expected_rows);
    if (layout.column[kTime] >= 0) data.raw.time_s.reserve(expected_rows);
  }
  if (raw) data.raw.source = source;
  if (named.column[kInstance] >= 0 &&
      std::find(std::begin(layout.column), std::begin(layout.column) + kInstance,
                named.column[kInstance]) == std::begin(layout.column) + kInstance) {
    layout.column[kInstance] = named.column[kInstance];
  } else {
    layout.column[kInstance] = -1;
  }
  layout.column[kTemperature] = sink != nullptr ? -1
                                                : TemperatureColumn(options.temperature, header,
                                                                    named, layout, ncols, source);
  if (raw && layout.column[kTemperature] >= 0) {
    data.raw.temperature_source = "column " + std::to_string(layout.column[kTemperature] + 1) +
                                  ColumnName(header, layout.column[kTemperature]);
  }
  if (columns != nullptr) {
    columns->time = layout.column[kTime] >= 0;
    if (columns->time && !header.empty()) {
      columns->time_name = header[std::size_t(layout.column[kTime])];
    }
    if (layout.column[kInstance] >= 0) {
      columns->instance_name = header[std::size_t(layout.column[kInstance])];
    }
  }
  RowParser parser(source, delim, ncols, layout, raw, options.progress);
  if (options.temperature.empty()) parser.LenientTemperature();  // found by its name
  std::vector<double> instances;
  std::string_view block;
  std::uint32_t lines = 0;
  std::size_t parsed_rows = 0;
  bool skip_header = has_header;
  while (blocks.Next(&block)) {
    if (raw && blocks.AtEnd()) LeaveOutCutLine(&block, lines, first_line, blocks.line_end(), &data);
    lines = parser.Parse(block, blocks.block_offset(), blocks.total(), lines, blocks.line_end(),
                         skip_header, &parsed_rows, &data, &instances);
    skip_header = false;
    if (sink != nullptr) {
      if (layout.column[kInstance] < 0) instances.clear();
      (*sink)(&data, &instances);
    }
  }
  if (sink != nullptr) return data;
  if (raw ? data.raw.samples.empty() : data.positions.empty()) {
    throw InputError(source, first_line, "a header but no data rows");
  }
  if (parser.temperatures_left_out() > 0) {
    // A column named like a temperature that holds something else: said, not an error, since
    // it was not asked for.
    const int c = layout.column[kTemperature];
    const std::string note = internal::Format(
        "column %d%s: %zu value%s no temperature in degC (from %g to %g; the first, %s, at "
        "line %u): left out",
        c + 1, ColumnName(header, c).c_str(), parser.temperatures_left_out(),
        parser.temperatures_left_out() == 1 ? " is" : "s are", kTemperatureRange_C[0],
        kTemperatureRange_C[1], parser.first_left_out().c_str(), parser.first_left_out_line());
    if (raw) {
      data.raw.temperature_note = note;
    } else {
      data.kind_reason += "; " + note;
    }
  }
  if (raw && std::none_of(data.raw.temperature_c.begin(), data.raw.temperature_c.end(),
                          [](double t) { return !std::isnan(t); })) {
    data.raw.temperature_c.clear();
    data.raw.temperature_source.clear();
  }
  if (layout.column[kInstance] >= 0) {
    SelectInstance(instances, header[std::size_t(layout.column[kInstance])], options.instance,
                   source, &data);
  } else if (options.instance) {
    throw InputError(source, 0, kNoInstanceColumn);
  }
  if (raw) {
    const int c = layout.column[kTime];
    internal::FinishRawLog(
        &data.raw, options.time_unit, options.rate_hz,
        header.empty() || c < 0 ? std::string_view() : std::string_view(header[std::size_t(c)]));
  }
  return data;
}

}  // namespace accelcal::internal
