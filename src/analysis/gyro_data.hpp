#pragma once
// The gyroscope's data from a recording (gyro_data.cpp): the still rates, the turns between
// positions and where the gyro is still, shared by the calibration and its verification on a new
// recording (verify.hpp).
#include <string>
#include <vector>

#include "accelcal/calibration_types.hpp"
#include "accelcal/gyro_calibration.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/positions.hpp"
#include "solvers/gyro_fit.hpp"

namespace accelcal::internal {

struct Built {
  GyroFitData data;
  std::vector<GyroRotation> rotations;     // one per motion
  std::vector<StaticInterval> still_runs;  // per position: where the gyro is still (or empty)
  std::vector<double> t;                   // the integration times
  double step_s = 0;                       // their typical step
};

/// `x` with `digits` significant digits, for the gyroscope's messages.
std::string Num(double x, int digits);
/// "x", "y" or "z".
std::string AxisName(int axis);

/// The samples first..last (inclusive) as a motion: times, raw rates, and the specific force of
/// the calibrated accelerometer at each (the last one it could calibrate, from `f0`).
GyroMotion SamplesOf(const RawLog& accel, const RawLog& gyro, const std::vector<double>& t,
                     const ModelParameters& accel_params, Vec3 f0, std::size_t first,
                     std::size_t last);

/// The gyro fit's data for `positions` of `accel` (their directions and forces from `accel_cal`,
/// its directions, gravity and parameters), checked: the gyro still in every position, no gap or
/// saturation in a turn. Throws DataError naming the position or line otherwise.
Built BuildData(const RawLog& accel, const RawLog& gyro, const std::vector<Position>& positions,
                const CalibrationResult& accel_cal, const GyroCalibrationOptions& options);

}  // namespace accelcal::internal
