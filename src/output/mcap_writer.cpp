// MCAP writer of one IMU (mcap_writer.hpp).
#include "accelcal/mcap_writer.hpp"

#include <lz4frame.h>
#include <zstd.h>

#include <cmath>
#include <cstring>
#include <stdexcept>

#include "core/crc32.hpp"
#include "io/ros_message.hpp"

namespace accelcal {

namespace {

constexpr char kMagic[8] = {'\x89', 'M', 'C', 'A', 'P', '0', '\r', '\n'};
constexpr std::size_t kChunkBytes = 768 * 1024;  // MCAP's writers' default
constexpr std::uint16_t kSchemaId = 1, kChannelId = 1;

template <typename T>
void Put(std::string* out, T v) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  out->append(b, sizeof(T));
}
void PutString(std::string* out, const std::string& s) {
  Put<std::uint32_t>(out, static_cast<std::uint32_t>(s.size()));
  *out += s;
}
// A record: its opcode, its content's length, its content.
std::string Record(unsigned char op, const std::string& content) {
  std::string r(1, static_cast<char>(op));
  Put<std::uint64_t>(&r, content.size());
  return r + content;
}

// CDR, little-endian: each value aligned to its size from the start after the encapsulation.
class Cdr {
 public:
  Cdr() : out_("\x00\x01\x00\x00", 4) {}
  template <typename T>
  void Put(T v) {
    while ((out_.size() - 4) % sizeof(T) != 0) out_ += '\0';
    accelcal::Put<T>(&out_, v);
  }
  void String(const std::string& s) {  // its length counts the terminating NUL
    Put<std::uint32_t>(static_cast<std::uint32_t>(s.size() + 1));
    out_ += s;
    out_ += '\0';
  }
  const std::string& bytes() const { return out_; }

 private:
  std::string out_;
};

std::string Compress(McapCompression c, const std::string& in) {
  if (c == McapCompression::kLz4) {
    std::string out(LZ4F_compressFrameBound(in.size(), nullptr), '\0');
    const std::size_t n = LZ4F_compressFrame(out.data(), out.size(), in.data(), in.size(), nullptr);
    if (LZ4F_isError(n)) throw std::runtime_error("lz4 could not compress a chunk");
    out.resize(n);
    return out;
  }
  std::string out(ZSTD_compressBound(in.size()), '\0');
  const std::size_t n = ZSTD_compress(out.data(), out.size(), in.data(), in.size(), 3);
  if (ZSTD_isError(n)) throw std::runtime_error("zstd could not compress a chunk");
  out.resize(n);
  return out;
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
  Put<std::uint16_t>(&schema, kSchemaId);
  PutString(&schema, "sensor_msgs/msg/Imu");
  PutString(&schema, "ros2msg");
  PutString(&schema, std::string(internal::KnownRos2Definition("sensor_msgs/msg/Imu")));
  out += Record(0x03, schema);
  std::string channel;
  Put<std::uint16_t>(&channel, kChannelId);
  Put<std::uint16_t>(&channel, kSchemaId);
  PutString(&channel, topic_);
  PutString(&channel, "cdr");
  Put<std::uint32_t>(&channel, 0);  // metadata: an empty map
  out += Record(0x04, channel);
  return out;
}

std::string McapImuWriter::Sample(std::uint64_t time_ns, const Vec3& accel, const Vec3& gyro) {
  if (!accel.allFinite() || !gyro.allFinite()) {
    throw std::invalid_argument("McapImuWriter: a reading that is not finite");
  }
  Cdr m;
  m.Put<std::int32_t>(static_cast<std::int32_t>(time_ns / 1000000000u));
  m.Put<std::uint32_t>(static_cast<std::uint32_t>(time_ns % 1000000000u));
  m.String("imu_link");
  for (double q : {0.0, 0.0, 0.0, 1.0}) m.Put<double>(q);
  for (int i = 0; i < 9; ++i) m.Put<double>(i == 0 ? -1.0 : 0.0);  // no orientation
  for (int a = 0; a < 3; ++a) m.Put<double>(gyro(a));
  for (int i = 0; i < 9; ++i) m.Put<double>(0.0);
  for (int a = 0; a < 3; ++a) m.Put<double>(accel(a));
  for (int i = 0; i < 9; ++i) m.Put<double>(0.0);
  std::string message;
  Put<std::uint16_t>(&message, kChannelId);
  Put<std::uint32_t>(&message, sequence_++);
  Put<std::uint64_t>(&message, time_ns);  // log time
  Put<std::uint64_t>(&message, time_ns);  // publish time
  message += m.bytes();
  if (records_.empty()) first_ns_ = time_ns;
  last_ns_ = time_ns;
  Put<std::uint64_t>(&index_, time_ns);
  Put<std::uint64_t>(&index_, records_.size());
  records_ += Record(0x05, message);
  return records_.size() >= kChunkBytes ? Flush() : std::string();
}

std::string McapImuWriter::Flush() {
  if (records_.empty()) return {};
  const bool compressed = compression_ != McapCompression::kNone;
  std::string chunk;
  Put<std::uint64_t>(&chunk, first_ns_);
  Put<std::uint64_t>(&chunk, last_ns_);
  Put<std::uint64_t>(&chunk, records_.size());
  Put<std::uint32_t>(
      &chunk,
      internal::Crc32(reinterpret_cast<const unsigned char*>(records_.data()), records_.size()));
  PutString(&chunk, compression_ == McapCompression::kLz4    ? "lz4"
                    : compression_ == McapCompression::kZstd ? "zstd"
                                                             : "");
  const std::string data = compressed ? Compress(compression_, records_) : records_;
  Put<std::uint64_t>(&chunk, data.size());
  chunk += data;
  std::string out = Record(0x06, chunk);
  std::string index;
  Put<std::uint16_t>(&index, kChannelId);
  Put<std::uint32_t>(&index, static_cast<std::uint32_t>(index_.size()));
  index += index_;
  out += Record(0x07, index);
  records_.clear();
  index_.clear();
  return out;
}

std::string McapImuWriter::Finish() {
  std::string out = Flush();
  std::string data_end;
  Put<std::uint32_t>(&data_end, 0);  // the data section's CRC: not computed
  out += Record(0x0F, data_end);
  std::string footer;
  Put<std::uint64_t>(&footer, 0);  // no summary
  Put<std::uint64_t>(&footer, 0);
  Put<std::uint32_t>(&footer, 0);
  out += Record(0x02, footer);
  out.append(kMagic, sizeof kMagic);
  return out;
}

}  // namespace accelcal
