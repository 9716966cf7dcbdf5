#pragma once
// The topics of a ROS recording as streams (rosbag.cpp, mcap.cpp): a topic becomes a stream at
// its first connection (a ROS 1 bag) or channel (MCAP), with the type its definition describes;
// its messages are counted, and decoded when the stream is kept. One piece for every ROS format.
// A stream's columns are its type's numeric fields, then `log_time`: the time the recorder logged
// the message (a ROS 1 record's time, MCAP's log_time, rosbag2's timestamp), in µs.

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "io/decoded_log.hpp"
#include "io/ros_message.hpp"

namespace accelcal::internal {

/// The column of the time a message was logged.
inline constexpr char kLogTime[] = "log_time";

class RosTopics {
 public:
  RosTopics(DecodedLog* out, const KeepStream& keep, const StoreColumns& store)
      : out_(out), keep_(keep), store_(store) {}

  /// The stream of `topic`, whose messages are of `type` as `definition` defines it (in
  /// `version`'s syntax); nullopt definition: a type accelcal cannot decode, for `why` (its
  /// messages are counted; keeping the stream is an error). Returns the stream's index, or the
  /// reason in `*error` when the topic had another type.
  /// `publisher`: the connection's publisher (a ROS 1 callerid; empty when the format has none).
  /// A topic published with two types or two definitions, or by two publishers, is an error when
  /// its stream is kept (its messages would be decoded by another's layout, or mixed); a
  /// definition that would make the log's definitions or columns exceed their bounds too.
  std::size_t Add(const std::string& topic, const std::string& type,
                  const std::optional<std::string>& definition, RosVersion version,
                  const std::string& why, std::string* error,
                  const std::string& publisher = std::string());

  /// One message of stream `stream`, recorded at `time_us` (its column `log_time`), its bytes
  /// `data` (n), at byte `at` of the file. Returns the reason when it does not decode.
  std::optional<std::string> Message(std::size_t stream, std::uint64_t time_us,
                                     const unsigned char* data, std::size_t n, std::uint64_t at);

 private:
  DecodedLog* out_;
  const KeepStream& keep_;
  const StoreColumns& store_;
  std::map<std::string, std::size_t> stream_of_;  // topic -> stream
  // Per stream: its type (null: undecodable), its type's name, its definition's SHA-256, its
  // first publisher.
  std::vector<std::shared_ptr<const RosMessageType>> types_;
  std::vector<std::string> type_names_, definition_digests_, publishers_;
  // Types parsed, by name, version and their definition's SHA-256 (a file repeats them).
  std::map<std::tuple<std::string, int, std::string>, std::shared_ptr<const RosMessageType>>
      parsed_;
  // A parsed type's columns as streams have them: its fields, then `log_time` (the time the
  // recorder logged each message); and those given in µs.
  struct Layout {
    std::shared_ptr<const std::vector<std::string>> columns;
    std::shared_ptr<const std::vector<std::size_t>> microseconds;
  };
  std::map<const RosMessageType*, Layout> layouts_;
  std::size_t definition_bytes_ = 0;  // parsed, in all
  std::size_t columns_ = 0;           // of every stream, in all
  std::vector<double> scratch_;
};

}  // namespace accelcal::internal
