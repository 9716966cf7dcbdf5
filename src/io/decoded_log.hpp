#pragma once
// What a binary log reader (ulog.cpp, dataflash.cpp, rosbag.cpp) gives: the log's streams, each a
// message type's instance with its numeric fields, counted, and decoded when asked for.

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace accelcal::internal {

/// One stream: a ULog topic's subscription (its multi id), a DataFlash message type's instance
/// (its I field), a ROS topic (instance 0).
struct DecodedStream {
  std::string topic;
  /// Its message type: a ULog topic's format and a DataFlash message's name (both the topic
  /// itself), a ROS topic's type (`sensor_msgs/Imu`).
  std::string type;
  int instance = 0;
  /// Its numeric fields, flattened as the format's own tools name them (pyulog: `x`,
  /// `gyro_rad[0]`, `a.b`; DataFlash: its column labels), in the format's order; padding and
  /// text fields left out, and those beyond the format's first kMaxFormatColumns. Shared by the
  /// streams of one format (a log may subscribe one format many times).
  std::shared_ptr<const std::vector<std::string>> columns;
  /// The columns its reader gives in µs by their type (a ROS message's time and duration fields,
  /// and `log_time`); null where they are known by name (ULog's timestamp and
  /// timestamp_sample, DataFlash's TimeUS and SampleUS).
  std::shared_ptr<const std::vector<std::size_t>> microseconds;
  /// Why its messages cannot be decoded (a ROS topic's definition that does not parse, a
  /// serialisation other than ROS's): empty when they can. Keeping such a stream is an error.
  std::string unreadable;
  std::size_t messages = 0;
  /// The time field [µs] of its first and last message (0 without messages).
  std::uint64_t first_us = 0, last_us = 0;
  /// The `device_id` field of its first message, when it has one.
  std::optional<std::uint64_t> device_id;
  /// The `header.frame_id` of its first message (a ROS message with a std_msgs/Header).
  std::optional<std::string> frame_id;
  /// Every `header.frame_id` its messages name, in the order of their first message, with how
  /// many messages name it (kMaxFrames at most): several are several sensors published on one
  /// topic (MCAP and rosbag2 carry no publisher to tell them apart).
  std::vector<std::pair<std::string, std::size_t>> frames;
  /// With `kept` and `frames`: each kept message's index into `frames`.
  std::vector<std::uint32_t> frame_of;
  /// Whether its messages were kept: then `values` holds the `stored` columns of each message
  /// (stored.size() values per message, message after message), and `offset` each message's
  /// byte offset in the file.
  bool kept = false;
  std::vector<std::size_t> stored;  ///< indices into columns, in the order chosen
  std::vector<double> values;
  std::vector<std::uint64_t> offset;
};

struct DecodedLog {
  std::uint64_t start_us = 0;          ///< the log's start, when it says
  std::vector<DecodedStream> streams;  ///< in the order of their first appearance
  /// The parameters in force when the log began: each one's first value logged.
  std::map<std::string, double> parameters;
  /// Every value logged of each parameter, in the log's order, with its time [µs, the streams'
  /// clock]: a parameter set while the log ran (a DataFlash PARM record after the first, a ULog
  /// parameter message among the data, timed by the last message before it) is in force from
  /// then on.
  std::map<std::string, std::vector<std::pair<std::uint64_t, double>>> parameter_history;
  /// Information whose value is a string (sys_name, ver_hw, ...).
  std::map<std::string, std::string> info;
  /// Set when the log ends inside a message (a log cut short): where, and how many messages were
  /// read whole before it.
  std::optional<std::string> truncated;
  std::uint64_t bytes = 0;  ///< read, in all
  /// What DecodedStream::offset counts: the message's byte in the file, or (a database) its row.
  std::string offset_name = "byte";
};

/// Which streams a reader decodes (given its topic, type, instance and columns); the others it
/// only counts.
using KeepStream = std::function<bool(const DecodedStream& stream)>;
/// Which columns of a kept stream a reader stores (indices into its columns, in the order
/// wanted); without one, all of them. Memory then grows with what is kept, not with the log.
using StoreColumns = std::function<std::vector<std::size_t>(const DecodedStream& stream)>;

/// A topic whose messages name more frame ids than this is not several sensors on one topic: a
/// kept one is refused, another's further frames are not listed.
inline constexpr std::size_t kMaxFrames = 64;
/// A format's numeric fields beyond this many are not columns (a huge array, arrays of arrays).
inline constexpr std::size_t kMaxFormatColumns = 4096;
/// A log whose formats define more columns than this in all is refused: a small file could
/// otherwise ask for gigabytes of field names.
inline constexpr std::size_t kMaxLogColumns = std::size_t{1} << 20;

}  // namespace accelcal::internal
