// Never silently wrong: the logs users really have (issue 15's numbered cases), each run as a
// user runs accelcal, asserting the exit status, the diagnosis and that a result that is kept is
// right. Inputs are built from the bundled recordings and the simulator.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "accelcal/gravity.hpp"
#include "accelcal/simulate.hpp"
#include "support/calibration_keys.hpp"
#include "support/cli_test.hpp"
#include "support/paths.hpp"

namespace accelcal {
namespace {

using test::CliRun;
using test::Slurp;
using Trust = test::CliTest;
using nlohmann::json;
namespace fs = std::filesystem;

const std::string kData = ACCELCAL_DATA_DIR;
constexpr double kG = kStandardGravity_ms2;

// A MEMS accelerometer logging m/s²: scale errors of a few per cent, misalignment, biases.
ModelParameters MemsDevice() {
  ModelParameters p;
  p.K << 1.01, 0, 0, 0.002, 0.99, 0, -0.003, 0.004, 1.005;
  p.bias = Vec3(0.05, -0.08, 0.12);
  return p;
}

// A simulated raw log of MemsDevice: 24 random positions, 5 s still each, 2 s turns, 100 Hz.
SimulatedLog MemsLog(double sigma, std::uint64_t seed = 3, int positions = 24) {
  RawLogSimulation o;
  o.rate_hz = 100;
  o.static_s = 5;
  o.transition_s = 2;
  o.sigma_raw_per_sample = Vec3::Constant(sigma);
  o.seed = seed;
  return SimulateRawLog(MemsDevice(), kG, RandomDirections(positions, seed), o);
}

// The log as text: a header, then time (scaled by `time_scale` and printed with `time_format`)
// and the samples with `decimals` decimals.
std::string LogText(const SimulatedLog& log, const std::string& header, double time_scale,
                    const char* time_format, int decimals) {
  std::string text = header + "\n";
  char line[256];
  for (std::size_t i = 0; i < log.samples.size(); ++i) {
    int n = std::snprintf(line, sizeof line, time_format, log.time_s[i] * time_scale);
    for (int a = 0; a < 3; ++a) {
      n += std::snprintf(line + n, sizeof line - std::size_t(n), ",%.*f", decimals,
                         log.samples[i](a));
    }
    text += line;
    text += '\n';
  }
  return text;
}

json Json(const std::string& path) { return test::AccelerometerKeys(Slurp(path)); }

std::vector<std::string> Codes(const json& doc) {
  std::vector<std::string> codes;
  for (const json& f : doc.at("diagnostics")) codes.push_back(f.at("code"));
  return codes;
}

bool Has(const json& doc, const std::string& code) {
  const std::vector<std::string> codes = Codes(doc);
  return std::find(codes.begin(), codes.end(), code) != codes.end();
}

// Every parameter of `doc` within `k` of its reported 1σ of `truth`.
void ExpectWithinSigma(const json& doc, const ModelParameters& truth, double k) {
  const json& K = doc.at("K");
  const json& sK = doc.at("std").at("K");
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j <= i; ++j) {
      const double sigma = sK[i][j].get<double>();
      EXPECT_LT(std::abs(K[i][j].get<double>() - truth.K(i, j)), k * sigma + 1e-12)
          << "K" << i << j;
    }
    EXPECT_LT(std::abs(doc.at("bias")[i].get<double>() - truth.bias(i)),
              k * doc.at("std").at("bias")[i].get<double>())
        << "b" << i;
  }
}

// 1. Time in µs, ms or ns: read in its unit from the column's name and step, the same
// calibration as in seconds; a unit that cannot be right, a rate that contradicts the time column
// and a window the rate cannot hold are errors.
TEST_F(Trust, TimeInAnyUnitGivesTheCalibrationOfSeconds) {
  const SimulatedLog log = MemsLog(0.02);
  const CliRun seconds = Exec("calibrate " + Write("s.csv", LogText(log, "t,x,y,z", 1, "%.2f", 6)) +
                              " -o " + Path("s.json"));
  ASSERT_EQ(seconds.status, 0) << seconds.err;
  const json reference = Json(Path("s.json"));
  EXPECT_EQ(reference.at("verdict"), "ok") << seconds.err;
  struct Case {
    const char* name;
    const char* header;
    double scale;
    const char* format;
    const char* unit;
  };
  for (const Case& c : {Case{"px4", "timestamp,x,y,z", 1e6, "%.0f", "us"},
                        Case{"ardupilot", "TimeUS,AccX,AccY,AccZ", 1e6, "%.0f", "us"},
                        Case{"ros", "%time,field.x,field.y,field.z", 1e9, "%.0f", "ns"},
                        Case{"ms", "time_ms,ax,ay,az", 1e3, "%.0f", "ms"},
                        Case{"comment-header", "# t[us] x y z", 1e6, "%.0f", "us"}}) {
    std::string text = LogText(log, c.header, c.scale, c.format, 6);
    const std::string columns =
        std::string(c.name) == "ros" ? " --columns %time,field.x,field.y,field.z" : "";
    const std::string json_path = Path(std::string(c.name) + ".json");
    const CliRun r = Exec("calibrate " + Write(std::string(c.name) + ".csv", text) + columns +
                          " -o " + json_path);
    ASSERT_EQ(r.status, 0) << c.name << ": " << r.err;
    const json doc = Json(json_path);
    EXPECT_EQ(doc.at("verdict"), "ok") << c.name << ": " << r.err;
    EXPECT_EQ(doc.at("positions").size(), reference.at("positions").size()) << c.name;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        EXPECT_NEAR(doc.at("K")[i][j].get<double>(), reference.at("K")[i][j].get<double>(), 1e-9)
            << c.name;
      }
    }
    bool unit_said = false;
    for (const json& f : doc.at("diagnostics")) {
      if (f.at("code") == "time_unit") {
        unit_said =
            f.at("message").get<std::string>().rfind(std::string("time in ") + c.unit, 0) == 0;
      }
    }
    EXPECT_TRUE(unit_said) << c.name;
  }
  // µs read as seconds: 1e-4 Hz, refused (before: 15087 samples at 0.0001 Hz, a fit): a given
  // unit is held to the rates of any log.
  const std::string us = Path("px4.csv");
  CliRun r = Exec("calibrate " + us + " --time-unit s -o " + Path("bad.json"));
  EXPECT_EQ(r.status, 3);
  EXPECT_EQ(r.err, "accelcal: " + us +
                       ": time column 'timestamp' in seconds, as given, has a median step of "
                       "10000: 0.0001 Hz, outside the 0.001 Hz-1 MHz of any log (another unit?)\n");
  EXPECT_FALSE(fs::exists(Path("bad.json")));
  // A rate that contradicts the time column; a window the rate cannot hold.
  r = Exec("calibrate " + us + " --rate 200");
  EXPECT_EQ(r.status, 3);
  EXPECT_EQ(r.err, "accelcal: " + us +
                       ": the given rate 200 Hz contradicts the time column, whose timestamps (us) "
                       "come at 100 Hz\n");
  r = Exec("calibrate " + us + " --rate 100");
  EXPECT_EQ(r.status, 0) << r.err;
  r = Exec("calibrate " + us + " --window 1e-9");
  EXPECT_EQ(r.status, 3);
  EXPECT_EQ(r.err, "accelcal: " + us +
                       ": a detection window of 1e-09 s holds 1e-07 samples at 100 Hz; it needs at "
                       "least 3\n");
  r = Exec("calibrate " + us + " --min-static 0.001");
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find("a minimum static duration of 0.001 s is 0.1 samples at 100 Hz"),
            std::string::npos)
      << r.err;
  // Durations beyond the log (1e308 s overflowed a cast to a sample count).
  r = Exec("calibrate " + us + " --min-static 1e308");
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find("a minimum static duration of 1e+308 s is longer than the log"),
            std::string::npos)
      << r.err;
  r = Exec("calibrate " + us + " --init-rest 1e308");
  EXPECT_EQ(r.status, 3);
  EXPECT_EQ(r.err, "accelcal: " + us + ": the initial rest period is longer than the log\n");
  // A name that contradicts the step, and a step that leaves the unit open.
  const std::string named = Write("named.csv", LogText(log, "time_ms,x,y,z", 1, "%.2f", 6));
  r = Exec("calibrate " + named);
  EXPECT_EQ(r.status, 3);
  EXPECT_EQ(r.err,
            "accelcal: " + named +
                ": time column 'time_ms' is in milliseconds by its name, but its median "
                "step 0.01 would then be 100 kHz, outside the 2 Hz-20 kHz of an IMU log: the "
                "column is not what its name says (give the time unit)\n");
  // Time stretched 20 times: a step of 0.2 is 5 Hz in seconds or 5 kHz in ms.
  const std::string slow = Write("slow.csv", LogText(log, "# a b c d", 20, "%.1f", 6));
  r = Exec("calibrate " + slow);
  EXPECT_EQ(r.status, 3);
  EXPECT_EQ(r.err, "accelcal: " + slow +
                       ": cannot tell the unit of time column 'a': its median step 0.2 is 5 Hz in "
                       "seconds, 5 kHz in milliseconds, 5000 kHz in microseconds, 5e+06 kHz in "
                       "nanoseconds; more than one is an IMU rate (2 Hz-20 kHz) (give the time "
                       "unit: s, ms, us or ns)\n");
  EXPECT_EQ(Exec("calibrate " + slow + " --time-unit s").status, 3);  // 5 Hz: window of 2.5
}

// 2. A gap in the time column (two sessions joined): the rate comes from the steps, windows and
// intervals stop at the gap, and the gap is reported.
TEST_F(Trust, AGapSplitsTheLogInsteadOfSlowingItsRate) {
  const std::string xsens = kData + "/imutk-xsens-mti/xsens_acc.mat";
  std::string text = Slurp(xsens), joined;
  std::size_t line = 0, start = 0;
  while (start < text.size()) {
    const std::size_t end = text.find('\n', start);
    std::string row = text.substr(start, end - start);
    if (++line > 20000) {
      double t;
      int used;
      std::sscanf(row.c_str(), "%lf%n", &t, &used);
      char buf[64];
      std::snprintf(buf, sizeof buf, "%.6f", t + 1000);
      row = buf + row.substr(std::size_t(used));
    }
    joined += row + "\n";
    start = end + 1;
  }
  const CliRun clean = Exec("calibrate " + xsens + " --gravity 9.81744 -o " + Path("clean.json"));
  ASSERT_EQ(clean.status, 0) << clean.err;
  const CliRun r = Exec("calibrate " + Write("gap.txt", joined) + " --gravity 9.81744 -o " +
                        Path("gap.json") + " --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const json doc = Json(Path("gap.json")), ref = Json(Path("clean.json"));
  EXPECT_TRUE(Has(doc, "time_gaps"));
  EXPECT_GE(doc.at("positions").size(), ref.at("positions").size());
  EXPECT_LE(doc.at("positions").size(), ref.at("positions").size() + 1);
  // The same calibration within its uncertainty (an interval cut at the gap is one more position).
  ModelParameters truth;
  for (int i = 0; i < 3; ++i) {
    truth.bias(i) = ref.at("bias")[i];
    for (int j = 0; j < 3; ++j) truth.K(i, j) = ref.at("K")[i][j];
  }
  ExpectWithinSigma(doc, truth, 1.0);
  for (const json& f : doc.at("diagnostics")) {
    if (f.at("code") == "time_gaps") {
      EXPECT_NE(f.at("message").get<std::string>().find("1 gap"), std::string::npos);
    }
    if (f.at("code") == "time_unit") {
      EXPECT_NEAR(f.at("numbers").at("rate_hz").get<double>(), 100.01, 0.01);  // not 33.9 Hz
    }
  }
}

// 3. No static poses: an 18-s rest, then a hand-like tumble (the speed swinging between 1 and
// 8 deg/s, the axis wandering), whose slow stretches look still window by window. Refused, never
// fitted; and a steady slow rotation, every window of which looks still.
TEST_F(Trust, ALogInContinuousMotionIsRefused) {
  std::uint64_t state = 7;
  const auto noise = [&] {  // deterministic, uniform with σ 0.02 m/s²
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return 0.02 * std::sqrt(12.0) * (double(state >> 11) / 9007199254740992.0 - 0.5);
  };
  const auto write = [&](const std::string& name, bool tumble) {
    std::string text = "t,x,y,z\n";
    Vec3 up = Vec3::UnitZ();
    char line[160];
    for (int i = 0; i < 13800; ++i) {
      const double t = i / 100.0;
      if (t >= 18) {
        const double deg_s = tumble ? 4.5 + 3.5 * std::sin(2 * M_PI * (t - 18) / 10) : 2.0;
        const Vec3 axis = tumble
                              ? Vec3(std::cos(0.05 * t), std::sin(0.05 * t) * std::cos(0.031 * t),
                                     std::sin(0.031 * t) + 0.3)
                                    .normalized()
                              : Vec3(0.3, 0.5, 0.81).normalized();
        up = Eigen::AngleAxisd(deg_s * M_PI / 180 / 100, axis) * up;
      }
      const Vec3 f = kG * up;
      std::snprintf(line, sizeof line, "%.2f,%.6f,%.6f,%.6f\n", t, f(0) + noise(), f(1) + noise(),
                    f(2) + noise());
      text += line;
    }
    return Write(name, text);
  };
  const std::string tumble = write("tumble.csv", true);
  CliRun r = Exec("calibrate " + tumble + " -o " + Path("out.json"));
  EXPECT_EQ(r.status, 3) << r.err;
  EXPECT_EQ(r.err,
            "accelcal: " + tumble + ": the linear model needs at least 9 positions, got 1\n");
  EXPECT_FALSE(fs::exists(Path("out.json")));
  r = Exec("detect " + tumble + " --verbose");
  EXPECT_EQ(r.status, 0);
  const std::string steady = write("steady.csv", false);
  r = Exec("calibrate " + steady + " -o " + Path("out.json"));
  EXPECT_EQ(r.status, 3) << r.err;
  EXPECT_EQ(r.err,
            "accelcal: " + steady + ": the linear model needs at least 9 positions, got 1\n");
  EXPECT_FALSE(fs::exists(Path("out.json")));
}

// 4. A quantised sensor (noise 0.1 of its step: a log written with 2 decimals): no still period in
// fragments, no false "saturated" warning, the calibration right within its reported σ.
TEST_F(Trust, AQuantisedLogCalibratesRight) {
  const SimulatedLog log = MemsLog(0.001);
  const CliRun r = Exec("calibrate " + Write("q.csv", LogText(log, "t,x,y,z", 1, "%.2f", 2)) +
                        " -o " + Path("q.json"));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.err.find("saturated"), std::string::npos) << r.err;
  const json doc = Json(Path("q.json"));
  EXPECT_EQ(doc.at("positions").size(), 24u);
  ExpectWithinSigma(doc, MemsDevice(), 3.0);
  EXPECT_FALSE(Has(doc, "exact_fit"));
}

// 4a. Only an estimated noise level can say the positions were fitted to round-off. The
// baselines (modulus, ellipsoid) estimate none; their σ̂ of 0 had said every real recording was
// fitted to round-off, and the file claimed a noise-free sensor.
TEST_F(Trust, OnlyAnEstimatedNoiseLevelCanSayRoundOff) {
  CliRun r;
  const std::string ctu =
      std::string(ACCELCAL_DATA_DIR) + "/ctu-innalabs-ahrs-m3/measured_accelerations_24pos.csv";
  for (const char* method : {"modulus", "modulus-norm", "ellipsoid"}) {
    r = Exec("calibrate " + ctu + " --units g --method " + method + " -o " + Path("b.json"));
    ASSERT_EQ(r.status, 0) << method << r.err;
    const json doc = Json(Path("b.json"));
    EXPECT_FALSE(Has(doc, "exact_fit")) << method;
    EXPECT_TRUE(doc.at("noise").at("sigma_raw").is_null()) << method;
  }
}

// 4b. As many positions as parameters: the fit passes through all of them, so nothing checks it
// (no residual, no covariance, no held-out position). It had said "ok".
TEST_F(Trust, AnExactlyDeterminedFitIsNotOk) {
  const SimulatedLog log = MemsLog(0.001, 9, 9);
  const CliRun r = Exec("calibrate " + Write("nine.csv", LogText(log, "t,x,y,z", 1, "%.4f", 6)) +
                        " -o " + Path("nine.json"));
  ASSERT_EQ(r.status, 0) << r.err;
  const json doc = Json(Path("nine.json"));
  EXPECT_EQ(doc.at("positions").size(), 9u);
  EXPECT_TRUE(Has(doc, "exactly_determined")) << r.err;
  EXPECT_NE(r.err.find("9 positions fitted for 9 parameters"), std::string::npos) << r.err;
  EXPECT_EQ(doc.at("verdict"), "warnings");
}

// 5. Duplicated rows (a positions file concatenated with itself): refused, not an exact fit with
// uncertainties of 1e-12.
TEST_F(Trust, RepeatedPositionsAreRefused) {
  const std::string positions =
      Slurp(kData + "/ctu-innalabs-ahrs-m3/measured_accelerations_24pos.csv");
  const std::string body = positions.substr(positions.find('\n') + 1);
  const std::string path = Write("twice.csv", positions + body);
  const CliRun r = Exec("calibrate " + path + " --units g -o " + Path("out.json"));
  EXPECT_EQ(r.status, 3);
  EXPECT_EQ(r.err,
            "accelcal: " + path +
                ": position 25 repeats position 1 exactly: repeated rows are not "
                "independent positions (they would shrink every uncertainty); remove them\n");
  EXPECT_FALSE(fs::exists(Path("out.json")));
}

// 6. Two IMU instances interleaved in one file (ArduPilot's I column): refused with the instances
// listed, or one of them read; without the column, the alternation fails the result's checks.
TEST_F(Trust, InterleavedInstancesAreRefusedOrChosen) {
  const SimulatedLog a = MemsLog(0.02);
  ModelParameters other = MemsDevice();
  other.K *= 1.03;
  other.bias += Vec3(0.2, -0.1, 0.3);
  RawLogSimulation o;
  o.rate_hz = 100, o.static_s = 5, o.transition_s = 2, o.seed = 3;
  o.sigma_raw_per_sample = Vec3::Constant(0.02);
  const SimulatedLog b = SimulateRawLog(other, kG, RandomDirections(24, 3), o);
  std::string with_i = "TimeUS,I,AccX,AccY,AccZ\n", without_i = "TimeUS,AccX,AccY,AccZ\n";
  std::string only_b = "TimeUS,AccX,AccY,AccZ\n";
  char line[200];
  for (std::size_t k = 0; k < a.samples.size(); ++k) {
    for (int inst = 0; inst < 2; ++inst) {
      const Vec3& p = inst == 0 ? a.samples[k] : b.samples[k];
      const long t = std::lround(a.time_s[k] * 1e6) + 2500 * inst;
      std::snprintf(line, sizeof line, "%ld,%d,%.6f,%.6f,%.6f\n", t, inst, p(0), p(1), p(2));
      with_i += line;
      std::snprintf(line, sizeof line, "%ld,%.6f,%.6f,%.6f\n", t, p(0), p(1), p(2));
      without_i += line;
      if (inst == 1) only_b += line;
    }
  }
  const std::string path = Write("imu.csv", with_i);
  CliRun r = Exec("calibrate " + path + " -o " + Path("out.json"));
  EXPECT_EQ(r.status, 3);
  const std::string rows = std::to_string(a.samples.size()) + " rows";
  EXPECT_EQ(r.err, "accelcal: " + path +
                       ": the rows belong to 2 sensors (instance column 'i': 0 (" + rows +
                       "), 1 (" + rows + ")): choose one instance\n");
  EXPECT_FALSE(fs::exists(Path("out.json")));
  r = Exec("calibrate " + path + " --instance 1 -o " + Path("one.json"));
  ASSERT_EQ(r.status, 0) << r.err;
  r = Exec("calibrate " + Write("b.csv", only_b) + " -o " + Path("b.json"));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(Json(Path("one.json")).at("K"), Json(Path("b.json")).at("K"));
  r = Exec("calibrate " + path + " --instance 7");
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find("no rows of instance 7 (column 'i' has 0 (" + rows + "), 1 (" + rows + "))"),
            std::string::npos)
      << r.err;
  // Without the instance column: written, marked failed, exit 6.
  r = Exec("calibrate " + Write("mixed.csv", without_i) + " -o " + Path("mixed.json"));
  EXPECT_EQ(r.status, 6) << r.err;
  EXPECT_NE(r.err.find("failed check (interleaved): successive samples alternate"),
            std::string::npos)
      << r.err;
  const json doc = Json(Path("mixed.json"));
  EXPECT_EQ(doc.at("verdict"), "failed");
  EXPECT_TRUE(Has(doc, "interleaved"));
}

// 7. An orientation file off by one line: a failure with that advice, not a calibration with
// K_xx = -101 +- 101 printed as a result.
TEST_F(Trust, AMisorderedOrientationFileFailsTheChecks) {
  const std::string dir = kData + "/imucal-ferraris/";
  const std::string right = Slurp(dir + "ferraris_orientations.csv");
  std::vector<std::string> lines;
  for (std::size_t s = 0, e; s < right.size(); s = e + 1) {
    e = right.find('\n', s);
    lines.push_back(right.substr(s, e - s));
  }
  // Comment, comment, header, then six directions: the first moved to the end.
  std::string shifted = lines[0] + "\n" + lines[1] + "\n" + lines[2] + "\n";
  for (std::size_t k = 4; k < 9; ++k) shifted += lines[k] + "\n";
  shifted += lines[3] + "\n";
  const std::string base = dir + "ferraris_raw_means.csv --gravity 9.81 --orientations ";
  CliRun r = Exec("calibrate " + base + Write("shifted.csv", shifted) + " -o " + Path("bad.json"));
  EXPECT_EQ(r.status, 6) << r.err;
  EXPECT_NE(r.err.find("failed check (misfit): the residuals of the known orientations are "),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("the orientation file does not describe these positions (lines out of "
                       "order or missing, or another frame or sign convention)"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(Json(Path("bad.json")).at("verdict"), "failed");
  // Written so that the reasons can be read, never applied or exported.
  for (const std::string& use : {"apply " + Path("bad.json") + " " + dir + "ferraris_raw_means.csv",
                                 "export " + Path("bad.json") + " --to yaml"}) {
    r = Exec(use + " -o " + Path("used.txt"));
    EXPECT_EQ(r.status, 3) << use;
    EXPECT_EQ(r.err, "accelcal: " + Path("bad.json") +
                         ": this calibration failed its checks (\"verdict\": \"failed\"; its "
                         "\"diagnostics\" say why): it is not applied or exported\n");
    EXPECT_FALSE(fs::exists(Path("used.txt")));
  }
  r = Exec("calibrate " + base + dir + "ferraris_orientations.csv -o " + Path("good.json"));
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(Json(Path("good.json")).at("verdict"), "warnings");  // its holds scatter 62x
}

// 8. Readings in g without --units g, and a gravity no place on Earth has: said, with the option.
TEST_F(Trust, UnitsAndGravityThatDoNotFitTheDataAreSaid) {
  const std::string ctu = kData + "/ctu-innalabs-ahrs-m3/measured_accelerations_24pos.csv";
  CliRun r = Exec("calibrate " + ctu);
  EXPECT_EQ(r.status, 0);
  EXPECT_NE(r.err.find("warning: " + ctu +
                       ": the readings' median magnitude is 0.9953, about 1 g, while gravity is "
                       "9.80665 m/s2: if they are in g, calibrate in g (the result then maps g to "
                       "g) (--units g)"),
            std::string::npos)
      << r.err;
  r = Exec("calibrate " + ctu + " --units g");
  EXPECT_EQ(r.status, 0);
  EXPECT_EQ(r.err, "");
  const std::string t265 = kData + "/imutk-t265/t265_acc.mat";
  r = Exec("calibrate " + t265 + " --gravity 1 --json");
  EXPECT_EQ(r.status, 0);
  EXPECT_TRUE(Has(test::AccelerometerKeys(r.out), "gravity_value"));
  r = Exec("calibrate " + t265 + " --units g --json");
  EXPECT_EQ(r.status, 0);
  EXPECT_NE(r.err.find("about 9.8 m/s2, while the result is in g: if they are in m/s2, calibrate "
                       "in m/s2 (--units m/s2)"),
            std::string::npos)
      << r.err;
}

// 9. A quadratic fit the data do not support says so, and the file's model is what it holds.
TEST_F(Trust, TheModelChoiceIsConsistent) {
  const std::string ctu =
      kData + "/ctu-innalabs-ahrs-m3/measured_accelerations_49pos.csv --units g";
  CliRun r = Exec("calibrate " + ctu + " --model quadratic --json");
  EXPECT_EQ(r.status, 0);
  json doc = test::AccelerometerKeys(r.out);
  EXPECT_EQ(doc.at("model"), "quadratic");
  EXPECT_EQ(doc.at("model_selection").at("chosen"), "linear");
  EXPECT_TRUE(Has(doc, "model_choice"));
  EXPECT_NE(r.err.find("the quadratic model was asked for, but the data do not support it"),
            std::string::npos);
  r = Exec("calibrate " + ctu + " --model auto --json");
  EXPECT_EQ(r.status, 0);
  doc = test::AccelerometerKeys(r.out);
  EXPECT_EQ(doc.at("model"), "linear");
  EXPECT_EQ(doc.at("model_selection").at("chosen"), "linear");
  EXPECT_FALSE(Has(doc, "model_choice"));
}

// 10. Warnings reach the terminal and the JSON; the screening's limit is an option, and reaching
// it is a warning.
TEST_F(Trust, ScreeningLimitIsAnOptionAndReachingItIsSaid) {
  std::vector<Vec3> readings = SimulatePositions(Yang2012Truth(), kYang2012Gravity_ms2,
                                                 RandomDirections(30, 4), Vec3::Constant(0.4), 5);
  readings[3] *= 1.002;  // one position off by 0.2 %: about 50 times the noise
  std::string text = "x,y,z\n";
  char line[128];
  for (const Vec3& p : readings) {
    std::snprintf(line, sizeof line, "%.17g,%.17g,%.17g\n", p(0), p(1), p(2));
    text += line;
  }
  const std::string path = Write("moved.csv", text) + " --gravity 9.7803267714";
  CliRun r = Exec("calibrate " + path + " --json");
  ASSERT_EQ(r.status, 0) << r.err;
  json doc = test::AccelerometerKeys(r.out);
  EXPECT_EQ(doc.at("outliers").size(), 1u);
  EXPECT_FALSE(Has(doc, "outlier_limit"));
  r = Exec("calibrate " + path + " --max-outliers 1 --json");  // the limit reached
  ASSERT_EQ(r.status, 0) << r.err;
  doc = test::AccelerometerKeys(r.out);
  EXPECT_TRUE(Has(doc, "outlier_limit"));
  EXPECT_NE(r.err.find("1 positions were left out, the most allowed: more may disagree (raise the "
                       "limit to test further) (--max-outliers)"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(doc.at("verdict"), "warnings");
}

// Several files of one device (sessions): positions pooled, time never joined across files; the
// split Xsens recording gives the whole one's calibration, and a bad file is named.
TEST_F(Trust, SeveralFilesArePooled) {
  const std::string xsens = kData + "/imutk-xsens-mti/xsens_acc.mat";
  const std::string text = Slurp(xsens);
  std::size_t cut = 0;
  for (int line = 0; line < 25000; ++line) cut = text.find('\n', cut) + 1;
  const std::string a = Write("a.txt", text.substr(0, cut));
  const std::string b = Write("b.txt", text.substr(cut));
  CliRun r = Exec("calibrate " + xsens + " --gravity 9.81744 -o " + Path("whole.json"));
  ASSERT_EQ(r.status, 0) << r.err;
  r = Exec("calibrate " + a + " " + b + " --gravity 9.81744 -o " + Path("two.json"));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("pooled    39 positions from 2 files"), std::string::npos) << r.out;
  const json whole = Json(Path("whole.json")), two = Json(Path("two.json"));
  EXPECT_EQ(two.at("sources"), json::array({a, b}));
  EXPECT_EQ(two.at("positions").front().at("file"), 0);
  EXPECT_EQ(two.at("positions").back().at("file"), 1);
  // The interval cut in two becomes two positions: the same device within its uncertainty.
  ModelParameters reference;
  for (int i = 0; i < 3; ++i) {
    reference.bias(i) = whole.at("bias")[i];
    for (int j = 0; j < 3; ++j) reference.K(i, j) = whole.at("K")[i][j];
  }
  ExpectWithinSigma(two, reference, 1.0);
  const std::string empty = Write("empty.csv", "");
  r = Exec("calibrate " + a + " " + empty);
  EXPECT_EQ(r.status, 3);
  EXPECT_EQ(r.err, "accelcal: " + empty + ": no data (the file is empty or all comments)\n");
}

// The bundled recordings keep their numbers and raise no warning that is not true.
TEST_F(Trust, BundledRecordingsPassTheirChecks) {
  struct Case {
    std::string args;
    std::string verdict;
    std::vector<std::string> warnings;  // codes of warnings and failures, in order
  };
  const std::vector<Case> cases = {
      {kData + "/imutk-xsens-mti/xsens_acc.mat --gravity 9.81744", "ok", {}},
      // Six orientations repeated: misalignment poorly determined, as the gyro issue measured;
      // its rest drifts (x by -1.3 mg a minute, t = -18.5), as issue 21 measured over the session.
      {kData + "/imutk-t265/t265_acc.mat --gravity 9.8016",
       "warnings",
       {"poorly_determined", "drifting_rest"}},
      {kData + "/ctu-innalabs-ahrs-m3/measured_accelerations_24pos.csv --units g", "ok", {}},
      {kData + "/ctu-innalabs-ahrs-m3/measured_accelerations_49pos.csv --units g", "ok", {}},
      // Its position 1 has a held-out error 7.2 times the typical, but the screening's test
      // (t, Bonferroni) does not find it discordant: no warning.
      {kData + "/ctu-innalabs-ahrs-m3/hassan_subset_31pos.csv --units g", "ok", {}},
      // Six hand-placed holds: they scatter 62 times their noise.
      {kData + "/imucal-ferraris/ferraris_raw_means.csv --gravity 9.81 --orientations " + kData +
           "/imucal-ferraris/ferraris_orientations.csv",
       "warnings",
       {"scatter_ratio"}},
  };
  for (const Case& c : cases) {
    const CliRun r = Exec("calibrate " + c.args + " --json");
    ASSERT_EQ(r.status, 0) << c.args << ": " << r.err;
    const json doc = test::AccelerometerKeys(r.out);
    EXPECT_EQ(doc.at("verdict"), c.verdict) << c.args;
    std::vector<std::string> warnings;
    for (const json& f : doc.at("diagnostics")) {
      if (f.at("severity") != "note") warnings.push_back(f.at("code"));
    }
    EXPECT_EQ(warnings, c.warnings) << c.args << ": " << r.err;
  }
}

// Issue 19: a rest whose bias drifts is said. The Xsens rest (52 s, 3.4 counts of noise a
// sample) with x rising by 3 counts over it (t = 14 on the slope of 16 batch means, against a
// limit of 5.0): a warning naming the axis and the rate; the recording as it is: none (the
// bundled test above), nor on 40 simulated white-noise logs (measured).
TEST_F(Trust, ADriftingRestIsSaid) {
  std::ifstream in(kData + "/imutk-xsens-mti/xsens_acc.mat");
  std::string line, text;
  for (int row = 0; std::getline(in, line); ++row) {
    if (row < 5224) {
      std::istringstream fields(line);
      double t, x, y, z;
      fields >> t >> x >> y >> z;
      char buf[160];
      std::snprintf(buf, sizeof buf, "%.9g %.17g %.17g %.17g", t, x + 3.0 * row / 5224, y, z);
      line = buf;
    }
    text += line + "\n";
  }
  const CliRun r = Exec("calibrate " + Write("ramp.mat", text) + " --gravity 9.81744 --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const json doc = test::AccelerometerKeys(r.out);
  EXPECT_TRUE(Has(doc, "drifting_rest"));
  EXPECT_NE(r.err.find("has an Allan deviation that rises with averaging time: x drifts +3."),
            std::string::npos)
      << r.err;
}

// Issue 16: a short raw log without a header (150 rows of x,y,z) is read as positions by its
// row count; the tool says it looks like one (each sample taken for a position), and a rate
// given with it makes it a raw log.
TEST_F(Trust, AShortHeaderlessRawLogIsNotSilentlyTakenForPositions) {
  RawLogSimulation o;
  o.rate_hz = 10;
  o.static_s = 1;
  o.transition_s = 0;
  o.sigma_raw_per_sample = Vec3::Constant(0.002);
  const SimulatedLog log = SimulateRawLog(MemsDevice(), kG, RandomDirections(15, 4), o);
  ASSERT_EQ(log.samples.size(), 150u);
  std::string text;
  char row[96];
  for (const Vec3& p : log.samples) {
    std::snprintf(row, sizeof row, "%.6f,%.6f,%.6f\n", p(0), p(1), p(2));
    text += row;
  }
  const std::string path = Write("short.csv", text);
  CliRun r = Exec("calibrate " + path + " -o " + Path("short.json"));
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("it looks like a raw log, each sample taken for a position"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("(--input-kind raw)"), std::string::npos) << r.err;
  EXPECT_TRUE(Has(Json(Path("short.json")), "positions_like_samples"));
  // The same rows as the positions file they are (repeated averages are distinct positions).
  const std::string positions = Write(
      "positions.csv", Slurp(std::string(ACCELCAL_DATA_DIR) + "/ctu-innalabs-ahrs-m3/"
                                                              "measured_accelerations_24pos.csv"));
  r = Exec("calibrate " + positions + " --units g -o " + Path("p.json"));
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_FALSE(Has(Json(Path("p.json")), "positions_like_samples"));
  // A rate belongs to a raw log: read as one, whatever its row count (1 s still periods at
  // 10 Hz are too short for the detection: its error shows the file was read as a raw log).
  r = Exec("calibrate " + path + " --rate 10 -o " + Path("raw.json"));
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find("no static interval found"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace accelcal
