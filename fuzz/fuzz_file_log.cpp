// libFuzzer harness: the binary logs read from their file by a library (native_log.hpp: MATLAB
// MAT-files through libmatio, ROS 2 SQLite bags through libsqlite3), which ParseInput refuses in
// memory. Each input is written to one temporary file, then inspected and read by ReadInput as a
// user would choose (nothing, a variable or topic, named columns).
// The only accepted failure is InputError (the file, the reason); anything else is a finding. What
// is read must be what a raw log promises: finite samples and times, times that never go back.
#include <fcntl.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "accelcal/error.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/native_log.hpp"
#include "input_check.hpp"

namespace {

// One file for the whole run, rewritten for each input.
const std::string& Path() {
  static const std::string path = [] {
    const char* dir = std::getenv("TMPDIR");
    std::string p =
        std::string(dir != nullptr && *dir != '\0' ? dir : "/tmp") + "/fuzz_file_log.XXXXXX";
    const int fd = ::mkstemp(p.data());
    if (fd < 0) std::abort();
    ::close(fd);
    std::atexit([] { ::unlink(Path().c_str()); });
    return p;
  }();
  return path;
}

void Read(const accelcal::ReadOptions& options) {
  try {
    accelcal::fuzz::CheckInput(accelcal::ReadInput(Path(), options), true);
  } catch (const accelcal::InputError&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  const accelcal::LogFormat format = accelcal::DetectLogFormat(bytes.substr(0, 16));
  if (format != accelcal::LogFormat::kMat && format != accelcal::LogFormat::kRosbag2Sqlite) {
    return 0;  // the others are read in memory: fuzz_native_log's and fuzz_log_reader's
  }
  const int fd = ::open(Path().c_str(), O_WRONLY | O_TRUNC | O_CLOEXEC);
  if (fd < 0) std::abort();
  for (std::size_t done = 0; done < size;) {
    const ssize_t n = ::write(fd, data + done, size - done);
    if (n <= 0) std::abort();
    done += static_cast<std::size_t>(n);
  }
  ::close(fd);
  try {
    accelcal::InspectLog(Path());
  } catch (const accelcal::InputError&) {
  }
  accelcal::ReadOptions options;
  Read(options);
  options.topic = format == accelcal::LogFormat::kMat ? "imu" : "/imu/data";
  Read(options);
  options.sensor = accelcal::SensorKind::kGyroscope;
  Read(options);
  options.sensor = accelcal::SensorKind::kAccelerometer;
  if (format == accelcal::LogFormat::kMat) {
    options.columns = {"2", "3", "4"};
  } else {
    options.columns = {"header.stamp", "angular_velocity.x", "angular_velocity.y",
                       "angular_velocity.z"};
  }
  Read(options);
  return 0;
}
