// The unit's calibration in the library (calibrate_unit.hpp): its rules between options, stated
// once and named by each edge in its own words, and the same file as the tool writes.
#include "accelcal/calibrate_unit.hpp"

#include <gtest/gtest.h>

#include "accelcal/error.hpp"
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

TEST(UnitRequest, StatesEachRuleBetweenOptionsOnce) {
  EXPECT_FALSE(Ctu24().Validate());
  UnitRequest r = Ctu24();
  r.orientations = "o.csv";
  r.gyro = GyroInput{"gyro.csv", {}, ""};
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

}  // namespace
}  // namespace accelcal
