#pragma once
/// @file rosbag2_writer.hpp
/// Writing a ROS 2 bag in SQLite (a rosbag2 `.db3`) of one IMU as rosbag2 records a
/// sensor_msgs/msg/Imu topic: Iron's tables (schema 4: schema, metadata, topics,
/// message_definitions, messages and their timestamp index), messages in CDR. For simulated
/// sessions (`accelcal simulate --raw --format db3`) and the tests of the reader (native_log.hpp).
/// Streamed into the database through libsqlite3, in one transaction, never held whole; the file
/// holds no time of writing, so the same samples give the same bytes.

#include <cstdint>
#include <memory>
#include <string>

#include "accelcal/types.hpp"

namespace accelcal {

class Rosbag2SqliteImuWriter {
 public:
  /// Creates the bag's tables in the database at `path`, which must be absent or empty. The
  /// metadata names the bag's file `file_name` (default: `path`'s last component; a temporary
  /// file renamed when whole gives its final name). Throws std::runtime_error (naming `path` and
  /// SQLite's reason) when it cannot.
  explicit Rosbag2SqliteImuWriter(const std::string& path, std::string topic = "/imu/data",
                                  std::string file_name = "");
  /// A bag not finished is closed, its transaction abandoned.
  ~Rosbag2SqliteImuWriter();
  Rosbag2SqliteImuWriter(const Rosbag2SqliteImuWriter&) = delete;
  Rosbag2SqliteImuWriter& operator=(const Rosbag2SqliteImuWriter&) = delete;

  /// One message stamped (header.stamp and the record's timestamp) `time_ns` [ns] since the
  /// epoch: `accel` [m/s²] as linear_acceleration, `gyro` [rad/s] as angular_velocity (float64:
  /// exact), no orientation. Throws std::invalid_argument for a value not finite or a time past
  /// 2^31 s, std::runtime_error when SQLite fails (a full disk).
  void Sample(std::uint64_t time_ns, const Vec3& accel, const Vec3& gyro);
  /// One message of an accelerometer alone: angular_velocity zero, and its covariance[0] = -1,
  /// which marks (REP 145) a field the sensor does not measure.
  void Sample(std::uint64_t time_ns, const Vec3& accel);
  /// The bag's metadata (rosbag2's metadata.yaml, version 8, as rosbag2 stores it in the
  /// database), then the transaction committed and the database closed.
  void Finish();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace accelcal
