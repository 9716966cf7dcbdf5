// The accelcal command as a user runs it: outputs, exit statuses and messages for bad input, and
// that a failure never leaves a partial output file.
#include <sys/wait.h>

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

// Provenance (calibration_file.hpp): the options given that change the result, in the tool's order
// whatever the command line's; every input by name, size and SHA-256 (as sha256sum prints it);
// a date only when given, checked as a date.
TEST_F(Cli, TheCalibrationFileSaysWhatMadeIt) {
  const std::string ctu = kData + "/ctu-innalabs-ahrs-m3/measured_accelerations_24pos.csv";
  const CliRun a = Exec("calibrate " + ctu + " --units g --no-crossval --model quadratic --json");
  const CliRun b = Exec("calibrate --model quadratic " + ctu + " --json --no-crossval --units g");
  ASSERT_EQ(a.status, 0) << a.err;
  EXPECT_EQ(a.out, b.out);  // the same calibration asked for in another order: the same bytes
  const nlohmann::json provenance = nlohmann::json::parse(a.out).at("provenance");
  EXPECT_EQ(provenance.at("command"), "accelcal calibrate");
  EXPECT_EQ(provenance.at("options"),
            nlohmann::json({{"units", "g"}, {"model", "quadratic"}, {"no-crossval", true}}));
  ASSERT_EQ(provenance.at("inputs").size(), 1u);
  EXPECT_EQ(provenance.at("inputs")[0].at("name"), ctu);
  EXPECT_EQ(provenance.at("inputs")[0].at("bytes"), fs::file_size(ctu));
  EXPECT_EQ(provenance.at("inputs")[0].at("sha256"), Sha256Hex(Slurp(ctu)));
  EXPECT_FALSE(provenance.contains("date"));
  const CliRun dated =
      Exec("calibrate " + ctu + " --units g --no-crossval --json --date 2026-11-23");
  ASSERT_EQ(dated.status, 0) << dated.err;
  EXPECT_EQ(nlohmann::json::parse(dated.out).at("provenance").at("date"), "2026-11-23");
  const CliRun bad = Exec("calibrate " + ctu + " --units g --date 2026-02-29 -o " + Path("d.json"));
  EXPECT_EQ(bad.status, 2);
  EXPECT_NE(bad.err.find("'2026-02-29': that month has no day 29"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(Path("d.json")));
  // Standard input is hashed as read; the orientations file is an input too.
  const std::string dir = kData + "/imucal-ferraris/";
  const CliRun known =
      Exec("calibrate - --orientations " + dir +
           "ferraris_orientations.csv --gravity 9.81 --json < " + dir + "ferraris_raw_means.csv");
  ASSERT_EQ(known.status, 0) << known.err;
  const nlohmann::json inputs = nlohmann::json::parse(known.out)["provenance"]["inputs"];
  ASSERT_EQ(inputs.size(), 2u);
  EXPECT_EQ(inputs[0]["name"], "-");
  EXPECT_EQ(inputs[0]["sha256"], Sha256Hex(Slurp(dir + "ferraris_raw_means.csv")));
  EXPECT_EQ(inputs[1]["sha256"], Sha256Hex(Slurp(dir + "ferraris_orientations.csv")));
}

TEST_F(Cli, CalibratesTheXsensRecording) {
  const CliRun r = Exec("calibrate " + kData +
                        "/imutk-xsens-mti/xsens_acc.mat --gravity 9.81744 -o " + Path("cal.json"));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("38 static intervals"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("rms |f|-g"), std::string::npos);
  const nlohmann::json doc = AccelerometerKeys(Slurp(Path("cal.json")));
  EXPECT_LE(doc["gravity_norm_rms_after"].get<double>(), 0.0012);
  EXPECT_EQ(doc["positions"].size(), 38u);
  EXPECT_EQ(doc["positions"][0]["interval"]["begin"].get<int>() > 0, true);
  // The means' noise from their samples (batch means, position_noise.hpp); the positions scatter
  // 3.07x more than it explains (4.57x more than the samples' σ/√n, which the sensor's filtered
  // output puts low), so the covariance is inflated by the scatter ratio.
  EXPECT_EQ(doc["noise"]["source"], "samples");
  EXPECT_NEAR(doc["noise"]["scatter_ratio"].get<double>(), 3.07, 0.01);
  EXPECT_TRUE(doc["noise"]["inflated"].get<bool>());
  EXPECT_NE(r.out.find("strongest correlations: b_x/K_xx +0.845"), std::string::npos) << r.out;
  // Leave-one-position-out validation by default: the compare table's held-out figure (README).
  EXPECT_NEAR(doc["crossval_rms"].get<double>(), 1.4031e-3, 1e-7);
  EXPECT_TRUE(doc["positions"][0].contains("crossval_error"));
  EXPECT_NE(r.out.find("held-out  rms |f|-g 0.0014031"), std::string::npos) << r.out;
  const CliRun quick =
      Exec("calibrate " + kData +
           "/imutk-xsens-mti/xsens_acc.mat --gravity 9.81744 --no-crossval --json");
  ASSERT_EQ(quick.status, 0) << quick.err;
  EXPECT_TRUE(AccelerometerKeys(quick.out)["crossval_rms"].is_null());

  // --json prints exactly the file; a second run gives the same bytes (determinism).
  const CliRun j =
      Exec("calibrate " + kData + "/imutk-xsens-mti/xsens_acc.mat --gravity 9.81744 --json");
  ASSERT_EQ(j.status, 0);
  EXPECT_EQ(j.out, Slurp(Path("cal.json")));

  // apply: the corrected log has |f| ≈ g while still.
  const CliRun a = Exec("apply " + Path("cal.json") + " " + kData +
                        "/imutk-xsens-mti/xsens_acc.mat -o " + Path("corrected.csv"));
  ASSERT_EQ(a.status, 0) << a.err;
  std::ifstream in(Path("corrected.csv"));
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line.rfind("# accelcal apply", 0), 0u);
  std::getline(in, line);
  EXPECT_EQ(line,
            "# time: seconds from the first sample, at 0.02984 s on the log's clock (read in s)");
  std::getline(in, line);
  EXPECT_EQ(line, "time,x,y,z");
  double t, x, y, z;
  char c;
  double sum = 0;
  int n = 0;
  while (n < 5000 && (in >> t >> c >> x >> c >> y >> c >> z)) {
    sum += std::sqrt(x * x + y * y + z * z);
    ++n;
  }
  EXPECT_EQ(n, 5000);  // the first 50 s are still
  EXPECT_NEAR(sum / n, 9.81744, 0.003);
}

TEST_F(Cli, CalibratesInTheZFirstFrame) {
  const std::string xsens = kData + "/imutk-xsens-mti/xsens_acc.mat --gravity 9.81744";
  const CliRun r = Exec("calibrate " + xsens + " --frame z-first -o " + Path("z.json"));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("frame z-first"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("tau_xy"), std::string::npos) << r.out;
  const nlohmann::json z = AccelerometerKeys(Slurp(Path("z.json")));
  EXPECT_EQ(z["frame"], "z-first");
  EXPECT_EQ(z["parameter_order"][0], "K_zz");
  EXPECT_EQ(z["K"][1][0].get<double>(), 0.0);
  EXPECT_EQ(z["K"][2][0].get<double>(), 0.0);
  EXPECT_EQ(z["K"][2][1].get<double>(), 0.0);
  EXPECT_TRUE(z["engineering"]["misalignment_rad"].contains("tau_yz"));
  const CliRun x = Exec("calibrate " + xsens + " -o " + Path("x.json"));
  ASSERT_EQ(x.status, 0) << x.err;
  const nlohmann::json xd = AccelerometerKeys(Slurp(Path("x.json")));
  EXPECT_EQ(xd["frame"], "x-first");
  // The same linear device: the same corrected magnitudes (to the solvers' convergence).
  EXPECT_NEAR(z["gravity_norm_rms_after"].get<double>(), xd["gravity_norm_rms_after"].get<double>(),
              1e-9);
  // apply reads the z-first file (K upper-triangular) and corrects alike.
  const std::string log = kData + "/imutk-xsens-mti/xsens_acc.mat";
  const CliRun az = Exec("apply " + Path("z.json") + " " + log + " -o " + Path("z.csv"));
  const CliRun ax = Exec("apply " + Path("x.json") + " " + log + " -o " + Path("x.csv"));
  ASSERT_EQ(az.status, 0) << az.err;
  ASSERT_EQ(ax.status, 0) << ax.err;
  std::ifstream fz(Path("z.csv")), fx(Path("x.csv"));
  std::string line;
  for (int i = 0; i < 3; ++i) std::getline(fz, line), std::getline(fx, line);
  double t, a, b, c, T, A, B, C;
  char sep;
  int n = 0;
  while (n < 1000 && (fz >> t >> sep >> a >> sep >> b >> sep >> c) &&
         (fx >> T >> sep >> A >> sep >> B >> sep >> C)) {
    EXPECT_NEAR(std::sqrt(a * a + b * b + c * c), std::sqrt(A * A + B * B + C * C), 1e-8);
    ++n;
  }
  EXPECT_EQ(n, 1000);
  const CliRun bad = Exec("calibrate " + xsens + " --frame y-first");
  EXPECT_EQ(bad.status, 2);
  EXPECT_NE(bad.err.find("--frame"), std::string::npos) << bad.err;
}

TEST_F(Cli, ModelAutoChoosesOnHeldOutError) {
  const std::string ctu =
      kData + "/ctu-innalabs-ahrs-m3/measured_accelerations_49pos.csv --units g --model auto";
  const CliRun r = Exec("calibrate " + ctu + " --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json doc = AccelerometerKeys(r.out);
  // CTU-49: the quadratic model fits better in sample but predicts held-out positions worse
  // (1.085e-3 g against 1.035e-3 g), so the linear model is kept.
  EXPECT_EQ(doc["model"], "linear");
  const auto& s = doc["model_selection"];
  EXPECT_EQ(s["requested"], "auto");
  EXPECT_EQ(s["chosen"], "linear");
  EXPECT_LT(s["linear_crossval_rms"].get<double>(), s["quadratic_crossval_rms"].get<double>());
  EXPECT_EQ(s["k2_t"].size(), 3u);
  EXPECT_EQ(s["reason"].get<std::string>().rfind("the quadratic model does not predict", 0), 0u);
  const CliRun text = Exec("calibrate " + ctu);
  EXPECT_NE(text.out.find("model     auto -> linear"), std::string::npos) << text.out;
  const CliRun bad = Exec("calibrate " + ctu + " --no-crossval");
  EXPECT_EQ(bad.status, 2);
  EXPECT_NE(bad.err.find("--model auto decides on held-out error"), std::string::npos) << bad.err;
}

// design --temperatures: the schedule's bound on each temperature coefficient, the same as the
// library's PredictThermalUncertainty (tested against the Cramér-Rao bound in test_thermal.cpp);
// its 1σ shrinks as 1/√(temperatures) at a fixed span, and too few temperatures are said.
TEST_F(Cli, DesignPlansATemperatureSchedule) {
  ASSERT_EQ(Exec("calibrate " + kData + "/imutk-t265/t265_acc.mat -q --no-crossval -o " +
                 Path("device.json"))
                .status,
            0);
  const std::string base =
      "design --positions yang18 --noise 0.002 --json --device " + Path("device.json");
  const CliRun three = Exec(base + " --temperatures 0,25,50");
  const CliRun five = Exec(base + " --temperatures=0,12.5,25,37.5,50 --thermal-degrees 1,1");
  ASSERT_EQ(three.status, 0) << three.err;
  ASSERT_EQ(five.status, 0) << five.err;
  const auto t3 = nlohmann::json::parse(three.out)["thermal"];
  const auto t5 = nlohmann::json::parse(five.out)["thermal"];
  EXPECT_TRUE(t3["observable"].get<bool>());
  EXPECT_EQ(t3["t_ref"].get<double>(), 25.0);
  ASSERT_EQ(t3["std"].size(), 18u);  // 9 at T_ref, 9 per K
  EXPECT_EQ(t3["order"][9], "K_xx*dT^1");
  // Σ ΔT² over the temperatures: 3·(2/3)·25² against 5·(1/2)·25²: ratio √(1250/1562.5).
  EXPECT_NEAR(t5["std"][9].get<double>() / t3["std"][9].get<double>(), std::sqrt(1250.0 / 1562.5),
              1e-6);
  const CliRun text = Exec("design --positions yang18 --noise 0.002 --device " +
                           Path("device.json") + " --temperatures 20,40 --thermal-degrees 1,2");
  EXPECT_EQ(text.status, 3) << text.err;  // as positions that do not determine the device
  EXPECT_NE(text.out.find("thermal   NOT determined: these temperatures cannot separate degrees "
                          "K:1 b:2: record the orientations at 3 temperatures or more"),
            std::string::npos)
      << text.out;
  EXPECT_EQ(t3["frame"], "x-first");
  ASSERT_EQ(t3["std_engineering"].size(), 9u);
  EXPECT_EQ(t3["std_engineering"][0]["unit"], "ppm/K");
  // Temperatures a sensor's resolution apart determine no slope.
  const CliRun close = Exec(base + " --temperatures 20,20.01");
  EXPECT_EQ(close.status, 3);
  EXPECT_FALSE(nlohmann::json::parse(close.out)["thermal"]["observable"].get<bool>());
  // Positions that do not determine the device: the section says why, in JSON too.
  const CliRun six = Exec("design --positions six --noise 0.002 --json --device " +
                          Path("device.json") + " --temperatures 0,40");
  EXPECT_EQ(six.status, 3);
  EXPECT_EQ(nlohmann::json::parse(six.out)["thermal"]["reason"],
            "the positions do not determine the parameters at one temperature");
  for (const std::string& bad :
       {std::string("--temperatures nan"),
        std::string("--temperatures 20,30 --thermal-degrees 1,1,1"),
        std::string("--temperatures 20,30 --thermal-degrees 4,1"),
        std::string("--temperatures 20,30 --thermal-degrees 0,0"),
        std::string("--temperatures 20,30 --bias-model linear"),
        std::string("--temperatures 20 --temperatures 30"), std::string("--thermal-degrees 1,1")}) {
    EXPECT_EQ(Exec(base + " " + bad).status, 2) << bad;
    // Checked whatever the positions determine.
    EXPECT_EQ(
        Exec("design --positions six --noise 0.002 --device " + Path("device.json") + " " + bad)
            .status,
        2)
        << bad;
  }
}

TEST_F(Cli, DesignPredictsTheBoundBeforeRecording) {
  // The nominal device: the Xsens calibration. Paper 000's 18 positions determine it; the six
  // axis-aligned ones (orientations unknown) do not, and the command says so with status 3.
  const CliRun c = Exec("calibrate " + kData +
                        "/imutk-xsens-mti/xsens_acc.mat --gravity 9.81744 --no-crossval -o " +
                        Path("device.json"));
  ASSERT_EQ(c.status, 0) << c.err;
  const std::string device = " --device " + Path("device.json");
  const CliRun y = Exec("design --positions yang18 --noise 0.12 --json" + device);
  ASSERT_EQ(y.status, 0) << y.err;
  const nlohmann::json doc = nlohmann::json::parse(y.out);
  EXPECT_EQ(doc["positions"], 18);
  EXPECT_TRUE(doc["observable"].get<bool>());
  EXPECT_EQ(doc["crlb"].size(), 9u);
  // σ_b ≈ σ·√(1/6·...) : every bias std is positive and below the reading noise.
  for (int i = 0; i < 3; ++i) {
    EXPECT_GT(doc["std"]["bias"][i].get<double>(), 0.0);
    EXPECT_LT(doc["std"]["bias"][i].get<double>(), 0.12);
  }
  // The same positions as attitudes (orientation_file.hpp: pitch = asin(−c_x), roll = atan2(c_y,
  // c_z)) give the same bound, to the 17 digits written.
  std::string attitudes = "roll_deg,pitch_deg,yaw_deg\n";
  for (const Vec3& up : Yang18Directions()) {
    char line[128];
    std::snprintf(line, sizeof line, "%.17g,%.17g,30\n", std::atan2(up(1), up(2)) * 180 / M_PI,
                  std::asin(-up(0)) * 180 / M_PI);
    attitudes += line;
  }
  const CliRun att =
      Exec("design --positions " + Write("att.csv", attitudes) + " --noise 0.12 --json" + device);
  ASSERT_EQ(att.status, 0) << att.err;
  const nlohmann::json att_doc = nlohmann::json::parse(att.out);
  for (int i = 0; i < 9; ++i) {
    EXPECT_NEAR(att_doc["crlb"][i][i].get<double>(), doc["crlb"][i][i].get<double>(),
                1e-9 * doc["crlb"][i][i].get<double>());
  }
  const CliRun six = Exec("design --positions six --noise 0.12" + device);
  EXPECT_EQ(six.status, 3);
  EXPECT_NE(six.out.find("NOT OBSERVABLE"), std::string::npos) << six.out;
  // The reason on stderr too, where a caller of the status (Python's InputError) reads it.
  EXPECT_NE(six.err.find("these positions do not determine parameter"), std::string::npos)
      << six.err;
  const std::string bad = Write("dirs.csv", "x,y,z\n1,0,0\n0,2,0\n");
  const CliRun b = Exec("design --positions " + bad + " --noise 0.1" + device);
  EXPECT_EQ(b.status, 3);
  EXPECT_NE(b.err.find("direction 2 (0, 2, 0) is not a unit vector"), std::string::npos) << b.err;
  EXPECT_EQ(Exec("design --positions yang18 --noise 0.1,0.2" + device).status, 2);
  // D-optimal choice of 18 among 200 candidates, compared with yang18.
  const CliRun d = Exec("design --positions random:200 --choose 18 --noise 0.12 --json" + device);
  ASSERT_EQ(d.status, 0) << d.err;
  const nlohmann::json chosen = nlohmann::json::parse(d.out);
  EXPECT_EQ(chosen["positions"], 18);
  EXPECT_EQ(chosen["chosen"].size(), 18u);
  EXPECT_NE(chosen["choice"].get<std::string>().find("D-optimal 18 of 200"), std::string::npos);
  EXPECT_NE(chosen["choice"].get<std::string>().find("A-efficiency"), std::string::npos);
  const CliRun a =
      Exec("design --positions random:200 --choose 18 --criterion a --noise 0.12 --json" + device);
  ASSERT_EQ(a.status, 0) << a.err;
  EXPECT_NE(nlohmann::json::parse(a.out)["choice"].get<std::string>().find("A-optimal 18 of 200"),
            std::string::npos);
  EXPECT_EQ(
      Exec("design --positions random:200 --choose 18 --criterion e --noise 0.12" + device).status,
      2);
  EXPECT_EQ(Exec("design --positions random:200 --choose 5 --noise 0.12" + device).status, 2);
  // The noise from a density: 10 ug/sqrt(Hz) at 100 Hz averaged over 60 s is 1.29 ug, times the
  // length of K's row (raw per m/s2) and the device's gravity per g.
  const CliRun nd = Exec(
      "design --positions yang18 --noise-density 10 --rate 100 --duration 60 "
      "--json" +
      device);
  ASSERT_EQ(nd.status, 0) << nd.err;
  const nlohmann::json dev = AccelerometerKeys(Slurp(Path("device.json")));
  double row0 = 0;
  for (int j = 0; j < 3; ++j) row0 += std::pow(dev["K"][0][j].get<double>(), 2);
  EXPECT_NEAR(nlohmann::json::parse(nd.out)["noise_raw"][0].get<double>(),
              std::sqrt(row0) * 10e-6 * 9.81744 * std::sqrt(100.0 / 6000.0), 1e-12);
  EXPECT_EQ(Exec("design --positions yang18 --noise-density 10" + device).status, 2);
}

TEST_F(Cli, MonteCarloPrintsTable4AgainstTheBound) {
  const CliRun r = Exec("montecarlo --scenario yang2012 --runs 60 --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json doc = nlohmann::json::parse(r.out);
  EXPECT_EQ(doc["scenario"], "yang2012");
  EXPECT_EQ(doc["method"], "joint");
  EXPECT_EQ(doc["runs"], 60);
  const std::vector<std::string> names = {"ka_x",   "ka_y",   "ka_z",   "tau_yx", "tau_zx",
                                          "tau_zy", "tau_yy", "tau_zz", "p0_x",   "p0_y",
                                          "p0_z",   "k2_x",   "k2_y",   "k2_z"};
  ASSERT_EQ(doc["parameters"].size(), names.size());
  for (std::size_t i = 0; i < names.size(); ++i) {
    const auto& p = doc["parameters"][i];
    EXPECT_EQ(p["name"], names[i]);
    for (const char* key :
         {"unit", "min", "max", "mean", "median", "std", "rmse", "crlb", "ratio", "rmse_ratio"}) {
      EXPECT_TRUE(p.contains(key)) << names[i] << " " << key;
    }
  }
  // Same seed, same bytes.
  EXPECT_EQ(Exec("montecarlo --runs 60 --json --threads 1").out, r.out);
  EXPECT_EQ(Exec("montecarlo --scenario nonesuch").status, 2);
  EXPECT_EQ(doc["estimator"], "ml");
  EXPECT_EQ(r.err, "");  // no progress bar when stderr is not a terminal
  const CliRun sx =
      Exec("montecarlo --scenario sunxu2020 --runs 10 --json --estimator bias-corrected");
  ASSERT_EQ(sx.status, 0) << sx.err;
  const nlohmann::json sunxu = nlohmann::json::parse(sx.out);
  EXPECT_EQ(sunxu["estimator"], "bias-corrected");
  ASSERT_EQ(sunxu["parameters"].size(), 9u);  // the flat parameters, z-first
  EXPECT_EQ(sunxu["parameters"][0]["name"], "K_zz");
  EXPECT_EQ(sunxu["diag_T_bias"].size(), 3u);
  EXPECT_GT(sunxu["e_T_percent_mean"].get<double>(), 0.0);
  EXPECT_EQ(Exec("montecarlo --method modulus").status, 2);
}

TEST_F(Cli, SimulateWritesRecordingsThatCalibrateBackToTheTruth) {
  // Paper 000's scenario as a raw log: 18 intervals detected, the Table-3 biases recovered
  // (b = k_a · p0: 48, 98, 150 raw, 0.074 raw 1σ at most).
  const CliRun s = Exec("simulate --scenario yang2012 --raw -o " + Path("log.csv"));
  ASSERT_EQ(s.status, 0) << s.err;
  const CliRun c = Exec("calibrate " + Path("log.csv") +
                        " --gravity 9.8 --model quadratic --json --no-crossval");
  ASSERT_EQ(c.status, 0) << c.err;
  const nlohmann::json doc = AccelerometerKeys(c.out);
  EXPECT_EQ(doc["positions"].size(), 18u);
  const double expected[3] = {48.0, 98.0, 150.0};
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(doc["bias"][i].get<double>(), expected[i],
                4.5 * doc["std"]["bias"][i].get<double>());
  }
  EXPECT_EQ(doc["noise"]["source"], "samples");
  // Positions files too, deterministic in the seed.
  const CliRun p1 = Exec("simulate --scenario yang2012 --seed 7");
  const CliRun p2 = Exec("simulate --scenario yang2012 --seed 7");
  ASSERT_EQ(p1.status, 0) << p1.err;
  EXPECT_EQ(p1.out, p2.out);
  EXPECT_NE(p1.out, Exec("simulate --scenario yang2012 --seed 8").out);
  EXPECT_EQ(p1.out.rfind("x,y,z,n,sx,sy,sz\n", 0), 0u);
  EXPECT_EQ(Exec("simulate").status, 2);
  // Paper 001's scenario: 300 averaged readings in g whose fit is biased as
  // docs/errata.md#001-ml-bias says, but calibrates to about 1 % (e_T ~ 0.9 %).
  const CliRun sx = Exec("simulate --scenario sunxu2020 -o " + Path("sunxu.csv"));
  ASSERT_EQ(sx.status, 0) << sx.err;
  const CliRun sc =
      Exec("calibrate " + Path("sunxu.csv") + " --units g --frame z-first --no-crossval --json");
  ASSERT_EQ(sc.status, 0) << sc.err;
  const nlohmann::json sd = AccelerometerKeys(sc.out);
  EXPECT_EQ(sd["positions"].size(), 300u);
  EXPECT_EQ(sd["noise"]["source"], "samples");
  EXPECT_NEAR(sd["K"][0][0].get<double>(), 1.15, 0.05);  // eq. (19): T_a(0,0) = 1.15
  EXPECT_EQ(sd["solver"]["estimator"], "ml");
  // The bias-corrected estimate lowers each diagonal entry by about σ²/T_ii ≈ 0.0087 (0.1 g noise,
  // calibrate.hpp); the shift is deterministic given the data, up to the O(σ⁴) terms: ±20 %.
  const CliRun bc =
      Exec("calibrate " + Path("sunxu.csv") +
           " --units g --frame z-first --no-crossval --json --estimator bias-corrected");
  ASSERT_EQ(bc.status, 0) << bc.err;
  const nlohmann::json bd = AccelerometerKeys(bc.out);
  EXPECT_EQ(bd["solver"]["estimator"], "bias-corrected");
  EXPECT_GE(bd["solver"]["correction_rounds"].get<int>(), 1);
  for (int i = 0; i < 3; ++i) {
    const double shift = sd["K"][i][i].get<double>() - bd["K"][i][i].get<double>();
    EXPECT_NEAR(shift, 0.01 / sd["K"][i][i].get<double>(), 0.2 * 0.01 / sd["K"][i][i].get<double>())
        << i;
  }
  EXPECT_EQ(Exec("calibrate " + Path("sunxu.csv") + " --estimator unbiased").status, 2);
  EXPECT_EQ(Exec("calibrate " + Path("sunxu.csv") + " --method modulus --estimator bias-corrected")
                .status,
            2);
  EXPECT_EQ(Exec("simulate --scenario sunxu2020 --raw").status, 2);
  EXPECT_EQ(Exec("simulate --scenario yang2012 --rate 0").status, 2);
}

TEST_F(Cli, PositionsFileInG) {
  const CliRun r = Exec("calibrate " + kData +
                        "/ctu-innalabs-ahrs-m3/measured_accelerations_24pos.csv --units g --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json doc = AccelerometerKeys(r.out);
  EXPECT_EQ(doc["units"]["specific_force"], "g");
  EXPECT_EQ(doc["gravity"], 1.0);
  EXPECT_LT(doc["gravity_norm_rms_after"].get<double>(),
            doc["gravity_norm_rms_before"].get<double>());
}

// From a hostile test: a file name is the user's, and may hold a line feed or a terminal's
// control sequence. Every message line shows it escaped: "verdict   ok" in a name cannot make a
// line of its own in a run that failed, nor ESC [2J clear the screen.
TEST_F(Cli, FileNamesCannotMakeLinesOfTheirOwn) {
  // Each odd name alone in its folder, given by a glob (the test's shell has no $'...').
  fs::create_directories(Path("odd"));
  fs::copy_file(kData + "/ctu-innalabs-ahrs-m3/measured_accelerations_24pos.csv",
                Path("odd/n\nverdict   ok\n\x1b[2J\u202ex.csv"));
  CliRun r = Exec("calibrate " + Path("odd") + "/n*x.csv --units g -o " + Path("out.json"));
  ASSERT_EQ(r.status, 0) << r.err;
  // One verdict line: the run's own.
  EXPECT_EQ(r.out.find("\nverdict "), r.out.rfind("\nverdict ")) << r.out;
  for (const std::string* text : {&r.out, &r.err}) {
    EXPECT_EQ(text->find('\x1b'), std::string::npos) << *text;
    EXPECT_EQ(text->find("\u202e"), std::string::npos) << *text;
  }
  EXPECT_NE(r.out.find("n\\nverdict   ok\\n\\x1B[2J\\u202Ex.csv: 24 positions"), std::string::npos)
      << r.out;
  // An error naming the file, on stderr.
  fs::create_directories(Path("bad"));
  Write("bad/b\nverdict   ok.csv", "x,y,z\n1,2\n");
  r = Exec("calibrate " + Path("bad") + "/b*.csv");
  EXPECT_EQ(r.status, 3);
  EXPECT_EQ(r.err.find("\nverdict   ok"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("b\\nverdict   ok.csv"), std::string::npos) << r.err;
}

TEST_F(Cli, ApplyInvertsTheQuadraticModelAndConvertsUnits) {
  // A quadratic calibration in g from the CTU set, applied to a 3-column log of its own readings:
  // every corrected reading must have |f| close to 1 g, and m/s2 output is 9.80665 times larger.
  const std::string positions = kData + "/ctu-innalabs-ahrs-m3/measured_accelerations_49pos.csv";
  const CliRun c =
      Exec("calibrate " + positions + " --units g --model quadratic -o " + Path("cal.json"));
  ASSERT_EQ(c.status, 0) << c.err;
  const CliRun g = Exec("apply " + Path("cal.json") + " " + positions + " --rate 1");
  const CliRun ms2 = Exec("apply " + Path("cal.json") + " " + positions + " --rate 1 --units m/s2");
  ASSERT_EQ(g.status, 0) << g.err;
  ASSERT_EQ(ms2.status, 0) << ms2.err;
  std::istringstream a(g.out), b(ms2.out);
  std::string line_a, line_b;
  std::getline(a, line_a);
  std::getline(a, line_a);
  EXPECT_EQ(line_a, "x,y,z");
  std::getline(b, line_b);
  std::getline(b, line_b);
  int rows = 0;
  double x, y, z, X, Y, Z;
  char sep;
  while (a >> x >> sep >> y >> sep >> z && b >> X >> sep >> Y >> sep >> Z) {
    // The fit's residuals are below 0.003 g on this set (RMS 0.0008 g).
    EXPECT_NEAR(std::sqrt(x * x + y * y + z * z), 1.0, 0.003);
    EXPECT_NEAR(X, 9.80665 * x, 1e-12 * std::abs(X) + 1e-15);
    ++rows;
  }
  EXPECT_EQ(rows, 49);
}

TEST_F(Cli, QuietSaysNothingAndVerboseAddsDiagnosticsOnStderr) {
  const std::string log = kData + "/imutk-xsens-mti/xsens_acc.mat";
  const CliRun quiet = Exec("calibrate " + log + " --no-crossval -q -o " + Path("q.json"));
  ASSERT_EQ(quiet.status, 0) << quiet.err;
  EXPECT_EQ(quiet.out, "");
  EXPECT_EQ(quiet.err, "");
  EXPECT_TRUE(fs::exists(Path("q.json")));  // results still go where asked
  const CliRun normal = Exec("calibrate " + log + " --no-crossval -o " + Path("n.json"));
  const CliRun verbose = Exec("--verbose calibrate " + log + " --no-crossval -o " + Path("v.json"));
  ASSERT_EQ(verbose.status, 0) << verbose.err;
  // The diagnostics go to stderr only: stdout is the usual summary (whose solver time varies).
  EXPECT_EQ(verbose.out.substr(0, verbose.out.find("solver ")),
            normal.out.substr(0, normal.out.find("solver ")));
  EXPECT_EQ(normal.err, "");
  EXPECT_NE(verbose.err.find("detection: 100.01 Hz, window 51 samples"), std::string::npos)
      << verbose.err;
  EXPECT_NE(verbose.err.find("done in "), std::string::npos) << verbose.err;
  EXPECT_EQ(Slurp(Path("q.json")), Slurp(Path("v.json")));
  EXPECT_EQ(Exec("-q -v calibrate " + log).status, 2);
  // --json is a result: quiet keeps it.
  const CliRun json = Exec("calibrate " + log + " --no-crossval --json --quiet");
  EXPECT_EQ(json.out, Slurp(Path("q.json")));
}

TEST_F(Cli, ExportWritesTheTargetFormatAndSaysWhatItDrops) {
  // Paper 001's simulated readings are in g: a calibration PX4 can take (offsets and scales in
  // m/s², misalignments dropped and measured).
  ASSERT_EQ(Exec("simulate --scenario sunxu2020 -o " + Path("sunxu.csv")).status, 0);
  const CliRun c = Exec("calibrate " + Path("sunxu.csv") +
                        " --units g --raw-units g --no-crossval -o " + Path("cal.json"));
  ASSERT_EQ(c.status, 0) << c.err;
  const CliRun px4 = Exec("export " + Path("cal.json") + " --to px4 --instance 1");
  ASSERT_EQ(px4.status, 0) << px4.err;
  EXPECT_NE(px4.out.find("\tCAL_ACC1_XOFF\t"), std::string::npos) << px4.out;
  EXPECT_NE(px4.out.find("\tCAL_ACC1_ZSCALE\t"), std::string::npos) << px4.out;
  EXPECT_NE(px4.err.find("dropped: the misalignments (K's off-diagonal terms)"), std::string::npos)
      << px4.err;
  EXPECT_NE(px4.err.find("on the calibration's 300 positions"), std::string::npos) << px4.err;
  // With -o the export goes to the file, the note to stdout; the file is the same text.
  const CliRun to_file =
      Exec("export " + Path("cal.json") + " --to px4 --instance 1 -o " + Path("cal.params"));
  ASSERT_EQ(to_file.status, 0) << to_file.err;
  EXPECT_EQ(Slurp(Path("cal.params")), px4.out);
  EXPECT_NE(to_file.out.find("dropped:"), std::string::npos);
  const CliRun header = Exec("export " + Path("cal.json") + " --to c-header");
  ASSERT_EQ(header.status, 0) << header.err;
  EXPECT_NE(header.err.find("exact: nothing of the model is dropped"), std::string::npos);
  // Refusals: an unknown format is a usage error; a raw unit PX4 cannot take names the file.
  const CliRun unknown = Exec("export " + Path("cal.json") + " --to csv");
  EXPECT_EQ(unknown.status, 2);
  EXPECT_NE(unknown.err.find("--to"), std::string::npos) << unknown.err;
  ASSERT_EQ(Exec("calibrate " + Path("sunxu.csv") +
                 " --units g --raw-units counts --no-crossval -o " + Path("counts.json"))
                .status,
            0);
  const CliRun counts =
      Exec("export " + Path("counts.json") + " --to ardupilot -o " + Path("never.param"));
  EXPECT_EQ(counts.status, 3);
  EXPECT_NE(counts.err.find(Path("counts.json") + ": ArduPilot applies its calibration to readings "
                                                  "already in m/s2"),
            std::string::npos)
      << counts.err;
  EXPECT_FALSE(fs::exists(Path("never.param")));
}

TEST_F(Cli, KnownOrientationsCalibrateImucalsFerrarisHolds) {
  // Six axis-aligned holds (raw counts) with their known directions: the full misalignment in the
  // platform frame (paper 003), a file apply reads, and the corrected holds within 0.045 m/s² of
  // gravity along their axes (test_known_orientation: the holds disagree by that much).
  const std::string dir = kData + "/imucal-ferraris/";
  const std::string args = "calibrate " + dir + "ferraris_raw_means.csv --orientations " + dir +
                           "ferraris_orientations.csv --gravity 9.81 --raw-units counts";
  const CliRun c = Exec(args + " -o " + Path("platform.json"));
  ASSERT_EQ(c.status, 0) << c.err;
  EXPECT_NE(c.out.find("frame platform"), std::string::npos) << c.out;
  EXPECT_NE(c.out.find("beta_xz, beta_xy, beta_yz, beta_yx, beta_zy, beta_zx"), std::string::npos)
      << c.out;
  const nlohmann::json doc = AccelerometerKeys(Slurp(Path("platform.json")));
  EXPECT_EQ(doc["frame"], "platform");
  EXPECT_EQ(doc["solver"]["method"], "known-orientation");
  EXPECT_EQ(doc["parameter_order"][1], "K_xy");
  EXPECT_EQ(doc["engineering"]["misalignment_rad"].size(), 6u);
  EXPECT_EQ(doc["covariance"].size(), 12u);
  EXPECT_NE(doc["K"][0][1].get<double>(), 0.0);  // full K
  EXPECT_NE(doc["K"][1][0].get<double>(), 0.0);
  // apply reads the full K: each hold corrected to K⁻¹(p − b), within 0.1 m/s² (a 0.6° tilt of
  // the hand-placed holds; the fit's residuals) of gravity along its axis.
  Mat33 K;
  Vec3 bias;
  for (int i = 0; i < 3; ++i) {
    bias(i) = doc["bias"][i].get<double>();
    for (int j = 0; j < 3; ++j) K(i, j) = doc["K"][i][j].get<double>();
  }
  std::string log = "x,y,z\n";
  std::vector<Vec3> holds;
  for (const auto& position : doc["positions"]) {
    holds.emplace_back(position["mean"][0].get<double>(), position["mean"][1].get<double>(),
                       position["mean"][2].get<double>());
    char row[128];
    std::snprintf(row, sizeof row, "%.17g,%.17g,%.17g\n", holds.back()(0), holds.back()(1),
                  holds.back()(2));
    log += row;
  }
  const std::vector<Vec3> up = {Vec3::UnitX(),  -Vec3::UnitX(), Vec3::UnitY(),
                                -Vec3::UnitY(), Vec3::UnitZ(),  -Vec3::UnitZ()};
  const CliRun a =
      Exec("apply " + Path("platform.json") + " " + Write("holds.csv", log) + " --rate 1");
  ASSERT_EQ(a.status, 0) << a.err;
  std::istringstream out(a.out);
  std::string line;
  std::getline(out, line);  // comment
  std::getline(out, line);  // header
  double x, y, z;
  char sep;
  std::size_t k = 0;
  while (out >> x >> sep >> y >> sep >> z) {
    ASSERT_LT(k, up.size());
    const Vec3 expected = K.inverse() * (holds[k] - bias);
    EXPECT_LT((Vec3(x, y, z) - expected).norm(), 1e-9) << k;
    EXPECT_LT((Vec3(x, y, z) - 9.81 * up[k]).norm(), 0.1) << k;
    ++k;
  }
  EXPECT_EQ(k, 6u);
  // Refusals: options of the orientation-free fit, and a count that does not match.
  EXPECT_EQ(Exec(args + " --method joint").status, 2);
  EXPECT_EQ(Exec(args + " --model auto").status, 2);
  const CliRun mismatch = Exec("calibrate " + dir + "ferraris_raw_means.csv --orientations " +
                               Write("five.csv", "1,0,0\n-1,0,0\n0,1,0\n0,-1,0\n0,0,1\n"));
  EXPECT_EQ(mismatch.status, 3);
  EXPECT_NE(mismatch.err.find("has 5 orientations for the 6 positions"), std::string::npos)
      << mismatch.err;
}

TEST_F(Cli, KnownOrientationsScreenAPositionSetInAnotherOrientation) {
  // 16 positions of a turntable with known directions (ν − 3 = 48 − 12 − 3 = 33); the fixture of
  // position 4 stood 2° off the orientation its line gives (|f| unchanged: only known orientations
  // can see it). The F test of known_orientation.hpp leaves it out, warns, and the file lists it;
  // --outliers off keeps it, and the options of the orientation-free fit remain refused.
  const std::vector<Vec3> directions = RandomDirections(16, 4);
  std::vector<Vec3> actual = directions;
  actual[3] = Eigen::AngleAxisd(2.0 * M_PI / 180.0, Vec3::UnitX()) * directions[3];
  const std::vector<Vec3> readings =
      SimulatePositions(Yang2012Truth(), 9.8, actual, Vec3(0.01, 0.01, 0.01), 5);
  std::string means = "x,y,z\n", orientations = "x,y,z\n";
  char line[160];
  for (std::size_t k = 0; k < readings.size(); ++k) {
    std::snprintf(line, sizeof line, "%.17g,%.17g,%.17g\n", readings[k](0), readings[k](1),
                  readings[k](2));
    means += line;
    std::snprintf(line, sizeof line, "%.17g,%.17g,%.17g\n", directions[k](0), directions[k](1),
                  directions[k](2));
    orientations += line;
  }
  const std::string args = "calibrate " + Write("turntable.csv", means) + " --orientations " +
                           Write("orientations.csv", orientations) + " --gravity 9.8";
  const CliRun r = Exec(args + " -o " + Path("turntable.json"));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("position 4 disagrees with the others"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("(Fisher F, 3 and 33 degrees of freedom)"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("It was left out of the fit."), std::string::npos) << r.err;
  const nlohmann::json doc = AccelerometerKeys(Slurp(Path("turntable.json")));
  ASSERT_EQ(doc["outliers"].size(), 1u);
  EXPECT_EQ(doc["outliers"][0]["position"], 4);
  EXPECT_EQ(doc["outliers"][0]["statistic"], "F");
  EXPECT_EQ(doc["positions"][3]["excluded"], true);
  const CliRun off = Exec(args + " --outliers off --json");
  ASSERT_EQ(off.status, 0) << off.err;
  EXPECT_EQ(off.err, "");
  EXPECT_TRUE(AccelerometerKeys(off.out)["outliers"].empty());
  EXPECT_EQ(Exec(args + " --outlier-probability 2").status, 2);
  EXPECT_EQ(Exec(args + " --estimator bias-corrected").status, 2);
}

// --bias-model: the T265 session drifts, and the linear bias that auto chooses halves the held-out
// error; what it needs (times, the joint fit, no gyroscope) is said when missing.
// A spline of many knots with a random-walk prior follows the T265's wandering bias: the held-out
// error falls below the linear drift's 0.346 mg (issue 21's aim of 0.34 mg); the prior is in the
// file, and the option is refused where it would be ignored or wrong.
TEST_F(Cli, BiasRandomWalkPriorOnTheT265) {
  const std::string t265 = kData + "/imutk-t265/t265_acc.mat";
  const CliRun r = Exec("calibrate " + t265 +
                        " --bias-model spline:12 --bias-random-walk 3e-4 -o " + Path("rw.json"));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("prior     bias random walk 0.0003 0.0003 0.0003 m/s^2/sqrt(s) "
                       "(--bias-random-walk): 0.000298 0.000295 0.000295 raw/sqrt(s)"),
            std::string::npos)
      << r.out;
  const nlohmann::json doc = AccelerometerKeys(Slurp(Path("rw.json")));
  EXPECT_LT(doc["crossval_rms"].get<double>(), 0.34e-3 * 9.80665);
  ASSERT_EQ(doc["bias_drift"]["random_walk"].size(), 3u);
  EXPECT_NEAR(doc["bias_drift"]["random_walk"][0].get<double>(), 2.98e-4, 0.01e-4);
  EXPECT_GT(doc["noise"]["sigma_raw"].get<double>(), 0);  // not "fitted to round-off"
  EXPECT_EQ(r.err.find("round-off"), std::string::npos) << r.err;
  // It reads back, and a drift whose prior is not positive is refused naming the key.
  ASSERT_EQ(Exec("report " + Path("rw.json") + " -o " + Path("rw.html")).status, 0);
  {
    nlohmann::json edited = nlohmann::json::parse(Slurp(Path("rw.json")));
    edited["sensors"]["accelerometer"]["bias_drift"]["random_walk"][1] = -1.0;
    std::ofstream(Path("rw-edited.json")) << edited.dump();
    const CliRun refused = Exec("export " + Path("rw-edited.json") + " --to imutk");
    EXPECT_EQ(refused.status, 3) << refused.err;
    EXPECT_NE(refused.err.find("random_walk' must be positive"), std::string::npos) << refused.err;
  }
  // Under auto the prior goes with the spline candidates; a line chosen leaves it unused, said.
  const CliRun chosen = Exec("calibrate " + t265 + " --bias-model auto --bias-random-walk 3e-4");
  ASSERT_EQ(chosen.status, 0) << chosen.err;
  EXPECT_NE(chosen.out.find("unused: the bias chosen is linear, and the prior is a spline's"),
            std::string::npos)
      << chosen.out;
  for (const std::string& bad :
       {std::string("--bias-random-walk 3e-4"), std::string("--bias-model linear --noise x.json"),
        std::string("--bias-model spline:4 --bias-random-walk 0"),
        std::string("--bias-model spline:4 --bias-random-walk -1e-4"),
        std::string("--bias-model spline:4 --bias-random-walk nan"),
        std::string("--bias-model spline:4 --bias-random-walk inf"),
        std::string("--bias-model spline:4 --bias-random-walk 1e300"),
        std::string("--bias-model spline:4 --bias-random-walk 1e-4,1e-200,1e-4"),
        std::string("--bias-model spline:4 --bias-random-walk 1e-4,2e-4"),
        std::string("--bias-model spline:4 --bias-random-walk 1e-4 --bias-random-walk 2e-4"),
        std::string("--bias-model spline:4 --bias-random-walk 1e-4 --noise x.json"),
        std::string("--bias-model spline:4 --bias-random-walk 1e-4 --orientations x.txt")}) {
    const CliRun b = Exec("calibrate " + t265 + " " + bad);
    EXPECT_EQ(b.status, 2) << bad << ": " << b.err;
  }
  // A q far larger than the bias wanders widens every uncertainty: said, not passed silently.
  const CliRun loose =
      Exec("calibrate " + t265 + " --bias-model spline:8 --bias-random-walk 0.1 -o " +
           Path("loose.json"));
  EXPECT_EQ(loose.status, 0) << loose.err;
  EXPECT_NE(loose.err.find("q is larger than this bias wanders"), std::string::npos) << loose.err;
  EXPECT_EQ(loose.out.find("inf"), std::string::npos) << loose.out;
  // Positions without samples have no noise to weigh them by.
  const CliRun means = Exec("calibrate " + kData +
                            "/imutk-t265/derived_static_means.csv --bias-model spline:4 "
                            "--bias-random-walk 3e-4");
  EXPECT_EQ(means.status, 3) << means.err;
  EXPECT_NE(means.err.find("weighs each position by the noise of its samples"), std::string::npos)
      << means.err;
}

TEST_F(Cli, BiasModelFollowsTheT265Drift) {
  const std::string t265 = kData + "/imutk-t265/t265_acc.mat";
  const CliRun r = Exec("calibrate " + t265 + " --bias-model auto --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json doc = AccelerometerKeys(r.out);
  EXPECT_EQ(doc["bias_model_selection"]["chosen"], "linear");
  const auto& steps = doc["bias_model_selection"]["steps"];
  ASSERT_EQ(steps.size(), 5u);  // linear accepted, spline:3 … spline:6 not
  EXPECT_TRUE(steps[0]["accepted"].get<bool>());
  for (std::size_t i = 1; i < 5; ++i) EXPECT_FALSE(steps[i]["accepted"].get<bool>()) << i;
  EXPECT_LT(doc["crossval_rms"].get<double>(), 0.40e-3 * 9.80665);
  const auto& drift = doc["bias_drift"];
  EXPECT_EQ(drift["model"], "linear");
  EXPECT_NEAR(drift["D"][0][0].get<double>(), -0.00652, 0.0001);  // m/s2 per minute
  EXPECT_EQ(drift["covariance"].size(), 12u);                     // 9 parameters and D
  EXPECT_TRUE(doc["positions"][0].contains("time"));
  EXPECT_TRUE(doc["positions"][0].contains("drift_offset"));
  // The rest's drift is a note once the fit's bias follows it.
  EXPECT_EQ(r.err.find("drifts"), std::string::npos) << r.err;
  const CliRun text = Exec("calibrate " + t265 + " --bias-model linear -o " + Path("l.json") +
                           " --report " + Path("l.html"));
  ASSERT_EQ(text.status, 0) << text.err;
  // The report shows the drift; the file reads back with it, and its report again.
  const std::string html = Slurp(Path("l.html"));
  EXPECT_NE(html.find("<h2>Bias over the session</h2>"), std::string::npos);
  EXPECT_NE(html.find("linear bias)"), std::string::npos);
  EXPECT_EQ(html.find("nan"), std::string::npos);
  const CliRun again = Exec("report " + Path("l.json") + " -o " + Path("again.html"));
  ASSERT_EQ(again.status, 0) << again.err;
  EXPECT_NE(Slurp(Path("again.html")).find("<polygon"), std::string::npos);
  // A hand-edited drift that no reading survives is refused when read, not reported as inf.
  {
    nlohmann::json edited = nlohmann::json::parse(Slurp(Path("l.json")));
    edited["sensors"]["accelerometer"]["bias_drift"]["D"][0][0] = 1e300;
    std::ofstream(Path("edited.json")) << edited.dump();
    const CliRun refused = Exec("export " + Path("edited.json") + " --to imutk");
    EXPECT_EQ(refused.status, 3) << refused.err;
    EXPECT_NE(refused.err.find("bias_drift' at the time of positions[0] leaves a reading the "
                               "model cannot invert"),
              std::string::npos)
        << refused.err;
  }
  EXPECT_NE(text.out.find("bias drift linear: b(t) = b + D (t - t_ref)"), std::string::npos);
  EXPECT_NE(text.out.find("note      the longest still interval"), std::string::npos);
  const CliRun constant = Exec("calibrate " + t265);
  EXPECT_NE(constant.err.find("(--bias-model auto fits a bias that follows time)"),
            std::string::npos)
      << constant.err;

  for (const char* bad : {"spline:1", "spline:33", "spline", "linear:2", "quadratic", ""}) {
    const CliRun b = Exec("calibrate " + t265 + " --bias-model '" + bad + "'");
    EXPECT_EQ(b.status, 2) << bad;
    EXPECT_NE(b.err.find("--bias-model"), std::string::npos) << bad << ": " << b.err;
  }
  const CliRun means =
      Exec("calibrate " + kData + "/imutk-t265/derived_static_means.csv --bias-model linear");
  EXPECT_EQ(means.status, 3) << means.err;
  EXPECT_NE(means.err.find("holds the positions' means without their times"), std::string::npos)
      << means.err;
  const CliRun auto_means =
      Exec("calibrate " + kData + "/imutk-t265/derived_static_means.csv --bias-model auto");
  EXPECT_EQ(auto_means.status, 0) << auto_means.err;
  EXPECT_NE(auto_means.out.find("bias      auto -> constant: no position has a time"),
            std::string::npos)
      << auto_means.out;
  for (const std::string& other :
       {std::string("--method two-step"), std::string("--estimator bias-corrected"),
        std::string("--no-crossval"), "--gyro " + kData + "/imutk-t265/t265_gyr.mat"}) {
    const CliRun b = Exec("calibrate " + t265 + " --bias-model auto " + other);
    EXPECT_EQ(b.status, 2) << other << ": " << b.err;
  }
  // A pause of 1000 s in the session: the drift is fitted across it, and the tool says so.
  {
    std::istringstream in(Slurp(t265));
    std::ofstream out(Path("gap.txt"));
    std::string line;
    for (int row = 0; std::getline(in, line); ++row) {
      if (row >= 32000) {
        std::istringstream fields(line);
        double t = 0;
        fields >> t;
        std::string rest;
        std::getline(fields, rest);
        char time[64];
        std::snprintf(time, sizeof time, "%.6f", t + 1000.0);
        line = time + rest;
      }
      out << line << "\n";
    }
  }
  const CliRun gap = Exec("calibrate " + Path("gap.txt") + " --bias-model linear");
  EXPECT_EQ(gap.status, 0) << gap.err;
  EXPECT_NE(gap.err.find("(1010 s, 171 times the median pause): the linear bias is fitted across"),
            std::string::npos)
      << gap.err;
  EXPECT_EQ(text.err.find("median pause"), std::string::npos) << text.err;
  const CliRun known =
      Exec("calibrate " + kData + "/imucal-ferraris/ferraris_raw_means.csv --orientations " +
           kData + "/imucal-ferraris/ferraris_orientations.csv --bias-model linear");
  EXPECT_EQ(known.status, 2) << known.err;
  EXPECT_NE(known.err.find("--bias-model"), std::string::npos) << known.err;
}

}  // namespace
}  // namespace accelcal
