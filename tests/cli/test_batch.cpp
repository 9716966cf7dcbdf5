// accelcal batch as a production line runs it: 200 simulated units with known parameters, some out
// of the MEMS example's limits, some with a bumped position or too few positions; every verdict,
// the same bytes whatever the number of jobs, a resumed batch, and a unit's file as calibrate's.
#include <sys/stat.h>

#include <cmath>
#include <random>
#include <set>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "accelcal/simulate.hpp"
#include "support/cli_test.hpp"

namespace accelcal {
namespace {

using test::CliRun;
using test::Slurp;
namespace fs = std::filesystem;

enum class Plan { kGood, kBias, kScale, kBumped, kFew };

Plan PlanOf(int unit) {
  if (unit % 25 == 0) return Plan::kFew;
  switch (unit % 10) {
    case 3:
      return Plan::kBias;
    case 6:
      return Plan::kScale;
    case 9:
      return Plan::kBumped;
    default:
      return Plan::kGood;
  }
}

// A unit's 18 positions (paper 000's scheme) as a positions file: a MEMS part read in m/s2 with
// scale factors within 1 %, misalignments within 5 mrad and biases within 0.2 m/s2 (the example's
// limits: 3 %, 20 mrad, 0.5 m/s2), each mean with 2 mm/s2 of noise.
std::string UnitPositions(int unit, Plan plan, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  ModelParameters truth;
  for (int a = 0; a < 3; ++a) truth.K(a, a) = 1 + 0.01 * u(rng);
  truth.K(1, 0) = 0.005 * u(rng);
  truth.K(2, 0) = 0.005 * u(rng);
  truth.K(2, 1) = 0.005 * u(rng);
  truth.bias = Vec3(0.2 * u(rng), 0.2 * u(rng), 0.2 * u(rng));
  if (plan == Plan::kBias) truth.bias(0) = 0.8;    // abs_max 0.5 m/s2
  if (plan == Plan::kScale) truth.K(1, 1) = 1.05;  // max 1.03
  std::vector<Vec3> directions = Yang18Directions();
  if (plan == Plan::kFew) directions.resize(6);  // the linear model needs 9
  std::vector<Vec3> readings =
      SimulatePositions(truth, 9.80665, directions, Vec3::Constant(0.002), seed + unit);
  if (plan == Plan::kBumped) readings[6](0) += 0.3;  // moved during its interval: 150 sigma
  std::string csv = "x,y,z\n";
  char line[128];
  for (const Vec3& p : readings) {
    std::snprintf(line, sizeof line, "%.17g,%.17g,%.17g\n", p(0), p(1), p(2));
    csv += line;
  }
  return csv;
}

class Batch : public test::CliTest {
 protected:
  static constexpr int kUnits = 200;
  // The line's files: IMU-0001_2026-11-28.csv ..., one file the pattern does not match, and a
  // note the glob leaves out.
  void WriteUnits() {
    fs::create_directories(Path("line"));
    for (int unit = 1; unit <= kUnits; ++unit) {
      char name[64];
      std::snprintf(name, sizeof name, "line/IMU-%04d_2026-11-28.csv", unit);
      Write(name, UnitPositions(unit, PlanOf(unit), 1000 + unit));
    }
    Write("line/spare.csv", UnitPositions(1, Plan::kGood, 1));
    Write("line/notes.txt", "fixture 3, operator 7\n");
  }
  std::string Command(const std::string& out, const std::string& extra = "") const {
    // The example's limits; the raw unit labelled as the limits ask; a screening whose false
    // alarms (1e-6 per calibration) cannot fail a good unit of 200, a bump of 150 sigma found.
    return "batch " + Path("line") + " --glob '*.csv' --unit-id '^(IMU-[0-9]{4})_' --limits " +
           std::string(ACCELCAL_SOURCE_DIR) + "/examples/limits-mems.yaml -o " + Path(out) +
           " --raw-units m/s2 --outlier-probability 1e-6 " + extra;
  }
};

TEST_F(Batch, TwoHundredUnitsEachGetTheirVerdict) {
  WriteUnits();
  const CliRun r = Exec(Command("out", "--jobs 2"));
  ASSERT_EQ(r.status, 6) << r.err;  // some units fail: not a success
  const nlohmann::json doc = nlohmann::json::parse(Slurp(Path("out/summary.json")));
  const nlohmann::json& units = doc.at("units");
  ASSERT_EQ(units.size(), kUnits + 1u);
  std::map<Plan, int> seen;
  for (int unit = 1; unit <= kUnits; ++unit) {
    const nlohmann::json& row = units[unit - 1];
    char id[16];
    std::snprintf(id, sizeof id, "IMU-%04d", unit);
    ASSERT_EQ(row.at("unit"), id);
    std::set<std::string> failed;
    for (const auto& f : row.at("failed")) failed.insert(f.at("quantity").get<std::string>());
    const Plan plan = PlanOf(unit);
    ++seen[plan];
    switch (plan) {
      case Plan::kGood:
        EXPECT_EQ(row.at("status"), "pass") << row.dump();
        break;
      case Plan::kBias:
        EXPECT_EQ(row.at("status"), "fail");
        EXPECT_EQ(failed, std::set<std::string>{"accelerometer.bias_specific_force_x"})
            << row.dump();
        break;
      case Plan::kScale:
        EXPECT_EQ(row.at("status"), "fail");
        EXPECT_EQ(failed, std::set<std::string>{"accelerometer.scale_factor_y"}) << row.dump();
        break;
      case Plan::kBumped:
        // Left out by the screening (the calibration stands on 17 positions), which the limits
        // and the diagnosis's warning each refuse.
        EXPECT_EQ(row.at("status"), "fail");
        EXPECT_EQ(failed,
                  (std::set<std::string>{"accelerometer.excluded_positions", "diagnosis"}))
            << row.dump();
        EXPECT_EQ(row.at("quantities").at("accelerometer.positions").at("value"), 17);
        break;
      case Plan::kFew:
        EXPECT_EQ(row.at("status"), "error");
        EXPECT_NE(row.at("message").get<std::string>().find("needs at least 9 positions, got 6"),
                  std::string::npos)
            << row.dump();
        EXPECT_FALSE(fs::exists(Path("out/units/") + id));
        break;
    }
    if (plan != Plan::kFew) {
      EXPECT_TRUE(fs::exists(Path("out/units/") + id + "/report.html"));
      // Every parameter with its 1 sigma.
      const nlohmann::json& b = row.at("quantities").at("accelerometer.b_x");
      EXPECT_GT(b.at("sigma").get<double>(), 0);
      EXPECT_EQ(b.at("unit"), "m/s2");
    }
  }
  EXPECT_EQ(seen[Plan::kFew], 8);
  EXPECT_EQ(seen[Plan::kBumped], 20);
  const nlohmann::json& stray = units[kUnits];
  EXPECT_EQ(stray.at("status"), "error");
  EXPECT_NE(stray.at("message").get<std::string>().find(
                "spare.csv: its name does not match the unit id pattern"),
            std::string::npos);
  EXPECT_EQ(doc.at("counts"),
            nlohmann::json({{"units", 201}, {"pass", 132}, {"fail", 60}, {"error", 9}}));
  // The table: a header and one row per unit, each parameter and its sigma in columns.
  const std::string csv = Slurp(Path("out/summary.csv"));
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), kUnits + 2);
  EXPECT_EQ(csv.rfind("unit,status,failed,files,verdict,worst_finding,message,accelerometer.K_xx,"
                      "accelerometer.K_xx.sigma,",
                      0),
            0u);
  EXPECT_NE(r.out.find("201 units: 132 pass, 60 fail, 9 error"), std::string::npos) << r.out;

  // A unit's file is the one `accelcal calibrate` writes with the same options.
  const std::string file = Path("line/IMU-0001_2026-11-28.csv");
  ASSERT_EQ(Exec("calibrate " + file + " --raw-units m/s2 --outlier-probability 1e-6 -o " +
                 Path("direct.json"))
                .status,
            0);
  EXPECT_EQ(Slurp(Path("out/units/IMU-0001/calibration.json")), Slurp(Path("direct.json")));

  // One job gives the same bytes as two.
  ASSERT_EQ(Exec(Command("one", "--jobs 1")).status, 6);
  EXPECT_EQ(Slurp(Path("one/summary.csv")), csv);
  EXPECT_EQ(Slurp(Path("one/summary.json")), Slurp(Path("out/summary.json")));
  EXPECT_EQ(Slurp(Path("one/units/IMU-0042/report.html")),
            Slurp(Path("out/units/IMU-0042/report.html")));

  // Resumed: the current calibrations are not redone (the errors are tried again), and the
  // summary is the same. A unit whose recording changed is calibrated again.
  CliRun again = Exec(Command("out"));
  ASSERT_EQ(again.status, 6);
  EXPECT_NE(again.out.find("(192 calibrations current, not redone)"), std::string::npos)
      << again.out;
  EXPECT_EQ(Slurp(Path("out/summary.csv")), csv);
  Write("line/IMU-0001_2026-11-28.csv", UnitPositions(1, Plan::kGood, 77));
  again = Exec(Command("out"));
  EXPECT_NE(again.out.find("(191 calibrations current, not redone)"), std::string::npos)
      << again.out;
  EXPECT_NE(Slurp(Path("out/units/IMU-0001/calibration.json")), Slurp(Path("direct.json")));
  // Other options: every unit again.
  again = Exec(Command("out", "--model quadratic --no-report"));
  EXPECT_NE(again.out.find("(0 calibrations current, not redone)"), std::string::npos)
      << again.out;
  again = Exec(Command("out", "--model quadratic --no-report --redo"));
  EXPECT_NE(again.out.find("(0 calibrations current, not redone)"), std::string::npos)
      << again.out;
}

TEST_F(Batch, RefusesWhatWouldMakeItsResultsWrong) {
  fs::create_directories(Path("in"));
  Write("in/a.csv", UnitPositions(1, Plan::kGood, 1));
  Write("in/b.csv", UnitPositions(2, Plan::kGood, 2));
  // Every unit passes: status 0.
  CliRun r = Exec("batch " + Path("in") + " -o " + Path("out") + " --json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out).at("counts").at("pass"), 2);
  // A file given twice, the output directory as an input directory, a FIFO, a bad pattern.
  r = Exec("batch " + Path("in") + " " + Path("in/a.csv") + " -o " + Path("out"));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("give each file once"), std::string::npos) << r.err;
  r = Exec("batch " + Path("in") + " -o " + Path("in"));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("its summary files would be taken for units"), std::string::npos) << r.err;
  ASSERT_EQ(::mkfifo(Path("fifo").c_str(), 0600), 0);
  r = Exec("batch " + Path("fifo") + " -o " + Path("out"));
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find("not a regular file"), std::string::npos) << r.err;
  r = Exec("batch " + Path("in") + " -o " + Path("out") + " --unit-id '('");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("is not a regular expression"), std::string::npos) << r.err;
  // A unit id that would leave the batch's directory.
  r = Exec("batch " + Path("in") + " -o " + Path("out") + " --unit-id '^()'");
  EXPECT_EQ(r.status, 6);
  EXPECT_NE(r.out.find("the unit id is empty"), std::string::npos) << r.out;
  // Limits that cannot be read stop it before anything is calibrated.
  Write("bad.yaml", "format: accelcal-limits\nversion: 1\nlimits:\n  accelerometer.bx: {max: 1}\n");
  r = Exec("batch " + Path("in") + " -o " + Path("out2") + " --limits " + Path("bad.yaml"));
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find("bad.yaml:4: 'accelerometer.bx' names no quantity"), std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(Path("out2")));
  // A calibrate option's usage error is said once, as calibrate says it.
  r = Exec("batch " + Path("in") + " -o " + Path("out3") + " --model cubic");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--model"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(Path("out3/summary.csv")));
}

}  // namespace
}  // namespace accelcal
