// ROS topics as streams (ros_topics.hpp).
#include "io/ros_topics.hpp"

#include <tuple>

#include "accelcal/error.hpp"
#include "accelcal/sha256.hpp"
#include "core/text_format.hpp"

namespace accelcal::internal {

namespace {
// A log's message definitions are read up to this many bytes in all (a real log's are kilobytes):
// past it, a small compressed file could take minutes to parse.
constexpr std::size_t kMaxDefinitionBytes = std::size_t{64} << 20;
// A log's topics are read up to this many (a robot's recording has hundreds): each stream costs
// about a kilobyte, and a small compressed file can name millions (800 MB for a 3 MB bz2 bag).
constexpr std::size_t kMaxTopics = std::size_t{1} << 16;
}  // namespace

std::size_t RosTopics::Add(const std::string& topic, const std::string& type,
                           const std::optional<std::string>& definition, RosVersion version,
                           const std::string& why, std::string* error,
                           const std::string& publisher) {
  const std::string digest = definition ? Sha256Hex(*definition) : std::string();
  auto [it, added] = stream_of_.emplace(topic, out_->streams.size());
  if (!added) {
    const std::size_t s = it->second;
    // Another connection of the topic: the same type, defined the same, from the same publisher,
    // else its stream cannot be read as one.
    std::string conflict;
    if (type_names_[s] != type) {
      conflict = "is published as " + type_names_[s] + " and as " + type;
    } else if (definition_digests_[s] != digest) {
      conflict = "is published with two different definitions of " + type;
    } else if (!publisher.empty() && !publishers_[s].empty() && publisher != publishers_[s]) {
      conflict = "has two publishers, " + publishers_[s] + " and " + publisher +
                 ", whose messages would be mixed in one stream";
    }
    if (!conflict.empty() && out_->streams[s].kept) {
      *error = "the topic " + topic + " " + conflict + ": record one publisher of one type";
    }
    return s;
  }
  if (out_->streams.size() == kMaxTopics) {
    stream_of_.erase(it);
    *error = Format("a log of more than %zu topics: no recording has that many", kMaxTopics);
    return 0;
  }
  std::shared_ptr<const RosMessageType> parsed;
  std::string unreadable = why;
  if (definition) {
    std::shared_ptr<const RosMessageType>& known =
        parsed_[std::make_tuple(type, static_cast<int>(version), digest)];
    if (!known) {
      definition_bytes_ += definition->size();
      if (definition_bytes_ > kMaxDefinitionBytes) {
        *error = Format("the log's message definitions hold more than %zu MiB",
                        kMaxDefinitionBytes >> 20);
        return 0;
      }
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
  if (parsed) {
    Layout& layout = layouts_[parsed.get()];
    if (!layout.columns) {
      auto columns = std::make_shared<std::vector<std::string>>(*parsed->columns());
      auto microseconds = std::make_shared<std::vector<std::size_t>>(parsed->microseconds());
      microseconds->push_back(columns->size());
      columns->push_back(kLogTime);
      layout = {std::move(columns), std::move(microseconds)};
    }
    s.columns = layout.columns;
    s.microseconds = layout.microseconds;
  } else {
    s.columns = std::make_shared<const std::vector<std::string>>();
    s.unreadable = unreadable.empty() ? "its type is not known" : unreadable;
  }
  columns_ += s.columns->size();
  if (columns_ > kMaxLogColumns) {
    *error = Format("the log's topics have more than %zu numeric fields in all", kMaxLogColumns);
    return 0;
  }
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
  definition_digests_.push_back(digest);
  publishers_.push_back(publisher);
  return it->second;
}

std::optional<std::string> RosTopics::Message(std::size_t stream, std::uint64_t time_us,
                                              const unsigned char* data, std::size_t n,
                                              std::uint64_t at) {
  DecodedStream& s = out_->streams[stream];
  // Every message's frame: two sensors published on one topic differ by it alone.
  std::optional<std::size_t> frame;
  if (types_[stream] != nullptr) {
    if (const std::optional<std::string> id = types_[stream]->FrameId(data, n)) {
      if (s.messages == 0) s.frame_id = id;
      for (std::size_t k = 0; k < s.frames.size() && !frame; ++k) {
        if (s.frames[k].first == *id) frame = k;
      }
      if (!frame && s.frames.size() < kMaxFrames) {
        frame = s.frames.size();
        s.frames.emplace_back(*id, 0);
      }
      if (frame) {
        ++s.frames[*frame].second;
      } else if (s.kept) {
        return Format(
            "%s names more than %zu frame ids (header.frame_id): no recording publishes "
            "that many sensors on one topic",
            VisibleLine(s.topic).c_str(), kMaxFrames);
      }
    }
  }
  if (s.messages == 0) s.first_us = time_us;
  s.last_us = time_us;
  ++s.messages;
  if (!s.kept) return std::nullopt;
  const RosMessageType& type = *types_[stream];
  scratch_.resize(s.columns->size());
  if (const std::optional<std::string> why = type.Decode(data, n, scratch_.data())) {
    return "a message of " + s.topic + " (" + s.type + "): " + *why;
  }
  scratch_.back() = static_cast<double>(time_us);  // log_time
  for (std::size_t col : s.stored) s.values.push_back(scratch_[col]);
  s.offset.push_back(at);
  if (frame) s.frame_of.push_back(static_cast<std::uint32_t>(*frame));
  return std::nullopt;
}

}  // namespace accelcal::internal
