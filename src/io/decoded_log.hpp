#pragma once
// What a binary log reader (ulog.cpp, dataflash.cpp) gives: the log's streams, each a message
// type's instance with its numeric fields, counted, and decoded when asked for.

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace accelcal::internal {

/// One stream: a ULog topic's subscription (its multi id), a DataFlash message type's instance
/// (its I field).
struct DecodedStream {
  std::string topic;
  int instance = 0;
  /// Its numeric fields, flattened as the format's own tools name them (pyulog: `x`,
  /// `gyro_rad[0]`, `a.b`; DataFlash: its column labels), in the format's order; padding and
  /// text fields left out.
  std::vector<std::string> columns;
  std::size_t messages = 0;
  /// The time field [µs] of its first and last message (0 without messages).
  std::uint64_t first_us = 0, last_us = 0;
  /// The `device_id` field of its first message, when it has one.
  std::optional<std::uint64_t> device_id;
  /// Whether its messages were kept: then `values` holds columns.size() values per message,
  /// message after message, and `offset` each message's byte offset in the file.
  bool kept = false;
  std::vector<double> values;
  std::vector<std::uint64_t> offset;
};

struct DecodedLog {
  std::uint64_t start_us = 0;          ///< the log's start, when it says
  std::vector<DecodedStream> streams;  ///< in the order of their first appearance
  /// The parameters in force when the log began.
  std::map<std::string, double> parameters;
  /// Information whose value is a string (sys_name, ver_hw, ...).
  std::map<std::string, std::string> info;
  /// Set when the log ends inside a message (a log cut short): where, and how many messages were
  /// read whole before it.
  std::optional<std::string> truncated;
  std::uint64_t bytes = 0;  ///< read, in all
};

/// Which streams a reader decodes (topic, instance); the others it only counts.
using KeepStream = std::function<bool(const std::string& topic, int instance)>;

}  // namespace accelcal::internal
