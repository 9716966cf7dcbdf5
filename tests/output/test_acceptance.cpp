// Acceptance limits (acceptance.hpp): the limits file as read, each refusal with its line, a
// calibration's quantities and the verdict on known answers.
#include <algorithm>
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "accelcal/acceptance.hpp"
#include "accelcal/engineering.hpp"
#include "accelcal/error.hpp"
#include "support/cli_test.hpp"
#include "support/paths.hpp"

namespace accelcal {
namespace {

const std::string kHeader = "format: accelcal-limits\nversion: 1\n";

TEST(Acceptance, PatternsMatchWithStarsOnly) {
  EXPECT_TRUE(QuantityMatches("accelerometer.b_x", "accelerometer.b_x"));
  EXPECT_FALSE(QuantityMatches("accelerometer.b_x", "accelerometer.b_xy"));
  EXPECT_TRUE(QuantityMatches("accelerometer.b_*", "accelerometer.b_z"));
  EXPECT_TRUE(QuantityMatches("*.heldout_rms*", "gyroscope.heldout_rms_deg"));
  EXPECT_TRUE(QuantityMatches("*", "accelerometer.K_xx"));
  EXPECT_TRUE(QuantityMatches("a*b*c", "aXbYbZc"));  // a star takes as much as it needs
  EXPECT_FALSE(QuantityMatches("a*b*c", "aXbYcZ"));
  EXPECT_FALSE(QuantityMatches("accelerometer.?_x", "accelerometer.b_x"));  // '?' is itself
}

TEST(Acceptance, TheMemsExampleReadsAsWritten) {
  const std::string path = std::string(ACCELCAL_SOURCE_DIR) + "/examples/limits-mems.yaml";
  const AcceptanceLimits l = ParseLimits(test::Slurp(path), path);
  EXPECT_EQ(l.part, "MEMS accelerometer, +-16 g, read in m/s2");
  EXPECT_EQ(l.specific_force_unit, ForceUnit::kMetersPerSecond2);
  EXPECT_EQ(l.raw_unit, "m/s2");
  ASSERT_EQ(l.max_severity, Severity::kNote);
  ASSERT_EQ(l.limits.size(), 8u);
  EXPECT_EQ(l.limits[0].pattern, "accelerometer.scale_factor_*");
  EXPECT_EQ(l.limits[0].statistic, LimitStatistic::kValue);
  EXPECT_EQ(l.limits[0].min, 0.97);
  EXPECT_EQ(l.limits[0].max, 1.03);
  EXPECT_FALSE(l.limits[0].abs_max);
  EXPECT_EQ(l.limits[3].pattern, "accelerometer.scale_factor_*");
  EXPECT_EQ(l.limits[3].statistic, LimitStatistic::kSigma);
  EXPECT_EQ(l.limits[3].max, 0.0005);
  EXPECT_EQ(l.limits[3].line, 17u);
}

// Every refusal names its line and says why.
TEST(Acceptance, RefusesWhatItCannotMeanAsWritten) {
  const struct {
    std::string text;
    std::size_t line;
    const char* reason;
  } cases[] = {
      {"", 0, "empty"},
      {"version: 1\n", 1, "not a limits file"},
      {"format: accelcal-limits\n", 1, "no 'version: 1'"},
      {"format: accelcal-limits\nversion: 2\n", 2, "reads version 1"},
      {kHeader, 1, "nothing to check"},
      {kHeader + "limit:\n  accelerometer.b_x: {max: 1}\n", 3, "unknown key 'limit'"},
      {kHeader + "limits:\n  accelerometer.bx: {max: 1}\n", 4, "names no quantity"},
      {kHeader + "limits:\n  accelerometer.b_x: {max: 1}\n  accelerometer.b_x: {max: 2}\n", 5,
       "given twice (first at line 4)"},
      {kHeader + "limits:\n  accelerometer.b_x: {max: .nan}\n", 4, "finite decimal number"},
      {kHeader + "limits:\n  accelerometer.b_x: {max: 1e999}\n", 4, "finite decimal number"},
      {kHeader + "limits:\n  accelerometer.b_x: {max: '1'}\n", 4, "without quotes"},
      {kHeader + "limits:\n  accelerometer.b_x: {max: [1]}\n", 4, "finite decimal number"},
      {kHeader + "limits:\n  accelerometer.b_x: {maximum: 1}\n", 4, "unknown key 'maximum'"},
      {kHeader + "limits:\n  accelerometer.b_x: {}\n", 4, "has no bounds"},
      {kHeader + "limits:\n  accelerometer.b_x:\n", 4, "must be a mapping"},
      {kHeader + "limits:\n  accelerometer.b_x: {min: 2, max: 1}\n", 4, "min is above max"},
      {kHeader + "limits:\n  accelerometer.b_x: {abs_max: -1}\n", 4, "abs_max is negative"},
      {kHeader + "limits:\n  accelerometer.positions.sigma: {max: 1}\n", 4, "has no 1 sigma"},
      {kHeader + "limits:\n  a: &x {max: 1}\n", 4, "anchor"},
      {kHeader + "limits:\n  accelerometer.b_x: !!map {max: 1}\n", 4, "tag"},
      {kHeader + "limits: [1, 2]\n", 3, "must be a mapping"},
      {kHeader + "limits:\n  accelerometer.b_x: {max: 1\n", 5, "not valid YAML"},
      {kHeader + "diagnosis: {max_severity: serious}\n", 3, "note, warning or failure"},
      {kHeader + "units: {specific_force: ft/s2}\n", 3, "m/s2 or g"},
      {kHeader + "diagnosis: {max_severity: note}\n---\na: 1\n", 4, "a second document"},
      {kHeader + "a: " + std::string(40, '[') + "\n", 3, "nested more than 32 deep"},
      {std::string(40, '[') + "\n", 1, "nested more than 32 deep"},
  };
  for (const auto& c : cases) {
    try {
      ParseLimits(c.text, "l.yaml");
      ADD_FAILURE() << "accepted: " << c.text;
    } catch (const InputError& e) {
      EXPECT_EQ(e.line(), c.line) << c.text << "\n" << e.what();
      EXPECT_NE(std::string(e.what()).find(c.reason), std::string::npos) << c.text << "\n"
                                                                         << e.what();
    }
  }
}

// A linear x-first calibration with a known K, bias and covariance.
LoadedCalibration Known() {
  LoadedCalibration cal;
  cal.model = ModelKind::kLinear;
  cal.frame = Frame::kXFirst;
  cal.gravity = 9.81;
  cal.raw_unit = "m/s2";
  cal.params.K << 1.01, 0, 0, 0.002, 0.99, 0, -0.001, 0.003, 1.0;
  cal.params.bias = Vec3(0.2, -0.6, 0.05);
  cal.covariance = Eigen::MatrixXd::Identity(9, 9);
  for (int i = 0; i < 9; ++i) cal.covariance(i, i) = 1e-6 * (i + 1) * (i + 1);
  cal.crossval_rms = 0.004;
  cal.positions.resize(18);
  cal.positions[4].excluded = true;
  cal.verdict = "warnings";
  cal.diagnostics = std::vector<Finding>{{"outlier", Severity::kWarning, "", {}},
                                         {"time_unit", Severity::kNote, "", {}}};
  return cal;
}

TEST(Acceptance, QuantitiesAreTheFilesParametersAndTheirEngineeringForms) {
  const LoadedCalibration cal = Known();
  const std::vector<CalibrationQuantity> q = CalibrationQuantities(cal);
  const auto find = [&](const std::string& name) {
    for (const CalibrationQuantity& c : q) {
      if (c.name == name) return c;
    }
    ADD_FAILURE() << name;
    return CalibrationQuantity{};
  };
  // The file's parameter order: K_xx, b_x, K_yx, K_yy, b_y, ...; σ the covariance's diagonal.
  EXPECT_EQ(q[0].name, "accelerometer.K_xx");
  EXPECT_EQ(q[1].name, "accelerometer.b_x");
  EXPECT_EQ(find("accelerometer.b_y").value, -0.6);
  EXPECT_DOUBLE_EQ(*find("accelerometer.b_y").sigma, 5e-3);  // slot 4 (0-based): sqrt(25e-6)
  EXPECT_EQ(find("accelerometer.b_y").unit, "m/s2");
  EXPECT_EQ(find("accelerometer.K_yx").unit, "m/s2 per m/s2");
  const EngineeringParameters eng = ToEngineering(cal.params, cal.gravity);
  EXPECT_DOUBLE_EQ(find("accelerometer.scale_factor_y").value, std::hypot(0.002, 0.99));
  EXPECT_DOUBLE_EQ(find("accelerometer.bias_specific_force_y").value, eng.bias_force(1));
  EXPECT_DOUBLE_EQ(find("accelerometer.misalignment_tau_yx").value, eng.tau_yx);
  EXPECT_TRUE(find("accelerometer.misalignment_tau_yx").sigma.has_value());
  EXPECT_EQ(find("accelerometer.heldout_rms").value, 0.004);
  EXPECT_EQ(find("accelerometer.positions").value, 17);
  EXPECT_EQ(find("accelerometer.excluded_positions").value, 1);
  for (const CalibrationQuantity& c : q) {
    EXPECT_EQ(c.name.rfind("accelerometer.", 0), 0u) << c.name;  // no gyroscope in this one
    EXPECT_TRUE(std::any_of(KnownQuantityNames().begin(), KnownQuantityNames().end(),
                            [&](const QuantityName& k) { return k.name == c.name; }))
        << c.name;
  }
}

TEST(Acceptance, EachLimitPassesOrFailsAsItsBoundsSay) {
  const LoadedCalibration cal = Known();
  const auto verdict = [&](const std::string& limits) {
    return Accept(cal, ParseLimits(kHeader + limits, "l.yaml"));
  };
  EXPECT_TRUE(verdict("limits:\n  accelerometer.b_*: {abs_max: 0.6}\n").passed);
  Acceptance a = verdict("limits:\n  accelerometer.b_*: {abs_max: 0.5}\n");
  EXPECT_EQ(a.checked, 3u);
  ASSERT_EQ(a.failures.size(), 1u);
  EXPECT_EQ(a.failures[0].quantity, "accelerometer.b_y");
  EXPECT_EQ(a.failures[0].value, -0.6);
  EXPECT_EQ(a.failures[0].line, 4u);
  EXPECT_EQ(a.failures[0].text, "accelerometer.b_y = -0.6 exceeds abs_max 0.5");
  a = verdict("limits:\n  accelerometer.b_y: {min: -0.5}\n  accelerometer.b_x: {max: 0.1}\n");
  ASSERT_EQ(a.failures.size(), 2u);
  EXPECT_EQ(a.failures[0].text, "accelerometer.b_y = -0.6 is below min -0.5");
  EXPECT_EQ(a.failures[1].text, "accelerometer.b_x = 0.2 is above max 0.1");
  // σ: b_x's is 2e-3 (slot 1), b_y's 5e-3.
  a = verdict("limits:\n  accelerometer.b_*.sigma: {max: 0.004}\n");
  ASSERT_EQ(a.failures.size(), 2u);
  EXPECT_EQ(a.failures[0].text, "accelerometer.b_y.sigma = 0.005 is above max 0.004");
  // A bound on what the calibration does not have fails: it cannot be checked.
  a = verdict("limits:\n  gyroscope.heldout_rms_deg: {max: 0.5}\n");
  ASSERT_EQ(a.failures.size(), 1u);
  EXPECT_EQ(a.failures[0].text, "gyroscope.heldout_rms_deg: not in this calibration");
  LoadedCalibration no_cov = cal;
  no_cov.covariance.resize(0, 0);
  a = Accept(no_cov, ParseLimits(kHeader + "limits:\n  accelerometer.b_x.sigma: {max: 1}\n", ""));
  ASSERT_EQ(a.failures.size(), 1u);
  EXPECT_NE(a.failures[0].text.find("no covariance"), std::string::npos);
  // A NaN never passes a bound.
  LoadedCalibration nan = cal;
  nan.crossval_rms = std::nan("");
  EXPECT_FALSE(Accept(nan, ParseLimits(kHeader + "limits:\n  accelerometer.heldout_rms: "
                                                 "{max: 1}\n",
                                       ""))
                   .passed);
  // accelerometer.*.sigma names the quantities that have a sigma (not rms, positions, ...).
  EXPECT_TRUE(verdict("limits:\n  accelerometer.*.sigma: {max: 1}\n").passed);
  // k2 is 0 by the linear model: a bound on it holds, a bound on its sigma cannot be checked.
  EXPECT_TRUE(verdict("limits:\n  accelerometer.k2_*: {abs_max: 0.01}\n").passed);
  EXPECT_FALSE(verdict("limits:\n  accelerometer.k2_x.sigma: {max: 1}\n").passed);
  // The positions used and left out.
  EXPECT_FALSE(verdict("limits:\n  accelerometer.excluded_positions: {max: 0}\n").passed);
  EXPECT_TRUE(verdict("limits:\n  accelerometer.positions: {min: 17}\n").passed);
}

TEST(Acceptance, DiagnosisUnitsAndTheCalibrationsOwnVerdict) {
  LoadedCalibration cal = Known();
  Acceptance a = Accept(cal, ParseLimits(kHeader + "diagnosis: {max_severity: note}\n", ""));
  ASSERT_EQ(a.failures.size(), 1u);
  EXPECT_EQ(a.failures[0].text, "diagnosis: warning outlier (above note)");
  EXPECT_TRUE(
      Accept(cal, ParseLimits(kHeader + "diagnosis: {max_severity: warning}\n", "")).passed);
  // Limits in g are never compared with a calibration in m/s2, nor a raw unit with another.
  a = Accept(cal, ParseLimits(kHeader + "units: {specific_force: g}\nlimits:\n  "
                                        "accelerometer.b_x: {max: 1}\n",
                              ""));
  ASSERT_EQ(a.failures.size(), 1u);
  EXPECT_EQ(a.failures[0].text, "the calibration's specific force is in m/s2, the limits' in g");
  EXPECT_FALSE(
      Accept(cal, ParseLimits(kHeader + "units: {raw: counts}\nlimits:\n  accelerometer.b_x: "
                                        "{max: 1}\n",
                              ""))
          .passed);
  // A calibration that failed its own checks fails whatever the limits.
  cal.verdict = "failed";
  a = Accept(cal, ParseLimits(kHeader + "diagnosis: {max_severity: failure}\n", ""));
  ASSERT_EQ(a.failures.size(), 1u);
  EXPECT_EQ(a.failures[0].quantity, "verdict");
}

}  // namespace
}  // namespace accelcal
