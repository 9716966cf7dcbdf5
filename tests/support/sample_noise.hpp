#pragma once
// A sensor's noise as `accelcal export --noise` takes it, for the tests that run every export
// format (the noise formats need one).
#include "accelcal/noise_file.hpp"

namespace accelcal::test {

inline ImuNoise SampleNoise(const std::string& source = "noise.json") {
  ImuNoise n;
  n.source = source;
  n.log = "still.csv";
  n.rate_hz = 200;
  n.accelerometer.white = Vec3(8.2e-4, 8.9e-4, 8.8e-4);
  n.accelerometer.random_walk = Vec3(6.8e-4, 8.5e-4, 1.9e-3);
  n.accelerometer.duration_s = 52;
  SensorNoiseDensities g;
  g.white = Vec3(6.1e-4, 6.1e-4, 6.2e-4);
  g.random_walk = Vec3(3.6e-4, 5.0e-4, 4.2e-4);
  g.random_walk_resolved = {true, false, true};
  g.duration_s = 52;
  n.gyroscope = g;
  return n;
}

}  // namespace accelcal::test
