// A MAT-file of one matrix (mat_writer.hpp).
#include "accelcal/mat_writer.hpp"

#include <cctype>
#include <stdexcept>
#include <utility>

#include "core/little_endian.hpp"

namespace accelcal {

namespace {

using internal::PutLittle;

// Data types and the array class (the specification's tables 1-1 and 1-3).
constexpr std::uint32_t kMiInt8 = 1, kMiInt32 = 5, kMiUint32 = 6, kMiDouble = 9, kMiMatrix = 14;
constexpr std::uint32_t kMxDoubleClass = 6;

std::uint64_t Padded(std::uint64_t n) { return (n + 7) / 8 * 8; }

void Tag(std::string* out, std::uint32_t type, std::uint32_t bytes) {
  PutLittle<std::uint32_t>(out, type);
  PutLittle<std::uint32_t>(out, bytes);
}

}  // namespace

MatMatrixWriter::MatMatrixWriter(std::string variable, std::uint32_t rows, std::uint64_t columns)
    : variable_(std::move(variable)), rows_(rows), columns_(columns) {
  bool identifier = !variable_.empty() && variable_.size() <= 63 &&
                    std::isalpha(static_cast<unsigned char>(variable_[0])) != 0;
  for (unsigned char c : variable_) identifier = identifier && (std::isalnum(c) != 0 || c == '_');
  if (!identifier) {
    throw std::invalid_argument(
        "a MAT-file variable's name is a letter, then up to 62 letters, "
        "digits or '_': not \"" +
        variable_ + "\"");
  }
  const std::uint64_t data = std::uint64_t{rows_} * columns_ * 8;
  if (rows_ == 0 || rows_ > 0x7fffffffu || columns_ > 0x7fffffffu ||
      data + 64 + Padded(variable_.size()) > 0xffffffffu) {
    throw std::invalid_argument(
        "a Level 5 MAT-file holds a matrix of at most 2^31 - 1 rows and columns and 2^32 - 1 "
        "bytes");
  }
}

std::string MatMatrixWriter::Header() const {
  std::string out = "MATLAB 5.0 MAT-file, written by accelcal";
  out.resize(116, ' ');
  out.append(8, '\0');                     // no subsystem data
  PutLittle<std::uint16_t>(&out, 0x0100);  // the version
  out += "IM";                             // 'M' 'I' as a uint16: little-endian
  const std::uint64_t name = Padded(variable_.size());
  const std::uint64_t data = std::uint64_t{rows_} * columns_ * 8;
  // The matrix: array flags, dimensions, name, real part.
  Tag(&out, kMiMatrix, static_cast<std::uint32_t>(16 + 16 + 8 + name + 8 + data));
  Tag(&out, kMiUint32, 8);
  PutLittle<std::uint32_t>(&out, kMxDoubleClass);  // real, not global, not logical
  PutLittle<std::uint32_t>(&out, 0);
  Tag(&out, kMiInt32, 8);
  PutLittle<std::int32_t>(&out, static_cast<std::int32_t>(rows_));
  PutLittle<std::int32_t>(&out, static_cast<std::int32_t>(columns_));
  Tag(&out, kMiInt8, static_cast<std::uint32_t>(variable_.size()));
  out += variable_;
  out.append(name - variable_.size(), '\0');
  Tag(&out, kMiDouble, static_cast<std::uint32_t>(data));
  return out;
}

std::string MatMatrixWriter::Column(const double* values) {
  if (written_ == columns_) {
    throw std::logic_error("MatMatrixWriter: more columns than the header announced");
  }
  ++written_;
  std::string out;
  out.reserve(rows_ * 8);
  for (std::uint32_t i = 0; i < rows_; ++i) PutLittle<double>(&out, values[i]);
  return out;
}

std::string MatMatrixWriter::Finish() const {
  if (written_ != columns_) {
    throw std::logic_error("MatMatrixWriter: fewer columns than the header announced");
  }
  return {};
}

}  // namespace accelcal
