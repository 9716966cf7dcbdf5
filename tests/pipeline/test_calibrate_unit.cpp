// The unit's calibration in the library (calibrate_unit.hpp): its rules between options, stated
// once and named by each edge in its own words, and the same file as the tool writes.
#include "accelcal/calibrate_unit.hpp"

#include <cstdio>
#include <map>
#include <string>

#include <gtest/gtest.h>

#include "accelcal/error.hpp"
#include "accelcal/simulate.hpp"
#include "support/cli_test.hpp"

namespace accelcal {
namespace {

using test::CliRun;
using test::CliTest;

const std::string kCtu24 =
    std::string(ACCELCAL_DATA_DIR) + "/ctu-innalabs-ahrs-m3/measured_accelerations_24pos.csv";

std::string Flag(const std::string& name) { return "--" + name; }

TEST(RenderOptionNames, NamesEachMarkedOptionAndLeavesOtherBracesAlone) {
  EXPECT_EQ(RenderOptionNames("{{gyro_columns}} takes x,y,z; {{no_crossval}}", Flag),
            "--gyro_columns takes x,y,z; --no_crossval");
  EXPECT_EQ(RenderOptionNames("a {b} {{Upper}} {{}} {{x y}} {{open", Flag),
            "a {b} {{Upper}} {{}} {{x y}} {{open");
  EXPECT_EQ(RenderOptionNames("", Flag), "");
  // The library's own words: the keyword, and the field for the flag that turns it off.
  const OptionError e("{{model}} auto needs what {{no_crossval}} turns off");
  EXPECT_STREQ(e.what(), "model auto needs what cross_validate false turns off");
  EXPECT_EQ(e.marked(), "{{model}} auto needs what {{no_crossval}} turns off");
}

UnitRequest Ctu24() {
  UnitRequest r;
  r.inputs = {kCtu24};
  r.units = ForceUnit::kStandardGravity;
  return r;
}

TEST(UnitRequest, AFitRefusedFromALogCutShortSaysItEndsEarly) {
  // The log's warning that it was cut short comes with a result; when the fit is refused for
  // too few positions, the refusal is where the user looks, and the part lost may hold them.
  const std::string path = ::testing::TempDir() + "/cut_one_position.csv";
  {
    std::string text = "t,ax,ay,az\n";
    for (int i = 0; i < 3000; ++i) text += std::to_string(0.01 * i) + ",0.01,-0.02,1.0\n";
    text += "30,0.01,-0.02,0.9";  // cut while "0.99..." was written
    std::FILE* f = std::fopen(path.c_str(), "wb");
    ASSERT_NE(f, nullptr);
    std::fwrite(text.data(), 1, text.size(), f);
    std::fclose(f);
  }
  UnitRequest r;
  r.inputs = {path};
  r.units = ForceUnit::kStandardGravity;
  try {
    CalibrateUnit(r);
    ADD_FAILURE() << "calibrated from one position";
  } catch (const DataError& e) {
    EXPECT_NE(std::string(e.what()).find(" (" + path +
                                         " ends early: the file ends inside line "
                                         "3002"),
              std::string::npos)
        << e.what();
  }
  std::remove(path.c_str());
}

TEST(UnitRequest, StatesEachRuleBetweenOptionsOnce) {
  EXPECT_FALSE(Ctu24().Validate());
  UnitRequest r = Ctu24();
  r.orientations = "o.csv";
  r.gyro = SensorInput{"gyro.csv", {}, ""};
  r.gyro_estimator = GyroEstimator::kJoint;
  ASSERT_TRUE(r.Validate());
  EXPECT_EQ(r.Validate()->rfind("{{gyro_estimator}} joint fits every position's gravity", 0), 0u)
      << *r.Validate();
  r = Ctu24();
  r.thermal = true;
  r.model.reset();  // auto
  ASSERT_TRUE(r.Validate());
  EXPECT_NE(r.Validate()->find("not with {{model}} auto"), std::string::npos) << *r.Validate();
  r = Ctu24();
  r.temperatures_c = {20};
  EXPECT_EQ(r.Validate(), "{{temperatures}} are for {{thermal}}: give it too");
  r = Ctu24();
  r.max_iterations = -1;
  ASSERT_TRUE(r.Validate());
  EXPECT_EQ(r.Validate()->rfind("{{max_iterations}}", 0), 0u) << *r.Validate();
  r = Ctu24();
  r.inputs.clear();
  EXPECT_TRUE(r.Validate());
  // CalibrateUnit refuses before it reads: the file named does not exist.
  r = Ctu24();
  r.inputs = {"/nonexistent/log.csv"};
  r.bias_model_auto = true;
  r.cross_validate = false;
  try {
    CalibrateUnit(r);
    ADD_FAILURE() << "no error";
  } catch (const OptionError& e) {
    EXPECT_EQ(RenderOptionNames(e.marked(), Flag).rfind("--bias_model auto decides", 0), 0u)
        << e.what();
  }
}

class UnitCalibration : public CliTest {};

// The library's unit and the tool's calibrate write the same bytes for the same options (the tool
// is a thin edge over it).
TEST_F(UnitCalibration, WritesTheToolsFile) {
  UnitRequest r = Ctu24();
  r.model.reset();  // auto
  r.provenance.command = "accelcal calibrate";
  r.provenance.options = {{"units", "g"}, {"model", "auto"}};
  const UnitOutcome unit = CalibrateUnit(r);
  ASSERT_TRUE(unit.converged());
  ASSERT_TRUE(unit.model_selection);
  const CliRun tool = Exec("calibrate " + kCtu24 + " --units g --model auto --json");
  ASSERT_EQ(tool.status, 0) << tool.err;
  EXPECT_EQ(CalibrationToJson(unit.accelerometer, unit.FileInfo()), tool.out);
}

// A drifting bias fitted across a long pause with no position in it: a finding of the file (it
// was a warning on the tool's stderr only, which Python and a later reader never saw).
TEST_F(UnitCalibration, ADriftFittedAcrossALongPauseIsAFinding) {
  const std::vector<Vec3> directions = Yang18Directions();
  RawLogSimulation sim;
  sim.rate_hz = 50;
  sim.static_s = 10;
  const std::vector<Vec3> first(directions.begin(), directions.begin() + 9);
  const std::vector<Vec3> second(directions.begin() + 9, directions.end());
  const SimulatedLog a = SimulateRawLog(Yang2012Truth(), 9.80665, first, sim);
  sim.seed = 2;
  const SimulatedLog b = SimulateRawLog(Yang2012Truth(), 9.80665, second, sim);
  const auto csv = [&](double pause_s) {
    std::string text = "t,x,y,z\n";
    char line[160];
    for (std::size_t i = 0; i < a.samples.size() + b.samples.size(); ++i) {
      const bool later = i >= a.samples.size();
      const std::size_t j = later ? i - a.samples.size() : i;
      const Vec3& x = later ? b.samples[j] : a.samples[j];
      const double t = later ? a.time_s.back() + pause_s + b.time_s[j] : a.time_s[j];
      std::snprintf(line, sizeof line, "%.17g,%.17g,%.17g,%.17g\n", t, x(0), x(1), x(2));
      text += line;
    }
    return text;
  };
  const auto codes = [&](double pause_s) {
    UnitRequest r;
    r.inputs = {Write("log" + std::to_string(pause_s) + ".csv", csv(pause_s))};
    r.bias_model = BiasModel{BiasModelKind::kLinear, 0};
    const UnitOutcome unit = CalibrateUnit(r);
    std::map<std::string, Severity> out;
    for (const Finding& f : unit.diagnosis.findings) out[f.code] = f.severity;
    return out;
  };
  const std::map<std::string, Severity> paused = codes(600);
  ASSERT_EQ(paused.count("drift_across_gap"), 1u);
  EXPECT_EQ(paused.at("drift_across_gap"), Severity::kWarning);
  EXPECT_EQ(codes(4).count("drift_across_gap"), 0u);
}

}  // namespace
}  // namespace accelcal
