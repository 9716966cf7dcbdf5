#pragma once
/// @file ulog_writer.hpp
/// Writing a PX4 ULog of one IMU, as PX4's logger writes its sensor_accel and sensor_gyro topics
/// (specification: PX4 documentation, "ULog File Format"): for simulated sessions (`accelcal
/// simulate --raw --format ulog`) and the tests of the reader (native_log.hpp). Streamed: the
/// header once, then one message per sample, never the whole log held.

#include <cmath>
#include <cstdint>
#include <string>

#include "accelcal/types.hpp"

namespace accelcal {

class ULogImuWriter {
 public:
  /// `device_id`: the device_id field of every sensor_accel message; `gyroscope`: a sensor_gyro
  /// stream too, its device_id `gyro_device_id` (each sensor has its own on PX4).
  explicit ULogImuWriter(std::uint32_t device_id = 1, bool gyroscope = false,
                         std::uint32_t gyro_device_id = 2)
      : device_id_(device_id), gyro_device_id_(gyro_device_id), gyroscope_(gyroscope) {}
  /// The header, flag bits, the formats, the log's information and the subscriptions (multi id
  /// 0: sensor_accel, then sensor_gyro).
  /// `parameters`: Parameter messages, written among the definitions (the values at the log's
  /// start).
  std::string Header(const std::string& parameters = {}) const;
  /// A parameter message (PX4's int32 parameters, as CAL_ACC0_ID): among the definitions (Header)
  /// a value at the log's start, among the samples a change made after the last one before it.
  static std::string Parameter(const std::string& name, std::int32_t value);
  /// One sensor_accel message: timestamp and timestamp_sample `time_us` [µs], the reading as
  /// float32 (x, y, z), the temperature [°C] (NaN: not measured, as PX4's drivers without one).
  /// Throws std::invalid_argument for a reading that is not finite or beyond float32's range.
  std::string Accel(std::uint64_t time_us, const Vec3& reading,
                    double temperature_c = std::nan("")) const;
  /// One sensor_gyro message, as Accel (with a gyroscope only: std::logic_error otherwise).
  std::string Gyro(std::uint64_t time_us, const Vec3& rate,
                   double temperature_c = std::nan("")) const;

 private:
  std::uint32_t device_id_, gyro_device_id_;
  bool gyroscope_;
};

}  // namespace accelcal
