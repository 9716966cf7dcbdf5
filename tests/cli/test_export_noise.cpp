// The sensor's noise handed to the estimators (issue 19): `accelcal export --noise` read back the
// way each tool reads it, on the Xsens recording's rest (the README's figures).
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "accelcal/calibration_file.hpp"
#include "support/cli_test.hpp"
#include "support/paths.hpp"

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
  // A random walk (or its bound) of 0: an estimator weighs the bias's change by 1/K², and a 0
  // pins the bias for ever (Basalt's weights would be infinite).
  nlohmann::json zero = doc_;
  nlohmann::json& walk = zero["accelerometer"]["axes"][1]["terms"]["random_walk"];
  walk["resolved"] = false;
  walk["high"] = 0;
  r = Exec("export " + cal_ + " --to basalt --noise " + Write("zero.json", zero.dump()));
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find("random_walk.high' must be positive: the random walk (or its upper bound)"),
            std::string::npos)
      << r.err;
  // Only the accelerometer's noise: Kalibr's imu.yaml needs the gyroscope's too.
  nlohmann::json accel_only = doc_;
  accel_only.erase("gyroscope");
  r = Exec("export " + cal_ + " --to kalibr-imu --noise " + Write("accel.json", accel_only.dump()));
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find("has none: analyse the log with the gyroscope"), std::string::npos) << r.err;
}

TEST_F(ExportNoise, OptionsAFormatDoesNotUseAreRefusedAndNoiseFilesAreChecked) {
  // An option the format has no use for is a mistake, not silently ignored (exit 2).
  for (const std::string& args : {std::string("--to basalt --noise ") + noise_ + " --rostopic /x",
                                  std::string("--to json --raw-unit g"),
                                  std::string("--to openvins --noise ") + noise_ + " --instance 1",
                                  std::string("--to px4 --c-prefix imu --raw-unit m/s2")}) {
    const CliRun r = Exec("export " + cal_ + " " + args);
    EXPECT_EQ(r.status, 2) << args << "\n" << r.err;
    EXPECT_NE(r.err.find("has no use for it"), std::string::npos) << r.err;
  }
  // A noise file's axes in another order would put one axis' noise on another's.
  nlohmann::json swapped = doc_;
  std::swap(swapped["gyroscope"]["axes"][0], swapped["gyroscope"]["axes"][2]);
  CliRun r = Exec("export " + cal_ + " --to ros --noise " + Write("swapped.json", swapped.dump()));
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find("'gyroscope.axes[0].axis' must be \"x\""), std::string::npos) << r.err;
  nlohmann::json banana = doc_;
  banana["verdict"] = "banana";
  r = Exec("export " + cal_ + " --to ros --noise " + Write("banana.json", banana.dump()));
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find("'verdict' must be \"passed\" or \"failed\""), std::string::npos) << r.err;
}

TEST_F(ExportNoise, AGyroscopeBesideAnAccelerometerInMetersPerSecond2IsLabelledRaw) {
  // calibrate --raw-units m/s2 names the accelerometer's unit; the gyroscope's counts are not in
  // m/s2 (its file had said "m/s2", and the exports read it as a unit they cannot take).
  const std::string data = std::string(ACCELCAL_DATA_DIR) + "/imutk-t265/";
  const std::string t265 = Path("t265.json");
  ASSERT_EQ(Exec("calibrate " + data + "t265_acc.mat --gravity 9.8016 --raw-units m/s2 --gyro " +
                 data + "t265_gyr.mat -q -o " + t265)
                .status,
            0);
  const nlohmann::json doc = nlohmann::json::parse(test::Slurp(t265));
  EXPECT_EQ(doc["sensors"]["gyroscope"]["units"]["raw"], "raw");
  // OpenVINS states a gyroscope model in any case: without the rates' unit it refuses (the
  // identity in place of the calibrated gyroscope would be a claim), and says what to give.
  CliRun r = Exec("export " + t265 + " --to openvins --noise " + noise_ + " -o " + Path("o.yaml"));
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find("give --gyro-raw-unit (rad/s or deg/s)"), std::string::npos) << r.err;
  EXPECT_FALSE(test::fs::exists(Path("o.yaml")));
  r = Exec("export " + t265 + " --to openvins --noise " + noise_ + " --gyro-raw-unit rad/s");
  EXPECT_EQ(r.status, 0) << r.err;
  // A unit that contradicts the file's is refused (exit 2).
  r = Exec("export " + t265 + " --to openvins --noise " + noise_ +
           " --raw-unit g --gyro-raw-unit rad/s");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--raw-unit 'g' contradicts the calibration, whose readings were in 'm/s2'"),
            std::string::npos)
      << r.err;
}

// The Xsens calibration as it would be of a driver's readings: its counts, 32768 at zero, taken to
// m/s2 and rad/s by its sensitivities (raw' = (raw − 32768) / s, s its K's first entry), so that
// the estimators' tests check its g-sensitive gyroscope in the units they read. The counts
// themselves, said to be m/s2 and rad/s, are refused: scales of 0.0024 are no sensor's in m/s2.
std::string InPhysicalUnits(const std::string& counts_json) {
  constexpr double kZero = 32768;
  nlohmann::ordered_json d = nlohmann::ordered_json::parse(counts_json);
  for (const char* sensor : {"accelerometer", "gyroscope"}) {
    nlohmann::ordered_json& c = d["sensors"][sensor];
    const double s = c["K"][0][0].get<double>();
    const auto scaled = [s](nlohmann::ordered_json& v, double zero) {
      for (auto& x : v) x = (x.get<double>() - zero) / s;
    };
    for (auto& row : c["K"]) scaled(row, 0);
    scaled(c["bias"], kZero);
    if (c.contains("g_sensitivity")) {
      for (auto& row : c["g_sensitivity"]) scaled(row, 0);
    }
    if (c.contains("positions")) {
      for (auto& position : c["positions"]) scaled(position["mean"], kZero);
    }
  }
  d["sensors"]["accelerometer"]["units"]["raw"] = "m/s2";
  d["sensors"]["gyroscope"]["units"]["raw"] = "rad/s";
  return d.dump();
}

// The raw readings the estimators' tests correct (one row per position of the Xsens calibration:
// its accelerometer mean and a rate of ~0.6 rad/s in a different direction each time), and
// accelcal's own correction of them: f from the calibration, w = K_g⁻¹ (raw − b_g − G f) in rad/s,
// without G when `with_g` is false.
struct Readings {
  std::string rows;        // "ax ay az wx wy wz" per line
  std::vector<Vec3> f, w;  // accelcal's correction
};
Readings XsensReadings(const LoadedCalibration& cal, bool with_g) {
  Readings r;
  const UnitGyroscope& g = *cal.gyroscope;
  for (std::size_t k = 0; k < cal.position_means.size(); ++k) {
    const Vec3& p = cal.position_means[k];
    const double t = static_cast<double>(k);
    const Vec3 raw_w = g.params.bias +
                       0.6 * g.params.K(0, 0) * Vec3(std::cos(t), std::sin(2 * t), std::cos(3 * t));
    const Vec3 f = *SpecificForce(cal.params, p);
    r.f.push_back(f);
    const Vec3 g_f = with_g ? Vec3(g.params.G * f) : Vec3::Zero();
    r.w.push_back(g.params.K.inverse() * (raw_w - g.params.bias - g_f));
    std::ostringstream line;
    line.precision(17);
    line << p(0) << " " << p(1) << " " << p(2) << " " << raw_w(0) << " " << raw_w(1) << " "
         << raw_w(2) << "\n";
    r.rows += line.str();
  }
  return r;
}

// The tool's corrected readings against accelcal's: the frames differ by a rotation (x-first
// against the calibration's), so the Gram matrix of all the vectors, accelerometer and gyroscope
// together, is compared: it fixes them up to one common rotation, and a wrong rotation between
// the two sensors, a transposed matrix or a bias in the wrong units changes it.
void ExpectSameUpToOneRotation(const std::vector<double>& tool, const Readings& ours,
                               double force_to_ms2) {
  std::vector<Vec3> a, b;
  for (std::size_t k = 0; k < ours.f.size(); ++k) {
    a.push_back(ours.f[k] * force_to_ms2);
    a.push_back(ours.w[k]);
    b.push_back(Vec3(tool[6 * k], tool[6 * k + 1], tool[6 * k + 2]));
    b.push_back(Vec3(tool[6 * k + 3], tool[6 * k + 4], tool[6 * k + 5]));
  }
  ASSERT_EQ(tool.size(), 6 * ours.f.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    for (std::size_t j = i; j < a.size(); ++j) {
      // Round-off: the files' numbers are exact (shortest round trip); the inverses and products
      // on ~10 m/s2 and ~1 rad/s vectors leave ~1e-13 relative.
      EXPECT_NEAR(b[i].dot(b[j]), a[i].dot(a[j]), 1e-9 * a[i].norm() * a[j].norm() + 1e-12)
          << i << " " << j;
    }
  }
}

// OpenVINS (ov_msckf): the file through OpenCV's FileStorage (the %YAML:1.0 directive, then a
// YAML mapping under imu0), VioManagerOptions (Dw = Tw⁻¹, Da = Ta⁻¹, model "kalibr" keeps their
// lower triangles) and Propagator::predict_and_compute's correction with the biases accelcal wrote
// beside them: a = R_ACCtoIMU Da (a_m − b_a), w = R_GYROtoIMU Dw (w_m − b_g − Tg a).
constexpr const char* kOpenVinsReader =
    "import re, sys, yaml, numpy as np\n"
    "text = open(sys.argv[1]).read()\n"
    "assert text.startswith(\"%YAML:1.0\\n\"), text[:20]\n"
    "d = yaml.safe_load(text.split(\"\\n\", 1)[1])[\"imu0\"]\n"
    "assert d[\"model\"] == \"kalibr\"\n"
    "for k in (\"accelerometer_noise_density\", \"accelerometer_random_walk\", "
    "\"gyroscope_noise_density\", \"gyroscope_random_walk\"):\n"
    "    assert isinstance(d[k], float) and d[k] > 0, k\n"
    "m = {k: np.array(d[k], dtype=float) for k in (\"Tw\", \"Ta\", \"R_IMUtoGYRO\", "
    "\"R_IMUtoACC\", \"Tg\")}\n"
    "for k, v in m.items(): assert v.shape == (3, 3), k\n"
    "Dw, Da = np.tril(np.linalg.inv(m[\"Tw\"])), np.tril(np.linalg.inv(m[\"Ta\"]))\n"
    "bias = lambda name: np.array([float(x) for x in re.search(\"# accelcal constant \" + name "
    "+ r\" \\[[^]]*\\]: \\[([^]]*)\\]\", text).group(1).split(\",\")])\n"
    "ba, bg = bias(\"bias\"), bias(\"gyro bias\")\n"
    "for row in open(sys.argv[2]):\n"
    "    v = np.array([float(x) for x in row.split()])\n"
    "    a = m[\"R_IMUtoACC\"].T @ Da @ (v[:3] - ba)\n"
    "    w = m[\"R_IMUtoGYRO\"].T @ Dw @ (v[3:] - bg - m[\"Tg\"] @ a)\n"
    "    print(\" \".join(repr(float(x)) for x in list(a) + list(w)))\n";

// calibrate --noise: the accelerometer's random walk of the noise file is the spline bias's prior,
// converted to raw units through K, its source named in the summary.
TEST_F(ExportNoise, CalibrateTakesTheBiasRandomWalkFromIt) {
  const std::string acc = std::string(ACCELCAL_DATA_DIR) + "/imutk-xsens-mti/xsens_acc.mat";
  const CliRun r = Exec("calibrate " + acc + " --gravity 9.81744 --bias-model spline:6 --noise " +
                        noise_ + " --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json doc = nlohmann::json::parse(r.out)["sensors"]["accelerometer"];
  ASSERT_EQ(doc["bias_drift"]["random_walk"].size(), 3u);
  // raw = K f + b: the walk of f shows as K q in the readings, q from the file per axis.
  const auto& K = doc["K"];
  for (int i = 0; i < 3; ++i) {
    double expected2 = 0;
    for (int j = 0; j < 3; ++j) {
      const auto& term = doc_["accelerometer"]["axes"][j]["terms"]["random_walk"];
      const double q = term[term["resolved"].get<bool>() ? "value" : "high"].get<double>();
      expected2 += std::pow(K[i][j].get<double>() * q, 2);
    }
    EXPECT_NEAR(doc["bias_drift"]["random_walk"][i].get<double>(), std::sqrt(expected2),
                1e-3 * std::sqrt(expected2))
        << i;
  }
}

TEST_F(ExportNoise, OpenVinsCorrectsReadingsAsAccelcalDoes) {
  const std::string si = Write("xsens-si.json", InPhysicalUnits(test::Slurp(cal_)));
  const LoadedCalibration cal = ParseCalibrationJson(test::Slurp(si), si);
  ASSERT_TRUE(cal.gyroscope && !cal.gyroscope->params.G.isZero(0));  // the g-sensitive model
  const std::string yaml = Path("kalibr_imu_chain.yaml");
  const CliRun r = Exec("export " + si + " --to openvins --noise " + noise_ + " -o " + yaml);
  ASSERT_EQ(r.status, 0) << r.err;
  const Readings ours = XsensReadings(cal, true);
  const std::string rows = Write("readings.txt", ours.rows);
  ExpectSameUpToOneRotation(Numbers(Python(kOpenVinsReader, yaml + " " + rows)), ours,
                            cal.unit == ForceUnit::kStandardGravity ? 9.80665 : 1.0);
  // Nothing of the linear model is dropped, and the noise is the largest axis' (as Kalibr's).
  EXPECT_NE(r.out.find("exact: nothing of the accelerometer's model is dropped"), std::string::npos)
      << r.out;
  EXPECT_NE(test::Slurp(yaml).find("accelerometer_noise_density: " +
                                   nlohmann::json(Largest("accelerometer", "white")).dump()),
            std::string::npos);
}

// Basalt: cereal's JSON (the root "value0", every field of Calibration's serialize present) and
// CalibAccelBias / CalibGyroBias::getCalibrated: a = (I + S_a) a_r − b_a with S_a's six entries
// filling the lower triangle column by column, w = (I + S_g) w_r − b_g with S_g column-major.
constexpr const char* kBasaltReader =
    "import json, sys, numpy as np\n"
    "d = json.load(open(sys.argv[1]))\n"
    "assert list(d) == [\"value0\"], list(d)\n"
    "c = d[\"value0\"]\n"
    "need = [\"T_imu_cam\", \"intrinsics\", \"resolution\", \"calib_accel_bias\", "
    "\"calib_gyro_bias\", \"imu_update_rate\", \"accel_noise_std\", \"gyro_noise_std\", "
    "\"accel_bias_std\", \"gyro_bias_std\", \"cam_time_offset_ns\", \"vignette\"]\n"
    "assert sorted(c) == sorted(need), sorted(c)\n"
    "assert len(c[\"calib_accel_bias\"]) == 9 and len(c[\"calib_gyro_bias\"]) == 12\n"
    "for k in need[6:10]: assert len(c[k]) == 3 and min(c[k]) > 0, k\n"
    "assert c[\"imu_update_rate\"] > 0\n"
    "p, q = np.array(c[\"calib_accel_bias\"]), np.array(c[\"calib_gyro_bias\"])\n"
    "Sa = np.zeros((3, 3))\n"
    "Sa[:, 0] = p[3:6]; Sa[1, 1] = p[6]; Sa[2, 1] = p[7]; Sa[2, 2] = p[8]\n"
    "Sg = np.column_stack([q[3:6], q[6:9], q[9:12]])\n"
    "for row in open(sys.argv[2]):\n"
    "    v = np.array([float(x) for x in row.split()])\n"
    "    a = v[:3] + Sa @ v[:3] - p[:3]\n"
    "    w = v[3:] + Sg @ v[3:] - q[:3]\n"
    "    print(\" \".join(repr(float(x)) for x in list(a) + list(w)))\n";

TEST_F(ExportNoise, BasaltCorrectsReadingsAsAccelcalDoesWithoutTheGSensitivity) {
  const std::string si = Write("xsens-si.json", InPhysicalUnits(test::Slurp(cal_)));
  const LoadedCalibration cal = ParseCalibrationJson(test::Slurp(si), si);
  const std::string json = Path("calib.json");
  const CliRun r = Exec("export " + si + " --to basalt --noise " + noise_ + " -o " + json);
  ASSERT_EQ(r.status, 0) << r.err;
  // Basalt has no g-sensitivity: its correction is accelcal's without G, and the export says so.
  const Readings ours = XsensReadings(cal, false);
  const std::string rows = Write("readings.txt", ours.rows);
  ExpectSameUpToOneRotation(Numbers(Python(kBasaltReader, json + " " + rows)), ours,
                            cal.unit == ForceUnit::kStandardGravity ? 9.80665 : 1.0);
  EXPECT_NE(r.out.find("dropped from the gyroscope: the g-sensitivity G (a rate error of up to"),
            std::string::npos)
      << r.out;
  // The noise per axis, in SI units, as the noise file has it.
  const nlohmann::json c = nlohmann::json::parse(test::Slurp(json))["value0"];
  for (std::size_t a = 0; a < 3; ++a) {
    EXPECT_EQ(c["accel_noise_std"][a], doc_["accelerometer"]["axes"][a]["terms"]["white"]["value"]);
    EXPECT_EQ(c["gyro_noise_std"][a], doc_["gyroscope"]["axes"][a]["terms"]["white"]["value"]);
  }
  EXPECT_EQ(c["imu_update_rate"], doc_["rate_hz"]);
}

}  // namespace
}  // namespace accelcal
