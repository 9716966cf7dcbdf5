// The calibration file: required keys, round trip, determinism, and refusal of malformed files.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "accelcal/calibration_file.hpp"
#include "accelcal/error.hpp"
#include "accelcal/simulate.hpp"

namespace accelcal {
namespace {

struct Fixture {
  CalibrationResult result;
  CalibrationFileInfo info;
};

Fixture Make(ModelKind model) {
  const ModelParameters truth = Yang2012Truth();
  Fixture f;
  std::vector<Vec3> readings =
      SimulatePositions(truth, 9.8, RandomDirections(20, 4), Vec3(0.05, 0.05, 0.05), 5);
  CalibrationOptions o;
  o.model = model;
  o.gravity = 9.8;
  f.result = Calibrate(readings, o);
  for (const Vec3& p : readings) {
    Position pos;
    pos.mean = p;
    pos.samples = 6000;
    f.info.positions.push_back(pos);
  }
  f.info.raw_unit = "pulses";
  f.info.source = "sim.csv";
  return f;
}

TEST(CalibrationFile, HasTheDocumentedKeys) {
  const Fixture f = Make(ModelKind::kQuadratic);
  const nlohmann::json doc = nlohmann::json::parse(CalibrationToJson(f.result, f.info));
  EXPECT_EQ(doc["format"], "accelcal-calibration");
  EXPECT_EQ(doc["version"], 1);
  EXPECT_EQ(doc["model"], "quadratic");
  EXPECT_EQ(doc["gravity"], 9.8);
  EXPECT_EQ(doc["units"]["raw"], "pulses");
  EXPECT_EQ(doc["units"]["specific_force"], "m/s2");
  EXPECT_TRUE(doc["equation"].is_string());
  EXPECT_EQ(doc["K"][1][0], f.result.params.K(1, 0));
  EXPECT_EQ(doc["K"][0][1], 0.0);
  EXPECT_EQ(doc["bias"][2], f.result.params.bias(2));
  EXPECT_EQ(doc["k2"][0], f.result.params.k2(0));
  ASSERT_EQ(doc["positions"].size(), 20u);
  EXPECT_EQ(doc["positions"][3]["samples"], 6000);
  EXPECT_EQ(doc["positions"][3]["direction"].size(), 3u);
  EXPECT_EQ(doc["positions"][3]["residual"].size(), 3u);
  EXPECT_TRUE(doc["gravity_norm_rms_before"].is_null());  // pulses are not m/s²
  EXPECT_LT(doc["gravity_norm_rms_after"].get<double>(), 1e-3);
  EXPECT_EQ(doc["solver"]["method"], "joint");
  EXPECT_EQ(doc["solver"]["converged"], true);
  EXPECT_EQ(doc["solver"]["termination"], std::string(ToString(f.result.summary.termination)));
  EXPECT_GT(doc["solver"]["iterations"].get<int>(), 0);
  EXPECT_EQ(doc["solver"]["cost"], f.result.summary.final_cost);
  EXPECT_EQ(doc["covariance"].size(), 12u);
  EXPECT_EQ(doc["parameter_order"][11], "k2_z");
  EXPECT_EQ(doc["std"]["K"][0][1], 0.0);
  EXPECT_GT(doc["std"]["bias"][0].get<double>(), 0.0);
}

TEST(CalibrationFile, RoundTripAndDeterminism) {
  const Fixture f = Make(ModelKind::kLinear);
  const std::string text = CalibrationToJson(f.result, f.info);
  EXPECT_EQ(text, CalibrationToJson(f.result, f.info));
  const LoadedCalibration cal = ParseCalibrationJson(text, "cal.json");
  EXPECT_EQ(cal.model, ModelKind::kLinear);
  EXPECT_EQ(cal.params.K, f.result.params.K);  // shortest round-trip doubles: bit-exact
  EXPECT_EQ(cal.params.bias, f.result.params.bias);
  EXPECT_EQ(cal.gravity, 9.8);
  EXPECT_EQ(cal.unit, ForceUnit::kMetersPerSecond2);
}

std::string LoadError(const std::string& text) {
  try {
    ParseCalibrationJson(text, "cal.json");
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(CalibrationFile, RefusesMalformedFiles) {
  const Fixture f = Make(ModelKind::kLinear);
  nlohmann::json good = nlohmann::json::parse(CalibrationToJson(f.result, f.info));
  EXPECT_EQ(LoadError("{").rfind("cal.json: not valid JSON", 0), 0u);
  nlohmann::json j = good;
  j["format"] = "other";
  EXPECT_EQ(
      LoadError(j.dump()),
      "cal.json: not an accelcal calibration file (\"format\" is not \"accelcal-calibration\")");
  j = good;
  j["version"] = 2;
  EXPECT_EQ(LoadError(j.dump()), "cal.json: unsupported calibration file version (expected 1)");
  j = good;
  j["K"][0][2] = 1.0;
  EXPECT_EQ(LoadError(j.dump()), "cal.json: 'K' must be lower-triangular (frame x-first)");
  j = good;
  j["frame"] = "z-first";  // with the x-first (lower-triangular) K of `good`
  EXPECT_EQ(LoadError(j.dump()), "cal.json: 'K' must be upper-triangular (frame z-first)");
  j["frame"] = "sideways";
  EXPECT_EQ(LoadError(j.dump()),
            "cal.json: 'frame' must be \"x-first\", \"z-first\" or \"platform\"");
  j = good;
  j.erase("frame");  // files written before the key existed are x-first
  EXPECT_EQ(LoadError(j.dump()), "no error");
  j = good;
  j["bias"] = {1, 2};
  EXPECT_EQ(LoadError(j.dump()), "cal.json: 'bias' must be an array of 3 numbers");
  j = good;
  j["k2"] = {1, 0, 0};
  EXPECT_EQ(LoadError(j.dump()), "cal.json: a linear model must have k2 = [0, 0, 0]");
  j = good;
  j["units"]["specific_force"] = "ft/s2";
  EXPECT_EQ(LoadError(j.dump()), "cal.json: 'units.specific_force' must be \"m/s2\" or \"g\"");
  // Found by the fuzzer (issue 16): a number where a string belongs escaped as a JSON type error,
  // "internal error" without the file's name.
  j = good;
  j["format"] = -0.7069;
  EXPECT_EQ(
      LoadError(j.dump()),
      "cal.json: not an accelcal calibration file (\"format\" is not \"accelcal-calibration\")");
  j = good;
  j["verdict"] = 3;
  EXPECT_EQ(LoadError(j.dump()), "cal.json: 'verdict' must be \"ok\", \"warnings\" or \"failed\"");
  // A key twice in one object: the last would win (a second identity K makes apply a no-op).
  std::string text = good.dump();
  text.insert(1, "\"K\": [[1, 0, 0], [0, 1, 0], [0, 0, 1]], ");
  EXPECT_EQ(LoadError(text), "cal.json: the key 'K' appears twice in one object");
  text = good.dump();
  text.insert(text.find("\"units\":{") + 9, "\"raw\":\"x\",");
  EXPECT_EQ(LoadError(text), "cal.json: the key 'raw' appears twice in one object");
  // The same key in different objects is not a repeat.
  EXPECT_EQ(LoadError(good.dump()), "no error");
}

}  // namespace
}  // namespace accelcal
