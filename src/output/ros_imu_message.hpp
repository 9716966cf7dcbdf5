#pragma once
// One sensor_msgs/Imu message as the ROS writers serialise it, for the bag writers
// (rosbag_writer.hpp, mcap_writer.hpp, rosbag2_writer.hpp): ROS 1 serialisation (ROS wiki,
// "roslib/Serialization": packed, little-endian, a string preceded by its uint32 length, time as
// uint32 sec and nsec) and ROS 2's CDR (little-endian, after the 4-byte encapsulation, each value
// aligned to its size; a string's length counts its terminating NUL). Both carry header.stamp
// `time_ns`, frame_id "imu_link", no orientation (orientation_covariance[0] = -1, as REP 145
// asks), `gyro` [rad/s] as angular_velocity and `accel` [m/s²] as linear_acceleration, float64:
// exact.

#include <cstdint>
#include <string>
#include <string_view>

#include "accelcal/types.hpp"

namespace accelcal::internal {

/// The ROS 1 definition of sensor_msgs/Imu as a bag's connection header carries it (the type's
/// fields, then each type it uses) and its MD5 sum (ROS's hash of the definition's canonical
/// text, which a ROS 1 reader checks against its own).
std::string_view Ros1ImuDefinition();
inline constexpr char kRos1ImuMd5[] = "6a62c6daae103f4ff57a132d6f95cec2";

/// The message in ROS 1 serialisation, its header's seq `seq`. `gyro` null: no rates
/// (angular_velocity zero and angular_velocity_covariance[0] = -1, as REP 145 marks a field the
/// sensor does not measure).
std::string Ros1ImuMessage(std::uint32_t seq, std::uint64_t time_ns, const Vec3& accel,
                           const Vec3* gyro);
/// The message in CDR (ROS 2: no seq).
std::string Ros2ImuMessage(std::uint64_t time_ns, const Vec3& accel, const Vec3* gyro);

}  // namespace accelcal::internal
