#pragma once
/// @file ulog_writer.hpp
/// Writing a PX4 ULog of one accelerometer, as PX4's logger writes its sensor_accel topic
/// (specification: PX4 documentation, "ULog File Format"): for simulated sessions (`accelcal
/// simulate --raw --format ulog`) and the tests of the reader (native_log.hpp). Streamed: the
/// header once, then one message per sample, never the whole log held.

#include <cstdint>
#include <string>

#include "accelcal/types.hpp"

namespace accelcal {

class ULogAccelWriter {
 public:
  /// `device_id`: the sensor_accel device_id field of every message.
  explicit ULogAccelWriter(std::uint32_t device_id = 1) : device_id_(device_id) {}
  /// The header, flag bits, the sensor_accel format, the log's information and the subscription
  /// (multi id 0).
  std::string Header() const;
  /// One sensor_accel message: timestamp and timestamp_sample `time_us` [µs], the reading as
  /// float32 (x, y, z), temperature NaN. Throws std::invalid_argument for a reading that is not
  /// finite or beyond float32's range.
  std::string Sample(std::uint64_t time_us, const Vec3& reading) const;

 private:
  std::uint32_t device_id_;
};

}  // namespace accelcal
