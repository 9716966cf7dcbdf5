// ROS 1 bags at the byte level (rosbag.hpp, ros_message.hpp, decompress.hpp): message definitions
// flattened and decoded with known answers; bags built record by record here, as the
// specification ("Bags/Format/2.0") lays them out, read whole, cut, killed and corrupt. The bags
// of ROS's own writer are tests/rosbag_test.py's.
#include <bzlib.h>
#include <lz4frame.h>
#include <zstd.h>

#include <chrono>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "accelcal/error.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/rosbag_writer.hpp"
#include "io/binary_stream.hpp"
#include "io/decompress.hpp"
#include "io/ros_message.hpp"
#include "io/rosbag.hpp"

namespace accelcal::internal {
namespace {

// --- message definitions -----------------------------------------------------------------------

// A type with what a definition may hold: comments, constants, a Header, nested types of the same
// package and of another, fixed and variable arrays, strings, time and duration.
const char kDefinition[] =
    "# a test message\n"
    "uint8 MODE_A=1   # a constant\n"
    "string NAME=x # y\n"
    "Header header\n"
    "Pair[2] pairs\n"
    "float32[] ignored   # variable: not columns\n"
    "string label\n"
    "geometry_msgs/Vector3 v\n"
    "int16 small\n"
    "duration span\n"
    "bool flag\n"
    "================================================================================\n"
    "MSG: std_msgs/Header\n"
    "uint32 seq\n"
    "time stamp\n"
    "string frame_id\n"
    "================================================================================\n"
    "MSG: test_msgs/Pair\n"
    "int8 a\n"
    "uint64 b\n"
    "================================================================================\n"
    "MSG: geometry_msgs/Vector3\n"
    "float64 x\n"
    "float64 y\n"
    "float64 z\n";

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

// One message of kDefinition, serialised as ROS 1 does.
std::string TestMessage() {
  std::string m;
  Put<std::uint32_t>(&m, 7);           // header.seq
  Put<std::uint32_t>(&m, 1700000000);  // header.stamp: seconds
  Put<std::uint32_t>(&m, 250000500);   //   and nanoseconds
  PutString(&m, "imu_link");
  Put<std::int8_t>(&m, -3);  // pairs[0]
  Put<std::uint64_t>(&m, 40);
  Put<std::int8_t>(&m, 5);  // pairs[1]
  Put<std::uint64_t>(&m, 41);
  Put<std::uint32_t>(&m, 2);  // ignored: two float32
  Put<float>(&m, 1.5f);
  Put<float>(&m, 2.5f);
  PutString(&m, "");
  Put<double>(&m, 0.1);  // v
  Put<double>(&m, -9.81);
  Put<double>(&m, 3);
  Put<std::int16_t>(&m, -300);
  Put<std::int32_t>(&m, -2);  // span: -2 s + 500 ns
  Put<std::int32_t>(&m, 500);
  Put<std::uint8_t>(&m, 1);
  return m;
}

TEST(RosMessage, FlattensAndDecodesEveryKindOfField) {
  const RosMessageType type("test_msgs/Test", kDefinition);
  {
    const std::string m = TestMessage();
    const auto* p = reinterpret_cast<const unsigned char*>(m.data());
    EXPECT_EQ(type.FrameId(p, m.size()), std::optional<std::string>("imu_link"));
    EXPECT_FALSE(type.FrameId(p, 14).has_value());  // cut inside the frame id
    const RosMessageType headless("a/B", "float64 x\nstring frame_id\n");
    EXPECT_FALSE(headless.FrameId(p, m.size()).has_value());
  }
  EXPECT_EQ(type.name(), "test_msgs/Test");
  const std::vector<std::string> want = {"header.seq", "header.stamp", "pairs[0].a", "pairs[0].b",
                                         "pairs[1].a", "pairs[1].b",   "v.x",        "v.y",
                                         "v.z",        "small",        "span",       "flag"};
  EXPECT_EQ(*type.columns(), want);
  ASSERT_TRUE(type.stamp().has_value());
  EXPECT_EQ(*type.stamp(), 1u);
  // The time and the duration are given in µs; the other fields are their numbers.
  EXPECT_EQ(type.microseconds(), (std::vector<std::size_t>{1, 10}));
  const std::string m = TestMessage();
  std::vector<double> v(want.size());
  const auto* p = reinterpret_cast<const unsigned char*>(m.data());
  ASSERT_FALSE(type.Decode(p, m.size(), v.data()).has_value());
  // Times in µs: 1700000000 s and 250000500 ns; -2 s and 500 ns.
  EXPECT_EQ(v, (std::vector<double>{7, 1700000000250000.5, -3, 40, 5, 41, 0.1, -9.81, 3, -300,
                                    -1999999.5, 1}));
  // A byte short, a byte long: each named.
  EXPECT_EQ(*type.Decode(p, m.size() - 1, v.data()), "a 92-byte message, shorter than its fields");
  const std::string longer = m + "x";
  EXPECT_EQ(
      *type.Decode(reinterpret_cast<const unsigned char*>(longer.data()), longer.size(), v.data()),
      "a 94-byte message whose fields end after 93 bytes");
  // A variable array whose count runs past the message.
  std::string lying = m;
  const std::size_t count_at = 4 + 8 + 4 + 8 + 2 * 9;
  lying[count_at] = '\x7f';
  EXPECT_TRUE(
      type.Decode(reinterpret_cast<const unsigned char*>(lying.data()), lying.size(), v.data())
          .has_value());
}

TEST(RosMessage, RefusesDefinitionsThatDoNotHold) {
  const auto why = [](const char* type, const char* definition) {
    try {
      RosMessageType t(type, definition);
    } catch (const DataError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(why("a/B", "float64 x\nVector3 v\n"),
            "the definition does not define the type a/Vector3 it uses");
  EXPECT_EQ(why("a/B", "a/B inner\n"), "the message type a/B contains itself");
  EXPECT_EQ(why("a/B", "a/C c\n===\nMSG: a/C\na/B back\n"), "the message type a/B contains itself");
  EXPECT_EQ(why("a/B", "float64 x\nint8 x\n"), "the definition of a/B has two fields x");
  EXPECT_EQ(why("a/B", "float64\n"),
            "the definition of a/B has the line \"float64\", not a type "
            "and a name");
  EXPECT_EQ(why("a/B", "float64[3x] v\n"),
            "the definition of a/B has the array type \"float64[3x]\"");
  EXPECT_EQ(why("a/B", "float64 x\n===\nfloat64 y\n"),
            "the definition of a/B has a section that does not begin \"MSG: package/Type\"");
  EXPECT_EQ(why("a/B", "float64 x-y\n"), "the definition of a/B names a field \"x-y\"");
}

// ROS 2: a ros2msg definition (bounded strings and sequences, defaults, builtin_interfaces/Time)
// and a CDR message, every value aligned to its size from after the encapsulation.
TEST(RosMessage, DecodesRos2Cdr) {
  const char definition[] =
      "std_msgs/Header header\n"
      "uint8 flag 1   # a default value\n"
      "int32 LIMIT = 7\n"
      "float64 value\n"
      "string<=8 label\n"
      "uint16 small\n"
      "float32[<=4] bounded\n"
      "int16[2] pair\n"
      "builtin_interfaces/Duration span\n"
      "================================================================================\n"
      "MSG: std_msgs/Header\n"
      "builtin_interfaces/Time stamp\n"
      "string frame_id\n"
      "================================================================================\n"
      "MSG: builtin_interfaces/Time\n"
      "int32 sec\n"
      "uint32 nanosec\n";
  const RosMessageType type("test_msgs/msg/Test", definition, RosVersion::kRos2);
  EXPECT_EQ(type.name(), "test_msgs/Test");
  const std::vector<std::string> want = {"header.stamp", "flag",    "value", "small",
                                         "pair[0]",      "pair[1]", "span"};
  EXPECT_EQ(*type.columns(), want);
  ASSERT_TRUE(type.stamp().has_value());
  EXPECT_EQ(type.microseconds(), (std::vector<std::size_t>{0, 6}));  // Time, Duration
  std::string m = std::string("\x00\x01\x00\x00", 4);                // CDR, little-endian
  Put<std::int32_t>(&m, 1700000000);                                 // offset 0: stamp.sec
  Put<std::uint32_t>(&m, 5000);                                      // 4: stamp.nanosec
  PutString(&m, std::string("imu\0", 4));                            // 8: length 4, "imu\0"
  Put<std::uint8_t>(&m, 9);                                          // 16: flag
  m += std::string(7, '\xee');                                       // 17: padding to 24
  Put<double>(&m, -9.81);                                            // 24: value
  PutString(&m, std::string("ab\0", 3));                             // 32: label (length 3), to 39
  m += '\xee';                                                       // 39: padding to 40
  Put<std::uint16_t>(&m, 65535);                                     // 40: small
  m += std::string(2, '\xee');                                       // 42: padding to 44
  Put<std::uint32_t>(&m, 2);                                         // 44: bounded: 2 float32
  Put<float>(&m, 1.5f);
  Put<float>(&m, 2.5f);
  Put<std::int16_t>(&m, -1);  // 56: pair
  Put<std::int16_t>(&m, 2);
  Put<std::int32_t>(&m, -3);  // 60: span
  Put<std::uint32_t>(&m, 500);
  std::vector<double> v(want.size());
  const auto* p = reinterpret_cast<const unsigned char*>(m.data());
  ASSERT_FALSE(type.Decode(p, m.size(), v.data()).has_value())
      << *type.Decode(p, m.size(), v.data());
  EXPECT_EQ(type.FrameId(p, m.size()), std::optional<std::string>("imu"));  // its NUL not kept
  EXPECT_EQ(v, (std::vector<double>{1700000000000005.0, 9, -9.81, 65535, -1, 2, -2999999.5}));
  // Up to 3 bytes of padding may end a message; a fourth is not padding.
  const std::string padded = m + std::string(3, '\0');
  EXPECT_FALSE(
      type.Decode(reinterpret_cast<const unsigned char*>(padded.data()), padded.size(), v.data())
          .has_value());
  const std::string longer = m + std::string(4, '\0');
  EXPECT_TRUE(
      type.Decode(reinterpret_cast<const unsigned char*>(longer.data()), longer.size(), v.data())
          .has_value());
  // Big-endian CDR is named, not misread.
  std::string big = m;
  big[1] = 0;
  EXPECT_EQ(*type.Decode(reinterpret_cast<const unsigned char*>(big.data()), big.size(), v.data()),
            "a message encoded as 00 00, not little-endian CDR (00 01), which accelcal reads");
}

// A huge fixed array is columns up to the cap; the message is still walked whole.
TEST(RosMessage, CapsTheColumnsOfAHugeArray) {
  const RosMessageType type("a/Big", "float32[5000] v\nuint8 last\n");
  EXPECT_EQ(type.columns()->size(), kMaxFormatColumns);
  EXPECT_EQ(type.columns()->back(), "v[4095]");
  std::string m(5000 * 4, '\0');
  m += '\x09';
  std::vector<double> v(type.columns()->size());
  EXPECT_FALSE(type.Decode(reinterpret_cast<const unsigned char*>(m.data()), m.size(), v.data())
                   .has_value());
  // Nested fixed arrays that would overflow a count are bounded too, and walk no further than
  // the message's bytes.
  const RosMessageType nested(
      "a/N", "a/M[4000000000] m\n===\nMSG: a/M\na/L[4000000000] l\n===\nMSG: a/L\nfloat64 x\n");
  EXPECT_EQ(nested.columns()->size(), kMaxFormatColumns);
  EXPECT_TRUE(nested.Decode(reinterpret_cast<const unsigned char*>(m.data()), m.size(), v.data())
                  .has_value());
}

// --- bags, record by record --------------------------------------------------------------------

std::string Field(const std::string& name, const std::string& value) {
  std::string f;
  PutString(&f, name + "=" + value);
  return f;
}
template <typename T>
std::string Bytes(T v) {
  std::string s;
  Put<T>(&s, v);
  return s;
}
std::string Record(const std::string& header, const std::string& data) {
  std::string r;
  PutString(&r, header);
  PutString(&r, data);
  return r;
}
std::string Op(char op) { return Field("op", std::string(1, op)); }

const char kVector3[] = "float64 x\nfloat64 y\nfloat64 z\n";

std::string Connection(std::uint32_t id, const std::string& topic) {
  return Record(Op(0x07) + Field("conn", Bytes<std::uint32_t>(id)) + Field("topic", topic),
                Field("topic", topic) + Field("type", "geometry_msgs/Vector3") +
                    Field("md5sum", "4a842b65f413084dc2b10fb484ea7f17") +
                    Field("message_definition", kVector3));
}
std::string Message(std::uint32_t id, std::uint32_t sec, std::uint32_t nsec, double x) {
  std::string data;
  Put<double>(&data, x);
  Put<double>(&data, 2 * x);
  Put<double>(&data, 3 * x);
  return Record(Op(0x02) + Field("conn", Bytes<std::uint32_t>(id)) +
                    Field("time", Bytes<std::uint32_t>(sec) + Bytes<std::uint32_t>(nsec)),
                data);
}
std::string Chunk(const std::string& records, const std::string& compression = "none") {
  std::string data = records;
  if (compression == "bz2") {
    std::vector<char> out(records.size() + records.size() / 100 + 700);
    unsigned n = static_cast<unsigned>(out.size());
    EXPECT_EQ(BZ2_bzBuffToBuffCompress(out.data(), &n, const_cast<char*>(records.data()),
                                       static_cast<unsigned>(records.size()), 9, 0, 0),
              BZ_OK);
    data.assign(out.data(), n);
  } else if (compression == "lz4") {
    std::vector<char> out(LZ4F_compressFrameBound(records.size(), nullptr));
    const std::size_t n =
        LZ4F_compressFrame(out.data(), out.size(), records.data(), records.size(), nullptr);
    data.assign(out.data(), n);
  }
  return Record(Op(0x05) + Field("compression", compression) +
                    Field("size", Bytes<std::uint32_t>(static_cast<std::uint32_t>(records.size()))),
                data);
}
std::string BagHeader() {
  std::string header = Op(0x03) + Field("index_pos", Bytes<std::uint64_t>(0)) +
                       Field("conn_count", Bytes<std::uint32_t>(0)) +
                       Field("chunk_count", Bytes<std::uint32_t>(0));
  return "#ROSBAG V2.0\n" + Record(header, std::string(64, ' '));
}

DecodedLog Read(const std::string& bag) {
  BinaryStream in(bag, "test.bag");
  return ReadRosBag(in, [](const DecodedStream&) { return true; });
}
std::string Why(const std::string& bag) {
  try {
    Read(bag);
  } catch (const InputError& e) {
    return e.reason();
  }
  return "read";
}

// Two topics, a message each in every chunk compression.
std::string TwoTopics(const std::string& compression) {
  return BagHeader() +
         Chunk(Connection(0, "/a") + Message(0, 10, 5000, 1.0) + Connection(3, "/b") +
                   Message(3, 10, 6000, 4.0) + Message(0, 11, 0, 2.0),
               compression) +
         Chunk(Message(0, 12, 999, 8.0), compression);
}

TEST(RosBag, ReadsEveryChunkCompression) {
  for (const char* compression : {"none", "bz2", "lz4"}) {
    const DecodedLog log = Read(TwoTopics(compression));
    ASSERT_EQ(log.streams.size(), 2u) << compression;
    const DecodedStream& a = log.streams[0];
    EXPECT_EQ(a.topic, "/a");
    EXPECT_EQ(a.type, "geometry_msgs/Vector3");
    EXPECT_EQ(a.instance, 0);
    // Its fields, then the time each message was logged (the record's, in µs).
    EXPECT_EQ(*a.columns, (std::vector<std::string>{"x", "y", "z", "log_time"}));
    EXPECT_EQ(*a.microseconds, (std::vector<std::size_t>{3}));
    EXPECT_EQ(a.messages, 3u);
    EXPECT_EQ(a.values,
              (std::vector<double>{1, 2, 3, 10000005, 2, 4, 6, 11000000, 8, 16, 24, 12000000}));
    // Record times in µs (10 s + 5000 ns, 12 s + 999 ns).
    EXPECT_EQ(a.first_us, 10000005u);
    EXPECT_EQ(a.last_us, 12000000u);
    EXPECT_EQ(log.streams[1].values, (std::vector<double>{4, 8, 12, 10000006}));
    EXPECT_FALSE(log.truncated.has_value());
  }
}

TEST(RosBag, NamesTheByteOfWhatIsWrong) {
  const std::string head = BagHeader();
  const std::size_t at = head.size();
  EXPECT_EQ(Why("#ROSBAG V1.2\n..."),
            "byte 0: a ROS bag of version 1.2: accelcal reads version 2.0, which ROS 1 writes "
            "since 2010 (rosbag fix migrates an older one)");
  // In an uncompressed chunk, a record's own byte; in a compressed one, the chunk's.
  const std::string orphan = Message(4, 1, 0, 1.0);
  EXPECT_EQ(Why(head + Chunk(orphan)),
            "byte " + std::to_string(at + Chunk(orphan).size() - orphan.size()) +
                ": a message of connection 4, which no connection record defined before it");
  EXPECT_EQ(Why(head + Chunk(orphan, "bz2")),
            "byte " + std::to_string(at) +
                ": a message of connection 4, which no connection record defined before it");
  EXPECT_EQ(
      Why(head + Record(Op(0x09), "")),
      "byte " + std::to_string(at) + ": a record of op 0x09, which ROS bag 2.0 does not define");
  const std::size_t inner = at + Chunk(Chunk("")).size() - Chunk("").size();
  EXPECT_EQ(Why(head + Chunk(Chunk(""))),
            "byte " + std::to_string(inner) + ": a chunk inside a chunk");
  EXPECT_EQ(Why(head + Record(Op(0x05) + Field("compression", "zstd") +
                                  Field("size", Bytes<std::uint32_t>(0)),
                              "")),
            "byte " + std::to_string(at) +
                ": a chunk compressed as zstd, which ROS bags do not use (none, bz2, lz4)");
  // A chunk whose size is not what it holds, compressed and not.
  std::string wrong = Chunk(Connection(0, "/a"), "lz4");
  const std::size_t size_at = wrong.find("size=") + 5;
  wrong[size_at] = static_cast<char>(wrong[size_at] + 1);
  EXPECT_NE(Why(head + wrong).find("a chunk that does not decompress: the lz4 frame holds"),
            std::string::npos)
      << Why(head + wrong);
  // A message whose bytes are not its type's.
  std::string bad = Connection(0, "/a") + Message(0, 1, 0, 1.0);
  bad.erase(bad.size() - 1);
  const std::size_t data_len_at = bad.size() - 23 - 4;
  bad[data_len_at] = 23;
  EXPECT_NE(Why(head + Chunk(bad))
                .find("a message of /a (geometry_msgs/Vector3): a 23-byte "
                      "message, shorter than its fields"),
            std::string::npos)
      << Why(head + Chunk(bad));
  // A record length beyond any chunk's is refused before it is read.
  std::string huge = head;
  Put<std::uint32_t>(&huge, 8);
  Put<std::uint32_t>(&huge, 4);
  huge += "op=\x05";
  Put<std::uint32_t>(&huge, 0xfffffff0u);
  EXPECT_NE(Why(huge).find("more than the 257 MiB accelcal reads in one"), std::string::npos)
      << Why(huge);
}

// A bomb of chunks, each within the bound of one but together far past what any recording
// inflates to: lz4 chunks of one 128 MiB message of another topic (0.5 MB each). Each was
// inflated (a 16 kB bag of 40 bz2 chunks of 255 MiB took 44 s and then read); now the first past
// kMaxFileInflatedBytes in all is refused, before it is inflated.
TEST(RosBag, RefusesChunksThatInflatePastTheBoundInAll) {
  const std::string junk =
      Record(Op(0x07) + Field("conn", Bytes<std::uint32_t>(1)) + Field("topic", "/junk"),
             Field("topic", "/junk") + Field("type", "std_msgs/String") + Field("md5sum", "*") +
                 Field("message_definition", "string data\n"));
  const std::size_t size = std::size_t{128} << 20;
  std::string text(size - junk.size() - 64, 'a');
  std::string message;
  PutString(&message, text);
  const std::string records =
      junk + Record(Op(0x02) + Field("conn", Bytes<std::uint32_t>(1)) +
                        Field("time", Bytes<std::uint32_t>(1) + Bytes<std::uint32_t>(0)),
                    message);
  ASSERT_LE(records.size(), size);
  const std::string bomb = Chunk(records, "lz4");
  const int bombs = int(kMaxFileInflatedBytes / records.size()) + 1;  // 9
  std::string bag = BagHeader();
  for (int k = 0; k < bombs; ++k) bag += bomb;
  bag += Chunk(Connection(0, "/a") + Message(0, 10, 0, 1.0) + Message(0, 10, 10000000, 2.0));
  ASSERT_LT(bag.size(), std::size_t{8} << 20);

  const auto start = std::chrono::steady_clock::now();
  const std::string why = Why(bag);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  // Named at the chunk that passes the bound: the last bomb.
  const std::size_t at = BagHeader().size() + std::size_t(bombs - 1) * bomb.size();
  EXPECT_EQ(why, "byte " + std::to_string(at) +
                     ": compressed chunks that inflate past 1024 MiB in all (64 times the file, "
                     "and at least 1024 MiB)");
  EXPECT_LT(seconds, 10.0);  // the chunks before it inflated (1 GiB of lz4), not the rest
  // Fewer such chunks (under 1 GiB in all) are read: a large real recording is not refused.
  std::string fewer = BagHeader();
  for (int k = 0; k + 1 < bombs; ++k) fewer += bomb;
  fewer += Chunk(Connection(0, "/a") + Message(0, 10, 0, 1.0) + Message(0, 10, 10000000, 2.0));
  const DecodedLog log = Read(fewer);
  ASSERT_EQ(log.streams.size(), 2u);
  EXPECT_EQ(log.streams[1].messages, 2u);
}

// A recorder killed leaves its open chunk with no length (0) and its records after it; a bag cut
// short keeps what is whole; zeros at the end are space never written.
TEST(RosBag, ReadsWhatAKilledOrCutRecordingLeft) {
  const std::string killed =
      BagHeader() + Chunk(Connection(0, "/a") + Message(0, 1, 0, 1.0)) +
      Record(Op(0x05) + Field("compression", "none") + Field("size", Bytes<std::uint32_t>(0)), "") +
      Message(0, 2, 0, 2.0) + Message(0, 3, 0, 3.0);
  DecodedLog log = Read(killed);
  ASSERT_EQ(log.streams.size(), 1u);
  EXPECT_EQ(log.streams[0].messages, 3u);
  EXPECT_FALSE(log.truncated.has_value());

  const std::string whole = TwoTopics("none");
  const std::string cut = whole.substr(0, whole.size() - 10);
  log = Read(cut);
  ASSERT_TRUE(log.truncated.has_value());
  EXPECT_NE(log.truncated->find("the bag ends inside a chunk at byte"), std::string::npos)
      << *log.truncated;
  EXPECT_EQ(log.streams[0].messages, 2u);  // the last chunk's message is lost

  // The cut inside the first, uncompressed chunk: its whole records are read.
  const std::string first_cut =
      BagHeader() + Chunk(Connection(0, "/a") + Message(0, 1, 0, 1.0) + Message(0, 2, 0, 2.0));
  log = Read(first_cut.substr(0, first_cut.size() - 5));
  ASSERT_TRUE(log.truncated.has_value());
  EXPECT_NE(log.truncated->find("after 1 whole messages"), std::string::npos) << *log.truncated;
  EXPECT_EQ(log.streams[0].values, (std::vector<double>{1, 2, 3, 1e6}));

  const std::string zeros = whole + std::string(5000, '\0');
  log = Read(zeros);
  ASSERT_TRUE(log.truncated.has_value());
  EXPECT_EQ(log.streams[0].messages, 3u);
  std::string not_zeros = zeros;
  not_zeros[whole.size() + 4000] = 1;
  EXPECT_NE(Why(not_zeros).find("is not zero: the file is corrupt here"), std::string::npos);
}

// Found by a hostile test: a killed recorder's compressed chunk (its header's lengths still the
// placeholder 0) ends what is read, with a warning, where it had made the whole bag unreadable; a
// bag cut where a chunk ended is known cut by its header's index_pos.
TEST(RosBag, KnowsAChunkNeverClosedAndAnIndexNeverReached) {
  const std::string chunks = Chunk(Connection(0, "/a") + Message(0, 1, 0, 1.0), "lz4");
  const std::string open =
      BagHeader() + chunks +
      Record(Op(0x05) + Field("compression", "lz4") + Field("size", Bytes<std::uint32_t>(0)), "") +
      std::string("\x04\x22\x4d\x18 half of an lz4 frame", 26);
  DecodedLog log = Read(open);
  ASSERT_TRUE(log.truncated.has_value());
  EXPECT_NE(log.truncated->find("a compressed chunk its recorder never closed"), std::string::npos)
      << *log.truncated;
  EXPECT_EQ(log.streams.at(0).messages, 1u);
  // A header whose index is past the end: cut between two chunks.
  std::string header = Op(0x03) + Field("index_pos", Bytes<std::uint64_t>(1u << 20)) +
                       Field("conn_count", Bytes<std::uint32_t>(1)) +
                       Field("chunk_count", Bytes<std::uint32_t>(2));
  log = Read("#ROSBAG V2.0\n" + Record(header, std::string(64, ' ')) + chunks);
  ASSERT_TRUE(log.truncated.has_value());
  EXPECT_NE(log.truncated->find("before its index at byte 1048576: a bag cut short"),
            std::string::npos)
      << *log.truncated;
}

// A topic is one stream only if one publisher published it with one definition: else reading
// it is refused (its messages would be decoded by another layout, or mixed), and another topic
// of the bag is read as if it were not there.
TEST(RosBag, RefusesATopicOfTwoDefinitionsOrTwoPublishers) {
  const auto connection = [](std::uint32_t id, const std::string& topic, const char* definition,
                             const std::string& callerid) {
    return Record(Op(0x07) + Field("conn", Bytes<std::uint32_t>(id)) + Field("topic", topic),
                  Field("topic", topic) + Field("type", "geometry_msgs/Vector3") +
                      Field("md5sum", "*") + Field("message_definition", definition) +
                      Field("callerid", callerid));
  };
  const std::string swapped = "float64 z\nfloat64 y\nfloat64 x\n";
  const std::string two_definitions =
      BagHeader() + Chunk(connection(0, "/a", kVector3, "/d") + Message(0, 1, 0, 1.0) +
                          connection(1, "/a", swapped.c_str(), "/d") + Message(1, 2, 0, 2.0));
  EXPECT_NE(Why(two_definitions)
                .find("the topic /a is published with two different definitions "
                      "of geometry_msgs/Vector3"),
            std::string::npos)
      << Why(two_definitions);
  const std::string two_publishers =
      BagHeader() + Chunk(connection(0, "/a", kVector3, "/driver") + Message(0, 1, 0, 1.0) +
                          connection(1, "/a", kVector3, "/relay") + Message(1, 1, 0, 1.0));
  EXPECT_NE(Why(two_publishers).find("has two publishers, /driver and /relay"), std::string::npos)
      << Why(two_publishers);
  // The same publisher again (a driver restarted): one stream.
  const std::string restarted =
      BagHeader() + Chunk(connection(0, "/a", kVector3, "/driver") + Message(0, 1, 0, 1.0) +
                          connection(1, "/a", kVector3, "/driver") + Message(1, 2, 0, 2.0));
  EXPECT_EQ(Read(restarted).streams.at(0).messages, 2u);
  // Only /b kept: /a's two definitions do not matter.
  BinaryStream in(two_definitions + Chunk(Connection(5, "/b") + Message(5, 3, 0, 3.0)), "b.bag");
  const DecodedLog log = ReadRosBag(in, [](const DecodedStream& s) { return s.topic == "/b"; });
  ASSERT_EQ(log.streams.size(), 2u);
  EXPECT_EQ(log.streams[1].values, (std::vector<double>{3, 6, 9, 3e6}));
}

TEST(RosBag, BoundsItsTopicsAndConnections) {
  // A 3 MB bz2 chunk can name a million topics (800 MB and 20 s read before): the topics and the
  // connections a bag may have are bounded, refused where the bound is passed.
  const auto many = [](std::uint32_t n, bool one_topic) {
    std::string records;
    for (std::uint32_t i = 0; i < n; ++i) {
      records += Connection(i, one_topic ? "/a" : "/t" + std::to_string(i));
    }
    return BagHeader() + Chunk(records);
  };
  const auto why = [](const std::string& bag) {
    const std::string reason = Why(bag);
    return reason.substr(reason.find(": ") + 2);  // less the record's byte
  };
  EXPECT_EQ(why(many(65537, false)), "a log of more than 65536 topics: no recording has that many");
  EXPECT_EQ(why(many(65537, true)),
            "a bag of more than 65536 connections (a topic's publisher each): no recording has "
            "that many");
}

// --- decompression -----------------------------------------------------------------------------

TEST(Decompress, ExactlyTheSizeSaid) {
  std::string text;
  for (int i = 0; i < 5000; ++i) text += "imu sample " + std::to_string(i) + "\n";
  for (const char* compression : {"bz2", "lz4", "zstd"}) {
    // The compressed bytes: a bag chunk's data (bz2, lz4), a zstd frame.
    std::string data;
    if (std::string(compression) == "zstd") {
      data.resize(ZSTD_compressBound(text.size()));
      data.resize(ZSTD_compress(data.data(), data.size(), text.data(), text.size(), 3));
    } else {
      const std::string chunk = Chunk(text, compression);
      const std::size_t header_len =
          LoadLittle<std::uint32_t>(reinterpret_cast<const unsigned char*>(chunk.data()));
      data = chunk.substr(8 + header_len);
    }
    const auto* p = reinterpret_cast<const unsigned char*>(data.data());
    const Compression c = std::string(compression) == "bz2"   ? Compression::kBz2
                          : std::string(compression) == "lz4" ? Compression::kLz4Frame
                                                              : Compression::kZstd;
    std::vector<unsigned char> out;
    ASSERT_FALSE(Decompress(c, p, data.size(), text.size(), &out).has_value()) << compression;
    EXPECT_EQ(std::string(out.begin(), out.end()), text);
    // Said longer or shorter than it is, followed by a byte, cut: each refused.
    EXPECT_TRUE(Decompress(c, p, data.size(), text.size() + 1, &out).has_value());
    EXPECT_TRUE(Decompress(c, p, data.size(), text.size() - 1, &out).has_value());
    const std::string more = data + "x";
    EXPECT_TRUE(Decompress(c, reinterpret_cast<const unsigned char*>(more.data()), more.size(),
                           text.size(), &out)
                    .has_value());
    EXPECT_TRUE(Decompress(c, p, data.size() - 3, text.size(), &out).has_value());
    // More than a block may hold, before anything is allocated.
    EXPECT_EQ(*Decompress(c, p, data.size(), kMaxDecompressedBytes + 1, &out),
              "a block of 268435457 bytes once decompressed, more than the 256 MiB accelcal "
              "reads in one");
  }
}

// A time is known by its ROS type, not its name: a custom message's float64 `timestamp` (seconds)
// is read as a text log's column (its unit from its step, or the time unit option), where it was
// taken as µs; without a time named, the time each message was logged (log_time) is the time.
// A bag of one topic of a custom type: 300 messages, `message(k)` the k-th's bytes, logged at
// 100 Hz from 100 s.
std::string CustomBag(const std::string& topic, const std::string& type,
                      const std::string& definition,
                      const std::function<std::string(std::uint32_t k)>& message) {
  std::string records =
      Record(Op(0x07) + Field("conn", Bytes<std::uint32_t>(0)) + Field("topic", topic),
             Field("topic", topic) + Field("type", type) + Field("md5sum", "*") +
                 Field("message_definition", definition));
  for (std::uint32_t k = 0; k < 300; ++k) {
    records += Record(Op(0x02) + Field("conn", Bytes<std::uint32_t>(0)) +
                          Field("time", Bytes<std::uint32_t>(100 + k / 100) +
                                            Bytes<std::uint32_t>(k % 100 * 10000000u)),
                      message(k));
  }
  return BagHeader() + Chunk(records);
}

// Readings near gravity, varying a little.
void PutReadings(std::string* data, std::uint32_t k) {
  for (double v : {0.1, 0.2, 9.8}) Put<double>(data, v + 1e-3 * (k % 7));
}

TEST(RosBag, OnlyTimeTypesAreMicroseconds) {
  const std::string bag =
      CustomBag("/c", "custom/Sample", "float64 timestamp\nfloat64 x\nfloat64 y\nfloat64 z\n",
                [](std::uint32_t k) {
                  std::string data;
                  Put<double>(&data, 0.01 * k);  // seconds
                  PutReadings(&data, k);
                  return data;
                });
  ReadOptions options;
  options.topic = "/c";
  options.columns = {"timestamp", "x", "y", "z"};
  InputData data = ParseInput(bag, "c.bag", options);
  ASSERT_TRUE(data.raw.time.has_value());
  EXPECT_EQ(data.raw.time->unit, TimeUnit::kSeconds) << data.raw.time->unit_reason;
  EXPECT_DOUBLE_EQ(data.raw.time->rate_hz, 100.0);
  options.time_unit = TimeUnit::kSeconds;  // not refused: the field is the message's number
  EXPECT_EQ(ParseInput(bag, "c.bag", options).raw.time->unit, TimeUnit::kSeconds);
  options.time_unit = TimeUnit::kAuto;
  options.columns = {"x", "y", "z"};
  data = ParseInput(bag, "c.bag", options);
  ASSERT_TRUE(data.raw.time.has_value());
  EXPECT_EQ(data.raw.time->unit, TimeUnit::kMicroseconds);
  EXPECT_DOUBLE_EQ(data.raw.time->origin_s, 100.0);  // the records' times
  EXPECT_DOUBLE_EQ(data.raw.time->rate_hz, 100.0);
}

// A publisher that does not stamp its messages (header.stamp 0 in every one): said, naming the
// field and the columns that read the time each was logged instead, which then read.
TEST(RosBag, AnUnstampedTopicIsNamedAndItsLogTimeOffered) {
  const char definition[] =
      "Header header\nfloat64 x\nfloat64 y\nfloat64 z\n"
      "================================================================================\n"
      "MSG: std_msgs/Header\nuint32 seq\ntime stamp\nstring frame_id\n";
  const std::string bag = CustomBag("/imu", "custom/Accel", definition, [](std::uint32_t k) {
    std::string data;
    Put<std::uint32_t>(&data, k);  // seq
    Put<std::uint32_t>(&data, 0);  // stamp: never set
    Put<std::uint32_t>(&data, 0);
    PutString(&data, "imu");
    PutReadings(&data, k);
    return data;
  });
  ReadOptions options;
  options.topic = "/imu";
  options.columns = {"x", "y", "z"};
  try {
    ParseInput(bag, "u.bag", options);
    ADD_FAILURE() << "read";
  } catch (const InputError& e) {
    EXPECT_NE(
        std::string(e.what()).find(
            "/imu's header.stamp is the same in every message (0 us): the sensor's driver does "
            "not stamp them; read the time the recorder logged each with the columns "
            "option (log_time,x,y,z)"),
        std::string::npos)
        << e.what();
  }
  options.columns = {"log_time", "x", "y", "z"};
  const InputData data = ParseInput(bag, "u.bag", options);
  ASSERT_TRUE(data.raw.time.has_value());
  EXPECT_DOUBLE_EQ(data.raw.time->rate_hz, 100.0);
  EXPECT_EQ(data.raw.samples.size(), 300u);
}

// accelcal's writer (rosbag_writer.hpp) read back; then its index (after every chunk) damaged:
// every message was read before it, so that is a warning naming where the index begins.
TEST(RosBag, ReadsItsOwnWriterAndTakesACorruptIndexAsAWarning) {
  RosBagImuWriter writer(RosBagCompression::kLz4);
  std::string bag = writer.Header();
  for (int k = 0; k < 5000; ++k) {  // three chunks
    bag += writer.Sample(1700000000000000000ull + 10000000ull * std::uint64_t(k),
                         Vec3(0.1, 0.2, 9.8 + 1e-4 * k), Vec3(0.01, 0.02, 0.03));
  }
  bag += writer.Finish();
  const std::string indexed = writer.IndexedHeader();
  bag.replace(RosBagImuWriter::kHeaderOffset, indexed.size(), indexed);
  DecodedLog log = Read(bag);
  ASSERT_EQ(log.streams.size(), 1u);
  EXPECT_EQ(log.streams[0].messages, 5000u);
  EXPECT_FALSE(log.truncated.has_value()) << *log.truncated;
  // The index position, from the header record's index_pos field.
  const std::size_t field = bag.find("index_pos=") + 10;
  std::uint64_t index_pos = 0;
  std::memcpy(&index_pos, bag.data() + field, 8);
  ASSERT_GT(index_pos, 4096u);
  ASSERT_LT(index_pos, bag.size());
  std::string damaged = bag;
  const std::uint32_t huge = 0x7ffffff0u;  // the first index record's header length
  std::memcpy(&damaged[index_pos], &huge, 4);
  log = Read(damaged);
  EXPECT_EQ(log.streams[0].messages, 5000u);
  ASSERT_TRUE(log.truncated.has_value());
  EXPECT_NE(log.truncated->find("the bag's index (from byte " + std::to_string(index_pos) +
                                ") cannot be read"),
            std::string::npos)
      << *log.truncated;
}

}  // namespace
}  // namespace accelcal::internal
