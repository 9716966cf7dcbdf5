// The rules between the gyroscope's calibration options (GyroCalibrationOptions::Validate).
#include <cmath>
#include <optional>
#include <string>

#include "accelcal/gyro_calibration.hpp"
#include "accelcal/thermal.hpp"
#include "core/text_format.hpp"

namespace accelcal {

std::optional<std::string> GyroCalibrationOptions::Validate() const {
  const bool imutk = estimator == GyroEstimator::kImuTk;
  if (thermal) {
    if (thermal->degree) {
      if (*thermal->degree < 0 || *thermal->degree > kMaxThermalDegree) {
        return internal::Format("{{gyro_thermal}}: '%d' is neither auto nor a degree from 0 to %d",
                                *thermal->degree, kMaxThermalDegree);
      }
    } else if (!validate) {
      return "{{gyro_thermal}} auto (the default with {{thermal}}) decides on held-out error: it "
             "needs the cross-validation that {{no_crossval}} turns off; give {{gyro_thermal}} 0 "
             "to 3";
    }
  }
  if (!model) {
    // imu_tk's method has one model: nothing to choose, so no validation needed to choose it.
    if (!validate && !imutk) {
      return "the gyro's model is chosen on held-out rotations ({{gyro_model}} auto, the "
             "default), which {{no_crossval}} turns off: give {{gyro_model}} linear or "
             "g-sensitive";
    }
  } else if (imutk && *model != GyroModelKind::kLinear) {
    return "{{gyro_estimator}} imutk is imu_tk's method, which has no g-sensitivity: "
           "{{gyro_model}} linear";
  }
  if (latitude_deg && !(std::abs(*latitude_deg) <= 90)) {
    return "{{latitude}} must lie in [-90, 90]";
  }
  if (threads < 0) return "the number of threads must be >= 0 (0: one per hardware thread)";
  return std::nullopt;
}

}  // namespace accelcal
