#pragma once
// The accelerometer's keys of a calibration file's text (calibration_file.hpp, version 2:
// `sensors.accelerometer`), for the tests that read the file as a user's script would.
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "accelcal/calibration_file.hpp"

namespace accelcal::test {

inline nlohmann::json AccelerometerKeys(const std::string& text) {
  const nlohmann::json doc = nlohmann::json::parse(text);
  EXPECT_EQ(doc.at("format"), "accelcal-calibration");
  EXPECT_EQ(doc.at("version"), kCalibrationFileVersion);
  // One sensor: the unit's verdict is the accelerometer's.
  EXPECT_EQ(doc.at("verdict"), doc.at("sensors").at("accelerometer").at("verdict"));
  return doc.at("sensors").at("accelerometer");
}

}  // namespace accelcal::test
