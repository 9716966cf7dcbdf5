#pragma once
/// @file log_reader.hpp
/// Reading accelerometer recordings from delimited text.
///
/// Accepted text: one record per line; fields separated by commas, tabs or runs of spaces (one kind
/// per file); `#` starts a comment to the end of the line; blank lines are skipped; the first
/// non-comment line may be a header of column names. Two kinds of file:
///   - raw logs: one sample per line, columns `time, x, y, z` (time in seconds; the imu_tk ASCII
///     format `t x y z` is of this kind) or `x, y, z` with the rate given separately;
///   - positions files: one averaged reading per line, `x, y, z`, optionally followed by the sample
///     count `n` and the per-axis standard deviations `sx, sy, sz`.
/// Every error names the file, the 1-based line and the reason (InputError).

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "accelcal/native_log.hpp"
#include "accelcal/positions.hpp"
#include "accelcal/time_axis.hpp"
#include "accelcal/types.hpp"

namespace accelcal {

/// What a file holds.
enum class InputKind {
  kAuto,       ///< decide from the header and the row count (see ReadOptions)
  kRaw,        ///< raw samples
  kPositions,  ///< one averaged reading per row
};
std::string_view ToString(InputKind kind);
std::optional<InputKind> InputKindFromString(std::string_view text);
template <>
struct EnumNames<InputKind> {
  static constexpr std::pair<InputKind, std::string_view> kTable[] = {
      {InputKind::kAuto, "auto"}, {InputKind::kRaw, "raw"}, {InputKind::kPositions, "positions"}};
};

/// A sensor of an IMU, as a log's streams are told apart.
enum class SensorKind { kAccelerometer, kGyroscope };
template <>
struct EnumNames<SensorKind> {
  static constexpr std::pair<SensorKind, std::string_view> kTable[] = {
      {SensorKind::kAccelerometer, "accelerometer"}, {SensorKind::kGyroscope, "gyroscope"}};
};

struct ReadOptions {
  InputKind kind = InputKind::kAuto;
  /// Column selection for wider logs: 3 entries (x, y, z) or 4 (time, x, y, z), each a 1-based
  /// column number or a header name. Empty: 4 columns are time,x,y,z and 3 are x,y,z.
  std::vector<std::string> columns;
  /// Sample rate [Hz] for logs without a time column. With a time column it must agree with the
  /// rate of the timestamps within kRateTolerance (InputError otherwise), and is then used.
  std::optional<double> rate_hz;
  /// kAuto: a file with at most this many data rows and no time column is a positions file; a
  /// header naming a time column (t, time, timestamp) makes it raw, one naming n/samples/count
  /// or std columns makes it a positions file; a given `rate_hz` makes it raw (a rate given for
  /// a positions file is an InputError).
  std::size_t max_rows_of_positions_file = 200;
  /// Called every 65536 data rows with the bytes parsed and the total (a progress bar); optional.
  std::function<void(std::size_t bytes_done, std::size_t bytes_total)> progress;
  /// Unit of the time column (time_axis.hpp): kAuto decides from its name and median step.
  TimeUnit time_unit = TimeUnit::kAuto;
  /// A file whose header names an instance column (i, instance, multi_id, device_id, imu,
  /// imu_id, sensor_id, id) may hold several sensors' rows: with more than one value there, the
  /// file is refused (InputError listing them) unless `instance` picks one, whose rows are kept.
  std::optional<double> instance;
  /// A binary log (native_log.hpp) holds several streams: the topic to read (its instance by
  /// `instance`). Empty: the log's only stream of `sensor` (KnownStreams), an InputError listing
  /// them when there are several. A text file with a topic given is an InputError.
  std::string topic{};
  /// A ROS topic whose messages name several `header.frame_id` (several sensors published on one
  /// topic; MCAP and rosbag2 carry no publisher to tell them apart): the frame whose messages are
  /// read. Empty: a topic of one frame (one of several is an InputError listing them). Given for
  /// a stream without frame ids, or naming none of its frames: an InputError.
  std::string frame_id{};
  /// Whose stream a binary log gives when no topic is given (the gyroscope's for its rates).
  SensorKind sensor = SensorKind::kAccelerometer;
  /// An input that is not a regular file (a pipe, standard input, a device such as /dev/zero) is
  /// refused (InputError) beyond this many bytes: it has no size to check first, and the reader
  /// must not read forever. 1 GiB: about 5 hours of a 1 kHz log as text (its samples then take
  /// up to 6 GB if its rows are as short as "1,2,3"). A regular file is read
  /// up to the size it had when opened, in blocks of whole lines (a file that shrinks meanwhile
  /// is an InputError).
  std::size_t max_stream_bytes = std::size_t{1} << 30;
  /// Also state the input's size and the SHA-256 of its bytes as read (InputData::bytes, sha256):
  /// what a calibration file's provenance records.
  bool fingerprint = false;
  /// The columns option of another stream read from the same file (the accelerometer's, when
  /// this read takes the gyroscope's; empty: its default layout): a column both would read is an
  /// InputError. Unset: no other stream.
  std::optional<std::vector<std::string>> other_columns = std::nullopt;
  /// The sensor's temperature [°C] with each sample (a raw log) or position (a positions file): a
  /// column (a 1-based number or a header name) of a text log or MAT-file, a field of a binary
  /// log's stream. Empty: a header column named as kTemperatureColumnNames says, or the known
  /// stream's field (KnownStream::temperature); none is not an error then. "none": not read.
  /// Values outside kTemperatureRange_C are an InputError naming the line (kelvin, raw counts or
  /// the wrong column) when the column was asked for; one found by its name has them left out
  /// (NaN, RawLog::temperature_note). Not read by StreamRawLog.
  std::string temperature{};
};

/// The header names a temperature column is found by when none is given.
inline constexpr const char* kTemperatureColumnNames[] = {
    "temperature",    "temp",           "temperature_c",    "temp_c",
    "temperature[c]", "temperature(c)", "temperature_degc", "temp_degc"};
/// A temperature [°C] outside this range is not an IMU's: a column in kelvin or raw counts, or
/// not a temperature at all (-80 °C to 150 °C: beyond any MEMS part's rating).
inline constexpr double kTemperatureRange_C[2] = {-80.0, 150.0};
/// Whether `t_c` is within kTemperatureRange_C (NaN is not).
inline bool InTemperatureRange(double t_c) {
  return t_c >= kTemperatureRange_C[0] && t_c <= kTemperatureRange_C[1];
}

/// A given rate may differ from the timestamps' by this fraction (clock error, rounding).
inline constexpr double kRateTolerance = 0.05;

/// A raw recording: samples in raw units, with optional timestamps.
struct RawLog {
  std::string source;  ///< file name, for messages
  /// Seconds from the first sample (time->origin_s is that sample's time); empty when the file
  /// has no time column.
  std::vector<double> time_s;
  std::vector<Vec3> samples;  ///< raw readings
  /// 1-based source line of each sample; in a binary log, the 1-based number of its message in
  /// its stream
  std::vector<std::uint32_t> line;
  /// Sample rate [Hz]: ReadOptions::rate_hz, else the rate of the timestamps' segments
  /// (TimeAxis::rate_hz), else unset.
  std::optional<double> rate_hz;
  /// The time column's unit, origin, gaps and regularity; unset without a time column.
  std::optional<TimeAxis> time;
  /// The sensor's temperature [°C] at each sample (ReadOptions::temperature), NaN where a binary
  /// log's message gives none; empty when the log has none.
  std::vector<double> temperature_c;
  /// Where it came from ("column 5 ('temperature')", "sensor_accel.temperature"); empty: none.
  std::string temperature_source;
  /// A column found by its name (not asked for) whose values were no temperature: which were
  /// left out (NaN; all of them: no temperature); empty otherwise.
  std::string temperature_note;
  /// What the reader could not read, though the samples above are whole (a binary log cut
  /// short: where it stopped); empty when it read everything.
  std::string read_warning;
};

/// What was read: either a raw log or a table of positions.
struct InputData {
  InputKind kind = InputKind::kRaw;  ///< never kAuto
  std::string kind_reason;           ///< why this kind was chosen (auto-detection), for messages
  /// Auto-detection decided by the row count alone (no header said what the file is): a short
  /// raw log without a header is then read as positions (Diagnose checks for that).
  bool kind_from_row_count = false;
  RawLog raw;                       ///< when kind == kRaw
  std::vector<Position> positions;  ///< when kind == kPositions
  /// With ReadOptions::fingerprint (ReadInput): the bytes read and their SHA-256 (hexadecimal).
  std::uint64_t bytes = 0;
  std::string sha256;
  /// A raw log read from a binary log's stream: which, and the calibration in force.
  std::optional<SourceStream> stream;
};

/// Parses text already in memory, or a binary log (native_log.hpp); `source` names it in errors.
InputData ParseInput(std::string_view text, const std::string& source, const ReadOptions& options);
/// Reads and parses a file; "-" reads standard input (named "<stdin>" in messages). Throws
/// InputError (unreadable path, parse error).
InputData ReadInput(const std::string& path, const ReadOptions& options);
/// What StreamRawLog found in a whole log whose samples went to its sink.
struct StreamedLog {
  std::string source;             ///< file name, for messages
  std::size_t samples = 0;        ///< handed to the sink
  std::optional<double> rate_hz;  ///< as RawLog::rate_hz, over the whole log
  /// The time column: its unit, origin and typical step decided on the first kStreamHeadSamples
  /// samples (as are its resolution and the fractions of repeated and irregular steps), its gaps
  /// and rate over the whole log. Unset without a time column.
  std::optional<TimeAxis> time;
  std::vector<std::uint32_t> gap_lines;  ///< the line of the first sample after each gap
  std::string read_warning;              ///< as RawLog::read_warning (a binary log cut short)
};
/// The samples StreamRawLog holds before it decides the time column's unit.
inline constexpr std::size_t kStreamHeadSamples = 65536;

/// A raw log too long to hold, read block by block (ReadInput's format and options; the kind is
/// raw): `sink` gets the samples in file order, in pieces (a RawLog whose time_s are seconds from
/// the first sample, with samples and line, and with a time column its `time`: the unit, origin,
/// typical step and resolution decided on the head, no gaps), which it may keep or drop, so that
/// memory does not grow with the log. The time column's unit is decided on the first
/// kStreamHeadSamples samples (all of a shorter log); a later timestamp that goes back is an
/// InputError, and a step longer than kGapFactor typical steps a gap. A file with an instance
/// column holding more than one value needs ReadOptions::instance (InputError at the first row of a
/// second value otherwise). Not fingerprinted. Throws InputError for what ReadInput refuses.
StreamedLog StreamRawLog(const std::string& path, const ReadOptions& options,
                         const std::function<void(const RawLog& piece)>& sink);

/// Calibration, orientation and other small files are refused beyond this size (64 MiB), so a
/// huge or sparse file given by mistake fails at once instead of filling memory.
inline constexpr std::size_t kMaxSmallFileBytes = std::size_t{64} << 20;
/// Reads a whole file into a string. Throws InputError when it cannot be read or is larger than
/// `max_bytes`.
std::string ReadFileToString(const std::string& path,
                             std::size_t max_bytes = static_cast<std::size_t>(-1));

}  // namespace accelcal
