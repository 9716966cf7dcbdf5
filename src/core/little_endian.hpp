#pragma once
// Little-endian values in bytes, at any alignment: read by the native log readers (io/), written
// by the log writers (output/). Every format accelcal reads or writes this way (ULog, DataFlash,
// ROS bags, CDR, MCAP, MAT-files) is little-endian, as are the machines it is built for (x86-64,
// ARM), so a value's bytes are its memory's bytes (memcpy).

#include <cstring>
#include <string>

namespace accelcal::internal {

/// The value of type T whose bytes are at `p`.
template <typename T>
T LoadLittle(const unsigned char* p) {
  static_assert(sizeof(T) <= 8, "scalars only");
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}

/// `value`'s bytes appended to `out`.
template <typename T>
void PutLittle(std::string* out, T value) {
  static_assert(sizeof(T) <= 8, "scalars only");
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out->append(bytes, sizeof(T));
}

}  // namespace accelcal::internal
