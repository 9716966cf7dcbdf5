// libFuzzer harness: binary logs (native_log.hpp: PX4 ULog, ArduPilot DataFlash, ROS bags) read by
// ParseInput as every stream choice a user could make (none, a topic, a topic and instance, named
// columns).
// The only accepted failure is InputError (the file, the byte or message, the reason); anything
// else is a finding. What is read must be what a raw log promises: finite samples and times, times
// from 0 that never go back.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "accelcal/error.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/native_log.hpp"
#include "input_check.hpp"

namespace {

void Read(std::string_view bytes, const accelcal::ReadOptions& options) {
  try {
    accelcal::fuzz::CheckInput(accelcal::ParseInput(bytes, "fuzz.ulg", options));
  } catch (const accelcal::InputError&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  // Text is fuzz_log_reader's.
  if (accelcal::DetectLogFormat(bytes.substr(0, 16)) == accelcal::LogFormat::kText) return 0;
  accelcal::ReadOptions options;
  Read(bytes, options);
  options.topic = "sensor_accel";
  Read(bytes, options);
  options.instance = 0;
  Read(bytes, options);
  options.topic = "IMU";
  options.instance = 1;
  options.sensor = accelcal::SensorKind::kGyroscope;
  Read(bytes, options);
  options.sensor = accelcal::SensorKind::kAccelerometer;
  options.topic = "sensor_combined";
  options.instance.reset();
  options.columns = {"timestamp", "gyro_rad[0]", "gyro_rad[1]", "gyro_rad[2]"};
  Read(bytes, options);
  options.topic = "/imu";
  options.columns = {"header.stamp", "angular_velocity.x", "angular_velocity.y",
                     "angular_velocity.z"};
  Read(bytes, options);
  return 0;
}
