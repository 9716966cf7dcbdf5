// A raw log read in pieces (StreamRawLog): the same samples, times and lines as ReadInput, in
// bounded pieces, and the same refusals.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "accelcal/error.hpp"
#include "accelcal/log_reader.hpp"

namespace accelcal {
namespace {

std::string WriteFile(const std::string& name, const std::string& text) {
  const std::string path = (std::filesystem::path(::testing::TempDir()) / name).string();
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

// `n` rows time,x,y,z, the time in microseconds (a unit to decide), a gap of 1 s after row
// `gap_at` when given, instance column values from `instance` (empty: no such column).
std::string Log(std::size_t n, std::size_t gap_at = 0, const std::vector<int>& instance = {}) {
  std::string s = instance.empty() ? "timestamp,x,y,z\n" : "timestamp,instance,x,y,z\n";
  char line[160];
  double t = 1.7e15;  // an epoch in µs: large values, read exactly relative to the first
  for (std::size_t k = 0; k < n; ++k) {
    t += 2500 + (k == gap_at && gap_at > 0 ? 1e6 : 0.0);
    const double x = 0.001 * static_cast<double>((k * 7919) % 1000);
    if (instance.empty()) {
      std::snprintf(line, sizeof line, "%.0f,%.6f,%.6f,%.6f\n", t, x, 9.8 - x, -x);
    } else {
      std::snprintf(line, sizeof line, "%.0f,%d,%.6f,%.6f,%.6f\n", t, instance[k % instance.size()],
                    x, 9.8 - x, -x);
    }
    s += line;
  }
  return s;
}

struct Streamed {
  StreamedLog log;
  RawLog all;
  std::size_t pieces = 0, largest = 0;
};

Streamed Stream(const std::string& path, const ReadOptions& options = {}) {
  Streamed out;
  out.log = StreamRawLog(path, options, [&](const RawLog& piece) {
    ++out.pieces;
    out.largest = std::max(out.largest, piece.samples.size());
    out.all.time_s.insert(out.all.time_s.end(), piece.time_s.begin(), piece.time_s.end());
    out.all.samples.insert(out.all.samples.end(), piece.samples.begin(), piece.samples.end());
    out.all.line.insert(out.all.line.end(), piece.line.begin(), piece.line.end());
  });
  return out;
}

void ExpectSameAsRead(const std::string& path, const ReadOptions& options = {}) {
  ReadOptions raw = options;
  raw.kind = InputKind::kRaw;
  const InputData read = ReadInput(path, raw);
  const Streamed s = Stream(path, options);
  EXPECT_EQ(s.log.samples, read.raw.samples.size());
  EXPECT_EQ(s.all.samples, read.raw.samples);
  EXPECT_EQ(s.all.time_s, read.raw.time_s);
  EXPECT_EQ(s.all.line, read.raw.line);
  ASSERT_EQ(s.log.rate_hz.has_value(), read.raw.rate_hz.has_value());
  if (s.log.rate_hz) {
    EXPECT_DOUBLE_EQ(*s.log.rate_hz, *read.raw.rate_hz);
  }
  ASSERT_EQ(s.log.time.has_value(), read.raw.time.has_value());
  if (s.log.time) {
    EXPECT_EQ(s.log.time->unit, read.raw.time->unit);
    EXPECT_EQ(s.log.time->origin_s, read.raw.time->origin_s);
    ASSERT_EQ(s.log.time->gaps.size(), read.raw.time->gaps.size());
    for (std::size_t g = 0; g < s.log.time->gaps.size(); ++g) {
      EXPECT_EQ(s.log.time->gaps[g].index, read.raw.time->gaps[g].index);
      EXPECT_EQ(s.log.gap_lines[g], read.raw.line[read.raw.time->gaps[g].index]);
    }
  }
}

TEST(StreamRawLog, GivesWhatReadInputGivesInPieces) {
  // Longer than the head the unit is decided on, with a gap after it.
  const std::string path = WriteFile("stream_long.csv", Log(200000, 150000));
  ExpectSameAsRead(path);
  const Streamed s = Stream(path);
  EXPECT_GT(s.pieces, 10u);
  EXPECT_LE(s.largest, kStreamHeadSamples + 20000) << "a piece is a block, the head at most";
  EXPECT_EQ(s.log.time->unit, TimeUnit::kMicroseconds);
  // Shorter than the head; no time column (a rate given).
  ExpectSameAsRead(WriteFile("stream_short.csv", Log(3000)));
  ReadOptions rate;
  rate.rate_hz = 400;
  rate.columns = {"x", "y", "z"};
  ExpectSameAsRead(WriteFile("stream_notime.csv", Log(100000)), rate);
  // One instance chosen of two.
  ReadOptions one;
  one.instance = 1;
  ExpectSameAsRead(WriteFile("stream_instances.csv", Log(150000, 0, {0, 1})), one);
}

std::string ErrorOf(const std::string& path, const ReadOptions& options = {}) {
  try {
    Stream(path, options);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(StreamRawLog, RefusesWhatReadInputRefuses) {
  // Time going back after the head, and in it.
  std::string text = Log(100000);
  const std::size_t at = text.find('\n', text.size() - 200) + 1;  // a late row: its time reset
  text.insert(at, "1700000000000000,0,0,0\n");
  const std::string back = WriteFile("stream_back.csv", text);
  EXPECT_NE(ErrorOf(back).find("stream_back.csv:"), std::string::npos);
  EXPECT_NE(ErrorOf(back).find("time goes backwards"), std::string::npos) << ErrorOf(back);
  // Two sensors and none chosen: the line of the second's first row.
  const std::string two = WriteFile("stream_two.csv", Log(1000, 0, {3, 3, 3, 5}));
  EXPECT_NE(ErrorOf(two).find("stream_two.csv:5: the rows belong to more than one sensor "
                              "(instance column 'instance': 3 from line 2, 5 here)"),
            std::string::npos)
      << ErrorOf(two);
  ReadOptions missing;
  missing.instance = 7;
  EXPECT_NE(ErrorOf(two, missing).find("no rows of instance 7"), std::string::npos);
  EXPECT_NE(ErrorOf(WriteFile("stream_empty.csv", "timestamp,x,y,z\n")).find("no data rows"),
            std::string::npos);
  EXPECT_NE(ErrorOf(WriteFile("stream_one.csv", Log(1))).find("one sample"), std::string::npos);
  EXPECT_NE(ErrorOf("/dev/zero").find("NUL byte"), std::string::npos);
  ReadOptions wrong;
  wrong.rate_hz = 100;
  EXPECT_NE(ErrorOf(WriteFile("stream_rate.csv", Log(3000)), wrong).find("contradicts"),
            std::string::npos);
  // Every row twice (a recorder that wrote each message twice): refused at the first copy.
  std::string twice;
  const std::string rows = Log(100000);
  for (std::size_t b = 0, e = 0; b < rows.size(); b = e) {
    e = rows.find('\n', b) + 1;
    twice += rows.substr(b, e - b);
    if (b > 0) twice += rows.substr(b, e - b);  // not the header
  }
  EXPECT_NE(ErrorOf(WriteFile("stream_twice.csv", twice))
                .find("stream_twice.csv:3: the recording repeats each sample"),
            std::string::npos)
      << ErrorOf(WriteFile("stream_twice.csv", twice));
}

TEST(StreamRawLog, ALastLineWithoutItsLineEndIsLeftOutAndSaid) {
  // As ReadInput: a recording cut while its last row was written.
  std::string text = Log(1000);
  text.resize(text.size() - 4);  // "...,-0.123456\n" cut to "...,-0.123"
  const std::string path = WriteFile("cut.csv", text);
  const Streamed s = Stream(path);
  const InputData whole = ReadInput(path, {});
  std::remove(path.c_str());
  EXPECT_EQ(s.log.samples, 999u);
  EXPECT_EQ(whole.raw.samples.size(), 999u);
  EXPECT_NE(s.log.read_warning.find("the file ends inside line 1001"), std::string::npos);
  EXPECT_EQ(s.log.read_warning, whole.raw.read_warning);
}

}  // namespace
}  // namespace accelcal
