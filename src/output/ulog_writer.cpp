// A ULog of one IMU (ulog_writer.hpp).
#include "accelcal/ulog_writer.hpp"

#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

#include "core/little_endian.hpp"

namespace accelcal {

namespace {

using internal::PutLittle;

// The message ids of the subscriptions.
constexpr std::uint16_t kAccelId = 0, kGyroId = 1;
// The fields of sensor_accel and sensor_gyro as PX4 logs them (the data messages are packed in
// this order).
constexpr const char* kFields =
    ":uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;float x;float y;float z;"
    "float temperature;uint32_t error_count;uint8_t[3] clip_counter;uint8_t samples;"
    "uint8_t[4] _padding0;";

// A message: uint16 size, uint8 type, then the payload.
std::string Message(char type, const std::string& payload) {
  std::string out;
  PutLittle<std::uint16_t>(&out, static_cast<std::uint16_t>(payload.size()));
  out.push_back(type);
  return out + payload;
}

std::string KeyValue(const std::string& key, const std::string& value) {
  std::string payload;
  payload.push_back(static_cast<char>(key.size()));
  return payload + key + value;
}

std::string Subscribe(std::uint16_t id, const std::string& topic) {
  std::string add;
  add.push_back('\0');  // multi id 0
  PutLittle<std::uint16_t>(&add, id);
  return Message('A', add + topic);
}

std::string Sample(std::uint16_t id, std::uint32_t device_id, std::uint64_t time_us, const Vec3& v,
                   double temperature_c) {
  const double most = std::numeric_limits<float>::max();
  if (!v.allFinite() || v.cwiseAbs().maxCoeff() > most) {
    throw std::invalid_argument(
        "a ULog's readings are float32: a reading is not finite or beyond its range");
  }
  std::string payload;
  PutLittle<std::uint16_t>(&payload, id);
  PutLittle<std::uint64_t>(&payload, time_us);  // timestamp
  PutLittle<std::uint64_t>(&payload, time_us);  // timestamp_sample
  PutLittle<std::uint32_t>(&payload, device_id);
  for (int a = 0; a < 3; ++a) PutLittle<float>(&payload, static_cast<float>(v(a)));
  PutLittle<float>(&payload, static_cast<float>(temperature_c));  // temperature
  PutLittle<std::uint32_t>(&payload, 0);                          // error_count
  payload.append(3, '\0');                                        // clip_counter
  payload.push_back('\1');                                        // samples
  // PX4's logger leaves the trailing padding out.
  return Message('D', payload);
}

}  // namespace

std::string ULogImuWriter::Parameter(const std::string& name, std::int32_t value) {
  std::string bytes;
  PutLittle<std::int32_t>(&bytes, value);
  return Message('P', KeyValue("int32_t " + name, bytes));
}

std::string ULogImuWriter::Header(const std::string& parameters) const {
  std::string out = {'U', 'L', 'o', 'g', 0x01, 0x12, 0x35, 0x01};
  PutLittle<std::uint64_t>(&out, 0);           // the log's start [µs]
  out += Message('B', std::string(40, '\0'));  // no flags, no appended data
  out += Message('F', std::string("sensor_accel") + kFields);
  if (gyroscope_) out += Message('F', std::string("sensor_gyro") + kFields);
  const std::string name = "accelcal simulate";
  out += Message('I', KeyValue("char[" + std::to_string(name.size()) + "] sys_name", name));
  out += parameters;
  out += Subscribe(kAccelId, "sensor_accel");
  if (gyroscope_) out += Subscribe(kGyroId, "sensor_gyro");
  return out;
}

std::string ULogImuWriter::Accel(std::uint64_t time_us, const Vec3& reading,
                                 double temperature_c) const {
  return Sample(kAccelId, device_id_, time_us, reading, temperature_c);
}

std::string ULogImuWriter::Gyro(std::uint64_t time_us, const Vec3& rate,
                                double temperature_c) const {
  if (!gyroscope_) throw std::logic_error("ULogImuWriter::Gyro: made without a gyroscope");
  return Sample(kGyroId, gyro_device_id_, time_us, rate, temperature_c);
}

}  // namespace accelcal
