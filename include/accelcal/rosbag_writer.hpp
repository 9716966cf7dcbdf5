#pragma once
/// @file rosbag_writer.hpp
/// Writing a ROS 1 bag (format 2.0) of one IMU as `rosbag record` writes a sensor_msgs/Imu topic
/// (specification: ROS wiki, "Bags/Format/2.0"): for simulated sessions (`accelcal simulate --raw
/// --format rosbag`) and the tests of the reader (native_log.hpp). Streamed: chunks of about
/// 768 kB (rosbag's default), each followed by its index, handed out as they fill. A bag's header
/// holds where its index begins, known only at the end: IndexedHeader() is written over the
/// header once the bag is finished, as rosbag does.

#include <cstdint>
#include <string>
#include <vector>

#include "accelcal/types.hpp"

namespace accelcal {

enum class RosBagCompression { kNone, kBz2, kLz4 };

class RosBagImuWriter {
 public:
  /// Where the bag header record begins (after the version line "#ROSBAG V2.0\n").
  static constexpr std::uint64_t kHeaderOffset = 13;

  /// The messages of topic `topic`, their chunks compressed with `compression`.
  explicit RosBagImuWriter(RosBagCompression compression = RosBagCompression::kNone,
                           std::string topic = "/imu/data");
  /// The version line and the bag header record, padded to 4096 bytes, its index position 0 (a
  /// bag not yet closed).
  std::string Header() const;
  /// One sensor_msgs/Imu message (header.seq counting from 0) stamped (header.stamp and record
  /// time) `time_ns` [ns] since the epoch, `accel` [m/s²] as linear_acceleration and `gyro`
  /// [rad/s] as angular_velocity (float64: exact), no orientation. Returns what is to be written
  /// now: a chunk and its index record when one is full, else nothing. Throws
  /// std::invalid_argument for a value not finite or a time past 2^32 s.
  std::string Sample(std::uint64_t time_ns, const Vec3& accel, const Vec3& gyro);
  /// One message of an accelerometer alone: angular_velocity zero, and its covariance[0] = -1,
  /// which marks (REP 145) a field the sensor does not measure.
  std::string Sample(std::uint64_t time_ns, const Vec3& accel);
  /// The last chunk, then the index section: the connection record and each chunk's info record.
  std::string Finish();
  /// After Finish: the bag header record (the same length as Header()'s) with the index position
  /// and the connection and chunk counts, to be written at byte kHeaderOffset.
  std::string IndexedHeader() const;

 private:
  struct ChunkInfo {
    std::uint64_t position = 0, first_ns = 0, last_ns = 0;
    std::uint32_t messages = 0;
  };
  std::string Flush();  // the chunk so far and its index record
  std::string Message(std::uint64_t time_ns, const Vec3& accel, const Vec3* gyro);  // a Sample

  RosBagCompression compression_;
  std::string topic_;
  std::string records_;  // the chunk being filled
  std::string index_;    // its index entries: (time, offset) of each message
  ChunkInfo chunk_;      // the chunk being filled
  std::vector<ChunkInfo> chunks_;
  std::uint64_t position_;  // bytes handed out so far (the header's from the start)
  std::uint64_t index_position_ = 0;
  std::uint32_t sequence_ = 0;
  bool connected_ = false, finished_ = false;
};

}  // namespace accelcal
