// A ROS 1 bag of one IMU (rosbag_writer.hpp).
#include "accelcal/rosbag_writer.hpp"

#include <algorithm>
#include <stdexcept>
#include <utility>

#include "core/little_endian.hpp"
#include "output/compress.hpp"
#include "output/ros_imu_message.hpp"

namespace accelcal {

namespace {

using internal::PutLittle;

constexpr char kVersion[] = "#ROSBAG V2.0\n";
constexpr std::size_t kHeaderRecordBytes = 4096;  // rosbag pads its header record's fields to this
constexpr std::size_t kChunkBytes = 768 * 1024;   // rosbag's default chunk threshold
constexpr std::uint32_t kConnection = 0;
enum Op : char {
  kMessage = 0x02,
  kBagHeader = 0x03,
  kIndex = 0x04,
  kChunk = 0x05,
  kChunkInfo = 0x06,
  kConnectionOp = 0x07
};

// A header field: its length, then "name=value".
void Field(std::string* header, const std::string& name, const std::string& value) {
  PutLittle<std::uint32_t>(header, static_cast<std::uint32_t>(name.size() + 1 + value.size()));
  *header += name;
  *header += '=';
  *header += value;
}
template <typename T>
std::string Bytes(T v) {
  std::string out;
  PutLittle<T>(&out, v);
  return out;
}
// A ROS time: uint32 seconds, then uint32 nanoseconds.
std::string Time(std::uint64_t ns) {
  return Bytes<std::uint32_t>(static_cast<std::uint32_t>(ns / 1000000000u)) +
         Bytes<std::uint32_t>(static_cast<std::uint32_t>(ns % 1000000000u));
}
std::string Op(char op) { return std::string(1, op); }
// A record: its header's length and header, its data's length and data.
std::string Record(const std::string& header, const std::string& data) {
  std::string out;
  PutLittle<std::uint32_t>(&out, static_cast<std::uint32_t>(header.size()));
  out += header;
  PutLittle<std::uint32_t>(&out, static_cast<std::uint32_t>(data.size()));
  return out + data;
}

std::string BagHeader(std::uint64_t index_position, std::uint32_t connections,
                      std::uint32_t chunks) {
  std::string header;
  Field(&header, "op", Op(kBagHeader));
  Field(&header, "index_pos", Bytes<std::uint64_t>(index_position));
  Field(&header, "conn_count", Bytes<std::uint32_t>(connections));
  Field(&header, "chunk_count", Bytes<std::uint32_t>(chunks));
  return Record(header, std::string(kHeaderRecordBytes - header.size(), ' '));
}

std::string ConnectionRecord(const std::string& topic) {
  std::string header;
  Field(&header, "op", Op(kConnectionOp));
  Field(&header, "conn", Bytes<std::uint32_t>(kConnection));
  Field(&header, "topic", topic);
  std::string data;
  Field(&data, "topic", topic);
  Field(&data, "type", "sensor_msgs/Imu");
  Field(&data, "md5sum", internal::kRos1ImuMd5);
  Field(&data, "message_definition", std::string(internal::Ros1ImuDefinition()));
  return Record(header, data);
}

}  // namespace

RosBagImuWriter::RosBagImuWriter(RosBagCompression compression, std::string topic)
    : compression_(compression), topic_(std::move(topic)), position_(Header().size()) {}

std::string RosBagImuWriter::Header() const { return kVersion + BagHeader(0, 0, 0); }

std::string RosBagImuWriter::Sample(std::uint64_t time_ns, const Vec3& accel, const Vec3& gyro) {
  return Message(time_ns, accel, &gyro);
}

std::string RosBagImuWriter::Sample(std::uint64_t time_ns, const Vec3& accel) {
  return Message(time_ns, accel, nullptr);
}

std::string RosBagImuWriter::Message(std::uint64_t time_ns, const Vec3& accel, const Vec3* gyro) {
  if (finished_) throw std::logic_error("RosBagImuWriter: a sample after Finish");
  const std::string message = internal::Ros1ImuMessage(sequence_, time_ns, accel, gyro);
  if (records_.empty()) chunk_ = ChunkInfo{position_, time_ns, time_ns, 0};
  if (!connected_) {  // the connection's record precedes its first message, in its chunk
    records_ += ConnectionRecord(topic_);
    connected_ = true;
  }
  ++sequence_;
  chunk_.first_ns = std::min(chunk_.first_ns, time_ns);
  chunk_.last_ns = std::max(chunk_.last_ns, time_ns);
  ++chunk_.messages;
  index_ += Time(time_ns);
  PutLittle<std::uint32_t>(&index_, static_cast<std::uint32_t>(records_.size()));
  std::string header;
  Field(&header, "op", Op(kMessage));
  Field(&header, "conn", Bytes<std::uint32_t>(kConnection));
  Field(&header, "time", Time(time_ns));
  records_ += Record(header, message);
  return records_.size() >= kChunkBytes ? Flush() : std::string();
}

std::string RosBagImuWriter::Flush() {
  if (records_.empty()) return {};
  const internal::Compression c =
      compression_ == RosBagCompression::kBz2   ? internal::Compression::kBz2
      : compression_ == RosBagCompression::kLz4 ? internal::Compression::kLz4Frame
                                                : internal::Compression::kNone;
  std::string header;
  Field(&header, "op", Op(kChunk));
  Field(&header, "compression",
        compression_ == RosBagCompression::kBz2   ? "bz2"
        : compression_ == RosBagCompression::kLz4 ? "lz4"
                                                  : "none");
  Field(&header, "size", Bytes<std::uint32_t>(static_cast<std::uint32_t>(records_.size())));
  std::string out = Record(header, internal::Compress(c, records_));
  std::string index;
  Field(&index, "op", Op(kIndex));
  Field(&index, "ver", Bytes<std::uint32_t>(1));
  Field(&index, "conn", Bytes<std::uint32_t>(kConnection));
  Field(&index, "count", Bytes<std::uint32_t>(chunk_.messages));
  out += Record(index, index_);
  chunks_.push_back(chunk_);
  records_.clear();
  index_.clear();
  position_ += out.size();
  return out;
}

std::string RosBagImuWriter::Finish() {
  if (finished_) throw std::logic_error("RosBagImuWriter: Finish twice");
  std::string out = Flush();
  finished_ = true;
  index_position_ = position_;
  if (connected_) out += ConnectionRecord(topic_);
  for (const ChunkInfo& chunk : chunks_) {
    std::string header;
    Field(&header, "op", Op(kChunkInfo));
    Field(&header, "ver", Bytes<std::uint32_t>(1));
    Field(&header, "chunk_pos", Bytes<std::uint64_t>(chunk.position));
    Field(&header, "start_time", Time(chunk.first_ns));
    Field(&header, "end_time", Time(chunk.last_ns));
    Field(&header, "count", Bytes<std::uint32_t>(1));
    out += Record(header, Bytes<std::uint32_t>(kConnection) + Bytes<std::uint32_t>(chunk.messages));
  }
  return out;
}

std::string RosBagImuWriter::IndexedHeader() const {
  if (!finished_) throw std::logic_error("RosBagImuWriter: IndexedHeader before Finish");
  return BagHeader(index_position_, connected_ ? 1 : 0, static_cast<std::uint32_t>(chunks_.size()));
}

}  // namespace accelcal
