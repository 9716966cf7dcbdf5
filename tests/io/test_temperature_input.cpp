// The sensor's temperature read with the samples (ReadOptions::temperature): a text log's column,
// PX4's sensor_accel.temperature against pyulog's decoding, ArduPilot's IMU.T; each static
// interval's and position's mean temperature; the calibration file's positions[].temperature.
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "accelcal/calibration_file.hpp"
#include "accelcal/error.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/positions.hpp"
#include "accelcal/static_detection.hpp"
#include "support/paths.hpp"

namespace accelcal {
namespace {

const std::string kPx4 = std::string(ACCELCAL_DATA_DIR) + "/px4-ulog/";

// The last column of pyulog's CSV of sample_log_small's sensor_accel instance `i`: temperature.
std::vector<double> PyulogTemperatures(int i) {
  std::ifstream f(kPx4 + "sample_log_small.sensor_accel." + std::to_string(i) + ".pyulog.csv");
  std::string line;
  std::getline(f, line);
  EXPECT_EQ(line.substr(line.rfind(',') + 1), "temperature");
  std::vector<double> out;
  while (std::getline(f, line)) out.push_back(std::stod(line.substr(line.rfind(',') + 1)));
  return out;
}

std::string ErrorOf(const std::string& text, const ReadOptions& options) {
  try {
    ParseInput(text, "t.csv", options);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(TemperatureInput, Px4SensorAccelTemperatureIsPyulogs) {
  for (int i = 0; i < 3; ++i) {
    ReadOptions options;
    options.topic = "sensor_accel";
    options.instance = i;
    const InputData data = ReadInput(kPx4 + "sample_log_small.ulg", options);
    const std::vector<double> want = PyulogTemperatures(i);
    ASSERT_EQ(data.raw.temperature_c.size(), want.size());
    for (std::size_t k = 0; k < want.size(); ++k) {
      EXPECT_EQ(data.raw.temperature_c[k], want[k]) << i << " " << k;  // float32, exactly
    }
    EXPECT_EQ(data.raw.temperature_source, "sensor_accel.temperature");
    // Not read when asked not to.
    options.temperature = "none";
    EXPECT_TRUE(ReadInput(kPx4 + "sample_log_small.ulg", options).raw.temperature_c.empty());
  }
  EXPECT_EQ(PyulogTemperatures(0).front(), 40.02537155151367);
  // sensor_combined has no temperature: none, and no error.
  ReadOptions combined;
  combined.topic = "sensor_combined";
  const InputData c = ReadInput(kPx4 + "sample_log_small.ulg", combined);
  EXPECT_TRUE(c.raw.temperature_c.empty());
  EXPECT_TRUE(c.raw.temperature_source.empty());
  // A field named that is not one.
  combined.temperature = "baro_temp_celcius";
  try {
    ReadInput(kPx4 + "sample_log_small.ulg", combined);
    ADD_FAILURE() << "read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("the temperature option names \"baro_temp_celcius\", "
                                         "which sensor_combined does not have"),
              std::string::npos)
        << e.what();
  }
}

TEST(TemperatureInput, PyulogsCsvHasItsTemperatureColumnFoundByName) {
  const std::string path = kPx4 + "sample_log_small.sensor_accel.0.pyulog.csv";
  ReadOptions options;
  options.kind = InputKind::kRaw;
  const InputData data = ReadInput(path, options);
  EXPECT_EQ(data.raw.temperature_c, PyulogTemperatures(0));
  EXPECT_EQ(data.raw.temperature_source, "column 6 ('temperature')");
  options.temperature = "6";
  EXPECT_EQ(ReadInput(path, options).raw.temperature_c, PyulogTemperatures(0));
  options.temperature = "none";
  EXPECT_TRUE(ReadInput(path, options).raw.temperature_c.empty());
}

TEST(TemperatureInput, ArduPilotImuT) {
  ReadOptions options;
  options.topic = "IMU";
  options.instance = 0;
  const InputData data = ReadInput(
      std::string(ACCELCAL_DATA_DIR) + "/ardupilot-dataflash/backend_log_80k.bin", options);
  ASSERT_EQ(data.raw.temperature_c.size(), data.raw.samples.size());
  EXPECT_EQ(data.raw.temperature_source, "IMU.T");
  for (double t : data.raw.temperature_c) {
    EXPECT_GT(t, 0);  // a board on a bench, in °C
    EXPECT_LT(t, 80);
  }
}

TEST(TemperatureInput, TextColumnChecks) {
  const std::string text =
      "t,x,y,z,temp\n0,1,2,3,25.5\n0.01,1,2,3,25.6\n0.02,1,2,3,25.7\n0.03,1,2,3,25.8\n";
  ReadOptions options;
  options.kind = InputKind::kRaw;
  const InputData data = ParseInput(text, "t.csv", options);
  EXPECT_EQ(data.raw.temperature_c, (std::vector<double>{25.5, 25.6, 25.7, 25.8}));
  // Kelvin, or the wrong column: found by its name, the value is left out and said; asked for,
  // refused at its line.
  std::string kelvin = text;
  kelvin.replace(kelvin.find("25.7"), 4, "298.85");
  const InputData found = ParseInput(kelvin, "t.csv", options);
  ASSERT_EQ(found.raw.temperature_c.size(), 4u);
  EXPECT_TRUE(std::isnan(found.raw.temperature_c[2]));
  EXPECT_EQ(found.raw.temperature_note,
            "column 5 ('temp'): 1 value is no temperature in degC (from -80 to 150; the first, "
            "298.85, at line 4): left out");
  std::string empty = text;
  empty.replace(empty.find("25.7"), 4, "");
  EXPECT_TRUE(std::isnan(ParseInput(empty, "t.csv", options).raw.temperature_c[2]));
  options.temperature = "temp";
  EXPECT_EQ(ErrorOf(empty, options), "t.csv:4: column 5: '' is not a number");
  EXPECT_EQ(ErrorOf(kelvin, options),
            "t.csv:4: column 5: the temperature 298.85 is outside -80 to 150 degC (kelvin, raw "
            "counts, or not a temperature?)");
  // A column already read as something else.
  options.temperature = "x";
  EXPECT_EQ(ErrorOf(text, options),
            "t.csv: the temperature column 2 ('x') is read as the x: each needs its own column");
  options.temperature = "9";
  EXPECT_EQ(ErrorOf(text, options),
            "t.csv: the temperature column '9' is not a column number between 1 and 5");
  options.temperature = "tc";
  EXPECT_EQ(ErrorOf(text, options), "t.csv: the temperature column 'tc' names no column");
  // Without a header, only by number; with an instance column, the chosen instance's rows.
  options.temperature = "5";
  options.columns = {"1", "2", "3", "4"};
  const InputData numbered =
      ParseInput("0,1,2,3,20\n0.01,1,2,3,21\n0.02,1,2,3,22\n", "t.csv", options);
  EXPECT_EQ(numbered.raw.temperature_c, (std::vector<double>{20, 21, 22}));
  options.temperature.clear();
  options.columns.clear();
  options.instance = 2;
  const InputData chosen = ParseInput(
      "t,i,x,y,z,temperature\n0,1,1,2,3,20\n0,2,1,2,3,40\n0.01,1,1,2,3,21\n0.01,2,1,2,3,41\n",
      "t.csv", options);
  EXPECT_EQ(chosen.raw.temperature_c, (std::vector<double>{40, 41}));
}

TEST(TemperatureInput, PositionsFileColumn) {
  ReadOptions options;
  options.kind = InputKind::kPositions;
  const InputData data =
      ParseInput("x,y,z,temperature\n0,0,9.8,10\n0,9.8,0,35.5\n", "p.csv", options);
  ASSERT_EQ(data.positions.size(), 2u);
  EXPECT_EQ(data.positions[0].temperature_c, 10.0);
  EXPECT_EQ(data.positions[1].temperature_c, 35.5);
  const InputData none = ParseInput("x,y,z\n0,0,9.8\n", "p.csv", options);
  EXPECT_FALSE(none.positions[0].temperature_c);
}

// Two still periods whose samples carry a temperature ramp, with NaN (not measured) in places:
// each interval's temperature is the mean over its samples that have one.
TEST(TemperatureInput, EachIntervalHasItsSamplesMeanTemperature) {
  RawLog log;
  log.source = "ramp";
  const double rate = 100;
  std::vector<double> t;
  for (int k = 0; k < 1000; ++k) {
    const bool second = k >= 500;
    const bool moving = k >= 450 && k < 550;
    Vec3 f = second ? Vec3(0, 0, 9.81) : Vec3(9.81, 0, 0);
    if (moving) f = Vec3(6, 6, 6) + Vec3::Constant(3 * std::sin(k * 0.3));
    f += 1e-3 * Vec3(std::sin(k * 1.7), std::cos(k * 2.3), std::sin(k * 0.9));
    log.samples.push_back(f);
    log.time_s.push_back(k / rate);
    log.line.push_back(static_cast<std::uint32_t>(k + 1));
    log.temperature_c.push_back(k % 7 == 3 ? std::nan("") : 20.0 + 0.01 * k);
  }
  log.rate_hz = rate;
  StaticDetectionOptions options;
  options.init_rest_s = 0;
  const StaticDetectionResult d = DetectStaticIntervals(log, options);
  ASSERT_EQ(d.intervals.size(), 2u);
  for (const StaticInterval& s : d.intervals) {
    double sum = 0;
    int n = 0;
    for (std::size_t k = s.begin; k < s.end; ++k) {
      if (k % 7 != 3) sum += 20.0 + 0.01 * static_cast<double>(k), ++n;
    }
    ASSERT_TRUE(s.temperature_c);
    EXPECT_NEAR(*s.temperature_c, sum / n, 1e-12);
  }
  const std::vector<Position> positions = PositionsFromIntervals(d.intervals);
  EXPECT_EQ(positions[1].temperature_c, d.intervals[1].temperature_c);
  // Without temperatures, none.
  log.temperature_c.clear();
  EXPECT_FALSE(DetectStaticIntervals(log, options).intervals[0].temperature_c);
}

}  // namespace
}  // namespace accelcal
