// The gyroscope's section of the calibration file, described once (section_io.hpp): what is
// written is what is read back, field by field, for every field the file holds; and a real
// calibration's section reads back to the same bytes.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "accelcal/calibrate_unit.hpp"
#include "accelcal/calibration_file.hpp"
#include "accelcal/error.hpp"
#include "accelcal/json_text.hpp"
#include "support/paths.hpp"

namespace accelcal {
namespace {

// Two doubles the same, NaN the same as NaN (a number that does not exist).
void ExpectSameNumber(double a, double b, const char* what) {
  if (std::isnan(a) || std::isnan(b)) {
    EXPECT_EQ(std::isnan(a), std::isnan(b)) << what;
  } else {
    EXPECT_EQ(a, b) << what;
  }
}

// Every field the file holds (the description's list, UnitGyroscope's documented exceptions
// aside: the joint fit's accelerometer, the solver's method, start and time, the lag's step).
void ExpectSameGyroscope(const UnitGyroscope& a, const UnitGyroscope& b) {
  EXPECT_EQ(a.model, b.model);
  EXPECT_EQ(a.model_reason, b.model_reason);
  EXPECT_EQ(a.estimator, b.estimator);
  EXPECT_EQ(a.unit, b.unit);
  EXPECT_EQ(a.params.K, b.params.K);
  EXPECT_EQ(a.params.bias, b.params.bias);
  if (a.model == GyroModelKind::kGSensitive) {
    EXPECT_EQ(a.params.G, b.params.G);
  }
  EXPECT_EQ(a.covariance, b.covariance);
  EXPECT_EQ(a.noise_sigma_raw, b.noise_sigma_raw);
  ASSERT_EQ(a.still_spans.size(), b.still_spans.size());
  for (std::size_t k = 0; k < a.still_spans.size(); ++k) {
    const GyroStillSpan &x = a.still_spans[k], &y = b.still_spans[k];
    EXPECT_EQ(x.first_sample, y.first_sample);
    EXPECT_EQ(x.last_sample, y.last_sample);
    EXPECT_EQ(x.mean_raw, y.mean_raw);
    EXPECT_EQ(x.turned_outside_deg, y.turned_outside_deg);
    EXPECT_EQ(x.still, y.still);
  }
  ASSERT_EQ(a.time_offset.has_value(), b.time_offset.has_value());
  if (a.time_offset) {
    EXPECT_EQ(a.time_offset->lag_s, b.time_offset->lag_s);
    EXPECT_EQ(a.time_offset->std_s, b.time_offset->std_s);
    EXPECT_EQ(a.time_offset->turns, b.time_offset->turns);
    EXPECT_EQ(a.time_offset->at_limit, b.time_offset->at_limit);
  }
  ASSERT_EQ(a.rotations.size(), b.rotations.size());
  for (std::size_t k = 0; k < a.rotations.size(); ++k) {
    const GyroRotation &x = a.rotations[k], &y = b.rotations[k];
    EXPECT_EQ(x.from, y.from);
    EXPECT_EQ(x.to, y.to);
    EXPECT_EQ(x.first_sample, y.first_sample);
    EXPECT_EQ(x.last_sample, y.last_sample);
    EXPECT_EQ(x.duration_s, y.duration_s);
    EXPECT_EQ(x.angle_deg, y.angle_deg);
    ExpectSameNumber(x.turned_deg, y.turned_deg, "turned_deg");
    EXPECT_EQ(x.turned_std_deg, y.turned_std_deg);
    EXPECT_EQ(x.residual_deg, y.residual_deg);
    ExpectSameNumber(x.heldout_deg, y.heldout_deg, "heldout_deg");
    ExpectSameNumber(x.statistic, y.statistic, "statistic");
    ExpectSameNumber(x.threshold, y.threshold, "threshold");
    EXPECT_EQ(x.flagged, y.flagged);
  }
  ExpectSameNumber(a.rms_deg, b.rms_deg, "rms_deg");
  ExpectSameNumber(a.heldout_rms_deg, b.heldout_rms_deg, "heldout_rms_deg");
  ExpectSameNumber(a.still_scatter_ratio, b.still_scatter_ratio, "still_scatter_ratio");
  ExpectSameNumber(a.rotation_scatter_ratio, b.rotation_scatter_ratio, "rotation_scatter_ratio");
  ExpectSameNumber(a.accel_scatter_ratio, b.accel_scatter_ratio, "accel_scatter_ratio");
  EXPECT_EQ(a.summary.iterations, b.summary.iterations);
  EXPECT_EQ(a.summary.termination, b.summary.termination);
  EXPECT_EQ(a.summary.termination_message, b.summary.termination_message);
  EXPECT_EQ(a.summary.initial_cost, b.summary.initial_cost);
  EXPECT_EQ(a.summary.final_cost, b.summary.final_cost);
  EXPECT_EQ(a.latitude_deg, b.latitude_deg);
  EXPECT_EQ(a.earth_rate_vertical_rad_s, b.earth_rate_vertical_rad_s);
  EXPECT_EQ(a.earth_rate_horizontal_rad_s, b.earth_rate_horizontal_rad_s);
  ASSERT_EQ(a.thermal.has_value(), b.thermal.has_value());
  if (a.thermal) {
    const GyroThermal &x = *a.thermal, &y = *b.thermal;
    EXPECT_EQ(x.bias.t_ref_c, y.bias.t_ref_c);
    EXPECT_EQ(x.bias.coefficients, y.bias.coefficients);
    EXPECT_EQ(x.bias.covariance, y.bias.covariance);
    EXPECT_EQ(x.temperatures_c, y.temperatures_c);
    EXPECT_EQ(x.range_c, y.range_c);
    EXPECT_EQ(x.temperature_source, y.temperature_source);
    EXPECT_EQ(x.reason, y.reason);
    EXPECT_EQ(x.scatter_ratio, y.scatter_ratio);
    ExpectSameNumber(x.heldout_rms_raw, y.heldout_rms_raw, "heldout_rms_raw");
  }
  EXPECT_EQ(a.source, b.source);
  EXPECT_EQ(a.raw_unit, b.raw_unit);
}

// Every field set, each to a value of its own (none at its default), with the records that
// may not exist present: offsets over temperature, the lag, the Earth rate.
UnitGyroscope EveryField() {
  UnitGyroscope g;
  g.model = GyroModelKind::kGSensitive;
  g.model_reason = "given";
  g.estimator = GyroEstimator::kTwoStage;
  g.unit = GyroUnit::kDegPerSecond;
  g.params.K << 57.1, 0.2, -0.1, 0.05, 57.4, 0.3, -0.2, 0.1, 56.9;
  g.params.bias << 0.31, -0.27, 1.0 / 3;
  g.params.G << 1e-3, 2e-3, 3e-3, 4e-3, 5e-3, 6e-3, 7e-3, 8e-3, 9e-3;
  g.covariance = Eigen::MatrixXd::Identity(21, 21) * 1e-6;
  g.covariance(0, 1) = g.covariance(1, 0) = 2e-7;
  g.noise_sigma_raw << 0.011, 0.012, 0.013;
  for (std::size_t k = 0; k < 3; ++k) {
    GyroStillSpan s;
    s.first_sample = 100 * k + 1;
    s.last_sample = 100 * k + 90;
    s.mean_raw = Vec3(0.1 * static_cast<double>(k), -0.2, 0.3 + 1e-17);
    s.turned_outside_deg = 0.25 * static_cast<double>(k);
    s.still = k != 1;
    g.still_spans.push_back(s);
  }
  g.time_offset = GyroTimeOffset{-0.0042, 0.0003, 0.0, 17, true};
  for (std::size_t k = 0; k < 2; ++k) {
    GyroRotation r;
    r.from = k;
    r.to = k + 1;
    r.first_sample = 100 * k + 91;
    r.last_sample = 100 * k + 99;
    r.duration_s = 0.9;
    r.angle_deg = 90.1;
    r.turned_deg = k == 0 ? 90.2 : std::nan("");
    r.turned_std_deg = 0.02;
    r.residual_deg = 0.05;
    r.heldout_deg = k == 0 ? 0.07 : std::nan("");
    r.statistic = 1.5;
    r.threshold = 3.2;
    r.flagged = k == 1;
    g.rotations.push_back(r);
  }
  g.rms_deg = 0.051;
  g.heldout_rms_deg = 0.072;
  g.still_scatter_ratio = 1.3;
  g.rotation_scatter_ratio = 2.1;
  g.accel_scatter_ratio = 1.1;
  g.summary.iterations = 7;
  g.summary.termination = TerminationType::kParameterTolerance;
  g.summary.termination_message = "|dx| <= 1e-10 (1 + |x|)";
  g.summary.initial_cost = 12.5;
  g.summary.final_cost = 0.125;
  g.latitude_deg = 50.1;
  g.earth_rate_vertical_rad_s = 5.6e-5;
  g.earth_rate_horizontal_rad_s = 4.7e-5;
  GyroThermal t;
  t.bias.t_ref_c = 25;
  t.bias.coefficients = {Vec3(1e-3, 2e-3, 3e-3), Vec3(-1e-5, 0, 2e-5)};
  t.bias.covariance = Eigen::MatrixXd::Identity(6, 6) * 1e-10;
  t.temperatures_c = {20.5, 25.25, 31};
  t.range_c = {20.5, 31};
  t.temperature_source = "imu temperature";
  t.reason = "held-out error";
  t.scatter_ratio = 1.4;
  t.heldout_rms_raw = 0.002;
  g.thermal = t;
  g.source = "gyro.csv";
  g.raw_unit = "deg/s";
  return g;
}

TEST(GyroscopeSection, EveryFieldReadsBackAsWritten) {
  const UnitGyroscope g = EveryField();
  const nlohmann::ordered_json section = GyroscopeToJson(g, ForceUnit::kStandardGravity);
  const UnitGyroscope back = GyroscopeFromJson(section, "imu.json");
  ExpectSameGyroscope(g, back);
  // Through the file's text too (every double in its shortest exact form, NaN as null).
  const UnitGyroscope through_text =
      GyroscopeFromJson(nlohmann::ordered_json::parse(JsonText(section)), "imu.json");
  ExpectSameGyroscope(g, through_text);
  EXPECT_EQ(JsonText(GyroscopeToJson(through_text, ForceUnit::kStandardGravity)),
            JsonText(section));
}

TEST(GyroscopeSection, TheLinearModelWithoutTheOptionalRecords) {
  UnitGyroscope g = EveryField();
  g.model = GyroModelKind::kLinear;
  g.params.G.setZero();
  g.covariance.resize(0, 0);
  g.time_offset.reset();
  g.latitude_deg.reset();
  g.earth_rate_vertical_rad_s = g.earth_rate_horizontal_rad_s = 0;
  g.thermal.reset();
  g.heldout_rms_deg = std::nan("");
  const nlohmann::ordered_json section = GyroscopeToJson(g, ForceUnit::kMetersPerSecond2);
  EXPECT_TRUE(section["g_sensitivity"].is_null());
  EXPECT_TRUE(section["covariance"].is_null());
  EXPECT_TRUE(section["time_offset"].is_null());
  EXPECT_FALSE(section.contains("thermal"));
  ExpectSameGyroscope(g, GyroscopeFromJson(section, "imu.json"));
}

TEST(GyroscopeSection, ARecordAnOlderFileLacksIsNotKnownNotADefault) {
  nlohmann::ordered_json section = GyroscopeToJson(EveryField(), ForceUnit::kStandardGravity);
  section.erase("noise");
  section.erase("validation");
  section.erase("units");
  const UnitGyroscope g = GyroscopeFromJson(section, "old.json");
  EXPECT_TRUE(std::isnan(g.still_scatter_ratio));
  EXPECT_TRUE(std::isnan(g.rotation_scatter_ratio));
  EXPECT_TRUE(std::isnan(g.rms_deg));
  EXPECT_EQ(g.raw_unit, "");
}

TEST(GyroscopeSection, EachKeyIsCheckedWithItsPlaceNamed) {
  const nlohmann::ordered_json good = GyroscopeToJson(EveryField(), ForceUnit::kStandardGravity);
  const auto refused = [&](const auto& damage, const std::string& says) {
    nlohmann::ordered_json section = good;
    damage(section);
    try {
      GyroscopeFromJson(section, "imu.json");
      ADD_FAILURE() << "accepted; expected: " << says;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
    }
  };
  using J = nlohmann::ordered_json;
  refused([](J& s) { s["model"] = "cubic"; }, "'model' must be \"linear\" or \"g-sensitive\"");
  refused([](J& s) { s.erase("K"); }, "'K' is missing");
  refused([](J& s) { s["K"][1][2] = "x"; }, "'K[1][2]' must be a number");
  refused(
      [](J& s) {
        s["K"] = J::array({J::array({1, 2, 3}), J::array({2, 4, 6}), J::array({0, 0, 1})});
      },
      "'K' is singular");
  refused([](J& s) { s["estimator"] = "ml"; }, "'estimator' must be");
  refused([](J& s) { s["rotations"][0]["from"] = 0; }, "'rotations[].from' must be a position's");
  refused([](J& s) { s["rotations"][1]["residual_deg"] = -1; }, "must not be negative");
  refused([](J& s) { s["noise"]["still_scatter_ratio"] = 0; }, "'noise.still_scatter_ratio' must");
  refused([](J& s) { s["stills"][0]["still"] = 1; }, "'stills[].still' must be true or false");
  refused([](J& s) { s["thermal"]["degree"] = 4; }, "'thermal.degree' must be a whole number");
  refused([](J& s) { s["thermal"]["degree"] = 1; }, "'thermal.coefficients' must be an array of 1");
  refused([](J& s) { s["thermal"]["t_ref"] = 40; }, "'thermal.t_ref' must be within");
  refused(
      [](J& s) {
        s["thermal"]["covariance"] = nullptr;
        s["thermal"]["covariance"] = 3;
      },
      "'thermal.covariance' must be null or a 6x6 array");
  refused([](J& s) { s["covariance"][0][0] = -1; }, "covariance");
  refused([](J& s) { s["time_offset"] = 5; }, "'time_offset' must be an object");
  refused([](J& s) { s["solver"]["termination"] = "bored"; }, "'solver.termination' must be");
  // Records that say nothing, or what no calibration is (found by a hostile round).
  refused([](J& s) { s["time_offset"] = J::object(); }, "'time_offset.lag_s' is missing");
  refused([](J& s) { s["time_offset"]["std_s"] = -1; }, "'time_offset.std_s' must not be negative");
  refused([](J& s) { s["earth_rate"] = J::object(); }, "'earth_rate.latitude_deg' is missing");
  refused([](J& s) { s["earth_rate"]["latitude_deg"] = 1000; }, "must be from -90 to 90");
  refused([](J& s) { s["rotations"][0]["duration_s"] = -1; }, "'rotations[].duration_s' must not");
  refused([](J& s) { s["rotations"][0]["first_sample"] = 1000; }, "must not be after");
  refused([](J& s) { s["stills"][1]["position"] = 99; }, "'stills[].position' must be its place");
  refused([](J& s) { s["stills"][0]["first_sample"] = 1000; }, "must not be after");
  refused([](J& s) { s["solver"]["iterations"] = 18446744073709551615ull; },
          "'solver.iterations' must be a whole number");
  refused([](J& s) { s["solver"]["iterations"] = -3; }, "'solver.iterations' must not be negative");
  refused([](J& s) { s.erase("estimator"); }, "'estimator' is missing");
  refused([](J& s) { s["estimator"] = "imutk"; }, "imutk fits the linear model only");
  refused([](J& s) { s["thermal"]["covariance"] = nullptr; },
          "'thermal.covariance' must be a 6x6 array");
  refused([](J& s) { s["thermal"]["std"][0][1] = -1; }, "'thermal.std' must not be negative");
  refused(
      [](J& s) {
        s["K"] = J::array(
            {J::array({1e-300, 0, 0}), J::array({0, 1e-300, 0}), J::array({0, 0, 1e-300})});
      },
      "'K' is singular");
}

TEST(GyroscopeSection, ARealCalibrationReadsBackToTheSameBytes) {
  UnitRequest r;
  const std::string dir = std::string(ACCELCAL_DATA_DIR) + "/imutk-xsens-mti/";
  r.inputs = {dir + "xsens_acc.mat"};
  r.gravity_ms2 = 9.81744;
  r.raw_units = "counts";
  r.gyro = SensorInput{dir + "xsens_gyro.mat", {}, ""};
  const UnitOutcome unit = CalibrateUnit(r);
  ASSERT_TRUE(unit.gyroscope);
  const std::string text = CalibrationToJson(unit.accelerometer, unit.FileInfo());
  const LoadedCalibration cal = ParseCalibrationJson(text, "xsens-imu.json");
  ASSERT_TRUE(cal.gyroscope);
  ExpectSameGyroscope(unit.gyroscope->calibration, *cal.gyroscope);
  EXPECT_EQ(JsonText(GyroscopeToJson(*cal.gyroscope, cal.unit)),
            JsonText(GyroscopeToJson(unit.gyroscope->calibration, unit.unit)));
}

}  // namespace
}  // namespace accelcal
