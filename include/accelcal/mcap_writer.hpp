#pragma once
/// @file mcap_writer.hpp
/// Writing an MCAP file of one IMU as ROS 2's recorder writes a sensor_msgs/msg/Imu topic
/// (specification: mcap.dev, "MCAP Format Specification"; the ros2msg schema, CDR messages): for
/// simulated sessions (`accelcal simulate --raw --format mcap`) and the tests of the reader
/// (native_log.hpp). Streamed: chunks of about 768 kB (each followed by its message index) are
/// handed out as they fill, never the whole file held.

#include <cstdint>
#include <string>

#include "accelcal/types.hpp"

namespace accelcal {

enum class McapCompression { kNone, kLz4, kZstd };

class McapImuWriter {
 public:
  /// The messages of topic `topic`, their chunks compressed with `compression`.
  explicit McapImuWriter(McapCompression compression = McapCompression::kZstd,
                         std::string topic = "/imu/data");
  /// The magic, the Header record (profile ros2), the schema and the channel.
  std::string Header() const;
  /// One sensor_msgs/msg/Imu message stamped (header.stamp and log time) `time_ns` [ns], with
  /// `accel` [m/s²] as its linear_acceleration and `gyro` [rad/s] its angular_velocity (float64:
  /// exact), no orientation (covariance[0] = -1, as REP 145 asks). Returns what is to be written
  /// now: a chunk and its message index when one is full, else nothing.
  std::string Sample(std::uint64_t time_ns, const Vec3& accel, const Vec3& gyro);
  /// One message of an accelerometer alone: angular_velocity zero, and its covariance[0] = -1,
  /// which marks (REP 145) a field the sensor does not measure.
  std::string Sample(std::uint64_t time_ns, const Vec3& accel);
  /// The last chunk, the Data End record, the Footer and the closing magic.
  std::string Finish();

 private:
  std::string Flush();  // the chunk so far, compressed, and its message index
  std::string Message(std::uint64_t time_ns, const Vec3& accel, const Vec3* gyro);  // a Sample

  McapCompression compression_;
  std::string topic_;
  std::string records_;  // the chunk being filled (Message records)
  std::string index_;    // its message index: (log time, offset) of each message
  std::uint64_t first_ns_ = 0, last_ns_ = 0;
  std::uint32_t sequence_ = 0;
};

}  // namespace accelcal
