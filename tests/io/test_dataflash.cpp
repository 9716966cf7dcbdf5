// The DataFlash reader on a real ArduPilot log cut short (data/ardupilot-dataflash): its IMU
// records against an independent decoding (Python's struct with the FMT's "QBffffffIIfBBHH"), its
// parameters, and where the log stops.
#include <string>

#include <gtest/gtest.h>

#include "accelcal/dataflash_writer.hpp"
#include "accelcal/error.hpp"
#include "io/binary_stream.hpp"
#include "io/dataflash.hpp"
#include "io/input_file.hpp"
#include "support/paths.hpp"

namespace accelcal::internal {
namespace {

const std::string kLog =
    std::string(ACCELCAL_DATA_DIR) + "/ardupilot-dataflash/backend_log_80k.bin";

DecodedLog Read(const std::string& path, const KeepStream& keep) {
  InputFile file(path, std::size_t{1} << 30);
  BinaryStream in(&file, "");
  return ReadDataFlash(in, keep);
}

TEST(DataFlash, ImuRecordsParametersAndTheCut) {
  const DecodedLog log = Read(kLog, [](const DecodedStream& s) { return s.topic == "IMU"; });
  // The last whole record ends at byte 81918 of 81920.
  ASSERT_TRUE(log.truncated.has_value());
  EXPECT_EQ(*log.truncated,
            "the log ends inside a record header at byte 81918, after 1817 whole records");
  EXPECT_EQ(log.bytes, 81920u);
  const DecodedStream* imu[2] = {nullptr, nullptr};
  for (const DecodedStream& s : log.streams) {
    if (s.topic == "IMU") imu[s.instance] = &s;
  }
  ASSERT_NE(imu[0], nullptr);
  ASSERT_NE(imu[1], nullptr);
  EXPECT_EQ(imu[0]->messages, 10u);
  EXPECT_EQ(imu[1]->messages, 10u);
  const std::vector<std::string> columns = {"TimeUS", "I",    "GyrX", "GyrY", "GyrZ",
                                            "AccX",   "AccY", "AccZ", "EG",   "EA",
                                            "T",      "GH",   "AH",   "GHz",  "AHz"};
  EXPECT_EQ(*imu[0]->columns, columns);
  // The first record of each instance, and the last of instance 1, as Python decodes them.
  const auto row = [&](const DecodedStream* s, std::size_t k) {
    return std::vector<double>(s->values.begin() + static_cast<std::ptrdiff_t>(k * 15),
                               s->values.begin() + static_cast<std::ptrdiff_t>(k * 15 + 15));
  };
  EXPECT_EQ(row(imu[0], 0),
            (std::vector<double>{140209868, 0, 0.005344705190509558, -0.003233567578718066,
                                 -0.0005263044149614871, 0.6129292845726013, 0.8672698140144348,
                                 -9.763680458068848, 0, 0, 37.3057975769043, 1, 1, 8001, 4000}));
  EXPECT_EQ(row(imu[1], 0),
            (std::vector<double>{140209868, 1, 0.003561674151569605, 0.0008406839915551245,
                                 -0.0008794313762336969, 0.48838382959365845, 0.9139217734336853,
                                 -9.737777709960938, 0, 0, 28.5, 1, 1, 1999, 2004}));
  EXPECT_EQ(row(imu[1], 9),
            (std::vector<double>{140575610, 1, -0.00012741498358082026, -0.0008575254469178617,
                                 -0.00048234910354949534, 0.4669237732887268, 0.9233852624893188,
                                 -9.744965553283691, 0, 0, 28.5, 1, 1, 1999, 2004}));
  EXPECT_EQ(imu[0]->offset.front(), 25853u);
  EXPECT_EQ(imu[1]->offset.back(), 80304u);
  EXPECT_EQ(imu[0]->first_us, 140209868u);
  // The calibration in force, as PARM records state it.
  EXPECT_EQ(log.parameters.at("INS_ACCOFFS_X"), static_cast<double>(-0.0941748321056366f));
  EXPECT_EQ(log.parameters.at("INS_ACCSCAL_Z"), static_cast<double>(0.9905402660369873f));
  EXPECT_EQ(log.parameters.at("INS_ACC_ID"), 2621706);
}

// A type redefined after records of it would have its later records read by the old layout (or
// crash on the shorter one): refused, naming the byte of the new FMT. The same FMT again is fine.
TEST(DataFlash, ATypeRedefinedAfterItsRecordsIsRefused) {
  const DataFlashImuWriter writer;
  std::string log = writer.Header();
  for (int k = 0; k < 3; ++k)
    log += writer.Sample(1000u * static_cast<unsigned>(k), Vec3(0, 0, 9.8), Vec3::Zero());
  // (The header: the FMT records of FMT, PARM and IMU, 89 bytes each.)
  const std::string again =
      log + writer.Header().substr(2 * 89) + writer.Sample(5000, Vec3(0, 0, 9.8), Vec3::Zero());
  BinaryStream same(again, "same.bin");
  EXPECT_EQ(ReadDataFlash(same, [](const DecodedStream&) { return true; }).streams[0].messages, 4u);
  // IMU (type 163) redefined as 24 bytes of QBfff.
  std::string fmt = writer.Header().substr(2 * 89);
  fmt[4] = static_cast<char>(24);
  std::string format = "QBfff";
  format.resize(16, '\0');
  fmt.replace(9, 16, format);
  std::string labels = "TimeUS,I,AccX,AccY,AccZ";
  labels.resize(64, '\0');
  fmt.replace(25, 64, labels);
  BinaryStream redefined(log + fmt, "redefined.bin");
  try {
    ReadDataFlash(redefined, [](const DecodedStream&) { return true; });
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("byte " + std::to_string(log.size()) +
                                         ": a FMT record redefines type 163 (IMU, "
                                         "QBffffffIIfBBHH) as IMU, QBfff with other labels after "
                                         "records of it"),
              std::string::npos)
        << e.what();
  }
}

TEST(DataFlash, CorruptionIsAnErrorAtItsByte) {
  InputFile file(kLog, std::size_t{1} << 30);
  std::string bytes(81920, '\0');
  bytes.resize(file.ReadFully(bytes.data(), bytes.size()));
  std::string bad = bytes;
  bad[25853] = 'x';  // the first IMU record's header
  BinaryStream in(bad, "bad.bin");
  try {
    ReadDataFlash(in, [](const DecodedStream&) { return false; });
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "bad.bin: byte 25853: a record begins 78 95, not A3 95: the file is corrupt here");
  }
  std::string undefined = bytes;
  undefined[25853 + 2] = static_cast<char>(3);  // a type no FMT defines
  BinaryStream in2(undefined, "undefined.bin");
  EXPECT_THROW(ReadDataFlash(in2, [](const DecodedStream&) { return false; }), InputError);
  EXPECT_TRUE(IsDataFlash(bytes.substr(0, 3)));
  EXPECT_FALSE(IsDataFlash("\xA3\x95"));
}

}  // namespace
}  // namespace accelcal::internal
