// accelcal noise as a user runs it: a simulated still log's noise terms back, and what it refuses.
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "accelcal/noise_simulation.hpp"
#include "support/cli_test.hpp"
#include "support/paths.hpp"

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
  // How the time column was read is said: a unit misread is a density 31.6 times off.
  EXPECT_EQ(doc["time_unit"],
            "time column 'time' read as seconds (suggested by its name; median "
            "step 0.01: 100 Hz)");
  const CliRun text = Exec("noise " + log);
  ASSERT_EQ(text.status, 0) << text.err;
  EXPECT_EQ(text.out.rfind("# time: time column 'time' read as seconds", 0), 0u) << text.out;
  EXPECT_NE(text.out.find("accelerometer (" + log + "): 16384 samples at 100 Hz (163.8 s), in raw"),
            std::string::npos)
      << text.out;
  // The same bytes again.
  EXPECT_EQ(Exec("noise " + log + " --json").out, r.out);
  // Without its time column, at the rate given: the same white noise, with --still too (the
  // detection had been given no rate: "no time column and no sample rate was given").
  std::string untimed;
  std::istringstream rows(test::Slurp(log));
  for (std::string row; std::getline(rows, row);) untimed += row.substr(row.find(',') + 1) + "\n";
  const std::string xyz = Write("xyz.csv", untimed);
  for (const char* still : {"", " --still"}) {
    const CliRun given = Exec("noise " + xyz + " --rate 100 --json" + still);
    ASSERT_EQ(given.status, 0) << still << given.err;
    const nlohmann::json d = nlohmann::json::parse(given.out);
    EXPECT_EQ(d["rate_hz"], 100.0);
    EXPECT_NEAR(d["accelerometer"]["axes"][0]["terms"]["white"]["value"].get<double>(), 1e-3,
                4 * axes[0]["terms"]["white"]["sigma"].get<double>())
        << still;
  }
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
  // Less a detection window (51 samples) at each end of samples 26-999.
  EXPECT_NE(r.out.find("# the longest still interval: samples 77-948"), std::string::npos) << r.out;
}

// A log time,x,y,z of white noise (density 1e-3 per axis around (0, 9.8, 0)) at the times `t`.
// From sample `turn` on, y and z swap (the sensor turned over).
// `vibration`: the amplitude of a 5 s sine on x.
std::string LogAt(const std::vector<double>& t, double scale = 1,
                  std::size_t turn = static_cast<std::size_t>(-1), double vibration = 0) {
  std::vector<std::vector<double>> axes;
  for (int a = 0; a < 3; ++a) {
    axes.push_back(SimulateNoise({0, 1e-3, 0, 0, 0}, t.size(), 0.01, 70 + std::uint64_t(a)));
  }
  std::string s = "time,x,y,z\n";
  char line[200];
  for (std::size_t k = 0; k < t.size(); ++k) {
    double y = 9.8 + axes[1][k], z = axes[2][k];
    if (k >= turn) std::swap(y, z);
    const double x = axes[0][k] + vibration * std::sin(2 * 3.14159265358979323846 * t[k] / 5);
    std::snprintf(line, sizeof line, "%.6f,%.17g,%.17g,%.17g\n", t[k], scale * x, scale * y,
                  scale * z);
    s += line;
  }
  return s;
}

std::vector<double> Times(std::size_t n, double rate_hz) {
  std::vector<double> t(n);
  for (std::size_t k = 0; k < n; ++k) t[k] = static_cast<double>(k) / rate_hz;
  return t;
}

// What a hostile test found accepted with wrong figures: each refused, naming where.
TEST_F(Cli, NoiseRefusesLogsThatAreNotOneStillStreamAtOneRate) {
  // 100 Hz, then 200 Hz: every step within half the first's, the windows' rates show it.
  std::vector<double> t = Times(8192, 100);
  for (std::size_t k = 1; k <= 8192; ++k) t.push_back(81.91 + static_cast<double>(k) / 200);
  const std::string two_rates = Write("two_rates.csv", LogAt(t));
  for (const char* still : {"", " --still"}) {
    const CliRun r = Exec("noise " + two_rates + still);
    EXPECT_EQ(r.status, 3) << still;
    // Named from the window where it changes (its rate between the two), and the largest step.
    EXPECT_NE(r.err.find("where the log starts at 100 Hz"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("at most 100 % away): the rate changes within the log"), std::string::npos)
        << r.err;
  }
  // Every 8th sample lost (a 2× step, below a gap's 10×): the period would be 14 % long.
  t.clear();
  for (std::size_t k = 0; k < 16384; ++k) {
    if (k % 8 != 7) t.push_back(static_cast<double>(k) / 100);
  }
  const std::string lossy = Write("lossy.csv", LogAt(t));
  // Steps of 10 ms, but a step every 11.4 ms over the span: lost samples, or 87.5 Hz printed to
  // 10 ms? The rate says which.
  CliRun r = Exec("noise " + lossy);
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find("either 2047 samples (14 %) of a 100 Hz stream are lost, or the timestamps "
                       "are rounded"),
            std::string::npos)
      << r.err;
  r = Exec("noise " + lossy + " --rate 100");
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find(lossy + ":9: 2047 samples are missing from a 100 Hz stream (14 %"),
            std::string::npos)
      << r.err;
  // Sparse: 1 in 200 lost, 0.5 %: counted, over the sampling period.
  t.clear();
  for (std::size_t k = 0; k < 16384; ++k) {
    if (k % 200 != 199) t.push_back(static_cast<double>(k) / 100);
  }
  r = Exec("noise " + Write("sparse.csv", LogAt(t)));
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find(":201: 81 samples are missing (0.5 % of the log"), std::string::npos)
      << r.err;
  // Turned over at 40.96 s: y and z swap.
  const std::string moved = LogAt(Times(8192, 100), 1, 4096);
  const std::string moving = Write("moving.csv", moved);
  r = Exec("noise " + moving);
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(
      r.err.find("the sensor moves: the mean of its y axis over 256 samples changes by 9.799 at "
                 "40.96 s after the first sample analysed"),
      std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("give --still"), std::string::npos) << r.err;
  // Readings whose squares double precision cannot hold.
  for (double scale : {1e101, 1e-101}) {
    const std::string huge = Write("scaled.csv", LogAt(Times(4096, 100), scale));
    r = Exec("noise " + huge);
    EXPECT_EQ(r.status, 3) << scale;
    EXPECT_NE(r.err.find("beyond the 1e-100 to 1e+100 the noise analysis holds"), std::string::npos)
        << r.err;
  }
  // Inside them, the figures scale with the readings (the fit is scale-free).
  const CliRun unit = Exec("noise " + Write("unit.csv", LogAt(Times(4096, 100))) + " --json");
  const CliRun big = Exec("noise " + Write("big.csv", LogAt(Times(4096, 100), 1e90)) + " --json");
  ASSERT_EQ(unit.status, 0) << unit.err;
  ASSERT_EQ(big.status, 0) << big.err;
  const double n1 =
      nlohmann::json::parse(unit.out)["accelerometer"]["axes"][0]["terms"]["white"]["value"];
  const double n2 =
      nlohmann::json::parse(big.out)["accelerometer"]["axes"][0]["terms"]["white"]["value"];
  EXPECT_NEAR(n2 / 1e90, n1, 1e-9 * n1);
}

TEST_F(Cli, NoiseRefusesOptionsThatDoNotFitTheLog) {
  const std::string log = Write("still.csv", LogAt(Times(4096, 100)));
  // An instance chosen in a log without an instance column, streamed or whole.
  for (const char* still : {"", " --still"}) {
    const CliRun r = Exec("noise " + log + " --instance 3" + still);
    EXPECT_EQ(r.status, 3) << still;
    EXPECT_NE(r.err.find("an instance was chosen, but the file has no instance column"),
              std::string::npos)
        << r.err;
  }
  // A column read twice.
  CliRun r = Exec("noise " + log + " --columns time,x,x,z");
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find("--columns names column 2 ('x') twice (as x and y)"), std::string::npos)
      << r.err;
  // The gyroscope's columns overlapping the accelerometer's.
  r = Exec("noise " + log + " --gyro-columns time,z,x,y");
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find("--gyro-columns reads column 4 ('z') as its x, which the accelerometer "
                       "reads as its z"),
            std::string::npos)
      << r.err;
  // A rate that is no log's.
  r = Exec("noise " + log + " --rate 1e-100");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--rate must be a number of Hz in [0.001, 1e+06]"), std::string::npos);
  r = Exec("noise " + log + " --columns 1,2");
  EXPECT_EQ(r.status, 2);
  // A given rate the time column contradicts by 2 %: the column's is taken, and said.
  r = Exec("noise " + log + " --rate 102 --json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NEAR(nlohmann::json::parse(r.out)["rate_hz"].get<double>(), 100, 1e-9);
  EXPECT_NE(r.err.find("--rate 102 Hz given, but the time column's samples come at 100 Hz"),
            std::string::npos)
      << r.err;
}

// A calibration of another sensor (here the Xsens's, on a log in other units) is refused at rest;
// a fit whose terms are not a result is written, marked failed, with exit status 6.
TEST_F(Cli, NoiseChecksTheCalibrationAndItsOwnFit) {
  const std::string data = std::string(ACCELCAL_DATA_DIR) + "/imutk-t265/";
  const std::string cal = Path("t265.json");
  ASSERT_EQ(Exec("calibrate " + data + "t265_acc.mat --gravity 9.8016 -q -o " + cal).status, 0);
  const std::string log = Write("still.csv", LogAt(Times(4096, 100)));
  CliRun r = Exec("noise " + log + " --calibration " + cal);
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find("where that calibration's gravity is 9.8016 m/s2"), std::string::npos)
      << r.err;
  // A vibration (a 5 s sine of the white noise's per-sample σ): bias instability 9.7σ below 0,
  // not chance: written, marked failed, status 6.
  const std::string out = Path("noise.json");
  const std::string shaken = Write("shaken.csv", LogAt(Times(65536, 100), 1, -1, 0.01));
  r = Exec("noise " + shaken + " --json -o " + out);
  EXPECT_EQ(r.status, 6) << r.err;
  nlohmann::json doc = nlohmann::json::parse(test::Slurp(out));
  EXPECT_EQ(doc["verdict"], "failed");
  EXPECT_EQ(doc["failed_axes"], nlohmann::json::array({"accelerometer x"}));
  std::string notes = doc["accelerometer"]["axes"][0]["notes"].dump();
  EXPECT_NE(notes.find("below 0, beyond chance"), std::string::npos) << notes;
  // The T265's rest: its accelerometer's y axis puts random walk 2.6σ below 0: a note (1 log
  // in 10 by chance), not a failure.
  r = Exec("noise " + data + "t265_acc.mat --still --calibration " + cal + " --json -o " + out);
  EXPECT_EQ(r.status, 0) << r.err;
  doc = nlohmann::json::parse(test::Slurp(out));
  EXPECT_EQ(doc["verdict"], "passed");
  notes = doc["accelerometer"]["axes"][1]["notes"].dump();
  EXPECT_NE(notes.find("random_walk (-2.6σ) below 0 beyond its 95 % interval"), std::string::npos)
      << notes;
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
  const double accel[3] = {86.0, 90.7, 89.9}, gyro[3] = {0.0350, 0.0350, 0.0354};
  for (std::size_t a = 0; a < 3; ++a) {
    const nlohmann::json& w = doc["accelerometer"]["axes"][a]["terms"]["white"];
    EXPECT_NEAR(w["value"].get<double>() * ug, accel[a], 0.05) << a;  // as the README rounds
    const nlohmann::json& g = doc["gyroscope"]["axes"][a]["terms"]["white"];
    EXPECT_NEAR(g["value"].get<double>() * deg, gyro[a], 0.00005) << a;
  }
  // The report: both sensors' Allan deviation plotted with a band per axis, the terms as the
  // text gives them (its table and the text's figures, one formatting), the same bytes twice.
  const std::string html = Path("noise.html"), text = Path("noise.txt");
  const std::string args = "noise " + data + "xsens_acc.mat --still --calibration " + cal +
                           " --gyro " + data + "xsens_gyro.mat";
  ASSERT_EQ(Exec(args + " --report " + html + " -o " + text).status, 0);
  const std::string page = test::Slurp(html);
  for (const char* id : {"<svg id=\"allan-0\"", "<svg id=\"allan-1\""}) {
    EXPECT_NE(page.find(id), std::string::npos) << id;
  }
  std::size_t bands = 0;
  for (std::size_t at = page.find("class=\"band\""); at != std::string::npos;
       at = page.find("class=\"band\"", at + 1)) {
    ++bands;
  }
  EXPECT_EQ(bands, 6u);
  // The white noise of x as the text prints it ("86.0x ± ..."), in the table.
  const double x_white = doc["accelerometer"]["axes"][0]["terms"]["white"]["value"].get<double>();
  char figure[32];
  std::snprintf(figure, sizeof figure, "%.4g &plusmn;", x_white * ug);
  EXPECT_NE(page.find(figure), std::string::npos) << figure;
  EXPECT_NE(page.find("<dd>passed</dd>"), std::string::npos);
  ASSERT_EQ(Exec(args + " --report " + Path("again.html") + " -o " + Path("again.txt")).status, 0);
  EXPECT_EQ(test::Slurp(Path("again.html")), page);
  // Both files or neither: an output that cannot be written leaves no report behind.
  const std::string lone = Path("lone.html");
  const CliRun bad = Exec(args + " --report " + lone + " -o " + Path("missing/dir/out.txt"));
  EXPECT_EQ(bad.status, 5) << bad.err;
  EXPECT_FALSE(test::fs::exists(lone));
}

}  // namespace
}  // namespace accelcal
