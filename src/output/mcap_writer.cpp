// MCAP writer of one IMU (mcap_writer.hpp).
#include "accelcal/mcap_writer.hpp"

#include <cmath>
#include <cstring>
#include <stdexcept>

#include "core/crc32.hpp"
#include "core/little_endian.hpp"
#include "io/ros_message.hpp"
#include "output/compress.hpp"
#include "output/ros_imu_message.hpp"

namespace accelcal {

namespace {

constexpr char kMagic[8] = {'\x89', 'M', 'C', 'A', 'P', '0', '\r', '\n'};
constexpr std::size_t kChunkBytes = 768 * 1024;  // MCAP's writers' default
constexpr std::uint16_t kSchemaId = 1, kChannelId = 1;

using internal::PutLittle;

void PutString(std::string* out, const std::string& s) {
  PutLittle<std::uint32_t>(out, static_cast<std::uint32_t>(s.size()));
  *out += s;
}
// A record: its opcode, its content's length, its content.
std::string Record(unsigned char op, const std::string& content) {
  std::string r(1, static_cast<char>(op));
  PutLittle<std::uint64_t>(&r, content.size());
  return r + content;
}

}  // namespace

McapImuWriter::McapImuWriter(McapCompression compression, std::string topic)
    : compression_(compression), topic_(std::move(topic)) {}

std::string McapImuWriter::Header() const {
  std::string out(kMagic, sizeof kMagic);
  std::string header;
  PutString(&header, "ros2");
  PutString(&header, "accelcal");
  out += Record(0x01, header);
  std::string schema;
  PutLittle<std::uint16_t>(&schema, kSchemaId);
  PutString(&schema, "sensor_msgs/msg/Imu");
  PutString(&schema, "ros2msg");
  PutString(&schema, std::string(internal::KnownRos2Definition("sensor_msgs/msg/Imu")));
  out += Record(0x03, schema);
  std::string channel;
  PutLittle<std::uint16_t>(&channel, kChannelId);
  PutLittle<std::uint16_t>(&channel, kSchemaId);
  PutString(&channel, topic_);
  PutString(&channel, "cdr");
  PutLittle<std::uint32_t>(&channel, 0);  // metadata: an empty map
  out += Record(0x04, channel);
  return out;
}

std::string McapImuWriter::Sample(std::uint64_t time_ns, const Vec3& accel, const Vec3& gyro) {
  return Message(time_ns, accel, &gyro);
}

std::string McapImuWriter::Sample(std::uint64_t time_ns, const Vec3& accel) {
  return Message(time_ns, accel, nullptr);
}

std::string McapImuWriter::Message(std::uint64_t time_ns, const Vec3& accel, const Vec3* gyro) {
  std::string message;
  PutLittle<std::uint16_t>(&message, kChannelId);
  PutLittle<std::uint32_t>(&message, sequence_++);
  PutLittle<std::uint64_t>(&message, time_ns);  // log time
  PutLittle<std::uint64_t>(&message, time_ns);  // publish time
  message += internal::Ros2ImuMessage(time_ns, accel, gyro);
  if (records_.empty()) first_ns_ = time_ns;
  last_ns_ = time_ns;
  PutLittle<std::uint64_t>(&index_, time_ns);
  PutLittle<std::uint64_t>(&index_, records_.size());
  records_ += Record(0x05, message);
  return records_.size() >= kChunkBytes ? Flush() : std::string();
}

std::string McapImuWriter::Flush() {
  if (records_.empty()) return {};
  std::string chunk;
  PutLittle<std::uint64_t>(&chunk, first_ns_);
  PutLittle<std::uint64_t>(&chunk, last_ns_);
  PutLittle<std::uint64_t>(&chunk, records_.size());
  PutLittle<std::uint32_t>(
      &chunk,
      internal::Crc32(reinterpret_cast<const unsigned char*>(records_.data()), records_.size()));
  PutString(&chunk, compression_ == McapCompression::kLz4    ? "lz4"
                    : compression_ == McapCompression::kZstd ? "zstd"
                                                             : "");
  const std::string data =
      internal::Compress(compression_ == McapCompression::kLz4    ? internal::Compression::kLz4Frame
                         : compression_ == McapCompression::kZstd ? internal::Compression::kZstd
                                                                  : internal::Compression::kNone,
                         records_);
  PutLittle<std::uint64_t>(&chunk, data.size());
  chunk += data;
  std::string out = Record(0x06, chunk);
  std::string index;
  PutLittle<std::uint16_t>(&index, kChannelId);
  PutLittle<std::uint32_t>(&index, static_cast<std::uint32_t>(index_.size()));
  index += index_;
  out += Record(0x07, index);
  records_.clear();
  index_.clear();
  return out;
}

std::string McapImuWriter::Finish() {
  std::string out = Flush();
  std::string data_end;
  PutLittle<std::uint32_t>(&data_end, 0);  // the data section's CRC: not computed
  out += Record(0x0F, data_end);
  std::string footer;
  PutLittle<std::uint64_t>(&footer, 0);  // no summary
  PutLittle<std::uint64_t>(&footer, 0);
  PutLittle<std::uint32_t>(&footer, 0);
  out += Record(0x02, footer);
  out.append(kMagic, sizeof kMagic);
  return out;
}

}  // namespace accelcal
