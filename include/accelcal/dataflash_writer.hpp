#pragma once
/// @file dataflash_writer.hpp
/// Writing an ArduPilot DataFlash log of one IMU, as ArduPilot logs its IMU records (FMT
/// "QBffffffIIfBBHH": TimeUS, I, GyrX..Z, AccX..Z, EG, EA, T, GH, AH, GHz, AHz): for simulated
/// sessions (`accelcal simulate --raw --format dataflash`) and the tests of the reader
/// (native_log.hpp). Streamed: the FMT records once, then one record per sample.

#include <cmath>
#include <cstdint>
#include <string>

#include "accelcal/types.hpp"

namespace accelcal {

class DataFlashImuWriter {
 public:
  /// `instance`: the I field of every record.
  explicit DataFlashImuWriter(std::uint8_t instance = 0) : instance_(instance) {}
  /// The FMT records of FMT itself, of PARM and of IMU.
  std::string Header() const;
  /// One PARM record (TimeUS, Name, Value: "QNf"), as ArduPilot logs each parameter at the start.
  std::string Parameter(std::uint64_t time_us, const std::string& name, float value) const;
  /// One IMU record at `time_us` [µs]: the accelerometer's reading and the gyroscope's rate as
  /// float32, and the temperature T [°C] (NaN: not measured). Throws std::invalid_argument for a
  /// value that is not finite or beyond float32's range.
  std::string Sample(std::uint64_t time_us, const Vec3& accel, const Vec3& gyro,
                     double temperature_c = std::nan("")) const;

 private:
  std::uint8_t instance_;
};

}  // namespace accelcal
