#include "accelcal/series_file.hpp"

#include <cmath>
#include <cstring>

#include <fast_float/fast_float.h>

#include "accelcal/error.hpp"
#include "accelcal/log_reader.hpp"
#include "io/input_file.hpp"
#include "io/text_lines.hpp"

namespace accelcal {

namespace {

constexpr std::size_t kRowBytes = 6 * sizeof(double);
static_assert(sizeof(double) == 8, "IEEE-754 binary64 doubles");

bool LittleEndian() {
  const std::uint16_t one = 1;
  unsigned char first = 0;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

void PutDouble(double v, char* out) {
  std::uint64_t bits = 0;
  std::memcpy(&bits, &v, 8);
  for (int i = 0; i < 8; ++i) out[i] = static_cast<char>((bits >> (8 * i)) & 0xffu);
}

double GetDouble(const char* in) {
  std::uint64_t bits = 0;
  if (LittleEndian()) {
    std::memcpy(&bits, in, 8);
  } else {
    for (int i = 7; i >= 0; --i) bits = (bits << 8) | static_cast<unsigned char>(in[i]);
  }
  double v = 0;
  std::memcpy(&v, &bits, 8);
  return v;
}

std::string RowError(long row, const char* what) {
  return "sample " + std::to_string(row) + ": " + what;
}

constexpr long kProgressEvery = 1 << 16;

// Whole 48-byte rows of one chunk; `first_row`: how many rows came before (for messages).
void ParseBinaryRows(std::string_view rows_bytes, long first_row, const std::string& source,
                     const std::function<void(const SystemSample&)>& sink) {
  const long rows = static_cast<long>(rows_bytes.size() / kRowBytes);
  for (long r = 0; r < rows; ++r) {
    const char* p = rows_bytes.data() + static_cast<std::size_t>(r) * kRowBytes;
    SystemSample s;
    s.t = GetDouble(p);
    s.f = Vec3(GetDouble(p + 8), GetDouble(p + 16), GetDouble(p + 24));
    s.roll = GetDouble(p + 32);
    s.pitch = GetDouble(p + 40);
    if (!std::isfinite(s.t) || !s.f.allFinite() || !std::isfinite(s.roll) ||
        !std::isfinite(s.pitch)) {
      throw InputError(source, 0, RowError(first_row + r + 1, "not finite"));
    }
    sink(s);
  }
}

std::string TruncatedMessage(std::size_t body_bytes) {
  return "truncated binary series: " + std::to_string(body_bytes) +
         " bytes after the header is not a whole number of 48-byte samples";
}

void ParseBinary(std::string_view body, const std::string& source,
                 const std::function<void(const SystemSample&)>& sink,
                 const SeriesProgress& progress) {
  if (body.size() % kRowBytes != 0) throw InputError(source, 0, TruncatedMessage(body.size()));
  const std::size_t chunk = kRowBytes * kProgressEvery;
  for (std::size_t at = 0; at < body.size(); at += chunk) {
    if (progress) progress(at, body.size());
    ParseBinaryRows(body.substr(at, chunk), static_cast<long>(at / kRowBytes), source, sink);
  }
}

// The text rows of a series, one block of whole lines at a time.
class TextRows {
 public:
  TextRows(const std::string& source, const std::function<void(const SystemSample&)>& sink)
      : source_(source), sink_(sink) {}
  void Parse(std::string_view block, char eol, const SeriesProgress& progress,
             std::size_t block_offset, std::size_t total) {
    internal::LineReader reader(block, source_, lines_, eol);
    internal::Line text_line;
    while (reader.Next(&text_line)) {
      if (progress && rows_++ % kProgressEvery == 0) {
        progress(block_offset + reader.offset(), total);
      }
      Row(text_line);
    }
    lines_ = reader.lines_read();
  }

 private:
  void Row(const internal::Line& text_line) {
    const std::string_view row = text_line.text;
    const std::uint32_t line = text_line.number;
    double v[6];
    int n = 0;
    const char* p = row.data();
    const char* const stop = row.data() + row.size();
    bool ok = true;
    while (p < stop) {
      while (p < stop && (*p == ' ' || *p == '\t' || *p == ',' || *p == '\r')) ++p;
      if (p == stop) break;
      if (n == 6) {
        ok = false;
        break;
      }
      const auto r = fast_float::from_chars(p, stop, v[n]);
      if (r.ec != std::errc()) {
        ok = false;
        break;
      }
      p = r.ptr;
      ++n;
    }
    if (!ok || n != 6) {
      if (first_data_ && !ok && n == 0) {  // a header line (its first field is no number)
        first_data_ = false;
        return;
      }
      throw InputError(source_, line, "expected 6 numbers (t,fx,fy,fz,roll,pitch)");
    }
    first_data_ = false;
    SystemSample s;
    s.t = v[0];
    s.f = Vec3(v[1], v[2], v[3]);
    s.roll = v[4];
    s.pitch = v[5];
    for (double x : v) {
      if (!std::isfinite(x)) throw InputError(source_, line, "a value is not finite");
    }
    sink_(s);
  }

  const std::string& source_;
  const std::function<void(const SystemSample&)>& sink_;  // outlives this (a named function)
  std::uint32_t lines_ = 0;
  std::size_t rows_ = 0;
  bool first_data_ = true;
};

void ParseText(std::string_view text, const std::string& source,
               const std::function<void(const SystemSample&)>& sink,
               const SeriesProgress& progress) {
  TextRows rows(source, sink);
  rows.Parse(text, internal::DetectLineEnd(text), progress, 0, text.size());
}

}  // namespace

void AppendSeriesHeader(std::string* out) { out->append(kSeriesMagic); }

void AppendSeriesSample(const SystemSample& s, std::string* out) {
  char row[kRowBytes];
  PutDouble(s.t, row);
  PutDouble(s.f(0), row + 8);
  PutDouble(s.f(1), row + 16);
  PutDouble(s.f(2), row + 24);
  PutDouble(s.roll, row + 32);
  PutDouble(s.pitch, row + 40);
  out->append(row, kRowBytes);
}

void ParseSeries(std::string_view content, const std::string& source,
                 const std::function<void(const SystemSample&)>& sink,
                 const SeriesProgress& progress) {
  long count = 0;
  const auto counted = [&](const SystemSample& s) {
    ++count;
    sink(s);
  };
  if (content.substr(0, kSeriesMagic.size()) == kSeriesMagic) {
    ParseBinary(content.substr(kSeriesMagic.size()), source, counted, progress);
  } else if (content.substr(0, 16) == "accelcal-series ") {
    throw InputError(source, 1,
                     "unsupported binary series header (expected: " +
                         std::string(kSeriesMagic.substr(0, kSeriesMagic.size() - 1)) + ")");
  } else {
    ParseText(content, source, counted, progress);
  }
  if (count == 0) throw InputError(source, 0, "no samples in the series");
}

void ReadSeries(const std::string& path, const std::function<void(const SystemSample&)>& sink,
                const SeriesProgress& progress) {
  // Read in blocks (a series of hours is gigabytes): never mapped, so a file that shrinks while
  // it is read is an InputError, not a SIGBUS; a pipe is read up to kMaxSeriesStreamBytes.
  internal::InputFile file(path, kMaxSeriesStreamBytes);
  long count = 0;
  const std::function<void(const SystemSample&)> counted = [&](const SystemSample& s) {
    ++count;
    sink(s);
  };
  std::string head(kSeriesMagic.size(), '\0');
  head.resize(file.ReadFully(head.data(), head.size()));
  if (head == kSeriesMagic) {
    constexpr std::size_t kChunkRows = 1 << 16;
    std::string chunk(kRowBytes * kChunkRows, '\0');
    std::size_t body = 0;  // bytes after the header so far
    while (true) {
      const std::size_t filled = file.ReadFully(chunk.data(), chunk.size());
      if (progress) progress(kSeriesMagic.size() + body, file.size());
      if (filled % kRowBytes != 0) {
        throw InputError(file.name(), 0, TruncatedMessage(body + filled));
      }
      ParseBinaryRows(std::string_view(chunk.data(), filled), static_cast<long>(body / kRowBytes),
                      file.name(), counted);
      body += filled;
      if (filled < chunk.size()) break;
    }
  } else if (head.substr(0, 16) == "accelcal-series ") {
    throw InputError(file.name(), 1,
                     "unsupported binary series header (expected: " +
                         std::string(kSeriesMagic.substr(0, kSeriesMagic.size() - 1)) + ")");
  } else {
    internal::TextBlocks blocks(&file, std::move(head));
    TextRows rows(file.name(), counted);
    std::string_view block;
    while (blocks.Next(&block)) {
      rows.Parse(block, blocks.line_end(), progress, blocks.block_offset(), blocks.total());
    }
  }
  if (count == 0) throw InputError(file.name(), 0, "no samples in the series");
}

}  // namespace accelcal
