#include "io/row_parser.hpp"

#include <algorithm>
#include <cmath>

#include "accelcal/error.hpp"
#include "core/text_format.hpp"
#include "io/number_parser.hpp"

namespace accelcal::internal {

RowParser::RowParser(const std::string& source, Delimiter delim, std::size_t ncols,
                     const Layout& layout, bool raw,
                     const std::function<void(std::size_t, std::size_t)>& progress)
    : source_(source),
      delim_(delim),
      ncols_(ncols),
      layout_(layout),
      raw_(raw),
      progress_(progress) {
  std::fill(std::begin(role_of_column_), std::end(role_of_column_), -1);
  for (int r = 0; r < kRoles; ++r) {
    if (layout_.column[r] >= 0) role_of_column_[layout_.column[r]] = r;
  }
  every_column_read_ = ncols_ <= kRoles;
  for (std::size_t c = 0; c < ncols_ && every_column_read_; ++c) {
    every_column_read_ = role_of_column_[c] >= 0;
  }
}

std::uint32_t RowParser::Parse(std::string_view block, std::size_t block_offset, std::size_t total,
                               std::uint32_t lines_before, char eol, bool skip_first,
                               std::size_t* rows, InputData* data,
                               std::vector<double>* instances) const {
  // Per-row tests as locals: the vectors' stores could otherwise change them for the compiler.
  const bool has_time = layout_.column[kTime] >= 0, has_instance = layout_.column[kInstance] >= 0;
  const bool has_temperature = layout_.column[kTemperature] >= 0;
  const bool raw = raw_, report = static_cast<bool>(progress_);
  std::size_t rows_read = *rows;
  RawLog& log = data->raw;
  LineReader reader(block, source_, lines_before, eol);
  Line line;
  if (skip_first) reader.Next(&line);
  const char* const last = block.data() + block.size();
  // A row's values (`values`, by role) kept, the row being line `number`, ending at `next`.
  const auto keep = [&](const double* v, std::uint32_t number, const char* next) {
    if (report && (++rows_read & 0xFFFF) == 0) {
      progress_(block_offset + static_cast<std::size_t>(next - block.data()), total);
    }
    const Vec3 xyz(v[kX], v[kY], v[kZ]);
    if (has_instance) instances->push_back(v[kInstance]);
    const double t_c = has_temperature ? CheckTemperature(v[kTemperature], number) : 0.0;
    if (raw) {
      if (has_time) log.time_s.push_back(v[kTime]);
      if (has_temperature) log.temperature_c.push_back(t_c);
      log.samples.push_back(xyz);
      log.line.push_back(number);
    } else {
      data->positions.push_back(MakePosition(xyz, v, number));
      if (has_temperature && std::isnan(t_c)) data->positions.back().temperature_c.reset();
    }
  };
  // The fast path reads lines ending in '\n' (a '\r' before it is blank); others, and any line
  // it does not read whole, take LineReader and ParseFields, which give every error.
  const bool fast = eol == '\n';
  double values[kRoles] = {};
  NumberShape shapes[kMaxFields];
  // Rows laid out as the last one the fast path read are read whole (RowTemplate); when they
  // keep changing layout (more than 1 in 8 rows, after the first 16), the template is dropped
  // for the block.
#if defined(__SSE2__)
  RowTemplate row_template;
  FieldSeen seen[kRoles];
  bool templates = fast && every_column_read_;
  std::size_t template_misses = 0, rows_in_block = 0;
#endif
  while (true) {
    const char* after = nullptr;
    if (fast && reader.lines_read() < UINT32_MAX) {
      const char* const row = reader.cursor();
#if defined(__SSE2__)
      if (templates && !row_template.empty()) {
        // As many rows as the template reads, line numbers below 2^32 - 1.
        const std::uint32_t first = reader.lines_read();
        std::uint32_t number = first;
        const auto whole_row = [&](const double* v, const char* next) { keep(v, ++number, next); };
        const char* const end =
            row_template.ReadRows(row, last, UINT32_MAX - 1 - first, values, whole_row);
        if (end != row) {
          reader.AcceptLines(static_cast<std::size_t>(end - row), number - first);
          rows_in_block += number - first;
          continue;
        }
      }
      if (templates) {
        ++rows_in_block;
        after = FastRow(row, last, values, shapes, seen);
        if (!row_template.empty() && ++template_misses > 16 + rows_in_block / 8) {
          templates = false;
        } else if (after != nullptr) {
          row_template.Build(row, static_cast<std::size_t>(after - row), seen, role_of_column_,
                             ncols_, delim_ == Delimiter::kComma);
        }
      } else {
        after = FastRow(row, last, values, shapes, nullptr);
      }
#else
      after = FastRow(row, last, values, shapes, nullptr);
#endif
    }
    if (after != nullptr) {
      keep(values, reader.AcceptLine(static_cast<std::size_t>(after - reader.cursor())), after);
    } else {
      if (!reader.Next(&line)) break;
      ParseFields(line, values);
      keep(values, line.number, reader.cursor());
    }
  }
  *rows = rows_read;
  return reader.lines_read();
}

namespace {

// A byte of a field, in the fast path: not a delimiter, a line end, a comment or a NUL (nor a
// control character or a non-ASCII byte: those lines take the general path).
inline bool IsFieldByte(char c) { return c > ' ' && c != ',' && c != '#'; }

}  // namespace

// One data row at `p` (the start of a line, in a text ending at `last`) whose fields are all
// plain and well formed, read into `values`: returns the position after its '\n'. nullptr for
// anything else (a blank line, a comment, a NUL byte, a field that is not a finite number, the
// wrong number of fields, no '\n' before `last`, a line longer than kMaxLineBytes): LineReader and
// ParseFields then read the line, and skip it or name what is wrong. Where this accepts a line,
// they give the same values.
const char* RowParser::FastRow(const char* p, const char* last, double* values, NumberShape* shapes,
                               FieldSeen* seen) const {
  const char* const line_begin = p;
  const bool comma = delim_ == Delimiter::kComma;
  for (std::size_t column = 0; column < ncols_; ++column) {
    const char* q = nullptr;
#if defined(__SSE2__)
    // Far from the block's end, 16 bytes at a time: the blanks before the field, and the number.
    if (last - p >= 64) {
      const unsigned blank = BlankMask(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p)));
      p += __builtin_ctz(~blank);  // at most 16
    }
#endif
    while (p != last && IsBlank(*p)) ++p;
    const int r = role_of_column_[column];
    if (r >= 0) {
      bool shaped = false;  // read by a layout, which `shapes[column]` now holds
#if defined(__SSE2__)
      if (last - p >= 32) {
        // The layout of this column's number in the last row first: a logger's printf writes
        // every row alike.
        NumberShape& shape = shapes[column];
        if (shape.mask != 0) q = ParseShaped(p, shape, &values[r]);
        if (q == nullptr) q = ParseDecimal16(p, &values[r], &shape);
        shaped = q != nullptr && shape.mask != 0;
      }
#endif
      if (q == nullptr) q = ParseShortDecimal(p, last, &values[r]);
      if (q == nullptr || q == last || !(IsBlank(*q) || *q == '\n' || (comma && *q == ','))) {
        // Not a short decimal ending the field: the whole field, correctly rounded.
        shaped = false;
        q = p;
        while (q != last && IsFieldByte(*q)) ++q;
        if (q == p || q == last || !ParseNumber(p, q, &values[r]) || !std::isfinite(values[r])) {
          return nullptr;
        }
      }
      if (seen != nullptr) {
        seen[column].start = static_cast<std::uint32_t>(p - line_begin);
        seen[column].shape = shapes[column];
        if (!shaped) seen[column].shape.mask = 0;
      }
      p = q;
    } else if (comma) {
      while (p != last && *p != ',' && *p != '\n' && *p != '#' && *p != '\0') ++p;
    } else {
      const char* begin = p;
      while (p != last && IsFieldByte(*p)) ++p;
      if (p == begin) return nullptr;
    }
    if (comma) {
      while (p != last && IsBlank(*p)) ++p;
      if (column + 1 < ncols_) {
        if (p == last || *p != ',') return nullptr;
        ++p;
      }
    }
  }
  while (p != last && IsBlank(*p)) ++p;
  if (p == last || *p != '\n' || static_cast<std::size_t>(p - line_begin) > kMaxLineBytes) {
    return nullptr;
  }
  return p + 1;
}

void RowParser::ParseFields(const Line& line, double* values) const {
  const char* p = line.text.data();
  const char* const end = p + line.text.size();
  std::size_t column = 0;
  while (true) {
    // One field: [field_begin, field_end), then p at the delimiter after it or the end.
    const char* field_begin = p;
    if (delim_ == Delimiter::kComma) {
      while (field_begin != end && IsBlank(*field_begin)) ++field_begin;
    }
    const int r = column < ncols_ ? role_of_column_[column] : -1;
    // Fast path: parse straight from the field's start and check that the field ends there.
    const char* q = r >= 0 ? ParseShortDecimal(field_begin, end, &values[r]) : nullptr;
    if (q != nullptr && delim_ == Delimiter::kComma) {
      while (q != end && IsBlank(*q)) ++q;
      if (q != end && *q != ',') q = nullptr;
    } else if (q != nullptr && q != end && !IsBlank(*q)) {
      q = nullptr;
    }
    if (q != nullptr) {
      p = q;
    } else {
      p = field_begin;
      const char* field_end;
      if (delim_ == Delimiter::kComma) {
        while (p != end && *p != ',') ++p;
        field_end = p;
        while (field_end != field_begin && IsBlank(field_end[-1])) --field_end;
      } else {
        while (p != end && !IsBlank(*p)) ++p;
        field_end = p;
      }
      if (r >= 0) ParseField(line, column, field_begin, field_end, &values[r]);
    }
    ++column;
    if (p == end) break;
    if (delim_ == Delimiter::kComma) {
      ++p;  // past the comma
    } else {
      while (p != end && IsBlank(*p)) ++p;
      if (p == end) break;
    }
  }
  if (column != ncols_) {
    if (delim_ == Delimiter::kWhitespace && line.text.find(',') != std::string_view::npos) {
      throw InputError(source_, line.number,
                       "mixed delimiters: a comma in a whitespace-separated file");
    }
    throw InputError(
        source_, line.number,
        "expected " + std::to_string(ncols_) + " columns, found " + std::to_string(column));
  }
}

// The slow path for one field: fast_float, and the error messages.
void RowParser::ParseField(const Line& line, std::size_t column, const char* field_begin,
                           const char* field_end, double* value) const {
  if (lenient_temperature_ && role_of_column_[column] == kTemperature &&
      !(ParseNumber(field_begin, field_end, value) && std::isfinite(*value))) {
    LeaveOut(line.number, "'" + std::string(field_begin, field_end) + "'");
    *value = std::nan("");
    return;
  }
  if (!ParseNumber(field_begin, field_end, value)) {
    if (delim_ == Delimiter::kWhitespace && std::find(field_begin, field_end, ',') != field_end) {
      throw InputError(source_, line.number,
                       "mixed delimiters: a comma in a whitespace-separated file");
    }
    const std::string field(field_begin, field_end);
    if (delim_ == Delimiter::kComma && std::any_of(field_begin, field_end, IsBlank)) {
      throw InputError(source_, line.number,
                       "mixed delimiters: column " + std::to_string(column + 1) + " ('" + field +
                           "') is separated by whitespace in a comma-separated file");
    }
    throw InputError(source_, line.number,
                     "column " + std::to_string(column + 1) + ": '" + field + "' is not a number");
  }
  if (!std::isfinite(*value)) {
    throw InputError(source_, line.number,
                     "column " + std::to_string(column + 1) + ": '" +
                         std::string(field_begin, field_end) + "' is not a finite number");
  }
}

void RowParser::LeaveOut(std::uint32_t line_number, const std::string& text) const {
  if (left_out_++ == 0) first_left_out_line_ = line_number, first_left_out_ = text;
}

double RowParser::CheckTemperature(double t_c, std::uint32_t line_number) const {
  if (std::isnan(t_c) && lenient_temperature_) return t_c;  // left out as it was read
  if (!InTemperatureRange(t_c)) {
    if (lenient_temperature_) {
      LeaveOut(line_number, Format("%.9g", t_c));
      return std::nan("");
    }
    throw InputError(
        source_, line_number,
        Format("column %d: the temperature %.9g is outside %g to %g degC (kelvin, raw counts, or "
               "not a temperature?)",
               layout_.column[kTemperature] + 1, t_c, kTemperatureRange_C[0],
               kTemperatureRange_C[1]));
  }
  return t_c;
}

Position RowParser::MakePosition(const Vec3& xyz, const double* values,
                                 std::uint32_t line_number) const {
  Position position;
  position.mean = xyz;
  if (layout_.column[kCount] >= 0) {
    // Beyond 2^53 a double no longer tells whole numbers apart (and the cast would overflow).
    if (!(values[kCount] >= 1 && values[kCount] <= 9007199254740992.0) ||
        values[kCount] != std::floor(values[kCount])) {
      throw InputError(source_, line_number,
                       "the sample count must be a whole number from 1 to 2^53");
    }
    position.samples = static_cast<std::size_t>(values[kCount]);
  }
  if (layout_.column[kSx] >= 0 && layout_.column[kSy] >= 0 && layout_.column[kSz] >= 0) {
    position.std = Vec3(values[kSx], values[kSy], values[kSz]);
    if ((position.std->array() < 0).any()) {
      throw InputError(source_, line_number, "a standard deviation is negative");
    }
  }
  if (layout_.column[kTemperature] >= 0) position.temperature_c = values[kTemperature];
  return position;
}

}  // namespace accelcal::internal
