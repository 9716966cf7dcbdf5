// ROS topics as streams (ros_topics.hpp).
#include "io/ros_topics.hpp"

#include <tuple>

#include "accelcal/error.hpp"

namespace accelcal::internal {

std::size_t RosTopics::Add(const std::string& topic, const std::string& type,
                           const std::optional<std::string>& definition, RosVersion version,
                           const std::string& why, std::string* error) {
  auto [it, added] = stream_of_.emplace(topic, out_->streams.size());
  if (!added) {
    // Another publisher of the topic: it must publish the same type.
    if (type_names_[it->second] != type) {
      *error =
          "the topic " + topic + " is published as " + type_names_[it->second] + " and as " + type;
    }
    return it->second;
  }
  std::shared_ptr<const RosMessageType> parsed;
  std::string unreadable = why;
  if (definition) {
    std::shared_ptr<const RosMessageType>& known =
        parsed_[std::make_tuple(type, static_cast<int>(version), *definition)];
    if (!known) {
      try {
        known = std::make_shared<const RosMessageType>(type, *definition, version);
      } catch (const DataError& e) {
        unreadable = std::string("its definition does not parse: ") + e.what();
      }
    }
    parsed = known;
  }
  DecodedStream s;
  s.topic = topic;
  s.type = type;
  s.columns = parsed ? parsed->columns() : std::make_shared<const std::vector<std::string>>();
  s.kept = keep_(s);
  if (s.kept && !parsed) {
    *error = "accelcal cannot decode the topic " + topic + " (" + type + "): " + unreadable;
  }
  if (s.kept) {
    if (store_) {
      s.stored = store_(s);
      for (std::size_t col : s.stored) {
        if (col >= s.columns->size()) *error = "internal: a stored column beyond the type's";
      }
    } else {
      for (std::size_t col = 0; col < s.columns->size(); ++col) s.stored.push_back(col);
    }
  }
  out_->streams.push_back(std::move(s));
  types_.push_back(parsed);
  type_names_.push_back(type);
  return it->second;
}

std::optional<std::string> RosTopics::Message(std::size_t stream, std::uint64_t time_us,
                                              const unsigned char* data, std::size_t n,
                                              std::uint64_t at) {
  DecodedStream& s = out_->streams[stream];
  if (s.messages == 0) s.first_us = time_us;
  s.last_us = time_us;
  ++s.messages;
  if (!s.kept) return std::nullopt;
  const RosMessageType& type = *types_[stream];
  scratch_.resize(s.columns->size());
  if (const std::optional<std::string> why = type.Decode(data, n, scratch_.data())) {
    return "a message of " + s.topic + " (" + s.type + "): " + *why;
  }
  for (std::size_t col : s.stored) s.values.push_back(scratch_[col]);
  s.offset.push_back(at);
  return std::nullopt;
}

}  // namespace accelcal::internal
