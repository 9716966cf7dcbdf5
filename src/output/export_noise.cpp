// The noise analysis as the exports write it (export_common.hpp): the densities a format needs,
// their comment lines and Kalibr's keys for them (Kalibr, OpenVINS).
#include "accelcal/error.hpp"
#include "output/export_common.hpp"

namespace accelcal::exports {

// The noise an export needs, or DataError naming what is missing.
const ImuNoise& NeedNoise(const ExportOptions& options, const char* format, bool gyroscope) {
  if (!options.noise) {
    throw DataError(std::string(format) +
                    " holds the sensor's noise: give the output of accelcal noise --json");
  }
  if (gyroscope && !options.noise->gyroscope) {
    throw DataError(std::string(format) + " holds the gyroscope's noise too, and " +
                    internal::VisibleLine(options.noise->source) +
                    " has none: analyse the log with the gyroscope (accelcal noise --gyro)");
  }
  return *options.noise;
}

// One value for a tool that takes one per sensor: the largest axis' (an estimator that assumes
// less noise than an axis has trusts that axis too much).
double Largest(const Vec3& v) { return v.maxCoeff(); }

// "x, y, z" of a vector, for comments.
std::string Axes(const Vec3& v) { return Number(v(0)) + ", " + Number(v(1)) + ", " + Number(v(2)); }

// Some axis' random walk is an upper bound, not resolved in the log.
bool Unresolved(const ImuNoise& n) {
  bool any = false;
  for (bool resolved : n.accelerometer.random_walk_resolved) any = any || !resolved;
  if (n.gyroscope) {
    for (bool resolved : n.gyroscope->random_walk_resolved) any = any || !resolved;
  }
  return any;
}

// Comment lines stating where the noise comes from and what each written value is.
std::string NoiseComments(const ImuNoise& n, const char* prefix) {
  std::string t = std::string(prefix) + " noise from " + internal::VisibleLine(n.source) + " (" +
                  internal::VisibleLine(n.log) + ", " + Number(n.rate_hz) + " Hz, " +
                  Format("%.0f", n.accelerometer.duration_s) +
                  " s): continuous-time densities, the largest axis' written\n";
  const auto sensor = [&](const char* name, const SensorNoiseDensities& s, const char* unit) {
    t += std::string(prefix) + " " + name + " white noise per axis [" + unit +
         "/sqrt(Hz)]: " + Axes(s.white) + "\n";
    bool bound = false;
    for (bool resolved : s.random_walk_resolved) bound = bound || !resolved;
    t += std::string(prefix) + " " + name + " random walk per axis [" + unit +
         "/s/sqrt(Hz)]: " + Axes(s.random_walk) +
         (bound ? " (where not resolved in this log: its 95 % upper bound)" : "") + "\n";
  };
  sensor("accelerometer", n.accelerometer, "m/s2");
  if (n.gyroscope) sensor("gyroscope", *n.gyroscope, "rad/s");
  return t;
}

// Kalibr's noise keys (ConfigReader.ImuParameters), at `indent`.
std::string KalibrNoiseKeys(const ImuNoise& n, const std::string& rostopic,
                            const std::string& indent) {
  std::string t;
  t += indent + "accelerometer_noise_density: " + YamlNumber(Largest(n.accelerometer.white)) + "\n";
  t += indent + "accelerometer_random_walk: " + YamlNumber(Largest(n.accelerometer.random_walk)) +
       "\n";
  if (n.gyroscope) {
    t += indent + "gyroscope_noise_density: " + YamlNumber(Largest(n.gyroscope->white)) + "\n";
    t += indent + "gyroscope_random_walk: " + YamlNumber(Largest(n.gyroscope->random_walk)) + "\n";
  }
  t += indent + "update_rate: " + YamlNumber(n.rate_hz) + "\n";
  t += indent + "rostopic: " + YamlQuoted(rostopic) + "\n";
  return t;
}

}  // namespace accelcal::exports
