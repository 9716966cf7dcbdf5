// The accelcal command as a user runs it (continued from test_cli.cpp): paper 003's commands,
// compare, detect, and what bad input, hostile files and options give: one clear message, the
// right exit status, no partial output, the same bytes on every run.
#include <sys/wait.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "accelcal/gimbal_platform.hpp"
#include "accelcal/sha256.hpp"
#include "accelcal/simulate.hpp"
#include "support/calibration_keys.hpp"
#include "support/cli_test.hpp"
#include "support/paths.hpp"

namespace accelcal {
namespace {

namespace fs = std::filesystem;
using test::AccelerometerKeys;
const std::string kData = ACCELCAL_DATA_DIR;

using Cli = test::CliTest;
using test::CliRun;
using test::PositionsCsv;
using test::Slurp;

TEST_F(Cli, SystemLevelFromASimulatedSeries) {
  // Paper 003 stage 3 end to end on 6 h at 10 Hz (the day at 100 Hz is in test_system_level):
  // the JSON the issue names, the rank and which parameters get no number.
  const CliRun s =
      Exec("simulate --scenario wu2018-system --rate 10 --duration 21600 --seed 3 -o " +
           Path("series.bin"));
  ASSERT_EQ(s.status, 0) << s.err;
  const CliRun r = Exec("system-level " + Path("series.bin") + " --latitude 40 --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json doc = nlohmann::json::parse(r.out);
  EXPECT_EQ(doc["samples"], 216000);
  for (const char* x : {"x1", "x2", "x3", "x4", "x5"}) {
    EXPECT_TRUE(doc["combined"][x].contains("value")) << x;
    EXPECT_GT(doc["combined"][x]["std"].get<double>(), 0.0) << x;
  }
  for (const char* key : {"mean", "c1", "s1", "c2", "s2"}) {
    EXPECT_TRUE(doc["fourier"]["pitch"].contains(key)) << key;
    EXPECT_TRUE(doc["fourier"]["roll"].contains(key)) << key;
  }
  EXPECT_EQ(doc["separated"]["rank"], 4);
  EXPECT_EQ(doc["separated"]["determined"].size(), 6u);
  EXPECT_TRUE(doc["separated"]["determined"].contains("dbeta_zy"));
  EXPECT_FALSE(doc["separated"]["determined"].contains("nabla_x/g"));  // never a number
  EXPECT_EQ(doc["separated"]["undetermined"].size(), 4u);
  // Same seed, same bytes; text output names what is not determined.
  EXPECT_EQ(Exec("system-level " + Path("series.bin") + " --latitude 40 --json").out, r.out);
  const CliRun text = Exec("system-level " + Path("series.bin") + " --latitude 40");
  EXPECT_NE(text.out.find("rank 4 of 6"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("not determined on their own"), std::string::npos) << text.out;
  // Bad input: a short series, a truncated file, no latitude.
  ASSERT_EQ(
      Exec("simulate --scenario wu2018-system --rate 1 --duration 3600 -o " + Path("short.bin"))
          .status,
      0);
  const CliRun short_series = Exec("system-level " + Path("short.bin") + " --latitude 40");
  EXPECT_EQ(short_series.status, 3);
  EXPECT_NE(short_series.err.find("short.bin: the series covers 0.999722 h"), std::string::npos)
      << short_series.err;
  const std::string bin = Slurp(Path("short.bin"));
  const CliRun truncated =
      Exec("system-level " + Write("cut.bin", bin.substr(0, bin.size() - 7)) + " --latitude 40");
  EXPECT_EQ(truncated.status, 3);
  EXPECT_NE(truncated.err.find("truncated binary series"), std::string::npos) << truncated.err;
  EXPECT_EQ(Exec("system-level " + Path("series.bin")).status, 2);
  EXPECT_EQ(Exec("simulate --scenario wu2018-system").status, 2);  // binary needs -o
}

TEST_F(Cli, GimbalCoarseAndFineStages) {
  // Paper 003 stages 1-2 from files: Table 1's commanded angles with a device's mean outputs (the
  // library's model, gimbal offsets of 3' and -2'), then the fine stage's outputs after
  // re-zeroing. Noise-free, but with squared terms the coarse stage ignores: they pull its offsets
  // by 1-2 arc-seconds (measured 4.7e-6 and 7.9e-6 rad), which the fine stage does not need.
  PlatformAccelerometer truth;
  truth.s = Vec3(1.0004, 0.9993, 1.0011);
  truth.bias = Vec3(2e-3, -1.5e-3, 3e-3);
  truth.beta << 1.2e-4, -0.8e-4, 0.5e-4, 2.0e-4, -1.1e-4, 0.7e-4;
  truth.k_nl = Vec3(5e-6, -3e-6, 4e-6);
  const double arcmin = 3.14159265358979323846 / 180 / 60;
  const Vec3 offsets(0.0, 3 * arcmin, -2 * arcmin);
  const double g = 9.80665;
  std::string coarse = "theta1_deg,theta2_deg,theta3_deg,ax,ay,az\n", fine = "ax,ay,az\n";
  for (const Vec3& a : Wu2018Table1Angles()) {
    const Vec3 out = PlatformOutput(truth, g * PlatformUp(a + offsets));
    const Vec3 deg = a * 180 / 3.14159265358979323846;
    char row[256];
    std::snprintf(row, sizeof row, "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", deg(0), deg(1), deg(2),
                  out(0), out(1), out(2));
    coarse += row;
    const Vec3 fine_out = PlatformOutput(truth, g * PlatformUp(a));  // re-zeroed platform
    std::snprintf(row, sizeof row, "%.17g,%.17g,%.17g\n", fine_out(0), fine_out(1), fine_out(2));
    fine += row;
  }
  const CliRun r = Exec("gimbal " + Write("coarse.csv", coarse) + " --fine " +
                        Write("fine.csv", fine) + " --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json doc = nlohmann::json::parse(r.out);
  EXPECT_NEAR(doc["coarse"]["offsets_rad"]["theta20"].get<double>(), offsets(1), 1.5e-5);
  EXPECT_NEAR(doc["coarse"]["offsets_rad"]["theta30"].get<double>(), offsets(2), 1.5e-5);
  EXPECT_NE(doc["coarse"]["note"].get<std::string>().find("theta10"), std::string::npos);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(doc["fine"]["device"]["sf_inverse"][i].get<double>(), truth.s(i), 1e-9);
    EXPECT_NEAR(doc["fine"]["device"]["k_nl"][i].get<double>(), truth.k_nl(i), 1e-11);
  }
  EXPECT_NE(doc["fine"]["note"].get<std::string>().find("not separable"), std::string::npos);
  const CliRun text = Exec("gimbal " + Path("coarse.csv"));
  EXPECT_EQ(text.status, 0) << text.err;
  EXPECT_NE(text.out.find("offsets theta20 180.97 +- "), std::string::npos) << text.out;
  const CliRun bad = Exec("gimbal " + Write("bad.csv", "1,2,3,4,5\n"));
  EXPECT_EQ(bad.status, 3);
  EXPECT_NE(bad.err.find("bad.csv:1: expected 6 numbers"), std::string::npos) << bad.err;
  // Only the first line may be a header: a second line of words is an error, not another header.
  const CliRun words = Exec("gimbal " + Write("words.csv", "a,b,c,d,e,f\ng,h,i,j,k,l\n"));
  EXPECT_EQ(words.status, 3);
  EXPECT_NE(words.err.find("words.csv:2: expected 6 numbers"), std::string::npos) << words.err;
  const CliRun directory = Exec("gimbal " + Path(""));
  EXPECT_EQ(directory.status, 3);
  EXPECT_NE(directory.err.find("is a directory, not a file"), std::string::npos) << directory.err;
}

TEST_F(Cli, LatitudeGivesWgs84Gravity) {
  const std::string in = Write("pos.csv", PositionsCsv(20));
  const CliRun r = Exec("calibrate " + in + " --latitude 45 --json");
  ASSERT_EQ(r.status, 0) << r.err;
  // Somigliana's formula in its original form (a γe cos²φ + b γp sin²φ) / √(a² cos²φ + b² sin²φ),
  // independent of the derived constants the library uses.
  const double a = 6378137.0, b = 6356752.3142, ge = 9.7803253359, gp = 9.8321849378;
  const double expected = (a * ge * 0.5 + b * gp * 0.5) / std::sqrt(a * a * 0.5 + b * b * 0.5);
  EXPECT_NEAR(AccelerometerKeys(r.out)["gravity"].get<double>(), expected, 1e-9);
}

TEST_F(Cli, CompareTabulatesEveryMethod) {
  const std::string in = kData + "/ctu-innalabs-ahrs-m3/measured_accelerations_24pos.csv";
  const CliRun j = Exec("compare " + in + " --units g --json");
  ASSERT_EQ(j.status, 0) << j.err;
  const nlohmann::json doc = nlohmann::json::parse(j.out);
  ASSERT_EQ(doc["methods"].size(), 6u);
  EXPECT_EQ(doc["positions"], 24);
  EXPECT_EQ(doc["methods"][1]["method"], "two-step");
  EXPECT_EQ(doc["methods"][1]["leave_one_out_from"], "joint");
  for (const auto& m : doc["methods"]) {
    EXPECT_TRUE(m["leave_one_out_rms"].is_number()) << m;
    EXPECT_EQ(m["parameters"].size(), 9u);
  }
  EXPECT_EQ(Exec("compare " + in + " --units g --json").out, j.out);  // reproducible bytes
  const CliRun t = Exec("compare " + in + " --units g --methods joint,modulus");
  ASSERT_EQ(t.status, 0) << t.err;
  EXPECT_NE(t.out.find("held-out rms"), std::string::npos);
  // Against its own joint calibration, the joint method's errors vanish.
  ASSERT_EQ(Exec("calibrate " + in + " --units g -o " + Path("ref.json")).status, 0);
  const CliRun r =
      Exec("compare " + in + " --units g --no-held-out --json --reference " + Path("ref.json"));
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json ref = nlohmann::json::parse(r.out);
  EXPECT_LT(ref["methods"][0]["e_T_percent"].get<double>(), 1e-12);
  EXPECT_LT(ref["methods"][0]["e_b_percent"].get<double>(), 1e-12);
  EXPECT_TRUE(ref["methods"][0]["leave_one_out_rms"].is_null());
  const CliRun bad = Exec("compare " + in + " --model quadratic --methods newton-lagrange");
  EXPECT_EQ(bad.status, 2);
  EXPECT_EQ(bad.err, "accelcal: usage: the newton-lagrange method fits the linear model only\n");
}

TEST_F(Cli, CompareScreensOnceAndFitsEveryMethodToTheSamePositions) {
  // The hostile corpus' log with position 7 moved during its interval (issue 7).
  const std::string in = std::string(ACCELCAL_SOURCE_DIR) + "/tests/hostile/moved.csv";
  const CliRun t = Exec("compare " + in + " --methods joint,modulus,ellipsoid");
  ASSERT_EQ(t.status, 0) << t.err;
  EXPECT_NE(t.out.find("every method fitted to 29 positions: position 7 left out (screening)"),
            std::string::npos)
      << t.out;
  EXPECT_NE(t.err.find("position 7 disagrees with the others"), std::string::npos) << t.err;
  EXPECT_NE(t.err.find("It was left out of every method's fit."), std::string::npos) << t.err;
  const CliRun j = Exec("compare " + in + " --json");
  ASSERT_EQ(j.status, 0) << j.err;
  const nlohmann::json doc = nlohmann::json::parse(j.out);
  EXPECT_EQ(doc["positions"], 30);
  EXPECT_EQ(doc["positions_used"], 29);
  ASSERT_EQ(doc["outliers"].size(), 1u);
  EXPECT_EQ(doc["outliers"][0]["position"], 7);
  EXPECT_EQ(doc["outliers"][0]["excluded"], true);
  const CliRun off = Exec("compare " + in + " --outliers off --json");
  ASSERT_EQ(off.status, 0) << off.err;
  EXPECT_EQ(off.err, "");
  EXPECT_EQ(nlohmann::json::parse(off.out)["positions_used"], 30);
  const CliRun flag = Exec("compare " + in + " --outliers flag --json");
  ASSERT_EQ(flag.status, 0) << flag.err;
  EXPECT_NE(flag.err.find("It was kept in the fits."), std::string::npos) << flag.err;
  EXPECT_EQ(nlohmann::json::parse(flag.out)["positions_used"], 30);
  EXPECT_EQ(Exec("compare " + in + " --outliers maybe").status, 2);
}

TEST_F(Cli, Detect) {
  const CliRun r = Exec("detect " + kData + "/imutk-xsens-mti/xsens_acc.mat --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json doc = nlohmann::json::parse(r.out);
  EXPECT_EQ(doc["intervals"].size(), 38u);
  EXPECT_EQ(doc["intervals"][0]["mean"].size(), 3u);
  EXPECT_EQ(doc["time"]["unit"], "s");
  EXPECT_EQ(doc["time"]["origin_s"], 0.02984);
  EXPECT_EQ(doc["time"]["gaps"], 0);
  const CliRun t = Exec("detect " + kData + "/imutk-xsens-mti/xsens_acc.mat");
  EXPECT_NE(t.out.find("38 static intervals"), std::string::npos);
  EXPECT_NE(t.out.find("\n# time in s: the time column read as seconds (its median step 0.01: "
                       "100 Hz)"),
            std::string::npos)
      << t.out;
}

struct BadCase {
  const char* name;
  std::string content;  // file content; empty name = nonexistent file
  std::string args;
  int status;
  std::string message;  // expected stderr, with FILE replaced by the input path
};

TEST_F(Cli, BadInputGivesOneClearMessageAndNoOutput) {
  std::string moving = "t,x,y,z\n";
  for (int i = 0; i < 2000; ++i) {
    moving += std::to_string(i * 0.01) + "," + std::to_string(1000 * std::sin(i * 0.05)) + "," +
              std::to_string(1000 * std::cos(i * 0.07)) + ",9.8\n";
  }
  std::string plane = "x,y,z\n";
  for (int k = 0; k < 16; ++k) {
    plane += std::to_string(9.8 * std::cos(0.4 * k)) + ",0.01," +
             std::to_string(9.8 * std::sin(0.4 * k)) + "\n";
  }
  const std::vector<BadCase> cases = {
      {"empty.csv", "", "", 3, "accelcal: FILE: no data (the file is empty or all comments)\n"},
      {"text.csv", "x,y,z\n1,2,3\n1,two,3\n", "", 3,
       "accelcal: FILE:3: column 2: 'two' is not a number\n"},
      {"nan.csv", "1,2,3\n1,NaN,3\n", "", 3,
       "accelcal: FILE:2: column 2: 'NaN' is not a finite number\n"},
      {"inf.csv", "1,2,3\n1,2,-inf\n", "", 3,
       "accelcal: FILE:2: column 3: '-inf' is not a finite number\n"},
      {"cols.csv", "1,2,3\n1,2\n", "", 3, "accelcal: FILE:2: expected 3 columns, found 2\n"},
      {"few.csv", PositionsCsv(6), "", 3,
       "accelcal: FILE: the linear model needs at least 9 positions, got 6\n"},
      {"fewq.csv", PositionsCsv(11), "--model quadratic", 3,
       "accelcal: FILE: the quadratic model needs at least 12 positions, got 11\n"},
      {"moving.csv", moving, "--input-kind raw", 3,
       "PREFIX accelcal: FILE: no static interval found"},
      {"plane.csv", plane, "", 3, "PREFIX accelcal: FILE: all 16 positions lie in one plane"},
      {"norate.csv",
       std::string(300, '\n') +
           [] {
             std::string r;
             for (int i = 0; i < 300; ++i) r += "1,2,3\n";
             return r;
           }(),
       "", 3, "accelcal: FILE: the log has no time column and no sample rate was given\n"},
      {"", "", "", 3, "accelcal: FILE: cannot open: No such file or directory\n"},
  };
  for (const BadCase& c : cases) {
    const std::string input = c.name[0] ? Write(c.name, c.content) : Path("missing.csv");
    const std::string out = Path("out.json");
    const CliRun r = Exec("calibrate " + input + " " + c.args + " -o " + out);
    EXPECT_EQ(r.status, c.status) << input << "\n" << r.err;
    std::string expected = c.message;
    for (std::size_t pos; (pos = expected.find("FILE")) != std::string::npos;)
      expected.replace(pos, 4, input);
    if (expected.rfind("PREFIX ", 0) == 0) {
      EXPECT_EQ(r.err.rfind(expected.substr(7), 0), 0u) << r.err;
    } else {
      EXPECT_EQ(r.err, expected);
    }
    EXPECT_FALSE(fs::exists(out)) << "partial output for " << input;
    EXPECT_TRUE(r.out.empty()) << r.out;
  }
}

// The committed corpus of hostile files (tests/hostile/cases.json): exact message and status,
// and no output file from a failure.
TEST_F(Cli, HostileCorpus) {
  const std::string dir = std::string(ACCELCAL_SOURCE_DIR) + "/tests/hostile/";
  const nlohmann::json manifest = nlohmann::json::parse(Slurp(dir + "cases.json"));
  ASSERT_GE(manifest["cases"].size(), 12u);
  for (const nlohmann::json& c : manifest["cases"]) {
    const std::string input = dir + c["file"].get<std::string>();
    const std::string out = Path("out.json");
    fs::remove(out);
    const CliRun r = Exec("calibrate " + input + " " + c["args"].get<std::string>() + " -o " + out);
    std::string expected = c["stderr"];
    for (std::size_t pos; (pos = expected.find("FILE")) != std::string::npos;)
      expected.replace(pos, 4, input);
    EXPECT_EQ(r.status, c["status"].get<int>()) << input << "\n" << r.err;
    EXPECT_EQ(r.err, expected) << input;
    EXPECT_EQ(fs::exists(out), c["output"].get<bool>()) << input;
  }
  // Made here rather than committed: a file that looks like 10 GB (sparse: it costs nothing) and
  // a line of 1 MB. Both fail on their first line at once, without reading the rest.
  fs::remove(Path("out.json"));
  const std::string sparse = Path("sparse.csv");
  { std::ofstream(sparse) << "time,x,y,z\n"; }
  fs::resize_file(sparse, std::uintmax_t{10} << 30);
  CliRun r = Exec("calibrate " + sparse + " -o " + Path("out.json"));
  EXPECT_EQ(r.status, 3);
  EXPECT_EQ(r.err, "accelcal: " + sparse +
                       ":2: a NUL byte at column 1: binary data, not a delimited text file\n");
  r = Exec("apply " + sparse + " " + dir + "clean.csv");
  EXPECT_EQ(r.err, "accelcal: " + sparse + ": larger than 64 MiB: not a file of this kind\n");
  fs::remove(sparse);
  const std::string long_line =
      Write("long.csv", "x,y,z\n1,2,3\n" + std::string(1 << 20, '7') + "\n");
  r = Exec("calibrate " + long_line + " -o " + Path("out.json"));
  EXPECT_EQ(r.status, 3);
  EXPECT_EQ(r.err,
            "accelcal: " + long_line + ":3: longer than 65536 bytes: not a delimited text file\n");
  EXPECT_FALSE(fs::exists(Path("out.json")));
}

// The same input gives the same bytes: every output file, on every run, and the Monte Carlo (the
// only command with threads) whatever the number of threads sharing its runs.
TEST_F(Cli, OutputsAreByteIdenticalAcrossRunsAndThreadCounts) {
  const std::string log = kData + "/imutk-xsens-mti/xsens_acc.mat";
  const std::vector<std::string> names = {"c.json", "r.html", "a.csv", "e.h", "s.csv"};
  std::vector<std::string> first;
  for (int run = 0; run < 2; ++run) {
    for (const std::string& name : names) fs::remove(Path(name));
    ASSERT_EQ(Exec("calibrate " + log + " -q -o " + Path("c.json") + " --report " + Path("r.html"))
                  .status,
              0);
    ASSERT_EQ(Exec("apply " + Path("c.json") + " " + log + " -o " + Path("a.csv")).status, 0);
    ASSERT_EQ(Exec("export " + Path("c.json") + " --to c-header -o " + Path("e.h")).status, 0);
    ASSERT_EQ(
        Exec("simulate --scenario yang2012 --raw --duration 5 --seed 5 -o " + Path("s.csv")).status,
        0);
    for (std::size_t i = 0; i < names.size(); ++i) {
      const std::string bytes = Slurp(Path(names[i]));
      EXPECT_GT(bytes.size(), 100u) << names[i];
      if (run == 0) {
        first.push_back(bytes);
      } else {
        EXPECT_TRUE(bytes == first[i]) << names[i] << " differs between runs";  // no huge diff
      }
    }
  }
  const CliRun one = Exec("montecarlo --runs 64 --json --threads 1");
  ASSERT_EQ(one.status, 0) << one.err;
  for (int threads : {2, 3, 7}) {
    EXPECT_TRUE(Exec("montecarlo --runs 64 --json --threads " + std::to_string(threads)).out ==
                one.out)
        << threads << " threads";
  }
}

TEST_F(Cli, FailureKeepsAnExistingOutputFileUntouched) {
  const std::string out = Write("cal.json", "previous contents\n");
  const std::string in = Write("bad.csv", "1,2,3\n1,x,3\n");
  EXPECT_EQ(Exec("calibrate " + in + " -o " + out).status, 3);
  EXPECT_EQ(Slurp(out), "previous contents\n");
  // No temporary file is left behind either.
  int files = 0;
  for (const auto& entry : fs::directory_iterator(dir_)) files += entry.is_regular_file();
  EXPECT_EQ(files, 3);  // cal.json, bad.csv, stderr.txt
}

TEST_F(Cli, UsageErrorsExitWithStatus2) {
  const std::string in = Write("pos.csv", PositionsCsv(20));
  EXPECT_EQ(Exec("").status, 2);
  EXPECT_EQ(Exec("calibrate").status, 2);
  EXPECT_EQ(Exec("calibrate " + in + " --no-such-option").status, 2);
  CliRun r = Exec("calibrate " + in + " --model cubic");
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err, "accelcal: usage: --model: 'cubic' is not one of linear, quadratic, auto\n");
  r = Exec("calibrate " + in + " --gravity 9.8 --latitude 45");
  EXPECT_EQ(r.status, 2);
  r = Exec("calibrate " + in + " --units furlongs");
  EXPECT_EQ(r.err, "accelcal: usage: --units: 'furlongs' is not one of m/s2, g\n");
  EXPECT_EQ(Exec("--help").status, 0);
  // Physical quantities outside any sensible range (issue 16), with the range.
  for (const char* g : {"1e-300", "1e300", "0", "-9.8", "nan", "inf"}) {
    r = Exec("calibrate " + in + " --gravity " + g + " -o " + Path("c.json"));
    EXPECT_EQ(r.status, 2) << g;
    EXPECT_EQ(r.err,
              "accelcal: usage: --gravity must be a number of m/s2 in [1, 100] (9.78-9.83 on "
              "Earth's surface)\n")
        << g;
  }
  for (const char* rate : {"0", "nan", "inf", "1e308", "-100", "1e-100", "0.0009"}) {
    r = Exec("calibrate " + in + " --rate " + rate);
    EXPECT_EQ(r.status, 2) << rate;
    EXPECT_EQ(r.err, "accelcal: usage: --rate must be a number of Hz in [0.001, 1e+06]\n") << rate;
  }
  r = Exec("calibrate " + in + " --latitude 45 --height 1e9");
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err,
            "accelcal: usage: --height must lie in [-20000, 20000] m (the WGS-84 formula's "
            "range)\n");
  EXPECT_FALSE(fs::exists(Path("c.json")));
  // An empty output name wrote nothing and said nothing.
  r = Exec("calibrate " + in + " -o \"\"");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--output: an empty file name"), std::string::npos) << r.err;
  // report's errors name its log (they named nothing: an empty file name).
  const std::string cal = Path("cal.json");
  ASSERT_EQ(Exec("calibrate " + in + " -o " + cal).status, 0);
  r = Exec("report " + cal + " " + in);
  EXPECT_EQ(r.status, 3);
  EXPECT_EQ(r.err,
            "accelcal: " + in + ": the log has no time column and no sample rate was given\n");
  // An iteration cap near INT_MAX: 100 times it overflowed, and a fit that converges in a few
  // iterations was reported as not converged.
  r = Exec("calibrate " + in + " --max-iterations 21474837");
  EXPECT_EQ(r.status, 0) << r.err;
}

// A position scheme with a count that is no count was taken for a file name ("cannot open
// random:-5"), and random:1000000000 allocated until the machine ran out (issue 16).
TEST_F(Cli, PositionSchemesAreCheckedBeforeAllocation) {
  for (const char* spec :
       {"random:-5", "random:0", "random:1e9", "random:1000000000", "random:9:x"}) {
    const CliRun r = Exec(std::string("simulate --scenario yang2012 --positions ") + spec + " -o " +
                          Path("s.csv"));
    EXPECT_EQ(r.status, 3) << spec;
    EXPECT_EQ(r.err, std::string("accelcal: ") + spec +
                         ": random:N[:SEED] takes a whole number of positions N from 1 to 100000 "
                         "and a whole-number seed\n");
    EXPECT_FALSE(fs::exists(Path("s.csv"))) << spec;
  }
  EXPECT_EQ(Exec("simulate --scenario yang2012 --positions random:30:4 -o " + Path("s.csv")).status,
            0);
}

// Monte Carlo sizes from options are bounded before allocation, and a thread count beyond the
// machine's no longer aborts (SIGABRT when a thread could not be created) (issue 16).
TEST_F(Cli, MonteCarloSizesAreBounded) {
  CliRun r = Exec("montecarlo --runs 2000000000");
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err, "accelcal: usage: --runs must be from 2 to 1000000\n");
  const CliRun many = Exec("montecarlo --runs 20 --threads 100000 --json");
  const CliRun one = Exec("montecarlo --runs 20 --threads 1 --json");
  ASSERT_EQ(many.status, 0) << many.err;
  EXPECT_EQ(many.out, one.out);
}

TEST_F(Cli, NonConvergenceWritesNothing) {
  const std::string in = Write("pos.csv", PositionsCsv(20));
  const CliRun r =
      Exec("calibrate " + in + " --method two-step --max-iterations 2 -o " + Path("c.json"));
  EXPECT_EQ(r.status, 4);
  EXPECT_NE(r.err.find("did not converge"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(Path("c.json")));
}

TEST_F(Cli, AxisAlignedPositionsAreNamedAsTheReason) {
  // Six axis-aligned orientations (three repeated): gravity's magnitude cannot separate the
  // misalignments from the orientations, the solver wanders, and the message says why.
  const CliRun r =
      Exec("calibrate " + kData +
           "/imucal-ferraris/derived_static_means_example_session.csv --gravity 9.81 -o " +
           Path("c.json"));
  EXPECT_EQ(r.status, 4);
  EXPECT_NE(r.err.find("did not converge"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("the positions barely determine parameter"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(Path("c.json")));
}

TEST_F(Cli, ApplyRejectsABadCalibrationFile) {
  const std::string cal = Write("cal.json", "{\"format\": \"something-else\"}");
  const std::string log = Write("log.csv", "0,1,2,3\n0.01,1,2,3\n");
  const CliRun r = Exec("apply " + cal + " " + log);
  EXPECT_EQ(r.status, 3);
  EXPECT_EQ(
      r.err,
      "accelcal: " + cal +
          ": not an accelcal calibration file (\"format\" is not \"accelcal-calibration\")\n");
}

}  // namespace
}  // namespace accelcal

namespace accelcal {
namespace {

// apply --gyro: the body rates it writes, integrated over a turn, turn the fitted gravity
// direction of one position into the next by the angle the calibration file records.
TEST_F(Cli, ApplyWritesRatesThatIntegrateToTheFilesRotations) {
  const std::string acc = kData + "/imutk-xsens-mti/xsens_acc.mat";
  const std::string gyro = kData + "/imutk-xsens-mti/xsens_gyro.mat";
  const CliRun cal = Exec("calibrate " + acc + " --gravity 9.81744 --gyro " + gyro +
                          " --gyro-model linear -q -o " + Path("imu.json"));
  ASSERT_EQ(cal.status, 0) << cal.err;
  const CliRun apply =
      Exec("apply " + Path("imu.json") + " " + acc + " --gyro " + gyro + " -o " + Path("f.csv"));
  ASSERT_EQ(apply.status, 0) << apply.err;
  // The rows: time, f (3), w (3).
  std::vector<std::array<double, 7>> rows;
  std::istringstream in(Slurp(Path("f.csv")));
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line[0] == 't') continue;
    std::array<double, 7> row{};
    std::istringstream fields(line);
    for (double& v : row) {
      fields >> v;
      fields.ignore(1);
    }
    rows.push_back(row);
  }
  ASSERT_EQ(rows.size(), 51175u);
  const nlohmann::json doc = nlohmann::json::parse(Slurp(Path("imu.json")));
  const auto& positions = doc["sensors"]["accelerometer"]["positions"];
  const auto& rotations = doc["sensors"]["gyroscope"]["rotations"];
  for (std::size_t k : {std::size_t{0}, std::size_t{17}, std::size_t{36}}) {
    const auto& r = rotations[k];
    Mat33 R = Mat33::Identity();
    for (std::size_t s = r["first_sample"]; s < r["last_sample"].get<std::size_t>(); ++s) {
      const double dt = rows[s + 1][0] - rows[s][0];
      const Vec3 w = 0.5 * (Vec3(rows[s][4], rows[s][5], rows[s][6]) +
                            Vec3(rows[s + 1][4], rows[s + 1][5], rows[s + 1][6]));
      R = R * Eigen::AngleAxisd(w.norm() * dt, w.normalized()).toRotationMatrix();
    }
    const auto direction = [&](int position) {
      const auto& d = positions[static_cast<std::size_t>(position - 1)]["direction"];
      return Vec3(d[0], d[1], d[2]);
    };
    const Vec3 v = R.transpose() * direction(r["from"]);
    const Vec3 c = direction(r["to"]);
    const double angle_deg = std::atan2(v.cross(c).norm(), v.dot(c)) * 180 / 3.14159265358979;
    // The file's residual of the same turn: the same rates, integrated by the library (its
    // series exponential against Eigen's angle-axis here, and rates printed to 17 digits).
    EXPECT_NEAR(angle_deg, r["residual_deg"].get<double>(), 1e-6) << k;
  }
}

// Every command that reads the gyroscope beside the accelerometer registers the same flags from
// one entry per sensor (cli_options.hpp's BesideSensor), and checks them the same way: a --gyro
// with an empty name, an empty --gyro-topic, and a --gyro-topic without the gyroscope's rates.
TEST_F(Cli, EveryCommandReadingTheGyroscopeTakesItsFlagsFromOneTable) {
  const std::string acc = kData + "/imutk-xsens-mti/xsens_acc.mat";
  const std::string cal = Write("cal.json", "{}");
  for (const std::string& command :
       {"calibrate " + acc, "verify " + cal + " " + acc, "apply " + cal + " " + acc, "noise " + acc,
        "compare " + acc}) {
    const std::string help = Exec(command.substr(0, command.find(' ')) + " --help").out;
    for (const char* flag : {"--gyro TEXT", "--gyro-columns TEXT", "--gyro-topic TEXT"}) {
      EXPECT_NE(help.find(flag), std::string::npos) << command << ": " << flag;
    }
    const CliRun empty = Exec(command + " --gyro \"\"");
    EXPECT_EQ(empty.status, 2) << command;
    EXPECT_NE(empty.err.find("--gyro: the file name is empty"), std::string::npos)
        << command << ": " << empty.err;
    const CliRun no_topic = Exec(command + " --gyro " + acc + " --gyro-topic \"\"");
    EXPECT_EQ(no_topic.status, 2) << command;
    EXPECT_NE(no_topic.err.find("--gyro-topic: an empty topic name"), std::string::npos)
        << command << ": " << no_topic.err;
    const CliRun alone = Exec(command + " --gyro-topic sensor_gyro");
    EXPECT_EQ(alone.status, 2) << command;
    EXPECT_NE(alone.err.find("--gyro-topic applies to the gyroscope: give its rates with --gyro "
                             "LOG or --gyro-columns"),
              std::string::npos)
        << command << ": " << alone.err;
  }
}

// An option the command does not have is named as such, with the nearest it has (a new user's
// typo, or a flag of another command), never CLI11's list of "arguments not expected".
TEST_F(Cli, AnUnknownOptionIsNamedWithTheNearestKnownOne) {
  const std::string acc = kData + "/imutk-xsens-mti/xsens_acc.mat";
  const CliRun typo = Exec("calibrate " + acc + " --gyro-unit=rad/s");
  EXPECT_EQ(typo.status, 2);
  EXPECT_NE(typo.err.find("calibrate has no option --gyro-unit; did you mean --gyro-units?"),
            std::string::npos)
      << typo.err;
  const CliRun other =
      Exec("verify " + Write("cal.json", "{}") + " " + acc + " --gyro-units rad/s");
  EXPECT_EQ(other.status, 2);
  EXPECT_NE(other.err.find("verify has no option --gyro-units (see --help)"), std::string::npos)
      << other.err;
  const CliRun far = Exec("detect " + acc + " --frobnicate");
  EXPECT_NE(far.err.find("detect has no option --frobnicate (see --help)"), std::string::npos)
      << far.err;
}

}  // namespace
}  // namespace accelcal
