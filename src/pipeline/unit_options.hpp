#pragma once
// The library's options of a unit's request (calibrate_unit.hpp), for unit_request.cpp and
// calibrate_unit.cpp.

#include <string>

#include "accelcal/calibrate_unit.hpp"
#include "accelcal/known_orientation.hpp"

namespace accelcal {

/// A bias random walk below 1e-12 m/s²/√s is none (1 ng after a day); above 1e3 it would move the
/// bias by a hundred g in a second.
inline constexpr double kMinRandomWalk = 1e-12, kMaxRandomWalk = 1e3;

/// The bias model as asked for: "auto", its name, or "constant" when none was.
std::string BiasModelText(const UnitRequest& r);
/// The gyroscope's estimator: as asked for, else two-stage on top of known orientations or a
/// calibration over temperature, else joint.
GyroEstimator GyroEstimatorOf(const UnitRequest& r);
/// The gyroscope's options (its thermal T_ref is the accelerometer's, set once that is fitted).
GyroCalibrationOptions GyroOptionsOf(const UnitRequest& r);
/// The orientation-free fit's options (the linear model when the model is chosen).
CalibrationOptions CalibrationOptionsOf(const UnitRequest& r);
KnownOrientationOptions KnownOrientationOptionsOf(const UnitRequest& r);

}  // namespace accelcal
