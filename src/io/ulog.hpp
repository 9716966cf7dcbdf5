#pragma once
// PX4 ULog (.ulg), read from its specification (PX4 documentation, "ULog File Format"): a 16-byte
// header (magic "ULog" 01 12 35, version, start time [µs]), then messages of `uint16 size, uint8
// type` and `size` bytes: the definitions (B flag bits, F formats, I/M information, P/Q
// parameters), then the data (A subscribes a format under a message id and multi id, D is one
// message of it, R unsubscribes; L/C logged strings, S sync, O dropout; P a changed parameter).
// Little-endian, packed as the format lists its fields (padding fields named `_padding…`).

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "io/binary_stream.hpp"

namespace accelcal::internal {

/// The header's first 7 bytes.
inline constexpr unsigned char kULogMagic[7] = {'U', 'L', 'o', 'g', 0x01, 0x12, 0x35};
bool IsULog(std::string_view first_bytes);

/// One subscription: a topic's instance (its multi id).
struct ULogStream {
  std::string topic;
  int multi_id = 0;
  /// Its numeric fields, flattened as pyulog names them (`x`, `gyro_rad[0]`, `a.b`), in the
  /// format's order; padding and char fields left out.
  std::vector<std::string> columns;
  std::size_t messages = 0;
  /// The `timestamp` field [µs] of its first and last message (0 without messages).
  std::uint64_t first_us = 0, last_us = 0;
  /// The `device_id` field of its first message, when it has one.
  std::optional<std::uint64_t> device_id;
  /// Whether its messages were kept: then `values` holds columns.size() values per message,
  /// message after message, and `offset` each message's byte offset in the file.
  bool kept = false;
  std::vector<double> values;
  std::vector<std::uint64_t> offset;
};

struct ULogContents {
  std::uint64_t start_us = 0;       ///< the header's timestamp
  std::vector<ULogStream> streams;  ///< in the order of their first subscription
  /// The parameters' values in force at the end of the definitions (P messages there).
  std::map<std::string, double> parameters;
  /// Information messages (I) whose value is a string (sys_name, ver_hw, ...).
  std::map<std::string, std::string> info;
  /// Set when the log ends inside a message (a log cut short): where, and how many messages were
  /// read whole before it.
  std::optional<std::string> truncated;
  std::uint64_t bytes = 0;  ///< read, in all
};

/// Reads a whole ULog from `in` (at its first byte), keeping the messages of the subscriptions
/// `keep` accepts (topic, multi id). Throws InputError (the file, the byte offset, the reason)
/// for what is not a ULog or is corrupt: an unknown message type, a format that does not parse
/// or refers to an unknown type, a data message whose size is not its format's, an incompatible
/// flag this reader does not know.
ULogContents ReadULog(BinaryStream& in,
                      const std::function<bool(const std::string& topic, int multi_id)>& keep);

}  // namespace accelcal::internal
