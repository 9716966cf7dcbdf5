// The MCAP reader at the byte level (mcap.hpp): a file of accelcal's writer read back, then
// damaged as files are: a chunk whose CRC-32 fails, cut inside a chunk, never closed, zeros at the
// end, a large attachment, an unknown compression, a topic of another encoding, a message of a
// channel never defined. The specification's own examples are tests/mcap_spec_test.py's.
#include <zstd.h>

#include <chrono>
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "accelcal/error.hpp"
#include "accelcal/mcap_writer.hpp"
#include "core/crc32.hpp"
#include "io/binary_stream.hpp"
#include "io/decompress.hpp"
#include "io/mcap.hpp"

namespace accelcal::internal {
namespace {

TEST(Crc32, KnownAnswers) {
  // The check value of CRC-32/ISO-HDLC, and the same in two pieces and at every alignment.
  const std::string nine = "123456789";
  const auto* p = reinterpret_cast<const unsigned char*>(nine.data());
  EXPECT_EQ(Crc32(p, 9), 0xCBF43926u);
  EXPECT_EQ(Crc32(p + 4, 5, Crc32(p, 4)), 0xCBF43926u);
  EXPECT_EQ(Crc32(p, 0), 0u);
  std::string longer(1000, '\0');
  for (std::size_t i = 0; i < longer.size(); ++i) longer[i] = static_cast<char>(i * 7 + 3);
  const auto* q = reinterpret_cast<const unsigned char*>(longer.data());
  for (std::size_t split = 0; split < 17; ++split) {
    EXPECT_EQ(Crc32(q + split, longer.size() - split, Crc32(q, split)), Crc32(q, longer.size()));
  }
}

// A file of `n` IMU messages at 100 Hz (several chunks when n is large), finished or not.
std::string Imu(McapCompression compression, int n, bool finish = true) {
  McapImuWriter writer(compression, "/imu");
  std::string out = writer.Header();
  for (int k = 0; k < n; ++k) {
    out += writer.Sample(1000000000ull + 10000000ull * std::uint64_t(k), Vec3(k, 2.0 * k, -9.81),
                         Vec3(0.01, 0.02, 0.03));
  }
  if (finish) out += writer.Finish();
  return out;
}

DecodedLog Read(const std::string& bytes) {
  BinaryStream in(bytes, "test.mcap");
  return ReadMcap(in, [](const DecodedStream&) { return true; });
}
std::string Why(const std::string& bytes) {
  try {
    Read(bytes);
  } catch (const InputError& e) {
    return e.reason();
  }
  return "read";
}

TEST(Mcap, ReadsItsWritersFileInEveryCompression) {
  for (const McapCompression c :
       {McapCompression::kNone, McapCompression::kLz4, McapCompression::kZstd}) {
    const DecodedLog log = Read(Imu(c, 5000));  // 5000 messages: more than one chunk
    ASSERT_EQ(log.streams.size(), 1u);
    const DecodedStream& s = log.streams[0];
    EXPECT_EQ(s.topic, "/imu");
    EXPECT_EQ(s.type, "sensor_msgs/msg/Imu");
    EXPECT_EQ(s.messages, 5000u);
    EXPECT_EQ(s.first_us, 1000000u);
    EXPECT_EQ(s.last_us, 1000000u + 49990000u);
    EXPECT_FALSE(log.truncated.has_value());
    EXPECT_EQ(log.info.at("profile"), "ros2");
    const auto col = [&](const char* name) {
      return std::size_t(std::find(s.columns->begin(), s.columns->end(), name) -
                         s.columns->begin());
    };
    const std::size_t w = s.columns->size(), k = 4321;
    EXPECT_EQ(s.values[k * w + col("header.stamp")], 1000000.0 + 10000.0 * k);
    EXPECT_EQ(s.values[k * w + col("linear_acceleration.y")], 2.0 * k);
    EXPECT_EQ(s.values[k * w + col("angular_velocity.z")], 0.03);
    EXPECT_EQ(s.values[k * w + col("orientation_covariance[0]")], -1.0);
  }
}

TEST(Mcap, NamesWhatIsWrong) {
  // A byte of a message changed in an uncompressed chunk: its CRC-32 fails.
  std::string bad = Imu(McapCompression::kNone, 50);
  const std::size_t chunk = bad.find(std::string("\x06", 1), 8 + 9);  // after magic and header
  bad[bad.size() - 2000] ^= 0x10;
  EXPECT_NE(Why(bad).find("fail their CRC-32"), std::string::npos) << Why(bad);
  EXPECT_NE(chunk, std::string::npos);
  // The compression named in the chunk replaced by one MCAP does not define.
  std::string other = Imu(McapCompression::kZstd, 50);
  other.replace(other.find("zstd"), 4, "brot");
  EXPECT_NE(Why(other).find("a chunk compressed as brot, which MCAP does not define"),
            std::string::npos)
      << Why(other);
  // A message before its channel: the first Channel record's opcode made a private one.
  // (The Channel record ends the writer's header: opcode, length, id, schema id, "/imu",
  // "cdr", an empty map: 32 bytes.)
  std::string orphan = Imu(McapCompression::kNone, 5);
  const std::size_t header = McapImuWriter(McapCompression::kNone, "/imu").Header().size();
  ASSERT_EQ(orphan[header - 32], '\x04');
  orphan[header - 32] = '\x80';
  EXPECT_NE(Why(orphan).find("which no Channel record defined before it"), std::string::npos)
      << Why(orphan);
  // Not MCAP after all.
  EXPECT_EQ(Why(std::string("\x89MCAP1\r\n", 8) + "...."),
            "byte 0: not an MCAP file (its magic is not 89 \"MCAP0\" 0D 0A)");
}

TEST(Mcap, ReadsWhatARecordingLeft) {
  const std::string whole = Imu(McapCompression::kZstd, 5000);
  // Cut inside its last chunk: the chunks before it are read, with a warning.
  DecodedLog log = Read(whole.substr(0, whole.size() / 2));
  ASSERT_TRUE(log.truncated.has_value());
  EXPECT_NE(log.truncated->find("the file ends inside a record at byte"), std::string::npos)
      << *log.truncated;
  EXPECT_GT(log.streams[0].messages, 0u);
  EXPECT_LT(log.streams[0].messages, 5000u);
  // Never closed: every chunk written is read; the warning says so.
  McapImuWriter writer(McapCompression::kLz4, "/imu");
  std::string open = writer.Header();
  for (int k = 0; k < 5000; ++k)
    open += writer.Sample(std::uint64_t(k) * 1000000, Vec3(1, 2, 3), Vec3(0, 0, 0));
  log = Read(open);
  ASSERT_TRUE(log.truncated.has_value());
  EXPECT_NE(log.truncated->find("without its Data End and Footer records (a recording never "
                                "closed)"),
            std::string::npos)
      << *log.truncated;
  // Zeros to the end (space never written) after the last chunk and its index.
  const std::size_t data_end = whole.size() - 8 - 29 - 13;  // Data End, Footer, magic
  ASSERT_EQ(whole[data_end], '\x0F');
  log = Read(whole.substr(0, data_end) + std::string(4096, '\0'));
  EXPECT_EQ(log.streams[0].messages, 5000u);
  ASSERT_TRUE(log.truncated.has_value());
  EXPECT_NE(log.truncated->find("zero bytes"), std::string::npos) << *log.truncated;
  // An attachment of 20 MB before the end is skipped, not held.
  std::string attachment;
  const auto put64 = [&](std::uint64_t v) {
    char b[8];
    std::memcpy(b, &v, 8);
    attachment.append(b, 8);
  };
  attachment += '\x09';
  put64(20u << 20);
  attachment += std::string(20u << 20, 'a');
  const std::string with = whole.substr(0, data_end) + attachment + whole.substr(data_end);
  log = Read(with);
  EXPECT_EQ(log.streams[0].messages, 5000u);
  EXPECT_FALSE(log.truncated.has_value()) << *log.truncated;
}

// A bomb of chunks, each within the bound of one but together far past what any recording
// inflates to: zstd chunks of 128 MiB of one private record (a few kB each), before the real
// ones. Each was inflated (a 3.4 MB file of 300 chunks of 255 MiB took 39 s and then read);
// now the first past kMaxFileInflatedBytes in all is refused, before it is inflated.
TEST(Mcap, RefusesChunksThatInflatePastTheBoundInAll) {
  const std::size_t size = std::size_t{128} << 20;
  std::string records(size, '\0');
  records[0] = '\x80';
  const std::uint64_t record_length = size - 9;
  std::memcpy(&records[1], &record_length, 8);
  std::string z(ZSTD_compressBound(size), '\0');
  z.resize(ZSTD_compress(z.data(), z.size(), records.data(), size, 1));
  ASSERT_FALSE(ZSTD_isError(z.size()));
  std::string body;
  const auto put = [&](auto v) { body.append(reinterpret_cast<const char*>(&v), sizeof(v)); };
  put(std::uint64_t{0});  // message start and end time
  put(std::uint64_t{0});
  put(std::uint64_t{size});
  put(std::uint32_t{0});  // no CRC
  put(std::uint32_t{4});
  body += "zstd";
  put(std::uint64_t{z.size()});
  body += z;
  std::string chunk(1, '\x06');
  const std::uint64_t body_length = body.size();
  chunk.append(reinterpret_cast<const char*>(&body_length), 8);
  chunk += body;

  McapImuWriter writer(McapCompression::kZstd, "/imu");
  std::string file = writer.Header();
  const int bombs = int(kMaxFileInflatedBytes / size) + 1;  // 9
  for (int k = 0; k < bombs; ++k) file += chunk;
  for (int k = 0; k < 50; ++k) {
    file += writer.Sample(1000000000ull + 10000000ull * std::uint64_t(k), Vec3(0, 0, 9.81),
                          Vec3(0, 0, 0));
  }
  file += writer.Finish();
  ASSERT_LT(file.size(), std::size_t{1} << 20);

  const auto start = std::chrono::steady_clock::now();
  const std::string why = Why(file);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  // Named at the chunk that passes the bound: the last bomb.
  const std::size_t at = writer.Header().size() + std::size_t(bombs - 1) * chunk.size();
  EXPECT_EQ(why, "byte " + std::to_string(at) +
                     ": compressed chunks that inflate past 1024 MiB in all (64 times the file, "
                     "and at least 1024 MiB)");
  // The chunks before it are inflated (1 GiB of zstd, well under a second), not the rest.
  EXPECT_LT(seconds, 10.0);
  // Two such chunks fewer (896 MiB in all, with the real ones) are read: as much as a large
  // real recording inflates to is not refused.
  McapImuWriter again(McapCompression::kZstd, "/imu");
  std::string fewer = again.Header();
  for (int k = 0; k + 2 < bombs; ++k) fewer += chunk;
  for (int k = 0; k < 50; ++k) {
    fewer += again.Sample(1000000000ull + 10000000ull * std::uint64_t(k), Vec3(0, 0, 9.81),
                          Vec3(0, 0, 0));
  }
  fewer += again.Finish();
  EXPECT_EQ(Read(fewer).streams[0].messages, 50u);
}

}  // namespace
}  // namespace accelcal::internal
