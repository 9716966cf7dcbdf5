// sensor_msgs/Imu serialised for ROS 1 and ROS 2 (ros_imu_message.hpp).
#include "output/ros_imu_message.hpp"

#include <stdexcept>

#include "core/little_endian.hpp"

namespace accelcal::internal {

namespace {

constexpr char kFrame[] = "imu_link";

// The body after the header, shared by both: orientation (none), angular velocity, linear
// acceleration, each with its covariance (float64, 8-aligned in CDR as they fall).
template <typename PutDouble>
void Body(const Vec3& accel, const Vec3* gyro, PutDouble put) {
  if (!accel.allFinite() || (gyro != nullptr && !gyro->allFinite())) {
    throw std::invalid_argument("a sensor_msgs/Imu reading that is not finite");
  }
  for (double q : {0.0, 0.0, 0.0, 1.0}) put(q);
  for (int i = 0; i < 9; ++i) put(i == 0 ? -1.0 : 0.0);  // no orientation
  for (int a = 0; a < 3; ++a) put(gyro != nullptr ? (*gyro)(a) : 0.0);
  for (int i = 0; i < 9; ++i) put(i == 0 && gyro == nullptr ? -1.0 : 0.0);  // no rates
  for (int a = 0; a < 3; ++a) put(accel(a));
  for (int i = 0; i < 9; ++i) put(0.0);
}

}  // namespace

std::string_view Ros1ImuDefinition() {
#define ACCELCAL_RULE \
  "================================================================================\n"
  static constexpr char kImu[] =
      "Header header\n"
      "geometry_msgs/Quaternion orientation\n"
      "float64[9] orientation_covariance\n"
      "geometry_msgs/Vector3 angular_velocity\n"
      "float64[9] angular_velocity_covariance\n"
      "geometry_msgs/Vector3 linear_acceleration\n"
      "float64[9] linear_acceleration_covariance\n" ACCELCAL_RULE
      "MSG: std_msgs/Header\n"
      "uint32 seq\n"
      "time stamp\n"
      "string frame_id\n" ACCELCAL_RULE
      "MSG: geometry_msgs/Quaternion\n"
      "float64 x\n"
      "float64 y\n"
      "float64 z\n"
      "float64 w\n" ACCELCAL_RULE
      "MSG: geometry_msgs/Vector3\n"
      "float64 x\n"
      "float64 y\n"
      "float64 z\n";
#undef ACCELCAL_RULE
  return kImu;
}

std::string Ros1ImuMessage(std::uint32_t seq, std::uint64_t time_ns, const Vec3& accel,
                           const Vec3* gyro) {
  if (time_ns / 1000000000u > 0xffffffffu) {
    throw std::invalid_argument("a ROS 1 time is at most 2^32 - 1 s (the year 2106)");
  }
  std::string out;
  out.reserve(330);
  PutLittle<std::uint32_t>(&out, seq);
  PutLittle<std::uint32_t>(&out, static_cast<std::uint32_t>(time_ns / 1000000000u));
  PutLittle<std::uint32_t>(&out, static_cast<std::uint32_t>(time_ns % 1000000000u));
  PutLittle<std::uint32_t>(&out, sizeof kFrame - 1);
  out.append(kFrame, sizeof kFrame - 1);
  Body(accel, gyro, [&](double v) { PutLittle<double>(&out, v); });
  return out;
}

std::string Ros2ImuMessage(std::uint64_t time_ns, const Vec3& accel, const Vec3* gyro) {
  if (time_ns / 1000000000u > 0x7fffffffu) {
    throw std::invalid_argument("a ROS 2 time is at most 2^31 - 1 s (the year 2038)");
  }
  std::string out("\x00\x01\x00\x00", 4);  // CDR, little-endian
  out.reserve(330);
  // Each value aligned to its size, counted from after the encapsulation.
  const auto align = [&](std::size_t size) {
    while ((out.size() - 4) % size != 0) out += '\0';
  };
  PutLittle<std::int32_t>(&out, static_cast<std::int32_t>(time_ns / 1000000000u));
  PutLittle<std::uint32_t>(&out, static_cast<std::uint32_t>(time_ns % 1000000000u));
  PutLittle<std::uint32_t>(&out, sizeof kFrame);  // with its NUL
  out.append(kFrame, sizeof kFrame);
  Body(accel, gyro, [&](double v) {
    align(sizeof v);
    PutLittle<double>(&out, v);
  });
  return out;
}

}  // namespace accelcal::internal
