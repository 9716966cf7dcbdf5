#pragma once
// A ROS message type read from its definition text, as a bag carries it (ROS 1 bag connection
// headers' message_definition, MCAP's ros1msg and ros2msg schemas: the type's own fields, then
// each type it uses after a line of '=' and "MSG: package/Type"), and its messages decoded from
// ROS 1 serialisation (ROS wiki, "msg" and "roslib/Serialization": little-endian, packed,
// strings and variable-length arrays preceded by a uint32 count, time and duration as two 32-bit
// integers) or ROS 2's CDR (OMG CDR, little-endian: each value aligned to its size from the
// message's start after the encapsulation, strings with their terminating NUL counted).

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace accelcal::internal {

/// ROS 1 (.msg of ROS 1, its serialisation) or ROS 2 (.msg of ROS 2, "ros2msg": bounded strings
/// and sequences, defaults, builtin_interfaces/Time; messages in CDR, little-endian, after the
/// 4-byte RTPS encapsulation).
enum class RosVersion { kRos1, kRos2 };

/// The ros2msg definitions (with the types they use) of the sensor types accelcal knows, for a
/// bag that does not carry its own (rosbag2's SQLite storage before Iron): sensor_msgs/msg/Imu,
/// Temperature and MagneticField. Empty for another type.
std::string_view KnownRos2Definition(std::string_view type);

class RosMessageType {
 public:
  /// Parses the definition of `type` ("sensor_msgs/Imu"; ROS 2's "sensor_msgs/msg/Imu" is the
  /// same name). Throws DataError (the reason) for a definition that does not parse, uses a type
  /// it does not define, or nests a type in itself.
  RosMessageType(std::string_view type, std::string_view definition,
                 RosVersion version = RosVersion::kRos1);
  ~RosMessageType();
  RosMessageType(RosMessageType&&) noexcept;

  const std::string& name() const;
  /// Its numeric fields flattened as rosbag's tools name them (`header.stamp`,
  /// `linear_acceleration.x`, `orientation_covariance[0]`): scalars, time and duration, and the
  /// elements of fixed-length arrays; strings and variable-length arrays are not columns, nor what
  /// lies beyond the first kMaxFormatColumns.
  const std::shared_ptr<const std::vector<std::string>>& columns() const;
  /// The column `header.stamp` (a std_msgs/Header first), if it has one.
  std::optional<std::size_t> stamp() const;
  /// Its columns of ROS time and duration types (time, duration, builtin_interfaces/Time and
  /// Duration), which Decode gives in µs; the others are the numbers the message holds.
  const std::vector<std::size_t>& microseconds() const;

  /// Decodes one message of `n` bytes at `p` into `values` (one per column; time and duration
  /// in µs). Returns the reason when its bytes are not one such message (too few, too many, not
  /// little-endian CDR).
  std::optional<std::string> Decode(const unsigned char* p, std::size_t n, double* values) const;
  /// The `header.frame_id` of one message of `n` bytes at `p`, when the type begins with a
  /// std_msgs/Header (as stamp() has it) and the header's bytes hold it; else nullopt.
  std::optional<std::string> FrameId(const unsigned char* p, std::size_t n) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace accelcal::internal
