#pragma once
/// @file native_log.hpp
/// The binary logs accelcal reads as they are recorded, told by their first bytes: PX4 ULog
/// (`.ulg`), ArduPilot DataFlash (`.bin`), ROS 1 bags (`.bag`) and MCAP (`.mcap`, ROS 2); and
/// MATLAB MAT-files, whose
/// numeric matrix (ReadOptions::topic names the variable) is read as its numbers as text. ReadInput
/// (log_reader.hpp) reads one stream of such a log as it reads a text log's columns: the stream by
/// ReadOptions::topic and
/// ::instance, its fields by ::columns; InspectLog says what a log holds. A log cut short gives
/// what is whole, with a warning (RawLog::read_warning); a corrupt one an InputError naming the
/// byte.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "accelcal/names.hpp"

namespace accelcal {

enum class LogFormat {
  kText,           ///< delimited text (log_reader.hpp)
  kULog,           ///< PX4 ULog
  kDataFlash,      ///< ArduPilot DataFlash
  kRosBag,         ///< ROS 1 bag (format 2.0)
  kMcap,           ///< MCAP (ROS 2's bags; ROS 1 messages too)
  kRosbag2Sqlite,  ///< ROS 2 bag in SQLite (rosbag2's .db3)
  kMat,            ///< MATLAB MAT-file (level 5, 7.3): a numeric matrix read as a text table
};
template <>
struct EnumNames<LogFormat> {
  static constexpr std::pair<LogFormat, std::string_view> kTable[] = {
      {LogFormat::kText, "text"},
      {LogFormat::kULog, "ulog"},
      {LogFormat::kDataFlash, "dataflash"},
      {LogFormat::kRosBag, "rosbag"},
      {LogFormat::kMcap, "mcap"},
      {LogFormat::kRosbag2Sqlite, "db3"},
      {LogFormat::kMat, "mat"}};
};
std::string_view ToString(LogFormat format);
/// The format of a file that begins with `first_bytes` (16 are enough).
LogFormat DetectLogFormat(std::string_view first_bytes);

/// What a sensor stream of a log gives accelcal by default.
struct KnownStream {
  /// The message type: a PX4 topic, an ArduPilot message, a ROS type (any topic of it).
  std::string_view type;
  std::string_view sensor;   ///< "accelerometer" or "gyroscope"
  std::string_view time;     ///< its sample time field [µs]
  std::string_view x, y, z;  ///< its fields
  std::string_view unit;     ///< of those fields
  /// Already corrected by the calibration in force when it was logged (calibrating it finds
  /// what that calibration left, not the sensor's own).
  bool corrected = false;
  /// How a message holds its readings.
  enum class Packing {
    kSample,  ///< one sample: x, y, z
    /// a sum over an interval: x, y, z divided by the field `interval` [µs] (PX4's vehicle_imu:
    /// delta_velocity over delta_velocity_dt)
    kDelta,
    /// several samples: the arrays x[i], y[i], z[i] times the field `scale`, the first `samples`
    /// of them, `dt` [µs] apart, the last at the time field (PX4's sensor_accel_fifo)
    kFifo,
  };
  Packing packing = Packing::kSample;
  std::string_view interval{};  ///< kDelta: the interval's field
  /// A field whose value -1 in every message says the readings are not measured (REP 145: a ROS
  /// Imu's covariance[0]); empty when the type has none.
  std::string_view unmeasured{};
  /// The sensor's temperature field [°C] (ReadOptions::temperature); empty when the type has none.
  std::string_view temperature{};
};
/// The streams accelcal reads without being told their fields: PX4's sensor_accel (the
/// driver's output, before the calibration), sensor_combined's accelerometer (after it),
/// sensor_gyro, sensor_combined's gyro, sensor_accel_fifo and sensor_gyro_fifo (the driver's
/// every sample), vehicle_imu (integrated, after the calibration); ArduPilot's IMU, ACC and GYR
/// records (after the calibration in force: INS_ACCOFFS, INS_ACCSCAL); a ROS sensor_msgs/Imu's
/// linear_acceleration and angular_velocity.
const std::vector<KnownStream>& KnownStreams();
/// The sensors accelcal reads from a stream of `type` by default (ROS 2's "pkg/msg/Type" is ROS
/// 1's "pkg/Type"): empty for a type it does not know.
std::vector<std::string_view> KnownSensors(std::string_view type);

/// The stream of a binary log a raw log was read from, as a calibration file's provenance records
/// it (`inputs[].stream`): what the parameters exported from the calibration are for.
struct SourceStream {
  std::string format;  ///< ToString(LogFormat): "ulog", "dataflash", "rosbag", "mcap", "db3"
  std::string topic;
  std::string type;  ///< its message type (a ROS type; a PX4 or ArduPilot topic's own name)
  int instance = 0;  ///< ULog multi id, DataFlash I
  std::optional<std::uint64_t> device_id;
  /// The readings' unit by the format's specification ("m/s2", "rad/s": a known stream's,
  /// KnownStream::unit); empty for fields the user chose.
  std::string unit;
  /// Already corrected by the calibration in force when it was logged (KnownStream::corrected):
  /// a calibration of it is a correction on top of that one.
  bool corrected = false;
  /// The log's parameters that make the sensor's calibration in force (PX4's CAL_ACC*, CAL_GYRO*,
  /// SENS_BOARD_*; ArduPilot's INS_ACC*, INS_GYR*, INS_TCAL*, AHRS_ORIENTATION; not the other
  /// sensor's own), at the stream's first sample: each one's last value logged at or before it.
  /// A log in which one of them changes during the samples is refused (InputError naming it, both
  /// values and their times).
  std::map<std::string, double> calibration_in_force;
};

/// One stream of a binary log: a topic's instance.
struct LogStreamInfo {
  std::string topic;
  std::string type;  ///< its message type (a ROS topic's; a PX4 or ArduPilot topic's own name)
  int instance = 0;  ///< ULog multi id, DataFlash I (0 for a ROS topic)
  std::optional<std::uint64_t> device_id;
  /// A ROS topic's `header.frame_id`, of its first message (the frame its readings are in).
  std::optional<std::string> frame_id;
  /// Every `header.frame_id` its messages name, with how many name it, in the order of their
  /// first message (up to 64): more than one is several sensors published on one topic, of which
  /// ReadOptions::frame_id reads one.
  std::vector<std::pair<std::string, std::size_t>> frames;
  std::size_t samples = 0;
  double first_s = 0, last_s = 0;  ///< timestamps of the first and last message [s]
  double rate_hz = 0;              ///< (samples − 1) / (last − first); 0 when undefined
  /// The sensors accelcal takes from it by default (KnownStreams), e.g. "accelerometer"; none
  /// when its messages cannot be decoded.
  std::vector<std::string> sensors;
  /// Why accelcal cannot decode its messages (a ROS topic serialised as JSON, a ros2idl or
  /// unparsable definition): empty when it can.
  std::string unreadable;
};

struct LogInventory {
  LogFormat format = LogFormat::kText;
  std::string source;
  std::uint64_t bytes = 0;
  std::vector<LogStreamInfo> streams;
  /// Each topic's numeric fields (the names --columns takes), once per topic.
  std::map<std::string, std::vector<std::string>> fields;
  /// The parameters at the log's start (each one's first value logged).
  std::map<std::string, double> parameters;
  /// The parameters set while the log ran: each change after its first value, with its time [s].
  struct ParameterChange {
    std::string name;
    double time_s = 0;
    double value = 0;
  };
  std::vector<ParameterChange> parameter_changes;
  std::map<std::string, std::string> info;  ///< the log's string information (sys_name, ...)
  std::optional<std::string> truncated;     ///< where a log cut short stopped
};

/// What a binary log holds. Throws InputError for what cannot be read, for a text file (it has
/// no streams: its columns are its header's) and for a corrupt log.
LogInventory InspectLog(const std::string& path);

}  // namespace accelcal
