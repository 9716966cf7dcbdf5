// accelcal batch as a production line runs it: 200 simulated units with known parameters, some out
// of the MEMS example's limits, some with a bumped position or too few positions; every verdict,
// the same bytes whatever the number of jobs, a resumed batch, and a unit's file as calibrate's.
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <random>
#include <set>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "accelcal/mcap_writer.hpp"
#include "accelcal/rosbag_writer.hpp"
#include "accelcal/sha256.hpp"
#include "accelcal/simulate.hpp"
#include "accelcal/ulog_writer.hpp"
#include "support/cli_test.hpp"
#include "support/paths.hpp"

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
// `noise_seed`: another session of the same unit (0: the truth's seed); `bias_shift_x`: its bias
// moved since [m/s2].
std::string UnitPositions(int unit, Plan plan, std::uint64_t seed, std::uint64_t noise_seed = 0,
                          double bias_shift_x = 0) {
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
  truth.bias(0) += bias_shift_x;
  std::vector<Vec3> directions = Yang18Directions();
  if (plan == Plan::kFew) directions.resize(6);  // the linear model needs 9
  std::vector<Vec3> readings = SimulatePositions(truth, 9.80665, directions, Vec3::Constant(0.002),
                                                 noise_seed != 0 ? noise_seed : seed + unit);
  if (plan == Plan::kBumped) readings[6](0) += 0.3;  // moved during its interval: 150 sigma
  return test::ReadingsCsv(readings);
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
        EXPECT_EQ(failed, (std::set<std::string>{"accelerometer.excluded_positions", "diagnosis"}))
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
  EXPECT_EQ(csv.rfind("unit,status,failed,files,verdict,worst_finding,message,sha256,"
                      "accelerometer.K_xx,accelerometer.K_xx.sigma,",
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
  EXPECT_NE(again.out.find("(0 calibrations current, not redone)"), std::string::npos) << again.out;
  again = Exec(Command("out", "--model quadratic --no-report --redo"));
  EXPECT_NE(again.out.find("(0 calibrations current, not redone)"), std::string::npos) << again.out;
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
  // From a hostile test: patterns that a backtracking search takes exponential time (or, with a
  // large automaton, minutes) over: "^(a|aa)*c" on a name of 200 a's ran for more than a minute.
  // Searched breadth-first over a bounded automaton they finish; a back-reference, which only
  // backtracking can match, and an automaton over the bound are refused before anything is read.
  fs::create_directories(Path("slow"));
  const std::string long_name = std::string(200, 'a') + "b.csv";
  Write("slow/" + long_name, UnitPositions(3, Plan::kGood, 3));
  r = Exec("batch " + Path("slow") + " -o " + Path("slow_out") + " --unit-id '^(a|aa)*c' --json");
  EXPECT_EQ(r.status, 6) << r.err;
  EXPECT_NE(r.out.find("does not match the unit id pattern"), std::string::npos) << r.out;
  r = Exec("batch " + Path("slow") + " -o " + Path("slow_out2") + " --unit-id '(a)\\1'");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("refers back to a group"), std::string::npos) << r.err;
  r = Exec("batch " + Path("slow") + " -o " + Path("slow_out3") + " --unit-id '(a{1,99}){1,99}c'");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("too large to search in bounded time"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(Path("slow_out3")));
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

// From a hostile test: what is in the batch's directory and is not batch's own is kept, and one
// unit's problem is that unit's.
TEST_F(Batch, KeepsWhatIsNotItsOwnAndStopsForNoUnit) {
  fs::create_directories(Path("in"));
  Write("in/a.csv", UnitPositions(1, Plan::kGood, 1));
  Write("in/b.csv", UnitPositions(2, Plan::kGood, 2));
  fs::create_directories(Path("out/units/a"));
  fs::create_directories(Path("out/units/b"));
  Write("out/units/a/calibration.json", "{\"operator notes\": \"rework ticket 4711\"}\n");
  Write("precious.txt", "user data\n");
  fs::create_symlink(Path("precious.txt"), Path("out/units/b/report.html"));
  CliRun r = Exec("batch " + Path("in") + " -o " + Path("out"));
  EXPECT_EQ(r.status, 6);
  EXPECT_NE(r.out.find("calibration.json exists and is not a calibration file: not replaced"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("report.html is a symbolic link"), std::string::npos) << r.out;
  EXPECT_EQ(Slurp(Path("out/units/a/calibration.json")),
            "{\"operator notes\": \"rework ticket 4711\"}\n");
  EXPECT_EQ(Slurp(Path("precious.txt")), "user data\n");
  fs::remove_all(Path("out"));
  // The summary through a link is not written either.
  fs::create_directories(Path("out"));
  fs::create_symlink(Path("precious.txt"), Path("out/summary.csv"));
  EXPECT_EQ(Exec("batch " + Path("in") + " -o " + Path("out")).status, 5);
  EXPECT_EQ(Slurp(Path("precious.txt")), "user data\n");
  fs::remove_all(Path("out"));
  // A read-only calibration of a unit whose recording changed is kept, and the unit is an error;
  // nothing of it is removed.
  ASSERT_EQ(Exec("batch " + Path("in") + " -o " + Path("out")).status, 0);
  const std::string approved = Slurp(Path("out/units/a/calibration.json"));
  fs::permissions(Path("out/units/a/calibration.json"), fs::perms::owner_read);
  Write("in/a.csv", UnitPositions(1, Plan::kGood, 9));
  r = Exec("batch " + Path("in") + " -o " + Path("out"));
  EXPECT_EQ(r.status, 6);
  EXPECT_NE(r.out.find("is read-only: not replaced"), std::string::npos) << r.out;
  EXPECT_EQ(Slurp(Path("out/units/a/calibration.json")), approved);
  EXPECT_TRUE(fs::exists(Path("out/units/a/report.html")));
  fs::permissions(Path("out/units/a/calibration.json"), fs::perms::owner_all);
  // Recalibrated without a report: the earlier report, of other data, does not stay beside it.
  ASSERT_EQ(Exec("batch " + Path("in") + " -o " + Path("out") + " --no-report").status, 0);
  EXPECT_FALSE(fs::exists(Path("out/units/a/report.html")));
  // One unit's usage problem (one value per file, and it has one file) is its error row.
  fs::create_directories(Path("two"));
  Write("two/A_20.csv", UnitPositions(1, Plan::kGood, 1));
  Write("two/A_40.csv", UnitPositions(1, Plan::kGood, 1, 5));
  Write("two/B_20.csv", UnitPositions(2, Plan::kGood, 2));
  r = Exec("batch " + Path("two") + " -o " + Path("t") + " --unit-id '^([A-Z])_' --no-report " +
           "--thermal 0,1 --temperatures 20,40");
  EXPECT_EQ(r.status, 6) << r.err;
  EXPECT_NE(r.out.find("B     error  usage: --temperatures: 2 given for 1 input file"),
            std::string::npos)
      << r.out;
  // The files of a unit in name order, whatever order they were given in: the same bytes.
  ASSERT_EQ(Exec("batch " + Path("two/A_40.csv") + " " + Path("two/A_20.csv") + " -o " +
                 Path("t2") + " --unit-id '^([A-Z])_' --no-report")
                .status,
            0);
  ASSERT_EQ(Exec("batch " + Path("two/A_20.csv") + " " + Path("two/A_40.csv") + " -o " +
                 Path("t3") + " --unit-id '^([A-Z])_' --no-report")
                .status,
            0);
  EXPECT_EQ(Slurp(Path("t2/units/A/calibration.json")), Slurp(Path("t3/units/A/calibration.json")));
  // One gyroscope log for several units is refused.
  r = Exec("batch " + Path("in") + " -o " + Path("g") + " --gyro " + Path("in/a.csv"));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--gyro names one gyroscope log for every unit"), std::string::npos)
      << r.err;
}

// Issue 47: below the directory named, batch follows no symbolic link, at any level; what it
// refuses is named, and nothing is written where a link points.
TEST_F(Batch, FollowsNoLinkBelowItsDirectory) {
  fs::create_directories(Path("in"));
  Write("in/a.csv", UnitPositions(1, Plan::kGood, 1));
  Write("in/b.csv", UnitPositions(2, Plan::kGood, 2));
  fs::create_directories(Path("elsewhere"));
  const auto untouched = [&] { return fs::is_empty(Path("elsewhere")); };
  const std::string run = "batch " + Path("in") + " -o " + Path("out") + " --no-report";
  // OUT/units a link: nothing calibrated into it.
  fs::create_directories(Path("out"));
  fs::create_directory_symlink(Path("elsewhere"), Path("out/units"));
  CliRun r = Exec(run);
  EXPECT_EQ(r.status, 5) << r.out << r.err;
  EXPECT_NE(r.err.find(Path("out/units") + ": is a symbolic link: not followed"), std::string::npos)
      << r.err;
  EXPECT_TRUE(untouched());
  EXPECT_FALSE(fs::exists(Path("out/summary.csv")));
  fs::remove_all(Path("out"));
  // OUT/units/a a link: unit a is an error row naming it, unit b is calibrated.
  fs::create_directories(Path("out/units"));
  fs::create_directory_symlink(Path("elsewhere"), Path("out/units/a"));
  r = Exec(run);
  EXPECT_EQ(r.status, 6) << r.out << r.err;
  EXPECT_NE(r.out.find(Path("out/units/a") + ": is a symbolic link: not followed"),
            std::string::npos)
      << r.out;
  EXPECT_TRUE(untouched());
  EXPECT_TRUE(fs::is_symlink(Path("out/units/a")));
  EXPECT_TRUE(fs::exists(Path("out/units/b/calibration.json")));
  fs::remove_all(Path("out"));
  // A FIFO where a calibration goes: an error row, never waited on; a directory where the
  // summary goes: nothing written.
  fs::create_directories(Path("out/units/a"));
  ASSERT_EQ(::mkfifo(Path("out/units/a/calibration.json").c_str(), 0600), 0);
  r = Exec(run);
  EXPECT_EQ(r.status, 6) << r.out << r.err;
  EXPECT_NE(r.out.find("calibration.json is not a regular file: not replaced"), std::string::npos)
      << r.out;
  fs::remove_all(Path("out"));
  fs::create_directories(Path("out/summary.json"));
  EXPECT_EQ(Exec(run).status, 5);
  EXPECT_FALSE(fs::exists(Path("out/summary.csv")));
  fs::remove_all(Path("out"));
  // The directory named may be a link the user made: followed, as every tool follows it.
  fs::create_directories(Path("real"));
  fs::create_directory_symlink(Path("real"), Path("out"));
  r = Exec(run);
  EXPECT_EQ(r.status, 0) << r.out << r.err;
  EXPECT_TRUE(fs::exists(Path("real/units/a/calibration.json")));
  EXPECT_TRUE(untouched());
}

// Issue 47: two batches into one directory at once replaced each other's units between judging
// and summing up. One batch at a time; the summary names each unit's file by its SHA-256, and
// store add takes no file the batch did not judge.
TEST_F(Batch, OneAtATimeAndTheSummaryNamesTheFilesItJudged) {
  fs::create_directories(Path("in"));
  Write("in/a.csv", UnitPositions(1, Plan::kGood, 1));
  Write("in/b.csv", UnitPositions(2, Plan::kGood, 2));
  const std::string run = "batch " + Path("in") + " -o " + Path("out") + " --no-report";
  ASSERT_EQ(Exec(run).status, 0);
  const std::string a = Slurp(Path("out/units/a/calibration.json"));
  const std::string b = Slurp(Path("out/units/b/calibration.json"));
  nlohmann::json summary = nlohmann::json::parse(Slurp(Path("out/summary.json")));
  EXPECT_EQ(summary["units"][0]["sha256"], Sha256Hex(a));
  EXPECT_EQ(summary["units"][1]["sha256"], Sha256Hex(b));
  const std::string csv = Slurp(Path("out/summary.csv"));
  EXPECT_EQ(csv.rfind("unit,status,failed,files,verdict,worst_finding,message,sha256,", 0), 0u)
      << csv;
  EXPECT_NE(csv.find("\na,pass,,"), std::string::npos);
  EXPECT_NE(csv.find(",," + Sha256Hex(a) + ","), std::string::npos) << csv;
  // Another batch holds the directory: this one is refused, and writes nothing.
  {
    const int fd = ::open(Path("out/.lock").c_str(), O_RDWR);
    ASSERT_GE(fd, 0);
    ASSERT_EQ(::flock(fd, LOCK_EX), 0);
    const CliRun r = Exec(run + " --redo");
    EXPECT_EQ(r.status, 5);
    EXPECT_NE(r.err.find(Path("out") + ": another batch is writing into it"), std::string::npos)
        << r.err;
    // Nor does store add read it meanwhile.
    const CliRun s = Exec("store add " + Path("store") + " " + Path("out"));
    EXPECT_EQ(s.status, 3);
    EXPECT_NE(s.err.find("a batch is writing into it"), std::string::npos) << s.err;
    ::close(fd);
  }
  EXPECT_EQ(Slurp(Path("out/units/a/calibration.json")), a);
  EXPECT_FALSE(fs::exists(Path("store/index.json")));
  // A unit's file replaced after the batch judged it (here by b's): store add refuses it, naming
  // it, and stores nothing.
  Write("out/units/a/calibration.json", b);
  CliRun r = Exec("store add " + Path("store") + " " + Path("out"));
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find(Path("out/units/a/calibration.json") + ": its SHA-256 is not the one"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(Path("store/index.json")));
  // A summary without the SHA-256s (an earlier accelcal's) is not trusted either.
  Write("out/units/a/calibration.json", a);
  summary["units"][0].erase("sha256");
  Write("out/summary.json", summary.dump());
  r = Exec("store add " + Path("store") + " " + Path("out"));
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find("unit a has no SHA-256 of its file"), std::string::npos) << r.err;
  // Run again, the batch's summary is whole again, and store add takes both.
  ASSERT_EQ(Exec(run).status, 0);
  r = Exec("store add " + Path("store") + " " + Path("out"));
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("2 added"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace accelcal

namespace accelcal {
namespace {

// A short simulated session of paper 000's 18 positions (3 s each), read in m/s2.
RawLogSimulation ShortSession() {
  RawLogSimulation sim;
  sim.static_s = 3;
  sim.transition_s = 1;
  sim.sigma_raw_per_sample = Vec3::Constant(0.02);
  return sim;
}

// A unit's id from the log itself: two PX4 logs of one sensor (device id 101, two sessions) and
// one of another (102), named anyhow; and the real PX4 log's board id.
TEST_F(Batch, UnitIdsFromTheLogs) {
  fs::create_directories(Path("logs"));
  RawLogSimulation sim = ShortSession();
  int file = 0;
  for (const std::uint32_t device : {101u, 101u, 102u}) {
    sim.seed = static_cast<std::uint64_t>(++file);
    ModelParameters truth;
    truth.bias = Vec3(0.01 * device - 1, 0.1, -0.1);
    const SimulatedLog log = SimulateRawLog(truth, 9.80665, Yang18Directions(), sim);
    const ULogImuWriter writer(device);
    std::string bytes = writer.Header();
    for (std::size_t i = 0; i < log.samples.size(); ++i) {
      bytes += writer.Accel(static_cast<std::uint64_t>(1e6 * log.time_s[i]) + 1000, log.samples[i]);
    }
    Write("logs/flight" + std::to_string(file) + ".ulg", bytes);
  }
  CliRun r = Exec("batch " + Path("logs") + " -o " + Path("out") +
                  " --unit-id-from device-id --no-report --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json doc = nlohmann::json::parse(r.out);
  ASSERT_EQ(doc.at("units").size(), 2u);
  EXPECT_EQ(doc["units"][0]["unit"], "101");
  EXPECT_EQ(doc["units"][0]["files"].size(), 2u);  // the sessions of one sensor, pooled
  EXPECT_EQ(doc["units"][1]["unit"], "102");
  EXPECT_EQ(doc["units"][0]["quantities"]["accelerometer.positions"]["value"], 36);
  // The real log's board (PX4's sys_uuid); its several accelerometer streams have several ids.
  const std::string real = std::string(ACCELCAL_DATA_DIR) + "/px4-ulog/sample_log_small.ulg";
  r = Exec("batch " + real + " -o " + Path("real") + " --unit-id-from info:sys_uuid --json");
  EXPECT_EQ(r.status, 6);  // the log is a flight: no calibration, but its unit is named
  EXPECT_EQ(nlohmann::json::parse(r.out)["units"][0]["unit"],
            "000600000000383638393239510d0035002d");
  r = Exec("batch " + real + " -o " + Path("real") + " --unit-id-from device-id");
  EXPECT_NE(r.out.find("device ids: choose one with --topic and --instance"), std::string::npos)
      << r.out;
  r = Exec("batch " + real + " -o " + Path("real") +
           " --unit-id-from device-id --topic "
           "sensor_accel --instance 1 --json");
  EXPECT_EQ(nlohmann::json::parse(r.out)["units"][0]["unit"], "3670050");
  r = Exec("batch " + real + " -o " + Path("real") + " --unit-id-from info:serial");
  EXPECT_NE(r.out.find("the log has no information 'serial' (it has sys_mcu, sys_name"),
            std::string::npos)
      << r.out;
  EXPECT_EQ(Exec("batch " + real + " -o " + Path("real") + " --unit-id-from serial").status, 2);
}

// ROS bags named by their Imu topic's header.frame_id, where a line names each unit's frame: two
// ROS 1 bags of one frame are one unit's sessions; an MCAP file (ROS 2's CDR) gives its own.
TEST_F(Batch, UnitIdsFromRosFrameIds) {
  fs::create_directories(Path("bags"));
  RawLogSimulation sim = ShortSession();
  // accelcal's writers name the frame imu_link; a unit's frame, of the same length, is put in
  // its place in a ROS 1 bag's uncompressed bytes (an MCAP chunk has a CRC: it keeps imu_link).
  const auto framed = [](std::string bytes, const std::string& frame) {
    std::size_t replaced = 0;
    for (std::size_t at = bytes.find("imu_link"); at != std::string::npos;
         at = bytes.find("imu_link", at + 8), ++replaced) {
      bytes.replace(at, 8, frame);
    }
    EXPECT_GT(replaced, 100u);
    return bytes;
  };
  int file = 0;
  for (const char* frame : {"imu_0042", "imu_0042", "imu_0043", "imu_link"}) {
    sim.seed = static_cast<std::uint64_t>(++file);
    ModelParameters truth;
    truth.bias = Vec3(0.1 * file, 0.1, -0.1);
    const SimulatedLog log = SimulateRawLog(truth, 9.80665, Yang18Directions(), sim);
    const auto ns = [&](std::size_t i) {
      return 1700000000000000000ull + static_cast<std::uint64_t>(1e9 * log.time_s[i]);
    };
    std::string bytes;
    if (file == 4) {
      McapImuWriter writer(McapCompression::kNone);
      bytes = writer.Header();
      for (std::size_t i = 0; i < log.samples.size(); ++i)
        bytes += writer.Sample(ns(i), log.samples[i]);
      bytes += writer.Finish();
    } else {
      RosBagImuWriter writer;
      bytes = writer.Header();
      for (std::size_t i = 0; i < log.samples.size(); ++i)
        bytes += writer.Sample(ns(i), log.samples[i]);
      bytes += writer.Finish();
      const std::string indexed = writer.IndexedHeader();
      bytes.replace(RosBagImuWriter::kHeaderOffset, indexed.size(), indexed);
    }
    Write("bags/session" + std::to_string(file) + (file == 4 ? ".mcap" : ".bag"),
          file == 4 ? bytes : framed(bytes, frame));
  }
  CliRun r = Exec("inspect --json " + Path("bags/session2.bag"));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["streams"][0]["frame_id"], "imu_0042");
  r = Exec("batch " + Path("bags") + " -o " + Path("out") +
           " --unit-id-from frame-id --no-report --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json doc = nlohmann::json::parse(r.out);
  ASSERT_EQ(doc.at("units").size(), 3u);
  EXPECT_EQ(doc["units"][0]["unit"], "imu_0042");
  EXPECT_EQ(doc["units"][0]["files"].size(), 2u);  // two sessions, pooled
  EXPECT_EQ(doc["units"][0]["quantities"]["accelerometer.positions"]["value"], 36);
  EXPECT_EQ(doc["units"][1]["unit"], "imu_0043");
  EXPECT_EQ(doc["units"][2]["unit"], "imu_link");
  // A topic that is not the accelerometer's has no frame id to give; nor has a ULog.
  // The row says what the log has.
  r = Exec("batch " + Path("bags/session3.bag") + " -o " + Path("other") +
           " --unit-id-from frame-id --topic /imu/other");
  EXPECT_EQ(r.status, 6);
  EXPECT_NE(
      r.out.find("the log has no accelerometer stream /imu/other with a frame id (a "
                 "sensor_msgs/Imu topic's header.frame_id); its accelerometer streams: /imu/data "
                 "(sensor_msgs/Imu, frame id 'imu_0043')"),
      std::string::npos)
      << r.out;
  const std::string real = std::string(ACCELCAL_DATA_DIR) + "/px4-ulog/sample_log_small.ulg";
  r = Exec("batch " + real + " -o " + Path("real") + " --unit-id-from frame-id");
  EXPECT_NE(r.out.find("the log has no accelerometer stream with a frame id"), std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("its accelerometer streams: sensor_combined (frame id none), "
                       "sensor_accel (frame id none), sensor_accel instance 1 (frame id none)"),
            std::string::npos)
      << r.out;
  // A frame id that would not read as itself is no unit's id: bytes that are not UTF-8 (two
  // such ids would both read as U+FFFD in the summary's JSON), a terminal's escape (shown
  // escaped), a leading space. --unit-id, a pattern on names, does not go with it, even empty.
  fs::create_directories(Path("odd"));
  const std::string session = Slurp(Path("bags/session3.bag"));
  int odd = 0;
  for (const std::string& frame : {std::string("imu\xff\xfe"
                                               "042"),
                                   std::string("imu\x1b[31m"), std::string(" imu_042")}) {
    std::string bytes = session;
    bytes.replace(bytes.find("imu_0043"), 8, frame);  // the first message's
    Write("odd/" + std::to_string(++odd) + ".bag", bytes);
  }
  r = Exec("batch " + Path("odd") + " -o " + Path("odd_out") + " --unit-id-from frame-id");
  EXPECT_EQ(r.status, 6);
  EXPECT_NE(r.out.find("the unit id 'imu\\xFF\\xFE042' is not UTF-8 text"), std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("the unit id 'imu\\x1B[31m' holds a '/', a control character"),
            std::string::npos)
      << r.out;
  EXPECT_EQ(r.out.find('\x1b'), std::string::npos);  // nothing raw reaches the terminal
  EXPECT_NE(r.out.find("the unit id ' imu_042' begins or ends with a space"), std::string::npos)
      << r.out;
  EXPECT_FALSE(fs::exists(Path("odd_out/units/ imu_042")));
  EXPECT_EQ(Exec("batch " + Path("odd") + " -o " + Path("odd_out") +
                 " --unit-id-from frame-id --unit-id ''")
                .status,
            2);
  EXPECT_EQ(Exec("batch " + Path("odd") + " -o " + Path("odd_out") + " --unit-id ''").status, 2);
}

}  // namespace
}  // namespace accelcal

namespace accelcal {
namespace {

// accelcal store: a unit's successive calibrations, each compared with the one before it.
class Store : public test::CliTest {
 protected:
  // One batch of `units` units: session `session` of each (the same truths, new noise); unit 2's
  // bias moved by `bump` m/s2 in x.
  std::string Session(int session, int units, double bump = 0) {
    const std::string dir = Path("s" + std::to_string(session));
    fs::create_directories(dir + "/line");
    for (int unit = 1; unit <= units; ++unit) {
      const std::string csv = UnitPositions(unit, Plan::kGood, 1000 + unit, 7919 * session + unit,
                                            unit == 2 ? bump : 0.0);
      char name[32];
      std::snprintf(name, sizeof name, "/line/U%03d.csv", unit);
      Write(dir.substr(Path("").size()) + name, csv);
    }
    const CliRun r = Exec("batch " + dir + "/line -o " + dir + "/out --no-report");
    EXPECT_EQ(r.status, 0) << r.err;
    return dir + "/out";
  }
};

TEST_F(Store, SuccessiveCalibrationsAreComparedWithinTheirCovariances) {
  const std::string store = Path("store");
  CliRun r = Exec("store add " + store + " " + Session(1, 3) + " --date 2026-10-01");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("U002  2026-10-01  added units/U002/2026-10-01_"), std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("the unit's first calibration"), std::string::npos);
  // The same unit again: its new calibration agrees with the first within their covariances.
  r = Exec("store add " + store + " " + Session(2, 3) + " --date 2026-11-01");
  ASSERT_EQ(r.status, 0) << r.out << r.err;
  EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 4) << r.out;
  EXPECT_NE(r.out.find("compatible with 2026-10-01"), std::string::npos) << r.out;
  // Unit 2's bias moved by 0.02 m/s2 (its 1 sigma about 1e-3): changed, b_x named first.
  r = Exec("store add " + store + " " + Session(3, 3, 0.02) + " --date 2026-11-28");
  EXPECT_EQ(r.status, 6) << r.out;
  EXPECT_NE(r.out.find("U002  2026-11-28  added"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("CHANGED since 2026-11-01"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("accelerometer largest: b_x 1"), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("1 calibration differs"), std::string::npos) << r.err;
  // Adding what is there adds nothing.
  r = Exec("store add " + store + " " + Path("s3/out") + " --date 2026-11-28");
  EXPECT_NE(r.out.find("0 added, 3 already in the store"), std::string::npos) << r.out;
  // list: a line per unit, or a unit's calibrations; get: the latest, or a date's.
  r = Exec("store list " + store);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 3) << r.out;
  r = Exec("store list " + store + " U002 --json");
  const nlohmann::json index = nlohmann::json::parse(r.out);
  ASSERT_EQ(index.at("entries").size(), 3u);
  EXPECT_EQ(index["entries"][2]["change"]["compatible"], false);
  // It is the bias that moved, not K.
  EXPECT_LT(index["entries"][2]["change"]["accelerometer_bias"]["p"].get<double>(), 1e-6);
  EXPECT_GT(index["entries"][2]["change"]["accelerometer_scale"]["p"].get<double>(), 1e-3);
  EXPECT_EQ(index["entries"][1]["change"]["compatible"], true);
  r = Exec("store get " + store + " U002");
  EXPECT_EQ(r.out, Slurp(Path("s3/out/units/U002/calibration.json")));
  r = Exec("store get " + store + " U002 --date 2026-11-01 -o " + Path("nov.json"));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(Slurp(Path("nov.json")), Slurp(Path("s2/out/units/U002/calibration.json")));
  r = Exec("store get " + store + " U009");
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find("no calibration of unit 'U009'"), std::string::npos) << r.err;
  // A stored file changed afterwards is refused, not given.
  Write("store/" + index["entries"][0]["file"].get<std::string>(), "{}");
  r = Exec("store get " + store + " U002 --date 2026-10-01");
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find("changed after it was stored"), std::string::npos) << r.err;
  // A part whose bias moves by 0.02 m/s2 between power-ups (its datasheet's repeatability): the
  // same move is within it.
  r = Exec("store add " + Path("store2") + " " + Path("s2/out") + " --date 2026-11-01");
  r = Exec("store add " + Path("store2") + " " + Path("s3/out") +
           " --date 2026-11-28 --bias-repeatability 0.02");
  EXPECT_EQ(r.status, 0) << r.out;
  EXPECT_EQ(r.out.find("CHANGED"), std::string::npos) << r.out;
  EXPECT_EQ(
      Exec("store add " + Path("store2") + " " + Path("s3/out") + " --bias-repeatability 0.1,,0.1")
          .status,
      2);
  // A single file needs its unit.
  r = Exec("store add " + store + " " + Path("s1/out/units/U001/calibration.json"));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("give its unit with --unit"), std::string::npos) << r.err;
}

// Two sessions of 100 units that did not change: each unit's chi2 / 9 follows F(9, 18) (9
// parameters; each covariance scaled by a noise level estimated from its fit's 9 residual degrees
// of freedom), so a change is flagged as often as its p says. (By chi2(9), 11 of these 100 had p
// below 0.05; by F, 4.)
TEST_F(Store, UnchangedUnitsAreCompatibleAsOftenAsTheirPSays) {
  const std::string store = Path("store");
  ASSERT_EQ(Exec("store add " + store + " " + Session(1, 100) + " --date 2026-10-01").status, 0);
  Exec("store add " + store + " " + Session(2, 100) + " --date 2026-11-01");
  const nlohmann::json index = nlohmann::json::parse(Slurp(store + "/index.json"));
  double sum = 0;
  int n = 0, flagged = 0, below_05 = 0;
  for (const auto& e : index.at("entries")) {
    if (e.at("change").is_null()) continue;
    const auto& a = e["change"]["accelerometer"];
    ASSERT_EQ(a.at("dof"), 9);
    ASSERT_GE(a.at("noise_dof").get<double>(), 16);  // 9 + 9, less a position screened out
    sum += a.at("chi2").get<double>();
    ++n;
    flagged += e["change"]["compatible"] ? 0 : 1;
    below_05 += a.at("p").get<double>() < 0.05 ? 1 : 0;
  }
  ASSERT_EQ(n, 100);
  // 9 F(9, 18) has mean 9 * 18 / 16 = 10.1 and sd 6.4: the mean of 100 within 5 of its sd 0.64.
  EXPECT_NEAR(sum / n, 10.125, 3.2);
  // p < 0.001 flags 0.1 of 100 on average: 3 or more would happen 1.5e-4 of the time.
  EXPECT_LE(flagged, 2);
  // p < 0.05: 5 expected, 1 sigma 2.2.
  EXPECT_LE(below_05, 12);
}

// From a hostile test of the store: the order of adding changes nothing, the index is the
// store's and cannot send a read elsewhere, and nothing is written over what it holds.
TEST_F(Store, KeepsEveryCalibrationComparedWithTheOneBeforeIt) {
  const std::string store = Path("store");
  const std::string s1 = Session(1, 2), s2 = Session(2, 2), s3 = Session(3, 2, 0.02);
  // Added newest first: each one added before another re-compares the one after it.
  EXPECT_EQ(Exec("store add " + store + " " + s3 + " --date 2026-06-01").status, 0);
  CliRun r = Exec("store add " + store + " " + s1 + " --date 2026-01-01");
  EXPECT_EQ(r.status, 6) << r.out;  // June's bias is 0.02 off January's
  EXPECT_NE(r.out.find("U002  2026-06-01  now; CHANGED since 2026-01-01"), std::string::npos)
      << r.out;
  r = Exec("store add " + store + " " + s2 + " --date 2026-03-01T10:00+05:00");
  EXPECT_NE(r.out.find("U002  2026-03-01T10:00+05:00  added"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("U002  2026-06-01  now; CHANGED since 2026-03-01T10:00+05:00"),
            std::string::npos)
      << r.out;
  const nlohmann::json index = nlohmann::json::parse(Slurp(store + "/index.json"));
  ASSERT_EQ(index["entries"].size(), 6u);
  EXPECT_EQ(index["entries"][3]["date"], "2026-01-01");  // U002's, in time order
  EXPECT_EQ(index["entries"][4]["change"]["against_date"], "2026-01-01");
  EXPECT_EQ(index["entries"][5]["change"]["against_date"], "2026-03-01T10:00+05:00");
  // A date in another zone is that instant.
  r = Exec("store get " + store + " U002 --date 2026-03-01T05:00Z");
  EXPECT_EQ(r.out, Slurp(Path("s2/out/units/U002/calibration.json"))) << r.err;
  // -o inside the store is refused: it would replace what the store holds.
  r = Exec("store get " + store + " U002 -o " + store + "/.lock");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("is inside the store"), std::string::npos) << r.err;
  // An index entry whose file leaves the store is refused, not read.
  nlohmann::json bad = index;
  bad["entries"][0]["file"] = "units/U001/../../../etc/passwd";
  Write("store/index.json", bad.dump());
  r = Exec("store get " + store + " U001");
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find("entry 1: 'file' units/U001/../../../etc/passwd is not units/U001/"),
            std::string::npos)
      << r.err;
  bad = index;
  bad["entries"][1]["change"] = "lol";
  Write("store/index.json", bad.dump());
  EXPECT_EQ(Exec("store list " + store).status, 3);
  // A calibration that failed its own checks is no reference.
  nlohmann::json failed = nlohmann::json::parse(Slurp(Path("s1/out/units/U001/calibration.json")));
  failed["verdict"] = "failed";
  Write("failed.json", failed.dump());
  Write("store/index.json", index.dump());
  r = Exec("store add " + store + " " + Path("failed.json") + " --unit U001");
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find("failed its own checks"), std::string::npos) << r.err;
}

// Issue 47: below the store named, store add follows no link (a unit's directory, the units'
// directory, the index), and the index cannot name a file by a string the system would cut.
TEST_F(Store, FollowsNoLinkAndTakesNoNameWithAControlCharacter) {
  const std::string store = Path("store");
  const std::string s1 = Session(1, 1);
  fs::create_directories(Path("elsewhere"));
  fs::create_directories(store + "/units");
  fs::create_directory_symlink(Path("elsewhere"), store + "/units/U001");
  CliRun r = Exec("store add " + store + " " + s1);
  EXPECT_EQ(r.status, 5) << r.out;
  EXPECT_NE(r.err.find(store + "/units/U001: is a symbolic link: not followed"), std::string::npos)
      << r.err;
  EXPECT_TRUE(fs::is_empty(Path("elsewhere")));
  EXPECT_FALSE(fs::exists(store + "/index.json"));
  fs::remove_all(store);
  fs::create_directories(store);
  fs::create_directory_symlink(Path("elsewhere"), store + "/units");
  EXPECT_EQ(Exec("store add " + store + " " + s1).status, 5);
  EXPECT_TRUE(fs::is_empty(Path("elsewhere")));
  fs::remove_all(store);
  // The index a link: neither read nor replaced (its target is another store's, or anything).
  ASSERT_EQ(Exec("store add " + Path("other") + " " + s1).status, 0);
  const std::string other = Slurp(Path("other/index.json"));
  fs::create_directories(store);
  fs::create_symlink(Path("other/index.json"), store + "/index.json");
  r = Exec("store add " + store + " " + Session(2, 1));
  EXPECT_EQ(r.status, 3) << r.out;
  EXPECT_NE(r.err.find(store + "/index.json: is a symbolic link"), std::string::npos) << r.err;
  EXPECT_EQ(Slurp(Path("other/index.json")), other);
  EXPECT_EQ(Exec("store list " + store).status, 3);
  fs::remove_all(store);
  // A stored unit's directory replaced by a link afterwards: get refuses to read through it.
  fs::create_directories(store);
  fs::copy(Path("other"), store, fs::copy_options::recursive);
  fs::rename(store + "/units/U001", Path("moved"));
  fs::create_directory_symlink(Path("moved"), store + "/units/U001");
  r = Exec("store get " + store + " U001");
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find(store + "/units/U001: is a symbolic link"), std::string::npos) << r.err;
  fs::remove(store + "/units/U001");
  fs::rename(Path("moved"), store + "/units/U001");
  // A NUL in an entry's file: the system would open the name up to it, another file. Refused,
  // naming the index and the entry.
  nlohmann::json index = nlohmann::json::parse(Slurp(store + "/index.json"));
  ASSERT_EQ(Exec("store get " + store + " U001").status, 0);
  index["entries"][0]["file"] =
      index["entries"][0]["file"].get<std::string>() + std::string("\0x", 2);
  Write("store/index.json", index.dump());
  r = Exec("store get " + store + " U001");
  EXPECT_EQ(r.status, 3) << r.out;
  EXPECT_NE(r.err.find(store + "/index.json: entry 1: 'file' units/U001/"), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("\\x00x holds a control character"), std::string::npos) << r.err;
  EXPECT_EQ(r.out, "");
}

}  // namespace
}  // namespace accelcal
