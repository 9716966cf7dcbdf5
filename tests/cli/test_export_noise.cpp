// The sensor's noise handed to the estimators (issue 19): `accelcal export --noise` read back the
// way each tool reads it, on the Xsens recording's rest (the README's figures).
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "support/cli_test.hpp"

namespace accelcal {
namespace {

using Cli = test::CliTest;
using test::CliRun;

// Runs python3 on `script` with `args`: its stdout, or "" with a failure when it fails.
std::string Python(const std::string& script, const std::string& args) {
  const std::string cmd = "/usr/bin/python3 -c '" + script + "' " + args;
  FILE* pipe = popen(cmd.c_str(), "r");
  std::string out;
  char buf[4096];
  std::size_t n;
  while ((n = fread(buf, 1, sizeof buf, pipe)) > 0) out.append(buf, n);
  const int status = pclose(pipe);
  EXPECT_EQ(WIFEXITED(status) ? WEXITSTATUS(status) : -1, 0) << cmd << "\n" << out;
  return out;
}

std::vector<double> Numbers(const std::string& text) {
  std::istringstream in(text);
  std::vector<double> v;
  double x;
  while (in >> x) v.push_back(x);
  return v;
}

class ExportNoise : public Cli {
 protected:
  // The Xsens recording calibrated, its rest analysed with the gyroscope: noise.json.
  void SetUp() override {
    Cli::SetUp();
    const std::string data = std::string(ACCELCAL_DATA_DIR) + "/imutk-xsens-mti/";
    cal_ = Path("xsens.json");
    noise_ = Path("noise.json");
    ASSERT_EQ(Exec("calibrate " + data + "xsens_acc.mat --gravity 9.81744 --gyro " + data +
                   "xsens_gyro.mat -q -o " + cal_)
                  .status,
              0);
    const CliRun r = Exec("noise " + data + "xsens_acc.mat --still --calibration " + cal_ +
                          " --gyro " + data + "xsens_gyro.mat --json -o " + noise_);
    ASSERT_EQ(r.status, 0) << r.err;
    doc_ = nlohmann::json::parse(test::Slurp(noise_));
  }
  // The largest axis' value of a term, in the file's unit.
  double Largest(const char* sensor, const char* term, const char* field = "value") const {
    double v = 0;
    for (const auto& axis : doc_[sensor]["axes"]) {
      const auto& t = axis["terms"][term];
      v = std::max(v, t[t["resolved"].get<bool>() ? "value" : field].get<double>());
    }
    return v;
  }
  std::string cal_, noise_;
  nlohmann::json doc_;
};

// Kalibr's ImuParameters (kalibr_common/ConfigReader.py): PyYAML safe_load, its checks (noise
// and random walk > 0, update_rate > 0, rostopic a str), and the discrete white noise it weights
// each sample with, density / sqrt(1 / update_rate).
constexpr const char* kKalibrReader =
    "import math, sys, yaml\n"
    "d = yaml.safe_load(open(sys.argv[1]))\n"
    "assert isinstance(d[\"rostopic\"], str), d\n"
    "r = d[\"update_rate\"]\n"
    "assert r > 0.0\n"
    "for s in (\"accelerometer\", \"gyroscope\"):\n"
    "    n, w = d[s + \"_noise_density\"], d[s + \"_random_walk\"]\n"
    "    assert isinstance(n, float) and isinstance(w, float) and n > 0.0 and w > 0.0\n"
    "    print(repr(n / math.sqrt(1.0 / r)), repr(w))\n"
    "print(repr(r), d[\"rostopic\"])\n";

TEST_F(ExportNoise, KalibrImuYamlIsReadAsKalibrReadsIt) {
  const std::string yaml = Path("imu.yaml");
  const CliRun r = Exec("export " + cal_ + " --to kalibr-imu --noise " + noise_ +
                        " --rostopic /xsens/imu -o " + yaml);
  ASSERT_EQ(r.status, 0) << r.err;
  std::istringstream lines(Python(kKalibrReader, yaml));
  std::string accel, gyro, rate;
  std::getline(lines, accel);
  std::getline(lines, gyro);
  std::getline(lines, rate);
  const double rate_hz = doc_["rate_hz"];
  const double g0 = 9.80665;  // the noise file's accelerometer is in m/s2 already
  ASSERT_EQ(doc_["accelerometer"]["unit"], "m/s2");
  const std::vector<double> a = Numbers(accel), w = Numbers(gyro);
  ASSERT_EQ(a.size(), 2u);
  ASSERT_EQ(w.size(), 2u);
  // The largest axis' density, discretised by Kalibr: the README's 90.7 µg/√Hz (y) × √100 Hz.
  EXPECT_DOUBLE_EQ(a[0], Largest("accelerometer", "white") * std::sqrt(rate_hz));
  EXPECT_NEAR(Largest("accelerometer", "white") / g0 * 1e6, 90.7, 0.05);
  EXPECT_DOUBLE_EQ(a[1], Largest("accelerometer", "random_walk", "high"));
  EXPECT_DOUBLE_EQ(w[0], Largest("gyroscope", "white") * std::sqrt(rate_hz));
  EXPECT_NEAR(Largest("gyroscope", "white") * 180 / 3.14159265358979323846, 0.0354, 0.00005);
  EXPECT_DOUBLE_EQ(w[1], Largest("gyroscope", "random_walk", "high"));
  EXPECT_EQ(rate, nlohmann::json(rate_hz).dump() + " /xsens/imu");
  // Said where the user looks: what the file holds and that the model is not in it.
  EXPECT_NE(r.out.find("the calibration's model is not in this file"), std::string::npos) << r.out;
  // The random walks are upper bounds in 52 s of rest, and the file says so.
  EXPECT_NE(test::Slurp(yaml).find("(where not resolved in this log: its 95 % upper bound)"),
            std::string::npos);
}

// sensor_msgs/Imu: three float64[9], row-major; the diagonal the variance of one sample.
TEST_F(ExportNoise, RosCovariancesAreTheVarianceOfOneSample) {
  const std::string yaml = Path("imu_covariance.yaml");
  ASSERT_EQ(Exec("export " + cal_ + " --to ros --noise " + noise_ + " -o " + yaml).status, 0);
  const std::string out = Python(
      "import sys, yaml\n"
      "d = yaml.safe_load(open(sys.argv[1]))\n"
      "for k in (\"linear_acceleration_covariance\", \"angular_velocity_covariance\", "
      "\"orientation_covariance\"):\n"
      "    assert len(d[k]) == 9, k\n"
      "    print(\" \".join(repr(float(v)) for v in d[k]))\n",
      yaml);
  const std::vector<double> v = Numbers(out);
  ASSERT_EQ(v.size(), 27u);
  const double rate_hz = doc_["rate_hz"];
  for (int s = 0; s < 2; ++s) {
    const char* sensor = s == 0 ? "accelerometer" : "gyroscope";
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        const double n = doc_[sensor]["axes"][std::size_t(i)]["terms"]["white"]["value"];
        EXPECT_DOUBLE_EQ(v[std::size_t(9 * s + 3 * i + j)], i == j ? n * n * rate_hz : 0.0)
            << sensor << i << j;
      }
    }
  }
  EXPECT_EQ(v[18], -1);  // no orientation
}

TEST_F(ExportNoise, KalibrModelCarriesTheNoiseKeysAndRefusalsNameTheirCause) {
  // Kalibr's output imu.yaml (imu0: model and noise keys together) from a calibration in m/s2.
  const std::string data = std::string(ACCELCAL_DATA_DIR) + "/imutk-t265/";
  const std::string t265 = Path("t265.json");
  ASSERT_EQ(
      Exec("calibrate " + data + "t265_acc.mat --gravity 9.8016 --raw-units m/s2 -q -o " + t265)
          .status,
      0);
  const std::string yaml = Path("kalibr.yaml");
  CliRun r = Exec("export " + t265 + " --to kalibr --noise " + noise_ + " -o " + yaml);
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string keys = Python(
      "import sys, yaml\n"
      "d = yaml.safe_load(open(sys.argv[1]))[\"imu0\"]\n"
      "print(d[\"model\"], len(d[\"accelerometers\"][\"M\"]), repr(d[\"accelerometer_noise_"
      "density\"]), repr(d[\"update_rate\"]), d[\"rostopic\"])\n",
      yaml);
  EXPECT_EQ(keys, "scale-misalignment 3 " +
                      nlohmann::json(Largest("accelerometer", "white")).dump() + " " +
                      nlohmann::json(doc_["rate_hz"]).dump() + " /imu0\n");
  // Without the noise, the noise formats say what they need; a format without noise refuses it.
  r = Exec("export " + cal_ + " --to kalibr-imu");
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find("holds the sensor's noise: give the output of accelcal noise --json"),
            std::string::npos)
      << r.err;
  r = Exec("export " + cal_ + " --to px4 --noise " + noise_);
  EXPECT_EQ(r.status, 2);
  // A noise file in raw units, or one whose verdict failed, is not a result to hand on.
  const std::string raw = Path("raw_noise.json");
  ASSERT_EQ(Exec("noise " + std::string(ACCELCAL_DATA_DIR) +
                 "/imutk-xsens-mti/xsens_acc.mat --still --json -o " + raw)
                .status,
            0);
  r = Exec("export " + cal_ + " --to ros --noise " + raw);
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find("'accelerometer.unit' is 'raw': an estimator takes densities in m/s2"),
            std::string::npos)
      << r.err;
  nlohmann::json failed = doc_;
  failed["verdict"] = "failed";
  const std::string bad = Write("failed.json", failed.dump());
  r = Exec("export " + cal_ + " --to ros --noise " + bad);
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find("'verdict' is 'failed'"), std::string::npos) << r.err;
  // Only the accelerometer's noise: Kalibr's imu.yaml needs the gyroscope's too.
  nlohmann::json accel_only = doc_;
  accel_only.erase("gyroscope");
  r = Exec("export " + cal_ + " --to kalibr-imu --noise " + Write("accel.json", accel_only.dump()));
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find("has none: analyse the log with the gyroscope"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace accelcal
