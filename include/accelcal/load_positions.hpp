#pragma once
/// @file load_positions.hpp
/// The input of a calibration: files read (log_reader.hpp), raw logs cut into static intervals
/// (static_detection.hpp) and averaged, the positions of several files pooled in file order (the
/// sessions of one device; time is never joined across files). One piece for the command line and
/// Python.

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "accelcal/log_reader.hpp"
#include "accelcal/positions.hpp"
#include "accelcal/static_detection.hpp"

namespace accelcal {

/// One input file as read, with its static intervals when it is a raw log.
struct LoadedFile {
  std::string path;
  InputData data;
  std::optional<StaticDetectionResult> detection;
};

/// The input files of a calibration.
struct LoadedInput {
  std::vector<LoadedFile> files;
  std::vector<Position> positions;
  /// The file of each position, when there are several files (else empty).
  std::vector<std::string> position_file;
  /// The first raw log, for the report's signal plot (nullptr: none).
  const LoadedFile* FirstRaw() const;
};

struct LoadOptions {
  ReadOptions read;
  StaticDetectionOptions detection;
  /// Called before each file is read (e.g. to set read.progress's display), with its path.
  std::function<void(const std::string& path)> before_file;
  /// Called after each file is read and, for a raw log, detected, before its positions are taken:
  /// to report on it, or to throw a more specific error than the default for a log without a
  /// static interval (DataError with NoStaticIntervalReason).
  std::function<void(const LoadedFile& file)> after_file;
};

/// Reads `paths` in order. Throws std::invalid_argument for invalid detection options, InputError
/// for a file that cannot be read or parsed, DataError for a log without a static interval; with
/// several files, any error names its file (InputError). Each file is read with
/// ReadOptions::fingerprint: its size and SHA-256 are in LoadedFile::data (a calibration's
/// provenance, InputRecords).
LoadedInput LoadPositions(const std::vector<std::string>& paths, const LoadOptions& options);

/// The gyroscope's log recorded beside the accelerometer's log `accel_path`, read as the
/// accelerometer's (`accel_read`: time unit, rate, instance) but as a raw log of the columns
/// `gyro_columns` (x,y,z or time,x,y,z; empty: the file's default layout): from `gyro_path`, or
/// from the accelerometer's log itself when it is empty (then its time column, when
/// `accel_read.columns` names one, is the rates' too, and it is not fingerprinted again). From a
/// binary log (native_log.hpp), the stream of `gyro_topic`, or when it is empty the log's
/// gyroscope stream (ReadOptions::sensor), of the accelerometer's instance when one was chosen.
/// Throws InputError as ReadInput, a DataError of the reader turned into an InputError naming the
/// file.
InputData ReadGyroInput(const std::string& accel_path, const ReadOptions& accel_read,
                        const std::string& gyro_path, const std::vector<std::string>& gyro_columns,
                        const std::string& gyro_topic = "");

}  // namespace accelcal
