#pragma once
/// @file noise_file.hpp
/// Reading what `accelcal noise --json` wrote, as the estimators' exports take it (issue 19):
/// continuous-time densities in SI units, axis by axis.

#include <array>
#include <optional>
#include <string>

#include "accelcal/types.hpp"

namespace accelcal {

/// One sensor's noise: m/s² for the accelerometer, rad/s for the gyroscope.
struct SensorNoiseDensities {
  Vec3 white = Vec3::Zero();  ///< noise density N [unit/√Hz]
  /// Bias random walk K [unit/s/√Hz = unit/√s]: the value where the log resolves it, else its
  /// 95 % upper bound (random_walk_resolved false): what an estimator can safely assume.
  Vec3 random_walk = Vec3::Zero();
  std::array<bool, 3> random_walk_resolved = {false, false, false};
  double duration_s = 0;  ///< of the samples analysed
};

struct ImuNoise {
  std::string source;  ///< the noise file
  std::string log;     ///< the log it analysed
  double rate_hz = 0;  ///< the log's sample rate
  SensorNoiseDensities accelerometer;
  std::optional<SensorNoiseDensities> gyroscope;
};

/// Reads `accelcal noise --json` output; `source` names it in errors. InputError (naming the key)
/// when it is not such a file, when its verdict is failed (its terms are not a result), when a
/// sensor is in its raw unit (the densities an estimator takes are in m/s² and rad/s: analyse
/// with a calibration), or when an axis' white noise is not resolved or random walk not fitted.
ImuNoise ParseNoiseJson(const std::string& text, const std::string& source);

}  // namespace accelcal
