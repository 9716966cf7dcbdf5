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

}  // namespace accelcal
