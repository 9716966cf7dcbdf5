#pragma once
// The topics of a ROS recording as streams (rosbag.cpp, mcap.cpp): a topic becomes a stream at
// its first connection (a ROS 1 bag) or channel (MCAP), with the type its definition describes;
// its messages are counted, and decoded when the stream is kept. One piece for every ROS format.

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "io/decoded_log.hpp"
#include "io/ros_message.hpp"

namespace accelcal::internal {

class RosTopics {
 public:
  RosTopics(DecodedLog* out, const KeepStream& keep, const StoreColumns& store)
      : out_(out), keep_(keep), store_(store) {}

  /// The stream of `topic`, whose messages are of `type` as `definition` defines it (in
  /// `version`'s syntax); nullopt definition: a type accelcal cannot decode, for `why` (its
  /// messages are counted; keeping the stream is an error). Returns the stream's index, or the
  /// reason in `*error` when the topic had another type.
  std::size_t Add(const std::string& topic, const std::string& type,
                  const std::optional<std::string>& definition, RosVersion version,
                  const std::string& why, std::string* error);

  /// One message of stream `stream`, recorded at `time_us`, its bytes `data` (n), at byte `at`
  /// of the file. Returns the reason when it does not decode.
  std::optional<std::string> Message(std::size_t stream, std::uint64_t time_us,
                                     const unsigned char* data, std::size_t n, std::uint64_t at);

 private:
  DecodedLog* out_;
  const KeepStream& keep_;
  const StoreColumns& store_;
  std::map<std::string, std::size_t> stream_of_;              // topic -> stream
  std::vector<std::shared_ptr<const RosMessageType>> types_;  // per stream (null: undecodable)
  std::vector<std::string> type_names_;
  // Types parsed, by name, version and definition (a file repeats them).
  std::map<std::tuple<std::string, int, std::string>, std::shared_ptr<const RosMessageType>>
      parsed_;
  std::vector<double> scratch_;
};

}  // namespace accelcal::internal
