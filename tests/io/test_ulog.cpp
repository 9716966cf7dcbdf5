// The ULog reader against pyulog's decoding of PX4's own sample log (data/px4-ulog): the same
// numbers, exactly (pyulog writes each float32 as the double it is).
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "accelcal/error.hpp"
#include "accelcal/ulog_writer.hpp"
#include "io/binary_stream.hpp"
#include "io/input_file.hpp"
#include "io/ulog.hpp"
#include "support/paths.hpp"

namespace accelcal::internal {
namespace {

const std::string kDir = std::string(ACCELCAL_DATA_DIR) + "/px4-ulog/";

DecodedLog Read(const std::string& path, const KeepStream& keep) {
  InputFile file(path, std::size_t{1} << 30);
  BinaryStream in(&file, "");
  return ReadULog(in, keep);
}

struct Csv {
  std::vector<std::string> header;
  std::vector<std::vector<double>> rows;
};
Csv ReadCsv(const std::string& path) {
  std::ifstream f(path);
  Csv out;
  std::string line;
  std::getline(f, line);
  std::stringstream h(line);
  for (std::string name; std::getline(h, name, ',');) out.header.push_back(name);
  while (std::getline(f, line)) {
    std::stringstream r(line);
    std::vector<double> row;
    for (std::string v; std::getline(r, v, ',');) row.push_back(std::stod(v));
    out.rows.push_back(row);
  }
  return out;
}

const DecodedStream* Find(const DecodedLog& c, const std::string& topic, int multi_id) {
  for (const DecodedStream& s : c.streams) {
    if (s.topic == topic && s.instance == multi_id) return &s;
  }
  return nullptr;
}

// Every column of pyulog's reference, every message, bit for bit.
void ExpectSameAsPyulog(const DecodedLog& c, const std::string& topic, int multi_id,
                        const std::string& csv) {
  SCOPED_TRACE(topic + "." + std::to_string(multi_id));
  const DecodedStream* s = Find(c, topic, multi_id);
  ASSERT_NE(s, nullptr);
  ASSERT_TRUE(s->kept);
  const Csv ref = ReadCsv(csv);
  ASSERT_EQ(s->messages, ref.rows.size());
  const std::size_t width = s->columns->size();
  for (std::size_t j = 0; j < ref.header.size(); ++j) {
    const auto it = std::find(s->columns->begin(), s->columns->end(), ref.header[j]);
    ASSERT_NE(it, s->columns->end()) << ref.header[j];
    const std::size_t col = std::size_t(it - s->columns->begin());
    for (std::size_t i = 0; i < ref.rows.size(); ++i) {
      ASSERT_EQ(s->values[i * width + col], ref.rows[i][j]) << ref.header[j] << " row " << i;
    }
  }
  EXPECT_EQ(s->first_us, static_cast<std::uint64_t>(ref.rows.front()[0]));
  EXPECT_EQ(s->last_us, static_cast<std::uint64_t>(ref.rows.back()[0]));
}

TEST(ULog, SameNumbersAsPyulogOnPx4SampleLog) {
  const DecodedLog c = Read(kDir + "sample_log_small.ulg", [](const DecodedStream& s) {
    return s.topic == "sensor_accel" || s.topic == "sensor_combined";
  });
  EXPECT_FALSE(c.truncated.has_value()) << *c.truncated;
  for (int i = 0; i < 3; ++i) {
    ExpectSameAsPyulog(c, "sensor_accel", i,
                       kDir + "sample_log_small.sensor_accel." + std::to_string(i) + ".pyulog.csv");
  }
  ExpectSameAsPyulog(c, "sensor_combined", 0,
                     kDir + "sample_log_small.sensor_combined.0.pyulog.csv");
  // Three accelerometers, each with its own device id.
  ASSERT_NE(Find(c, "sensor_accel", 0)->device_id, std::nullopt);
  EXPECT_EQ(*Find(c, "sensor_accel", 0)->device_id, 2424842u);
  // Streams not kept are counted, not stored.
  const DecodedStream* other = Find(c, "sensor_gyro", 0);
  if (other != nullptr) {
    EXPECT_FALSE(other->kept);
    EXPECT_TRUE(other->values.empty());
  }
  EXPECT_GT(c.parameters.size(), 100u);
  EXPECT_EQ(c.info.count("sys_name"), 1u);
}

std::string Bytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

std::string WriteTemp(const std::string& bytes, const char* name) {
  const std::string path = ::testing::TempDir() + name;
  std::ofstream(path, std::ios::binary) << bytes;
  return path;
}

// A log cut short (as a crashed vehicle's): what is whole, and where it stopped.
TEST(ULog, TruncatedLogGivesWhatIsWholeAndSaysWhere) {
  const std::string all = Bytes(kDir + "sample_log_small.ulg");
  const auto keep = [](const DecodedStream& s) { return s.topic == "sensor_combined"; };
  const DecodedLog whole = Read(kDir + "sample_log_small.ulg", keep);
  const std::size_t n = whole.streams.empty() ? 0 : Find(whole, "sensor_combined", 0)->messages;
  const DecodedLog cut = Read(WriteTemp(all.substr(0, all.size() / 2 + 7), "cut.ulg"), keep);
  ASSERT_TRUE(cut.truncated.has_value());
  EXPECT_NE(cut.truncated->find("ends inside a message"), std::string::npos) << *cut.truncated;
  const DecodedStream* s = Find(cut, "sensor_combined", 0);
  ASSERT_NE(s, nullptr);
  EXPECT_GT(s->messages, n / 4);
  EXPECT_LT(s->messages, n);
  // The messages read are the whole log's first ones.
  const DecodedStream* w = Find(whole, "sensor_combined", 0);
  for (std::size_t i = 0; i < s->values.size(); ++i) ASSERT_EQ(s->values[i], w->values[i]);
}

// Zeros to the end are space the logger reserved: a warning; a byte after them is corruption.
TEST(ULog, ZerosToTheEndAreAWarningAndAByteAfterThemAnError) {
  const std::string all = Bytes(kDir + "sample_log_small.ulg");
  BinaryStream zeros(all + std::string(5000, '\0'), "zeros.ulg");
  const DecodedLog c = ReadULog(zeros, [](const DecodedStream&) { return false; });
  ASSERT_TRUE(c.truncated.has_value());
  const std::string said = "the log ends in zero bytes from byte " + std::to_string(all.size()) +
                           " (space the logger reserved but never wrote), after ";
  EXPECT_EQ(c.truncated->rfind(said, 0), 0u) << *c.truncated;
  EXPECT_EQ(c.bytes, all.size() + 5000);
  BinaryStream after(all + std::string(5000, '\0') + "x", "after.ulg");
  try {
    ReadULog(after, [](const DecodedStream&) { return false; });
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("but byte " + std::to_string(all.size() + 5000) +
                                         " is not zero"),
              std::string::npos)
        << e.what();
  }
}

// Corruption is an error naming the byte, never a silent stop.
TEST(ULog, CorruptMessageTypeIsAnErrorAtItsByte) {
  std::string all = Bytes(kDir + "sample_log_small.ulg");
  // Walk the messages to the 1000th and give it an unknown type.
  std::size_t at = 16;
  for (int i = 0; i < 1000; ++i) {
    at += 3 + static_cast<unsigned char>(all[at]) + 256 * static_cast<unsigned char>(all[at + 1]);
  }
  all[at + 2] = 'Z';
  try {
    Read(WriteTemp(all, "corrupt.ulg"), [](const DecodedStream&) { return false; });
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("byte " + std::to_string(at) + ":"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("unknown message type"), std::string::npos) << e.what();
  }
}

// A ULog built from messages (uint16 size, uint8 type, payload).
std::string Message(char type, const std::string& payload) {
  std::string out(3, '\0');
  out[0] = static_cast<char>(payload.size() & 0xff);
  out[1] = static_cast<char>(payload.size() >> 8);
  out[2] = type;
  return out + payload;
}
std::string Header() {
  return std::string("ULog\x01\x12\x35\x01", 8) + std::string(8, '\0') +
         Message('B', std::string(40, '\0'));
}
std::string Subscribe(int multi_id, int id, const std::string& topic) {
  std::string p(3, '\0');
  p[0] = static_cast<char>(multi_id);
  p[1] = static_cast<char>(id & 0xff);
  p[2] = static_cast<char>(id >> 8);
  return Message('A', p + topic);
}

// A few bytes must not ask for much memory: 256 subscriptions of a format with a 65000-element
// array share one list of names, capped at kMaxFormatColumns (it was 532 MB for 1.9 kB).
TEST(ULog, ManySubscriptionsOfAHugeFormatShareTheirCappedColumns) {
  std::string log = Header() + Message('F', "t:uint64_t timestamp;uint8_t[65000] a");
  for (int m = 0; m < 256; ++m) log += Subscribe(m, m, "t");
  BinaryStream in(log, "bomb.ulg");
  const DecodedLog c = ReadULog(in, [](const DecodedStream&) { return false; });
  ASSERT_EQ(c.streams.size(), 256u);
  EXPECT_EQ(c.streams[0].columns->size(), kMaxFormatColumns);
  for (const DecodedStream& s : c.streams) EXPECT_EQ(s.columns.get(), c.streams[0].columns.get());
}

// Nested formats repeat their parents' names in each column's: long names at every level had
// asked for 7.7 GB from 960 kB. A name is at most 255 bytes, and the columns past the cap get none.
TEST(ULog, LongNestedNamesAreBounded) {
  std::string log = Header();
  log += Message('F', "f0:f1 " + std::string(300, 'a') + ";");
  BinaryStream in(log + Subscribe(0, 0, "f0"), "long.ulg");
  EXPECT_THROW(ReadULog(in, [](const DecodedStream&) { return false; }), InputError);
  std::string deep = Header();
  for (int i = 0; i < 15; ++i) {
    deep += Message('F', "f" + std::to_string(i) + ":f" + std::to_string(i + 1) + " " +
                             std::string(250, static_cast<char>('a' + i)) + ";");
  }
  deep += Message('F', "f15:uint8_t[20000] " + std::string(250, 'z') + ";");
  deep += Subscribe(0, 0, "f0");
  BinaryStream in2(deep, "deep.ulg");
  const DecodedLog c = ReadULog(in2, [](const DecodedStream&) { return false; });
  ASSERT_EQ(c.streams.size(), 1u);
  EXPECT_EQ(c.streams[0].columns->size(), kMaxFormatColumns);
}

// A name from the log reaches a message escaped: no terminal control sequence.
TEST(ULog, NamesInMessagesAreEscaped) {
  const std::string log = Header() + Message('F', "\x1b[2Jx:float a;float a");
  BinaryStream in(log, "esc.ulg");
  try {
    ReadULog(in, [](const DecodedStream&) { return false; });
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).find('\x1b'), std::string::npos) << e.what();
  }
}

// What pyulog would refuse is refused: a format that names a field twice.
TEST(ULog, AFormatNamingAFieldTwiceIsRefused) {
  const std::string log =
      Header() + Message('F', "sensor_accel:uint64_t timestamp;float x;float x;float z");
  BinaryStream in(log, "twice.ulg");
  try {
    ReadULog(in, [](const DecodedStream&) { return true; });
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "twice.ulg: byte 59: format sensor_accel names the field x twice");
  }
}

// Only the columns asked for are stored: memory grows with what is kept, not with the log.
TEST(ULog, OnlyTheColumnsAskedForAreStored) {
  const auto keep = [](const DecodedStream& s) { return s.topic == "sensor_combined"; };
  const DecodedLog all = Read(kDir + "sample_log_small.ulg", keep);
  InputFile file(kDir + "sample_log_small.ulg", std::size_t{1} << 30);
  BinaryStream in(&file, "");
  const DecodedLog some = ReadULog(in, keep, [](const DecodedStream&) {
    return std::vector<std::size_t>{6, 0};  // accelerometer_m_s2[0], timestamp
  });
  const DecodedStream& a = *Find(all, "sensor_combined", 0);
  const DecodedStream& b = *Find(some, "sensor_combined", 0);
  ASSERT_EQ(b.values.size(), 2 * b.messages);
  for (std::size_t i = 0; i < b.messages; ++i) {
    ASSERT_EQ(b.values[2 * i], a.values[i * a.columns->size() + 6]);
    ASSERT_EQ(b.values[2 * i + 1], a.values[i * a.columns->size()]);
  }
}

// A sensor_accel instance whose device_id changes within the log (another sensor in its place:
// a driver restarted on another bus, two logs joined) was read as one sensor and exported with
// the first's CAL_ACC0_ID; it is refused at the message where the id changes, with both ids. An
// instance that is not read is listed (inspect) as one accelcal cannot read, saying why.
TEST(ULog, ADeviceIdThatChangesWithinAnInstanceIsRefused) {
  const ULogImuWriter first(1), second(999);
  std::string log = first.Header();
  for (int k = 0; k < 200; ++k) {
    const ULogImuWriter& w = k < 100 ? first : second;
    log += w.Accel(1000000 + 10000 * std::uint64_t(k), Vec3(0.1 * k, 0, -9.81));
  }
  const std::string path = WriteTemp(log, "devid_switch.ulg");
  std::string why;
  try {
    Read(path, [](const DecodedStream&) { return true; });
  } catch (const InputError& e) {
    why = e.what();
  }
  EXPECT_NE(why.find("sensor_accel instance 0: its device_id changes from 1 to 999 at its "
                     "message 101 (timestamp 2000000 us): two sensors' samples in one instance"),
            std::string::npos)
      << why;
  const DecodedLog listed = Read(path, [](const DecodedStream&) { return false; });
  ASSERT_NE(Find(listed, "sensor_accel", 0), nullptr);
  EXPECT_EQ(*Find(listed, "sensor_accel", 0)->device_id, 1u);
  EXPECT_EQ(Find(listed, "sensor_accel", 0)->messages, 200u);
  EXPECT_NE(Find(listed, "sensor_accel", 0)->unreadable.find("its device_id changes from 1 to 999"),
            std::string::npos);
  // One id throughout: read.
  std::string same = first.Header();
  for (int k = 0; k < 200; ++k) {
    same += first.Accel(1000000 + 10000 * std::uint64_t(k), Vec3(0.1 * k, 0, -9.81));
  }
  const DecodedLog read =
      Read(WriteTemp(same, "devid_same.ulg"), [](const DecodedStream&) { return true; });
  EXPECT_EQ(Find(read, "sensor_accel", 0)->messages, 200u);
}

TEST(ULog, NotAULogIsRefused) {
  EXPECT_THROW(
      Read(WriteTemp("ULog\x01\x12", "short.ulg"), [](const DecodedStream&) { return true; }),
      InputError);
  EXPECT_FALSE(IsULog("ULog\x01\x12"));
  EXPECT_TRUE(IsULog(std::string("ULog\x01\x12\x35\x01", 8)));
}

}  // namespace
}  // namespace accelcal::internal
