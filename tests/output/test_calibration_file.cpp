// The calibration file: required keys, round trip, determinism, and refusal of malformed files.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "accelcal/calibration_file.hpp"
#include "accelcal/error.hpp"
#include "accelcal/simulate.hpp"
#include "accelcal/version.hpp"

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
  Fixture f = Make(ModelKind::kQuadratic);
  f.info.provenance.command = "test";
  f.info.provenance.options["gravity"] = "9.8";
  f.info.provenance.inputs.push_back({"sim.csv", 1234, std::string(64, 'a')});
  f.info.provenance.inputs.push_back({"unhashed.csv", 0, ""});
  const nlohmann::json top = nlohmann::json::parse(CalibrationToJson(f.result, f.info));
  EXPECT_EQ(top["format"], "accelcal-calibration");
  EXPECT_EQ(top["version"], 2);
  EXPECT_EQ(top["verdict"], "ok");
  ASSERT_EQ(top["sensors"].size(), 1u);
  const nlohmann::json& doc = top["sensors"]["accelerometer"];
  EXPECT_EQ(doc["verdict"], "ok");
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
  const nlohmann::json& provenance = top["provenance"];
  EXPECT_EQ(provenance["accelcal_version"], std::string(Version()));
  EXPECT_EQ(provenance["command"], "test");
  EXPECT_EQ(provenance["options"], nlohmann::json({{"gravity", "9.8"}}));
  EXPECT_EQ(
      provenance["inputs"][0],
      nlohmann::json({{"name", "sim.csv"}, {"bytes", 1234}, {"sha256", std::string(64, 'a')}}));
  EXPECT_EQ(provenance["inputs"][1], nlohmann::json({{"name", "unhashed.csv"}, {"bytes", 0}}));
  EXPECT_FALSE(provenance.contains("date"));  // none given: none written
}

TEST(CalibrationFile, ProvenanceDatesAreCheckedBeforeAnythingIsWritten) {
  for (const char* date : {"2026-11-23", "2024-02-29", "2026-11-23T14:05", "2026-11-23T14:05:09Z",
                           "2026-11-23T23:59:60+01:00", "2026-11-23T00:00-05:30"}) {
    EXPECT_EQ(CheckProvenanceDate(date), std::nullopt) << date;
  }
  for (const char* date : {"", "2026-11-31", "2023-02-29", "2026-13-01", "2026-1-23", "23.11.2026",
                           "2026-11-23 14:05", "2026-11-23T24:00", "2026-11-23T14:05Z+", "today",
                           "2026-11-23T14:05:09.5Z", "2026-11-23T14:05+1:00"}) {
    EXPECT_NE(CheckProvenanceDate(date), std::nullopt) << date;
  }
  EXPECT_EQ(*CheckProvenanceDate("2026-11-31"), "'2026-11-31': that month has no day 31");
  Fixture f = Make(ModelKind::kLinear);
  f.info.provenance.date = "2026-02-30";
  EXPECT_THROW(CalibrationToJson(f.result, f.info), std::invalid_argument);
  f.info.provenance.date = "2026-02-28";
  EXPECT_EQ(ParseCalibrationJson(CalibrationToJson(f.result, f.info), "x").provenance.date,
            "2026-02-28");
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
  EXPECT_EQ(cal.version, 2);
  EXPECT_EQ(cal.verdict, "ok");
  EXPECT_EQ(cal.raw_unit, "pulses");
  EXPECT_EQ(cal.source, "sim.csv");
  // What the report reads, typed: every position's numbers bit-exact.
  ASSERT_EQ(cal.positions.size(), f.info.positions.size());
  for (std::size_t k = 0; k < cal.positions.size(); ++k) {
    EXPECT_EQ(cal.positions[k].mean, f.info.positions[k].mean);
    EXPECT_EQ(cal.positions[k].samples, f.info.positions[k].samples);
    EXPECT_EQ(*cal.positions[k].direction, f.result.directions[k]);
    EXPECT_EQ(*cal.positions[k].residual, f.result.residuals[k]);
  }
  EXPECT_EQ(cal.covariance, f.result.covariance);
  EXPECT_EQ(cal.solver.method, "joint");
  EXPECT_EQ(cal.solver.iterations, f.result.summary.iterations);
  EXPECT_TRUE(cal.solver.converged);
  ASSERT_TRUE(cal.diagnostics.has_value());
  EXPECT_EQ(cal.provenance.accelcal_version, std::string(Version()));
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
  const nlohmann::json good = nlohmann::json::parse(CalibrationToJson(f.result, f.info));
  EXPECT_EQ(LoadError("{").rfind("cal.json: not valid JSON", 0), 0u);
  nlohmann::json j = good;
  j["format"] = "other";
  EXPECT_EQ(
      LoadError(j.dump()),
      "cal.json: not an accelcal calibration file (\"format\" is not \"accelcal-calibration\")");
  j = good;
  j["version"] = 3;
  EXPECT_EQ(LoadError(j.dump()),
            "cal.json: unsupported calibration file version 3 (this accelcal reads versions 1 and "
            "2)");
  j.erase("version");
  EXPECT_EQ(LoadError(j.dump()),
            "cal.json: unsupported calibration file version (none) (this accelcal reads versions "
            "1 and 2)");
  j = good;
  j["sensors"].erase("accelerometer");
  j["sensors"]["gyroscope"] = nlohmann::json::object();
  EXPECT_EQ(LoadError(j.dump()),
            "cal.json: holds no accelerometer calibration ('sensors' has no 'accelerometer')");
  j = good;
  j["sensors"] = nlohmann::json::array();
  EXPECT_EQ(LoadError(j.dump()), "cal.json: 'sensors' must be an object");
  // The accelerometer's keys, named by their place in the file.
  nlohmann::json a = good;
  nlohmann::json& acc = a["sensors"]["accelerometer"];
  acc["K"][0][2] = 1.0;
  EXPECT_EQ(LoadError(a.dump()),
            "cal.json: 'sensors.accelerometer.K' must be lower-triangular (frame x-first)");
  // So small that a reading times its inverse is no specific force (apply wrote 1e301 m/s2).
  nlohmann::json tiny = good;
  tiny["sensors"]["accelerometer"]["K"] = {{1e-300, 0, 0}, {0, 1e-300, 0}, {0, 0, 1e-300}};
  EXPECT_EQ(LoadError(tiny.dump()).rfind("cal.json: 'sensors.accelerometer.K' is singular", 0), 0u)
      << LoadError(tiny.dump());
  acc = good["sensors"]["accelerometer"];
  acc["frame"] = "z-first";  // with the x-first (lower-triangular) K of `good`
  EXPECT_EQ(LoadError(a.dump()),
            "cal.json: 'sensors.accelerometer.K' must be upper-triangular (frame z-first)");
  acc["frame"] = "sideways";
  EXPECT_EQ(LoadError(a.dump()),
            "cal.json: 'sensors.accelerometer.frame' must be \"x-first\", \"z-first\" or "
            "\"platform\"");
  acc = good["sensors"]["accelerometer"];
  acc["bias"] = {1, 2};
  EXPECT_EQ(LoadError(a.dump()),
            "cal.json: 'sensors.accelerometer.bias' must be an array of 3 numbers");
  acc = good["sensors"]["accelerometer"];
  acc["k2"] = {1, 0, 0};
  EXPECT_EQ(LoadError(a.dump()),
            "cal.json: a linear model must have 'sensors.accelerometer.k2' = [0, 0, 0]");
  acc = good["sensors"]["accelerometer"];
  acc["units"]["specific_force"] = "ft/s2";
  EXPECT_EQ(LoadError(a.dump()),
            "cal.json: 'sensors.accelerometer.units.specific_force' must be \"m/s2\" or \"g\"");
  acc = good["sensors"]["accelerometer"];
  acc["positions"][2]["interval"] = {{"begin", 1}};
  EXPECT_EQ(LoadError(a.dump()),
            "cal.json: 'sensors.accelerometer.positions[2].interval.end' is missing");
  acc = good["sensors"]["accelerometer"];
  acc["diagnostics"] = {{{"code", "x"}, {"severity", "fatal"}, {"message", "m"}}};
  EXPECT_EQ(LoadError(a.dump()),
            "cal.json: 'sensors.accelerometer.diagnostics[0].severity' must be \"note\", "
            "\"warning\" or \"failure\"");
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
  // The unit's verdict and the sensor's: the worse counts (apply refuses a failed file).
  j = good;
  j["verdict"] = "failed";
  EXPECT_EQ(ParseCalibrationJson(j.dump(), "cal.json").verdict, "failed");
  // Provenance.
  j = good;
  j["provenance"]["inputs"] = {{{"name", "a.csv"}, {"sha256", "ABC"}}};
  EXPECT_EQ(LoadError(j.dump()),
            "cal.json: 'provenance.inputs[0].sha256' must be 64 lowercase hexadecimal digits");
  j["provenance"]["inputs"] = {{{"bytes", 5}}};
  EXPECT_EQ(LoadError(j.dump()), "cal.json: 'provenance.inputs[0].name' is missing");
  j = good;
  j["provenance"]["date"] = "yesterday";
  EXPECT_EQ(LoadError(j.dump()).rfind("cal.json: 'provenance.date': 'yesterday' is not a date", 0),
            0u);
  // A key twice in one object: the last would win (a second identity K makes apply a no-op).
  std::string text = good.dump();
  text.insert(text.find("\"K\":"), "\"K\": [[1, 0, 0], [0, 1, 0], [0, 0, 1]], ");
  EXPECT_EQ(LoadError(text), "cal.json: the key 'K' appears twice in one object");
  text = good.dump();
  text.insert(text.find("\"units\":{") + 9, "\"raw\":\"x\",");
  EXPECT_EQ(LoadError(text), "cal.json: the key 'raw' appears twice in one object");
  // The same key in different objects is not a repeat.
  EXPECT_EQ(LoadError(good.dump()), "no error");
}

}  // namespace
}  // namespace accelcal
