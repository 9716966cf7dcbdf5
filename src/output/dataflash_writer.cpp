// A DataFlash log of one IMU (dataflash_writer.hpp).
#include "accelcal/dataflash_writer.hpp"

#include <cstring>
#include <limits>
#include <stdexcept>

#include "core/little_endian.hpp"

namespace accelcal {

namespace {

using internal::PutLittle;

constexpr unsigned char kFmt = 128, kImu = 163, kParm = 64;

// A text field of `size` bytes, NUL-padded.
void PutText(std::string* out, const std::string& text, std::size_t size) {
  std::string field = text.substr(0, size);
  field.resize(size, '\0');
  *out += field;
}

std::string Head(unsigned char type) {
  return {static_cast<char>(0xA3), static_cast<char>(0x95), static_cast<char>(type)};
}

std::string FmtRecord(unsigned char type, unsigned char length, const std::string& name,
                      const std::string& format, const std::string& labels) {
  std::string out = Head(kFmt);
  PutLittle<std::uint8_t>(&out, type);
  PutLittle<std::uint8_t>(&out, length);
  PutText(&out, name, 4);
  PutText(&out, format, 16);
  PutText(&out, labels, 64);
  return out;
}

}  // namespace

std::string DataFlashImuWriter::Header() const {
  return FmtRecord(kFmt, 89, "FMT", "BBnNZ", "Type,Length,Name,Format,Columns") +
         FmtRecord(kParm, 31, "PARM", "QNf", "TimeUS,Name,Value") +
         FmtRecord(kImu, 54, "IMU", "QBffffffIIfBBHH",
                   "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ,EG,EA,T,GH,AH,GHz,AHz");
}

std::string DataFlashImuWriter::Parameter(std::uint64_t time_us, const std::string& name,
                                          float value) const {
  if (name.empty() || name.size() > 16) {
    throw std::invalid_argument("a DataFlash parameter's name has 1 to 16 characters");
  }
  std::string out = Head(kParm);
  PutLittle<std::uint64_t>(&out, time_us);
  PutText(&out, name, 16);
  PutLittle<float>(&out, value);
  return out;
}

std::string DataFlashImuWriter::Sample(std::uint64_t time_us, const Vec3& accel, const Vec3& gyro,
                                       double temperature_c) const {
  const double most = std::numeric_limits<float>::max();
  if (!accel.allFinite() || !gyro.allFinite() || accel.cwiseAbs().maxCoeff() > most ||
      gyro.cwiseAbs().maxCoeff() > most) {
    throw std::invalid_argument(
        "a DataFlash log's readings are float32: a reading is not finite or beyond its range");
  }
  std::string out = Head(kImu);
  PutLittle<std::uint64_t>(&out, time_us);
  PutLittle<std::uint8_t>(&out, instance_);
  for (int a = 0; a < 3; ++a) PutLittle<float>(&out, static_cast<float>(gyro(a)));
  for (int a = 0; a < 3; ++a) PutLittle<float>(&out, static_cast<float>(accel(a)));
  PutLittle<std::uint32_t>(&out, 0);                          // EG
  PutLittle<std::uint32_t>(&out, 0);                          // EA
  PutLittle<float>(&out, static_cast<float>(temperature_c));  // T
  PutLittle<std::uint8_t>(&out, 1);                           // GH
  PutLittle<std::uint8_t>(&out, 1);                           // AH
  PutLittle<std::uint16_t>(&out, 0);                          // GHz
  PutLittle<std::uint16_t>(&out, 0);                          // AHz
  return out;
}

}  // namespace accelcal
