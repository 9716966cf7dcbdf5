// accelcal noise as a user runs it: a simulated still log's noise terms back, and what it refuses.
#include <cmath>
#include <cstdio>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "accelcal/noise_simulation.hpp"
#include "support/cli_test.hpp"

namespace accelcal {
namespace {

using Cli = test::CliTest;
using test::CliRun;

// A still log time,x,y,z at 100 Hz: white noise of density 1e-3, 2e-3, 4e-3 per axis.
std::string StillLog(std::size_t n, bool with_gap = false) {
  std::vector<std::vector<double>> axes;
  for (int a = 0; a < 3; ++a) {
    axes.push_back(
        SimulateNoise({0, 1e-3 * std::pow(2.0, a), 0, 0, 0}, n, 0.01, 40 + std::uint64_t(a)));
  }
  std::string s = "time,x,y,z\n";
  char line[160];
  for (std::size_t k = 0; k < n; ++k) {
    const double t = 0.01 * static_cast<double>(k) + (with_gap && k >= n / 2 ? 5.0 : 0.0);
    std::snprintf(line, sizeof line, "%.5f,%.17g,%.17g,%.17g\n", t, axes[0][k], 9.8 + axes[1][k],
                  axes[2][k]);
    s += line;
  }
  return s;
}

TEST_F(Cli, NoiseGivesTheWhiteNoiseOfEachAxis) {
  const std::string log = Write("still.csv", StillLog(16384));
  const CliRun r = Exec("noise " + log + " --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json doc = nlohmann::json::parse(r.out);
  EXPECT_NEAR(doc["rate_hz"].get<double>(), 100.0, 1e-9);
  const nlohmann::json& axes = doc["accelerometer"]["axes"];
  ASSERT_EQ(axes.size(), 3u);
  for (int a = 0; a < 3; ++a) {
    const nlohmann::json& white = axes[std::size_t(a)]["terms"]["white"];
    EXPECT_TRUE(white["resolved"].get<bool>());
    EXPECT_NEAR(white["value"].get<double>(), 1e-3 * std::pow(2.0, a),
                4 * white["sigma"].get<double>())
        << a;
    EXPECT_EQ(axes[std::size_t(a)]["allan"].size(), 13u);  // m = 1 … 4096
  }
  const CliRun text = Exec("noise " + log);
  ASSERT_EQ(text.status, 0) << text.err;
  EXPECT_NE(text.out.find("accelerometer (" + log + "): 16384 samples at 100 Hz (163.8 s), in raw"),
            std::string::npos)
      << text.out;
  // The same bytes again.
  EXPECT_EQ(Exec("noise " + log + " --json").out, r.out);
}

TEST_F(Cli, NoiseRefusesWhatItCannotCharacterise) {
  const std::string gap = Write("gap.csv", StillLog(4096, true));
  CliRun r = Exec("noise " + gap);
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find(gap + ":2050: a gap in the samples"), std::string::npos) << r.err;
  const std::string short_log = Write("short.csv", StillLog(100));
  r = Exec("noise " + short_log);
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find("100 samples give 5 octaves"), std::string::npos) << r.err;
  const std::string no_time = Write("notime.csv", "x,y,z\n1,2,3\n1,2,3\n");
  r = Exec("noise " + no_time);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("has no time column: give the sample rate with --rate"), std::string::npos)
      << r.err;
  const std::string log = Write("still.csv", StillLog(1024));
  r = Exec("noise " + log + " -o " + log);
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_EQ(test::Slurp(log), StillLog(1024)) << "the input was overwritten";
  r = Exec("noise " + log + " --still");
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("# the longest still interval: samples 26-999"), std::string::npos) << r.out;
}

// The README's figures: the Xsens recording's rest, calibrated by its own calibration.
TEST_F(Cli, NoiseOfTheXsensRestIsTheReadmes) {
  const std::string data = std::string(ACCELCAL_DATA_DIR) + "/imutk-xsens-mti/";
  const std::string cal = Path("xsens.json");
  ASSERT_EQ(Exec("calibrate " + data + "xsens_acc.mat --gravity 9.81744 --gyro " + data +
                 "xsens_gyro.mat -q -o " + cal)
                .status,
            0);
  const CliRun r = Exec("noise " + data + "xsens_acc.mat --still --calibration " + cal +
                        " --gyro " + data + "xsens_gyro.mat --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json doc = nlohmann::json::parse(r.out);
  const double ug = 1e6 / 9.80665, deg = 180 / 3.14159265358979323846;
  const double accel[3] = {83.6, 91.1, 90.2}, gyro[3] = {0.0350, 0.0350, 0.0354};
  for (std::size_t a = 0; a < 3; ++a) {
    const nlohmann::json& w = doc["accelerometer"]["axes"][a]["terms"]["white"];
    EXPECT_NEAR(w["value"].get<double>() * ug, accel[a], 0.05) << a;  // as the README rounds
    const nlohmann::json& g = doc["gyroscope"]["axes"][a]["terms"]["white"];
    EXPECT_NEAR(g["value"].get<double>() * deg, gyro[a], 0.00005) << a;
  }
}

}  // namespace
}  // namespace accelcal
