// `accelcal verify` (issue 19): a calibration checked on a new recording of the same unit. The
// Xsens recording split in two halves (each calibrates, the other verifies), a deliberately wrong
// calibration, simulated sessions of a known device, and the refusals.
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "support/cli_test.hpp"

namespace accelcal {
namespace {

using Cli = test::CliTest;
using test::CliRun;

class Verify : public Cli {
 protected:
  // The Xsens recording's two halves, cut in the turn between positions 19 and 20 (line 26386:
  // position 19 ends at sample 26127, position 20 begins at 26645), each calibrated.
  void SetUp() override {
    Cli::SetUp();
    std::ifstream in(std::string(ACCELCAL_DATA_DIR) + "/imutk-xsens-mti/xsens_acc.mat");
    std::string line, first, second;
    for (int n = 1; std::getline(in, line); ++n) (n <= 26386 ? first : second) += line + "\n";
    half_[0] = Write("first.mat", first);
    half_[1] = Write("second.mat", second);
    for (int h = 0; h < 2; ++h) {
      cal_[h] = Path("half" + std::to_string(h) + ".json");
      ASSERT_EQ(Exec("calibrate " + half_[h] + " --gravity 9.81744 -q -o " + cal_[h]).status, 0);
    }
  }
  std::string half_[2], cal_[2];
};

TEST_F(Verify, EachXsensHalfHoldsOnTheOther) {
  for (int h = 0; h < 2; ++h) {
    const std::string out = Path("verify" + std::to_string(h) + ".json");
    const CliRun r = Exec("verify " + cal_[h] + " " + half_[1 - h] + " --json -o " + out);
    EXPECT_EQ(r.status, 0) << r.err;
    const nlohmann::json v = nlohmann::json::parse(test::Slurp(out));
    EXPECT_EQ(v["verdict"], "passed");
    EXPECT_EQ(v["dof"], 19);  // the other half's still positions
    // Measured: chi2 = 9.8 (calibrated on the first half) and 19.9 (on the second) for 19
    // positions: p = 0.96 and 0.40. The test fails at p < 0.001, chi2 = 43.8.
    EXPECT_LT(v["chi2"].get<double>(), 43.8);
    EXPECT_GT(v["chi2"].get<double>(), 5.0);  // p > 0.999 would be a prediction far too loose
  }
}

TEST_F(Verify, AWrongCalibrationFailsWithExitSixAndSaysWhere) {
  // One scale factor 0.1 % off (about the calibration's own 1σ times 30): each position's |f|
  // moves by up to 10 mm/s2 against a predicted 1.3-1.9 mm/s2.
  nlohmann::ordered_json doc = nlohmann::ordered_json::parse(test::Slurp(cal_[0]));
  doc["sensors"]["accelerometer"]["K"][0][0] =
      doc["sensors"]["accelerometer"]["K"][0][0].get<double>() * 1.001;
  const std::string wrong = Write("wrong.json", doc.dump());
  const std::string out = Path("verify.txt");
  const CliRun r = Exec("verify " + wrong + " " + half_[1] + " -o " + out);
  EXPECT_EQ(r.status, 6) << r.err;
  const std::string text = test::Slurp(out);  // written, with the verdict
  EXPECT_NE(text.find("# verdict: failed: the errors |f| - g are larger than the calibration "
                      "predicts: chi2 = "),
            std::string::npos)
      << text;
  EXPECT_NE(r.err.find("does not hold on"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("furthest off: position "), std::string::npos) << r.err;
  // Another sensor's log (the T265's, in m/s2) on the Xsens calibration (counts): the reason
  // says what is likely wrong.
  const CliRun other = Exec("verify " + cal_[0] + " " + std::string(ACCELCAL_DATA_DIR) +
                            "/imutk-t265/t265_acc.mat -o " + Path("other.txt"));
  EXPECT_EQ(other.status, 6);
  EXPECT_NE(other.err.find("is the log in the calibration's raw unit, and from this sensor?"),
            std::string::npos)
      << other.err;
}

TEST_F(Verify, RefusesWhatItCannotVerify) {
  // No still position: nothing to verify (exit 3, nothing written).
  std::string moving = "time,x,y,z\n";
  for (int i = 0; i < 3000; ++i) {
    const double t = i * 0.01;
    char row[128];
    std::snprintf(row, sizeof row, "%.2f,%.6f,%.6f,%.6f\n", t, 33000 + 3000 * std::sin(t),
                  33000 + 3000 * std::cos(t), 36000.0);
    moving += row;
  }
  const std::string out = Path("never.txt");
  CliRun r = Exec("verify " + cal_[0] + " " + Write("moving.csv", moving) + " -o " + out);
  EXPECT_EQ(r.status, 3) << r.err;
  EXPECT_FALSE(test::fs::exists(out));
  // The output may not be an input; gravity must be a number of m/s2 in [1, 100].
  r = Exec("verify " + cal_[0] + " " + half_[1] + " -o " + half_[1]);
  EXPECT_EQ(r.status, 2) << r.err;
  r = Exec("verify " + cal_[0] + " " + half_[1] + " --gravity 981");
  EXPECT_EQ(r.status, 2) << r.err;
}

// Simulated sessions of one linear device (50 µg/√Hz, Yang's 18 positions, 10 s each): each
// calibrates on one seed and verifies on the next. When the calibration holds, χ² has N degrees
// of freedom if every part of the prediction is exact; the misfit estimated from the
// calibration's 9 residual degrees of freedom is kept only when positive, which makes the test
// conservative: measured mean χ²/N 0.81 over 30 pairs.
TEST_F(Verify, SimulatedSessionsPassAndAScaleErrorFails) {
  const int pairs = ACCELCAL_TESTS_SANITIZED ? 8 : 30;
  const std::string truth = cal_[0];  // the first half's linear calibration as the device
  double sum = 0;
  int failed = 0, caught = 0;
  for (int s = 0; s < pairs; ++s) {
    const auto simulate = [&](int seed, const std::string& name) {
      return Exec("simulate --truth " + truth +
                  " --positions yang18 --noise-density 50 --raw --duration 10 --seed " +
                  std::to_string(seed) + " -o " + Path(name))
          .status;
    };
    ASSERT_EQ(simulate(2 * s + 10, "a.csv"), 0);
    ASSERT_EQ(simulate(2 * s + 11, "b.csv"), 0);
    ASSERT_EQ(Exec("calibrate " + Path("a.csv") + " -q -o " + Path("a.json")).status, 0);
    const CliRun r = Exec("verify " + Path("a.json") + " " + Path("b.csv") + " --json");
    ASSERT_TRUE(r.status == 0 || r.status == 6) << r.err;
    const nlohmann::json v = nlohmann::json::parse(r.out);
    sum += v["chi2"].get<double>() / v["dof"].get<double>();
    failed += r.status == 6;
    // The same calibration with K_yy 0.05 % off: found.
    nlohmann::ordered_json doc = nlohmann::ordered_json::parse(test::Slurp(Path("a.json")));
    auto& K = doc["sensors"]["accelerometer"]["K"];
    K[1][1] = K[1][1].get<double>() * 1.0005;
    const std::string wrong = Write("wrong.json", doc.dump());
    caught += Exec("verify " + wrong + " " + Path("b.csv") + " -o " + Path("w.txt")).status == 6;
  }
  // At the 0.1 % level, two failures in 30 correct pairs happen with probability 4e-4.
  EXPECT_LE(failed, 1);
  // Never looser than exact (a mean above 1 + 3σ, σ = √(2/18/30) = 0.061, would be a prediction
  // too tight), and not uselessly loose.
  EXPECT_LE(sum / pairs, 1.18);
  EXPECT_GE(sum / pairs, 0.6);
  EXPECT_EQ(caught, pairs);
}

}  // namespace
}  // namespace accelcal
