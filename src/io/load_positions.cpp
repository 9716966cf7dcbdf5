#include "accelcal/load_positions.hpp"

#include <stdexcept>

#include "accelcal/error.hpp"

namespace accelcal {

const LoadedFile* LoadedInput::FirstRaw() const {
  for (const LoadedFile& f : files) {
    if (f.data.kind == InputKind::kRaw) return &f;
  }
  return nullptr;
}

namespace {

LoadedFile LoadFile(const std::string& path, const LoadOptions& options) {
  if (options.before_file) options.before_file(path);
  LoadedFile loaded;
  loaded.path = path;
  ReadOptions read = options.read;
  read.fingerprint = true;  // for the calibration's provenance
  loaded.data = ReadInput(path, read);
  if (loaded.data.kind == InputKind::kRaw) {
    loaded.detection = DetectStaticIntervals(loaded.data.raw, options.detection);
  }
  if (options.after_file) options.after_file(loaded);
  if (loaded.detection && loaded.detection->intervals.empty()) {
    throw DataError(NoStaticIntervalReason(*loaded.detection));
  }
  return loaded;
}

}  // namespace

LoadedInput LoadPositions(const std::vector<std::string>& paths, const LoadOptions& options) {
  if (auto why = options.detection.Validate()) throw std::invalid_argument(*why);
  LoadedInput loaded;
  for (const std::string& path : paths) {
    try {
      loaded.files.push_back(LoadFile(path, options));
    } catch (const DataError& e) {  // what is wrong with one file of several names that file
      if (paths.size() == 1) throw;
      throw InputError(path, 0, e.what());
    }
    const LoadedFile& f = loaded.files.back();
    const std::vector<Position> positions = f.data.kind == InputKind::kPositions
                                                ? f.data.positions
                                                : PositionsFromIntervals(f.detection->intervals);
    loaded.positions.insert(loaded.positions.end(), positions.begin(), positions.end());
    if (paths.size() > 1) loaded.position_file.resize(loaded.positions.size(), path);
  }
  return loaded;
}

InputData ReadGyroInput(const std::string& accel_path, const ReadOptions& accel_read,
                        const std::string& gyro_path, const std::vector<std::string>& gyro_columns,
                        const std::string& gyro_topic) {
  ReadOptions read = accel_read;
  read.kind = InputKind::kRaw;
  read.sensor = SensorKind::kGyroscope;
  read.topic = gyro_topic;
  read.columns = gyro_columns;
  // The temperature option names a column of the accelerometer's log: the gyroscope's takes it
  // from the same file; from a file of its own, its temperature is found as without one (a
  // column named for it, PX4's sensor_gyro.temperature), unless the option is "none".
  const bool same_file = gyro_path.empty() || gyro_path == accel_path;
  if (!same_file && accel_read.temperature != "none") read.temperature.clear();
  if (gyro_path.empty() && read.columns.size() == 3 && accel_read.columns.size() == 4) {
    read.columns.insert(read.columns.begin(), accel_read.columns.front());
  }
  if (gyro_path.empty()) read.other_columns = accel_read.columns;  // the accelerometer's
  read.fingerprint = accel_read.fingerprint && !gyro_path.empty();
  const std::string& path = gyro_path.empty() ? accel_path : gyro_path;
  try {
    return ReadInput(path, read);
  } catch (const DataError& e) {
    throw InputError(path, 0, e.what());
  }
}

}  // namespace accelcal
