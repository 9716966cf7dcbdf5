#include "accelcal/series_file.hpp"

#include <cmath>
#include <cstring>

#include <fast_float/fast_float.h>

#include "accelcal/error.hpp"
#include "accelcal/log_reader.hpp"
#include "mapped_file.hpp"
#include "text_lines.hpp"

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

void ParseBinary(std::string_view body, const std::string& source,
                 const std::function<void(const SystemSample&)>& sink,
                 const SeriesProgress& progress) {
  if (body.size() % kRowBytes != 0) {
    throw InputError(source, 0,
                     "truncated binary series: " + std::to_string(body.size()) +
                         " bytes after the header is not a whole number of 48-byte samples");
  }
  const long rows = static_cast<long>(body.size() / kRowBytes);
  for (long r = 0; r < rows; ++r) {
    const char* p = body.data() + static_cast<std::size_t>(r) * kRowBytes;
    if (progress && r % kProgressEvery == 0) {
      progress(static_cast<std::size_t>(r) * kRowBytes, body.size());
    }
    SystemSample s;
    s.t = GetDouble(p);
    s.f = Vec3(GetDouble(p + 8), GetDouble(p + 16), GetDouble(p + 24));
    s.roll = GetDouble(p + 32);
    s.pitch = GetDouble(p + 40);
    if (!std::isfinite(s.t) || !s.f.allFinite() || !std::isfinite(s.roll) ||
        !std::isfinite(s.pitch)) {
      throw InputError(source, 0, RowError(r + 1, "not finite"));
    }
    sink(s);
  }
}

void ParseText(std::string_view text, const std::string& source,
               const std::function<void(const SystemSample&)>& sink,
               const SeriesProgress& progress) {
  internal::LineReader reader(text, source);
  internal::Line text_line;
  bool first_data = true;
  std::size_t rows = 0;
  while (reader.Next(&text_line)) {
    if (progress && rows++ % kProgressEvery == 0) progress(reader.offset(), text.size());
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
      if (first_data && !ok && n == 0) {  // a header line (its first field is no number)
        first_data = false;
        continue;
      }
      throw InputError(source, line, "expected 6 numbers (t,fx,fy,fz,roll,pitch)");
    }
    first_data = false;
    SystemSample s;
    s.t = v[0];
    s.f = Vec3(v[1], v[2], v[3]);
    s.roll = v[4];
    s.pitch = v[5];
    for (double x : v) {
      if (!std::isfinite(x)) throw InputError(source, line, "a value is not finite");
    }
    sink(s);
  }
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
  const internal::MappedFile mapped(path);
  if (mapped.ok()) {
    ParseSeries(mapped.text(), path, sink, progress);
    return;
  }
  ParseSeries(ReadFileToString(path), path, sink,
              progress);  // pipes, empty files, errors with errno
}

}  // namespace accelcal
