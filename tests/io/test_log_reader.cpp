// Reading raw logs and positions files, and the messages for malformed ones.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "accelcal/error.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/ulog_writer.hpp"
#include "io/number_parser.hpp"

namespace accelcal {
namespace {

InputData Parse(const std::string& text, ReadOptions options = {}) {
  return ParseInput(text, "test.csv", options);
}

std::string ErrorOf(const std::string& text, ReadOptions options = {}) {
  try {
    Parse(text, options);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

std::string ManyRows(int n, const char* sep, bool with_time) {
  std::string s;
  for (int i = 0; i < n; ++i) {
    if (with_time) s += std::to_string(0.01 * i) + sep;
    s += std::to_string(i) + sep + "2.5" + sep + "-3e-1\n";
  }
  return s;
}

TEST(LogReader, ReportsProgressEvery65536Rows) {
  std::string text = "t,x,y,z\n";
  for (int k = 0; k < 200000; ++k) text += std::to_string(k) + ",1,2,3\n";
  ReadOptions options;
  options.kind = InputKind::kRaw;
  std::vector<std::pair<std::size_t, std::size_t>> reports;
  options.progress = [&](std::size_t done, std::size_t total) {
    reports.emplace_back(done, total);
  };
  const InputData d = ParseInput(text, "big.csv", options);
  ASSERT_EQ(d.raw.samples.size(), 200000u);
  ASSERT_EQ(reports.size(), 3u);  // after rows 65536, 131072, 196608
  for (std::size_t r = 0; r < reports.size(); ++r) {
    EXPECT_EQ(reports[r].second, reports[0].second);
    if (r > 0) {
      EXPECT_GT(reports[r].first, reports[r - 1].first);
    }
    EXPECT_LT(reports[r].first, reports[r].second);
  }
  // Row 65536 ends where the parser stands: ~65536/200000 of the data.
  EXPECT_NEAR(static_cast<double>(reports[0].first) / static_cast<double>(reports[0].second),
              65536.0 / 200000.0, 0.02);
}

TEST(LogReader, ImuTkAsciiWithTime) {
  const InputData d = Parse(
      "   2.98e-02   3.3108e+04   3.3329e+04   3.6429e+04\n"
      "   3.98e-02   3.3096e+04   3.3336e+04   3.6437e+04\n",
      ReadOptions{InputKind::kRaw, {}, std::nullopt, 200, nullptr, TimeUnit::kAuto, std::nullopt});
  ASSERT_EQ(d.kind, InputKind::kRaw);
  ASSERT_EQ(d.raw.samples.size(), 2u);
  EXPECT_EQ(d.raw.samples[1], Vec3(33096, 33336, 36437));
  // Times are seconds from the first sample, whose time is the origin.
  EXPECT_EQ(d.raw.time_s[0], 0.0);
  ASSERT_TRUE(d.raw.time);
  EXPECT_DOUBLE_EQ(d.raw.time->origin_s, 0.0298);
  EXPECT_EQ(d.raw.time->unit, TimeUnit::kSeconds);
  EXPECT_NEAR(*d.raw.rate_hz, 100.0, 1e-9);
  EXPECT_EQ(d.raw.line[1], 2u);
}

TEST(LogReader, CommaTabAndSpaceDelimitersWithHeaderAndComments) {
  for (const char* sep : {",", "\t", "  ", ", "}) {
    const std::string text = "# recorded by hand\n\ntime" + std::string(sep) + "ax" + sep + "ay" +
                             sep + "az\n" + ManyRows(300, sep, true);
    const InputData d = Parse(text);
    ASSERT_EQ(d.kind, InputKind::kRaw) << "sep '" << sep << "'";
    ASSERT_EQ(d.raw.samples.size(), 300u);
    EXPECT_EQ(d.raw.samples[299], Vec3(299, 2.5, -0.3));
    EXPECT_EQ(d.raw.line[0], 4u);
  }
}

TEST(LogReader, ThreeColumnsNeedARateForDetectionButParse) {
  const InputData d = Parse(ManyRows(300, ",", false));
  EXPECT_EQ(d.kind, InputKind::kRaw);
  EXPECT_FALSE(d.raw.rate_hz.has_value());
  ReadOptions o;
  o.rate_hz = 50;
  EXPECT_EQ(*Parse(ManyRows(300, ",", false), o).raw.rate_hz, 50);
}

TEST(LogReader, ColumnSelectionByNumberAndName) {
  std::string text = "part,samples,acc_x,acc_y,acc_z,gyr_x\n";
  for (int i = 0; i < 300; ++i) text += "x_p," + std::to_string(i) + ",1,2,3,9\n";
  ReadOptions o;
  o.columns = {"acc_x", "acc_y", "acc_z"};
  o.rate_hz = 204.8;
  InputData d = Parse(text, o);
  EXPECT_EQ(d.raw.samples[5], Vec3(1, 2, 3));
  o.columns = {"2", "3", "4", "5"};
  // A sample counter as the time column: by its step 1 it is read as ms (1 kHz), which the given
  // rate contradicts; in the unit it really has, it agrees.
  EXPECT_EQ(ErrorOf(text, o),
            "test.csv: the given rate 204.8 Hz contradicts the time column, whose timestamps (ms) "
            "come at 1000 Hz");
  o.rate_hz.reset();
  o.time_unit = TimeUnit::kMilliseconds;
  d = Parse(text, o);
  EXPECT_EQ(d.raw.samples[5], Vec3(1, 2, 3));
  EXPECT_EQ(d.raw.time_s[5], 0.005);
  o.rate_hz = 1000;
  o.columns = {"acc_q", "acc_y", "acc_z"};
  EXPECT_EQ(ErrorOf(text, o), "test.csv: the columns option's entry 'acc_q' names no column");
  o.columns = {"9", "2", "3"};
  EXPECT_EQ(ErrorOf(text, o),
            "test.csv: the columns option's entry '9' is not a column number between 1 and 6");
}

TEST(LogReader, AHeaderWithASampleCountMeansPositionsWhateverTheRowCount) {
  // 300 averaged readings (paper 001's scenario as accelcal simulate writes it): more rows than a
  // positions file usually has, but only averaged readings carry a sample count.
  std::string text = "x,y,z,n,sx,sy,sz\n";
  for (int k = 0; k < 300; ++k) text += "0.1,0.2,0.97,100,1,1,1\n";
  const InputData d = Parse(text);
  ASSERT_EQ(d.kind, InputKind::kPositions);
  EXPECT_EQ(d.kind_reason, "auto: the header is a positions file's (n, sx, sy, sz)");
  EXPECT_EQ(d.positions.size(), 300u);
  EXPECT_EQ(d.positions[0].samples, 100u);
}

TEST(LogReader, PositionsFilesAutoDetected) {
  const InputData d = Parse("ax_g,ay_g,az_g\n0.1,0.2,0.97\n-0.9,0.1,0.3\n");
  ASSERT_EQ(d.kind, InputKind::kPositions);
  ASSERT_EQ(d.positions.size(), 2u);
  EXPECT_EQ(d.positions[1].mean, Vec3(-0.9, 0.1, 0.3));
  EXPECT_EQ(d.positions[1].samples, 1u);

  const InputData e = Parse("1,2,3,100,0.1,0.2,0.3\n4,5,6,200,0.4,0.5,0.6\n");
  ASSERT_EQ(e.positions.size(), 2u);
  EXPECT_EQ(e.positions[1].samples, 200u);
  EXPECT_EQ(*e.positions[1].std, Vec3(0.4, 0.5, 0.6));

  // The derived-means layout: names find the columns, extra ones are ignored.
  const InputData f = Parse("start_idx0,end_idx0_excl,n_samples,ax,ay,az\n50,5192,5142,1,2,3\n");
  EXPECT_EQ(f.positions[0].samples, 5142u);
  EXPECT_EQ(f.positions[0].mean, Vec3(1, 2, 3));
}

TEST(LogReader, ErrorsNameFileLineAndReason) {
  EXPECT_EQ(ErrorOf(""), "test.csv: no data (the file is empty or all comments)");
  EXPECT_EQ(ErrorOf("# only\n\n"), "test.csv: no data (the file is empty or all comments)");
  EXPECT_EQ(ErrorOf("x,y,z\n"), "test.csv:1: a header but no data rows");
  EXPECT_EQ(ErrorOf("1,2,3\n4,abc,6\n"), "test.csv:2: column 2: 'abc' is not a number");
  EXPECT_EQ(ErrorOf("1,2,3\n4,nan,6\n"), "test.csv:2: column 2: 'nan' is not a finite number");
  EXPECT_EQ(ErrorOf("1,2,3\n4,5,inf\n"), "test.csv:2: column 3: 'inf' is not a finite number");
  EXPECT_EQ(ErrorOf("1,2,3\n# c\n4,5\n"), "test.csv:3: expected 3 columns, found 2");
  EXPECT_EQ(ErrorOf("1 2 3\n4,5 6\n"),
            "test.csv:2: mixed delimiters: a comma in a whitespace-separated file");
  EXPECT_EQ(ErrorOf("1,2,3,4,5\n"),
            "test.csv:1: 5 columns: a positions file has x,y,z [,n [,sx,sy,sz]]");
  ReadOptions raw;
  raw.kind = InputKind::kRaw;
  EXPECT_EQ(ErrorOf("1,2,3,4,5\n", raw),
            "test.csv:1: 5 columns: use the columns option to choose time,x,y,z or x,y,z");
  EXPECT_EQ(ErrorOf("0,1,2,3\n1,1,2,3\n0.5,1,2,3\n", raw),
            "test.csv:3: time goes backwards (0.5 after 1)");
  EXPECT_EQ(ErrorOf("1,2,3,4\n1,2,3,4\n", raw), "test.csv: the timestamps do not advance");
  EXPECT_EQ(ErrorOf("1,2,3,0\n"),
            "test.csv:1: the sample count must be a whole number from 1 to 2^53");
  // Found by fuzz_log_reader: a count too large for any integer (the cast was undefined).
  EXPECT_EQ(ErrorOf("1,2,3,3.6437e+41\n"),
            "test.csv:1: the sample count must be a whole number from 1 to 2^53");
  EXPECT_EQ(ErrorOf("1,2,3,9007199254740994\n"),
            "test.csv:1: the sample count must be a whole number from 1 to 2^53");
}

// `n` rows time,x,y,z at 100 Hz of a noisy sensor, each written `copies` times; `time(k)` the
// k-th sample's time [s] as written, `value(k)` its x.
std::string Noisy(int n, int copies, const std::function<double(int)>& time,
                  const std::function<double(int)>& value) {
  std::string s = "time,x,y,z\n";
  for (int k = 0; k < n; ++k) {
    char row[128];
    std::snprintf(row, sizeof row, "%.6f,%.6f,%.6f,%.6f\n", time(k), value(k), 9.8 + 0.5 * value(k),
                  -value(k));
    for (int c = 0; c < copies; ++c) s += row;
  }
  return s;
}

// A recorder or a merge that wrote every message twice: each sample followed by an exact copy
// (time and values). Read as it was, it had twice the samples at 200 Hz, its repeated timestamps
// blamed on their resolution; it is refused at the first copy. Not refused: a few copies, values
// repeated at distinct times (a driver re-sending its last reading, a still sensor quantised
// coarser than its noise), timestamps coarser than the period with values that differ.
TEST(LogReader, ARecordingThatRepeatsEachSampleIsRefused) {
  const auto at_100hz = [](int k) { return 0.01 * k; };
  const auto noise = [](int k) { return 0.001 * ((k * 7919) % 1000); };
  EXPECT_EQ(ErrorOf(Noisy(400, 2, at_100hz, noise)),
            "test.csv:3: the recording repeats each sample: this sample is an exact copy of the "
            "one before it, the same time and values, as are 400 of its 800 samples (a recorder "
            "or a merge that wrote every message twice); read as it is, its rate and sample count "
            "would be twice the sensor's: keep one of each");
  // Five copies in 400 samples: read, all of them.
  std::string few = "time,x,y,z\n";
  for (int k = 0; k < 400; ++k) {
    char row[96];
    std::snprintf(row, sizeof row, "%.2f,%.3f,9.8,0\n", 0.01 * k, noise(k));
    few += row;
    if (k % 80 == 7) few += row;
  }
  EXPECT_EQ(Parse(few).raw.samples.size(), 405u);
  // Every value held for two samples at their own times (a sensor at half the log's rate, or a
  // quantised one at rest): read.
  const InputData held = Parse(Noisy(400, 1, at_100hz, [&](int k) { return noise(k / 2); }));
  EXPECT_EQ(held.raw.samples.size(), 400u);
  EXPECT_NEAR(*held.raw.rate_hz, 100, 1e-6);
  // Four samples to a timestamp (400 Hz stamped in 10 ms), values that differ: read.
  const InputData coarse = Parse(Noisy(
      800, 1, [](int k) { return 0.01 * (k / 4); }, noise));
  EXPECT_EQ(coarse.raw.samples.size(), 800u);
  // The same quantised values at rest, two to a timestamp: their values repeat at distinct
  // times as often as at the same time, so not copies: read.
  const InputData still = Parse(Noisy(
      400, 1, [](int k) { return 0.005 * (k / 2); },
      [&](int k) { return k % 50 < 40 ? 0.0 : noise(k); }));
  EXPECT_EQ(still.raw.samples.size(), 400u);
  // A binary log's copies are named by their topic, message and byte (a ULog's, here).
  const ULogImuWriter ulog;
  std::string twice = ulog.Header();
  for (int k = 0; k < 400; ++k) {
    const std::string message =
        ulog.Accel(1000000 + 10000 * std::uint64_t(k), Vec3(noise(k), 0, -9.8));
    twice += message + message;
  }
  try {
    ParseInput(twice, "twice.ulg", {});
    ADD_FAILURE() << "read";
  } catch (const InputError& e) {
    const std::size_t second =
        ulog.Header().size() + ulog.Accel(1000000, Vec3(noise(0), 0, -9.8)).size();
    const std::string named = "twice.ulg: sensor_accel message 2 (byte " + std::to_string(second) +
                              "): the recording repeats each sample";
    EXPECT_EQ(std::string(e.what()).find(named), 0u) << e.what();
  }
}

TEST(LogReader, NumbersAreCorrectlyRounded) {
  // Every spelling a logger produces must give the correctly rounded double (glibc's strtod is), on
  // the fast path and on the fast_float fallback alike.
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> mant(-1.0, 1.0);
  std::uniform_int_distribution<int> expo(-30, 30), prec(1, 19);
  const char* formats[] = {"%.*g", "%.*e", "%.*f", "%+.*E"};
  std::string text;
  std::vector<double> expected;
  for (int i = 0; i < 3000; ++i) {
    const int exponent = expo(rng);  // drawn first: the order of the operands of * is unspecified
    const double v = mant(rng) * std::pow(10.0, exponent);
    char buf[3][96];
    for (int a = 0; a < 3; ++a) {
      std::snprintf(buf[a], sizeof buf[a], formats[(i + a) % 4], prec(rng), v * (a + 1));
      expected.push_back(std::strtod(buf[a], nullptr));
    }
    text += std::string(buf[0]) + "," + buf[1] + "," + buf[2] + "\n";
  }
  text += "007,-0.000,+1.\n.5,-.25e1,1E+2\n";
  for (double v : {7.0, -0.0, 1.0, 0.5, -2.5, 100.0}) expected.push_back(v);
  ReadOptions o;
  o.kind = InputKind::kRaw;
  o.rate_hz = 1;
  const InputData d = Parse(text, o);
  ASSERT_EQ(d.raw.samples.size() * 3, expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    const double got = d.raw.samples[i / 3](static_cast<Eigen::Index>(i % 3));
    EXPECT_EQ(std::memcmp(&got, &expected[i], sizeof got), 0)
        << "value " << i << ": " << got << " vs " << expected[i];
  }
  EXPECT_EQ(ErrorOf("1,2,3\n1,+-2,3\n"), "test.csv:2: column 2: '+-2' is not a number");
  EXPECT_EQ(ErrorOf("1,2,3\n1,2 5,3\n"),
            "test.csv:2: mixed delimiters: column 2 ('2 5') is separated by whitespace in a "
            "comma-separated file");
  EXPECT_EQ(ErrorOf("1,2,3\n1,1e,3\n"), "test.csv:2: column 2: '1e' is not a number");
  EXPECT_EQ(ErrorOf("1,2,3\n1,0x10,3\n"), "test.csv:2: column 2: '0x10' is not a number");
}

TEST(LogReader, UnreadablePath) {
  try {
    ReadInput("/nonexistent/dir/log.csv", {});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "/nonexistent/dir/log.csv: cannot open: No such file or directory");
  }
}

// Text as spreadsheets and old tools write it (issue 16): a UTF-8 byte-order mark is skipped (it
// made the first row of a headerless file a "header" and dropped it), CR-only line ends are line
// ends, and UTF-16 and semicolon-separated exports are named in the message.
TEST(LogReader, AFileWhoseSizeIsZeroButHasContentIsReadToItsEnd) {
  // /proc's files say they have 0 bytes: read, their content is what is judged (here, not a log),
  // not called empty.
  try {
    ReadInput("/proc/self/status", {});
    ADD_FAILURE() << "read /proc/self/status as a log";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).find("no data"), std::string::npos) << e.what();
    EXPECT_EQ(e.line(), 1u) << e.what();
  }
}

TEST(LogReader, ByteOrderMarksLineEndsAndSemicolons) {
  const std::string rows = "1,2,3\n4,5,6\n7,8,9\n";
  InputData d = Parse("\xEF\xBB\xBF" + rows);
  ASSERT_EQ(d.positions.size(), 3u);
  EXPECT_EQ(d.positions[0].mean, Vec3(1, 2, 3));
  d = Parse("\xEF\xBB\xBFt,x,y,z\n0,1,2,3\n0.01,1,2,3\n0.02,1,2,4\n");
  ASSERT_EQ(d.kind, InputKind::kRaw);
  EXPECT_EQ(d.raw.samples.size(), 3u);
  ASSERT_TRUE(d.raw.time);
  EXPECT_EQ(d.raw.time->unit, TimeUnit::kSeconds);
  d = Parse("x,y,z\r1,2,3\r4,5,6\r");
  ASSERT_EQ(d.positions.size(), 2u);
  EXPECT_EQ(d.positions[1].mean, Vec3(4, 5, 6));
  d = Parse("x,y,z\r\n1,2,3\r\n4,5,6\r\n");
  EXPECT_EQ(d.positions.size(), 2u);
  EXPECT_EQ(ErrorOf("\xFF\xFEx\0,\0"),
            "test.csv:1: UTF-16 text (it starts with a byte-order mark): save it as UTF-8");
  EXPECT_EQ(ErrorOf("x;y;z\n0,01;0,02;0,99\n"),
            "test.csv:1: semicolons separate the fields (a spreadsheet's export with decimal "
            "commas?); accelcal reads commas, tabs or spaces between fields and points in "
            "numbers");
}

TEST(LogReader, AGivenRateMakesAShortHeaderlessFileARawLog) {
  const std::string rows = ManyRows(30, ",", false);
  EXPECT_EQ(Parse(rows).kind, InputKind::kPositions);
  EXPECT_TRUE(Parse(rows).kind_from_row_count);
  ReadOptions options;
  options.rate_hz = 100;
  const InputData raw = Parse(rows, options);
  EXPECT_EQ(raw.kind, InputKind::kRaw);
  EXPECT_EQ(raw.kind_reason, "auto: a sample rate was given: a raw log");
  EXPECT_FALSE(raw.kind_from_row_count);
  // A header that says positions wins, and then the rate is a mistake, not ignored.
  EXPECT_NE(ErrorOf("x,y,z,n,sx,sy,sz\n1,2,3,10,1,1,1\n", options)
                .find("a sample rate was given, but this is a positions file"),
            std::string::npos);
}

// The number parser's fast paths (number_parser.hpp) against the C library's correctly rounded
// strtod, bit for bit: every decimal they accept, in the spellings loggers write.
std::string RandomNumber(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> mantissa(-10, 10);
  std::uniform_int_distribution<int> exponent(-30, 30), digits(0, 18), style(0, 5);
  const double v = mantissa(rng) * std::pow(10.0, exponent(rng));
  char buf[64];
  const int p = digits(rng);
  switch (style(rng)) {
    case 0:
      std::snprintf(buf, sizeof buf, "%.*e", p, v);
      break;
    case 1:
      std::snprintf(buf, sizeof buf, "%.*f", p % 10, v / std::pow(10.0, exponent(rng) / 3));
      break;
    case 2:
      std::snprintf(buf, sizeof buf, "%.*g", p + 1, v);
      break;
    case 3:
      std::snprintf(buf, sizeof buf, "+%.*E", p, v < 0 ? -v : v);
      break;
    case 4:
      std::snprintf(buf, sizeof buf, "00%.*f", p % 9, std::abs(v) / std::pow(10.0, exponent(rng)));
      break;
    default:
      std::snprintf(buf, sizeof buf, "%d.%0*de%+d", static_cast<int>(rng() % 100), p % 9 + 1,
                    static_cast<int>(rng() % 1000), exponent(rng) / 2);
      break;
  }
  return buf;
}

std::uint64_t Bits(double v) {
  std::uint64_t b;
  std::memcpy(&b, &v, sizeof b);
  return b;
}

TEST(NumberParser, FastPathsAreCorrectlyRounded) {
  std::mt19937_64 rng(17);
  int wide = 0, short_path = 0;
  for (int i = 0; i < 200000; ++i) {
    const std::string number = RandomNumber(rng);
    // Followed by what ends a field, and bytes enough for the 16-byte path.
    const std::string text = number + (i % 2 ? " " : ",") + std::string(40, '7');
    const double expected = std::strtod(number.c_str(), nullptr);
    double value = 0;
    const char* last = text.data() + text.size();
    if (const char* end = internal::ParseShortDecimal(text.data(), last, &value)) {
      ++short_path;
      ASSERT_EQ(end - text.data(), static_cast<std::ptrdiff_t>(number.size())) << number;
      ASSERT_EQ(Bits(value), Bits(expected)) << number;
    }
#if defined(__SSE2__)
    value = 0;
    if (const char* end = internal::ParseDecimal16(text.data(), &value)) {
      ++wide;
      if (end - text.data() == static_cast<std::ptrdiff_t>(number.size())) {
        ASSERT_EQ(Bits(value), Bits(expected)) << number;
      } else {  // a number longer than 16 bytes: the caller sees a digit where it must end
        ASSERT_GE(end - text.data(), 16) << number;
      }
    }
#endif
    ASSERT_TRUE(internal::ParseNumber(number, &value)) << number;
    ASSERT_EQ(Bits(value), Bits(expected)) << number;
  }
  EXPECT_GT(short_path, 50000);
#if defined(__SSE2__)
  EXPECT_GT(wide, 50000);
#endif
}

TEST(LogReader, ColumnsWrittenByOnePrintfFormatAreReadAsStrtodReadsThem) {
  // The fast path keeps each column's number layout from the row before (NumberShape) and checks
  // the next row against it: every format a logger's printf writes, with signs and exponent signs
  // changing from row to row, bit-identical to strtod.
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> unit(-1, 1);
  std::uniform_int_distribution<int> decade(-9, 9);
  for (const char* format : {"%15.7e", "%.6f", "%+.4E", "%12.3f", "%.9e", "%.0f", "%g"}) {
    for (const char* sep : {" ", ","}) {
      std::string text;
      std::vector<std::array<double, 3>> expected;
      for (int i = 0; i < 2000; ++i) {
        std::array<double, 3> row{};
        for (int a = 0; a < 3; ++a) {
          char field[64];
          // Mostly one magnitude (the layout repeats), sometimes another (it changes).
          const int e = i % 13 == 0 ? decade(rng) : 2;
          std::snprintf(field, sizeof field, format, unit(rng) * std::pow(10.0, e));
          text += (a ? sep : "") + std::string(field);
          row[static_cast<std::size_t>(a)] = std::strtod(field, nullptr);
        }
        text += "\n";
        expected.push_back(row);
      }
      const InputData d = Parse(text);
      ASSERT_EQ(d.raw.samples.size(), expected.size()) << format << sep;
      for (std::size_t i = 0; i < expected.size(); ++i) {
        for (int a = 0; a < 3; ++a) {
          ASSERT_EQ(Bits(d.raw.samples[i](a)), Bits(expected[i][static_cast<std::size_t>(a)]))
              << "row " << i << " format " << format << " separated by '" << sep << "'";
        }
      }
    }
  }
}

TEST(LogReader, RowsLaidOutAlikeWithExponentsBeyondTheExactRangeAreReadAsStrtodReadsThem) {
  // A row laid out as the row before keeps its exponents when they are the same bytes; when they
  // change it reads them again, and when one is beyond 10^±22 (the exact powers of ten) the row
  // goes field by field. Every row alike here, its exponents moving in and out of that range and
  // its signs changing.
  std::mt19937_64 rng(23);
  std::uniform_int_distribution<int> sign(0, 1), decade(0, 6), side(0, 1);
  std::string text;
  std::vector<std::array<double, 3>> expected;
  for (int i = 0; i < 3000; ++i) {
    std::array<double, 3> row{};
    // Runs of rows with one set of exponents, as a log's values keep their decade for a while.
    const int run = (i / 7) % 5;
    for (int a = 0; a < 3; ++a) {
      // %15.7e: 8 digits, so 10^(e - 7): e from -18 to -12 (-25 to -19: out below -22) and from
      // 25 to 31 (18 to 24: out above 22).
      const int e = run == 0 ? 2 : (side(rng) ? -12 - decade(rng) : 25 + decade(rng));
      const double v = (sign(rng) ? -1.0 : 1.0) * (1.0 + 0.123456 * (a + 1)) * std::pow(10.0, e);
      char field[64];
      std::snprintf(field, sizeof field, "%15.7e", v);
      text += field;
      row[static_cast<std::size_t>(a)] = std::strtod(field, nullptr);
    }
    text += "\n";
    expected.push_back(row);
  }
  const InputData d = Parse(text);
  ASSERT_EQ(d.raw.samples.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    for (int a = 0; a < 3; ++a) {
      ASSERT_EQ(Bits(d.raw.samples[i](a)), Bits(expected[i][static_cast<std::size_t>(a)]))
          << "row " << i + 1 << " axis " << a;
    }
  }
}

TEST(LogReader, AFieldLaidOutAsTheRowBeforeButNotANumberIsAnError) {
  // Its digits where the last row's were, but another byte where the point, the exponent letter
  // or its sign was: not read as the row before's layout.
  const std::string row = "   2.9840000e-02   3.3108000e+04   3.3329000e+04   3.6429000e+04\n";
  for (const char* bad : {"3.3108000x+04", "3,3108000e+04", "3.3108000e*04", "3.3108000e 04",
                          "3.31080000+04", "3.3108000ee04"}) {
    std::string text;
    for (int i = 0; i < 10; ++i) text += row;
    std::string broken = row;
    broken.replace(broken.find("3.3108000e+04"), 13, bad);
    text += broken + row;
    const std::string error = ErrorOf(text);
    EXPECT_EQ(error.rfind("test.csv:11: ", 0), 0u) << bad << ": " << error;
  }
}

TEST(LogReader, ARowLaidOutAsTheRowBeforeButForItsSeparatorsIsNotReadAsIt) {
  // Rows are read whole against the last row's layout (RowTemplate), where a sign may replace the
  // blank before a number only when the number still begins a field there: with one blank between
  // two numbers, a sign in its place joins them into one field that is not a number.
  struct Case {
    const char* row;
    const char* broken;
    const char* error;
  };
  for (const Case& c : {
           Case{"1.5 2.5 3.5\n", "1.5-2.5 3.5\n",
                "test.csv:11: column 1: '1.5-2.5' is not a number"},
           Case{"1.5 2.5 3.5\n", "1.5+2.5 3.5\n",
                "test.csv:11: column 1: '1.5+2.5' is not a number"},
           Case{"1.5\t2.5\t3.5\n", "1.5-2.5\t3.5\n",
                "test.csv:11: column 1: '1.5-2.5' is not a number"},
           Case{"1.5,2.5,3.5\n", "1.5,2.5-3.5\n",
                "test.csv:11: column 2: '2.5-3.5' is not a number"},
           Case{"-1.5  2.5  3.5\n", "x1.5  2.5  3.5\n",
                "test.csv:11: column 1: 'x1.5' is not a number"},
           Case{"1.5e+01 2.5 3.5\n", "1.5e 01 2.5 3.5\n",
                "test.csv:11: column 1: '1.5e' is not a number"},
           Case{"1.5  2.5  3.5\n", "1.5 \x01 2.5  3.5\n",
                "test.csv:11: column 2: '\x01' is not a number"},
       }) {
    std::string text;
    for (int i = 0; i < 10; ++i) text += c.row;
    text += c.broken;
    for (int i = 0; i < 300; ++i) text += c.row;
    EXPECT_EQ(ErrorOf(text), c.error) << c.broken;
  }
  // And where the sign may change, the numbers are read with it: blanks before each number, in
  // a line of exactly 32 bytes (the template's last 16-byte block is checked whole).
  std::string text;
  for (int i = 0; i < 300; ++i) {
    text += i % 2 ? "  -1.250000  +2.500000 3.750000\n" : "   1.250000  -2.500000 3.750000\n";
  }
  ASSERT_EQ(text.find('\n'), 31u);
  const InputData d = Parse(text);
  ASSERT_EQ(d.raw.samples.size(), 300u);
  for (std::size_t i = 0; i < 300; ++i) {
    EXPECT_EQ(d.raw.samples[i], i % 2 ? Vec3(-1.25, 2.5, 3.75) : Vec3(1.25, -2.5, 3.75)) << i;
  }
}

TEST(LogReader, TheFastPathsReadWhatTheGeneralPathReads) {
  // Lines ending in '\r' alone take the general path (LineReader and ParseFields) for every row;
  // lines ending in '\n' take the fast paths (the row template, the column layouts, FastRow). The
  // same rows either way must give the same values, bit for bit, or the same error: rows of a few
  // printf formats with signs changing, and now and then one byte of a row replaced.
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> unit(-1, 1);
  const char* formats[] = {"%15.7e", "%.6f", "%+.4E", "%12.3f", "%g", "%.3e"};
  const char replacements[] = {'-', '+', ' ', '.', 'e', ',', '\t', '0', '9', 'x', '#', '\0'};
  int errors = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const char* format = formats[trial % 6];
    const char* sep = trial % 3 == 0 ? "," : (trial % 3 == 1 ? " " : "  ");
    std::string text;
    for (int i = 0; i < 260; ++i) {
      std::string line;
      for (int a = 0; a < 3; ++a) {
        char field[64];
        std::snprintf(field, sizeof field, format, unit(rng) * (i % 29 == 0 ? 1e4 : 50.0));
        line += (a ? sep : "") + std::string(field);
      }
      if (trial % 2 == 0 && i == 20 + trial % 200) {  // one byte replaced
        line[rng() % line.size()] = replacements[rng() % sizeof replacements];
      }
      text += line + "\n";
    }
    std::string mac = text;
    std::replace(mac.begin(), mac.end(), '\n', '\r');
    const std::string fast_error = ErrorOf(text), general_error = ErrorOf(mac);
    ASSERT_EQ(fast_error, general_error) << text;
    if (fast_error != "no error") {
      ++errors;
      continue;
    }
    const InputData fast = Parse(text), general = Parse(mac);
    ASSERT_EQ(fast.raw.samples.size(), general.raw.samples.size());
    for (std::size_t i = 0; i < fast.raw.samples.size(); ++i) {
      for (int a = 0; a < 3; ++a) {
        ASSERT_EQ(Bits(fast.raw.samples[i](a)), Bits(general.raw.samples[i](a)))
            << "row " << i << " of " << text;
      }
    }
    ASSERT_EQ(fast.raw.line, general.raw.line);
  }
  EXPECT_GT(errors, 50);   // both kinds of text are
  EXPECT_LT(errors, 250);  // exercised
}

TEST(LogReader, EveryRowIsReadAsStrtodReadsIt) {
  // Whitespace and comma logs of mixed spellings (long mantissas, signs, exponents, CRLF, blank
  // lines and comments between the rows), read by the fast path and the general one: every value
  // bit-identical to strtod's. The last row has no line end: a recording cut while it was
  // written, that row left out and said.
  std::mt19937_64 rng(5);
  for (const char* sep : {"   ", ",", " , ", "\t"}) {
    std::string text;
    std::vector<std::array<std::string, 4>> rows;
    for (int i = 0; i < 3000; ++i) {
      std::array<std::string, 4> row{std::to_string(0.01 * i), RandomNumber(rng), RandomNumber(rng),
                                     RandomNumber(rng)};
      if (i % 3 == 0) text += "  ";
      for (int c = 0; c < 4; ++c) text += (c ? sep : "") + row[c];
      text += i % 7 == 0 ? " \r\n" : (i % 11 == 0 ? "  # note\n" : "\n");
      if (i % 97 == 0) text += "\n# a comment line\n";
      rows.push_back(row);
    }
    text.pop_back();  // the last row without its line end
    const InputData d = Parse(text);
    ASSERT_EQ(d.raw.samples.size(), rows.size() - 1) << sep;
    EXPECT_NE(d.raw.read_warning.find("the file ends inside line"), std::string::npos);
    for (std::size_t i = 0; i + 1 < rows.size(); ++i) {
      for (int a = 0; a < 3; ++a) {
        ASSERT_EQ(Bits(d.raw.samples[i](a)), Bits(std::strtod(rows[i][a + 1].c_str(), nullptr)))
            << "row " << i << " '" << rows[i][a + 1] << "' separated by '" << sep << "'";
      }
    }
  }
}

TEST(LogReader, ARawLogWhoseLastLineHasNoLineEndLeavesItOutAndSaysSo) {
  // A logger cut while it wrote "34799": the last row ends "34", read as wrong as any number.
  // From a file, as a recording comes: the row is left out and said (a binary log's record cut
  // short is said alike).
  std::string text = "t,ax,ay,az\n" + ManyRows(300, ",", true) + "3,1.5,2.5,34";
  const std::string path = ::testing::TempDir() + "/cut_mid_number.csv";
  std::FILE* f = std::fopen(path.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  std::fwrite(text.data(), 1, text.size(), f);
  std::fclose(f);
  const InputData d = ReadInput(path, {});
  std::remove(path.c_str());
  ASSERT_EQ(d.kind, InputKind::kRaw);
  EXPECT_EQ(d.raw.samples.size(), 300u);
  EXPECT_EQ(d.raw.samples.back(), Vec3(299, 2.5, -0.3));
  EXPECT_EQ(
      d.raw.read_warning,
      "the file ends inside line 302, which has no line end (the recording was cut while "
      "it was written; its last value may be cut short), left out: the rows before it were read");

  // A row cut before all its fields were written is left out alike, not refused.
  EXPECT_EQ(Parse("t,ax,ay,az\n" + ManyRows(300, ",", true) + "3,1.5").raw.samples.size(), 300u);
  // A comment or blanks after the last line end: nothing cut, nothing said.
  const InputData c = Parse(ManyRows(300, ",", true) + "# stopped  ");
  EXPECT_EQ(c.raw.samples.size(), 300u);
  EXPECT_EQ(c.raw.read_warning, "");
  // A positions file's every row is a position, typed by hand as often as not: its last line
  // without a line end is whole and read.
  const InputData p = Parse("ax_g,ay_g,az_g\n0.1,0.2,0.97\n-0.9,0.1,0.3");
  ASSERT_EQ(p.kind, InputKind::kPositions);
  ASSERT_EQ(p.positions.size(), 2u);
  EXPECT_EQ(p.positions[1].mean, Vec3(-0.9, 0.1, 0.3));
  ReadOptions positions;
  positions.kind = InputKind::kPositions;
  EXPECT_EQ(Parse("1,2,3\n4,5,6", positions).positions.size(), 2u);
}

TEST(LogReader, ErrorsDeepInTheFileNameTheirLine) {
  // Line 2001 of a log whose rows the fast path reads: what it does not take whole goes to the
  // general path, which names it as before.
  std::string ws, csv;
  for (int i = 0; i < 2000; ++i) {
    ws += "  " + std::to_string(0.01 * i) + "   1.5e+00   -2.25   3\n";
    csv += std::to_string(0.01 * i) + ",1.5e+00,-2.25,3\n";
  }
  EXPECT_EQ(ErrorOf(ws + "20 1,5 2 3\n" + ws),
            "test.csv:2001: mixed delimiters: a comma in a whitespace-separated file");
  EXPECT_EQ(ErrorOf(ws + "20 1 2\n" + ws), "test.csv:2001: expected 4 columns, found 3");
  EXPECT_EQ(ErrorOf(ws + "20 1 2 3 4\n" + ws), "test.csv:2001: expected 4 columns, found 5");
  EXPECT_EQ(ErrorOf(ws + "20 1 nan 3\n" + ws),
            "test.csv:2001: column 3: 'nan' is not a finite number");
  EXPECT_EQ(ErrorOf(ws + "20 1 1e400 3\n" + ws),
            "test.csv:2001: column 3: '1e400' is not a finite number");
  EXPECT_EQ(ErrorOf(ws + "20 1 2x 3\n" + ws), "test.csv:2001: column 3: '2x' is not a number");
  EXPECT_EQ(ErrorOf(ws + std::string("20 1 2 3\0\n", 10) + ws),
            "test.csv:2001: a NUL byte at column 9: binary data, not a delimited text file");
  EXPECT_EQ(ErrorOf(csv + "20,1,2 5,3\n" + csv),
            "test.csv:2001: mixed delimiters: column 3 ('2 5') is separated by whitespace in a "
            "comma-separated file");
  EXPECT_EQ(ErrorOf(csv + "20,1,,3\n" + csv), "test.csv:2001: column 3: '' is not a number");
  EXPECT_EQ(ErrorOf(csv + "20,1,2,3,\n" + csv), "test.csv:2001: expected 4 columns, found 5");
  EXPECT_EQ(ErrorOf(csv + "20,1,2\n" + csv), "test.csv:2001: expected 4 columns, found 3");
  EXPECT_EQ(ErrorOf(csv + "20,1,2,3\n" + csv), "test.csv:2002: time goes backwards (0 after 20)");
  // Comments, blank lines and a long number in between change nothing.
  const InputData d = Parse(ws + "# c\n\n  20.5 1.00000000000000001 -0.0 3 # x\n");
  ASSERT_EQ(d.raw.samples.size(), 2001u);
  EXPECT_EQ(d.raw.line.back(), 2003u);
  EXPECT_EQ(d.raw.samples.back()(0), 1.0);
  EXPECT_TRUE(std::signbit(d.raw.samples.back()(1)));
}

}  // namespace
}  // namespace accelcal
