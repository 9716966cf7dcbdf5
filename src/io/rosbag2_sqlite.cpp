// ROS 2 bags in SQLite (rosbag2_sqlite.hpp).
#include "io/rosbag2_sqlite.hpp"

#include <sqlite3.h>

#include <cstring>
#include <map>
#include <memory>
#include <optional>

#include "accelcal/error.hpp"
#include "core/text_format.hpp"
#include "io/ros_topics.hpp"
#include "io/sqlite_wal.hpp"

namespace accelcal::internal {

bool IsSqlite(std::string_view first_bytes) {
  return first_bytes.size() >= 16 && std::memcmp(first_bytes.data(), "SQLite format 3\0", 16) == 0;
}

namespace {

struct Finalize {
  void operator()(sqlite3_stmt* s) const { sqlite3_finalize(s); }
};
using Statement = std::unique_ptr<sqlite3_stmt, Finalize>;

[[noreturn]] void Fail(const std::string& name, const std::string& why) {
  throw InputError(name, 0, VisibleLine(why));
}

std::string Text(sqlite3_stmt* s, int column) {
  const unsigned char* t = sqlite3_column_text(s, column);
  return t != nullptr ? std::string(reinterpret_cast<const char*>(t),
                                    static_cast<std::size_t>(sqlite3_column_bytes(s, column)))
                      : std::string();
}

}  // namespace

DecodedLog ReadRosbag2Sqlite(const std::string& path, const std::string& name,
                             const KeepStream& keep, const StoreColumns& store) {
  // Read as committed, its write-ahead log included, nothing written (sqlite_wal.hpp).
  const SqliteSnapshot snapshot(path, name);
  sqlite3* db = snapshot.db();
  const auto prepare = [&](const char* sql) {
    sqlite3_stmt* s = nullptr;
    if (sqlite3_prepare_v2(db, sql, -1, &s, nullptr) != SQLITE_OK) {
      Statement failed(s);
      return Statement();
    }
    return Statement(s);
  };
  const auto error = [&](const std::string& what) {
    Fail(name, what + " (SQLite: " + sqlite3_errmsg(db) + ")");
  };
  Statement topics = prepare("SELECT id, name, type, serialization_format FROM topics ORDER BY id");
  if (!topics) {
    error(
        "an SQLite database, but not a ROS 2 bag: it has no table topics (id, name, type, "
        "serialization_format)");
  }
  // The definitions a bag since Iron carries.
  std::map<std::string, std::pair<std::string, std::string>> definitions;  // type -> encoding, text
  if (Statement d = prepare("SELECT topic_type, encoding, encoded_message_definition FROM "
                            "message_definitions")) {
    while (sqlite3_step(d.get()) == SQLITE_ROW) {
      definitions[Text(d.get(), 0)] = {Text(d.get(), 1), Text(d.get(), 2)};
    }
  }
  DecodedLog out;
  out.offset_name = "row";
  RosTopics streams(&out, keep, store);
  std::map<sqlite3_int64, std::size_t> stream_of;  // topic id -> stream
  int rc = 0;
  while ((rc = sqlite3_step(topics.get())) == SQLITE_ROW) {
    const sqlite3_int64 id = sqlite3_column_int64(topics.get(), 0);
    const std::string topic = Text(topics.get(), 1), type = Text(topics.get(), 2),
                      format = Text(topics.get(), 3);
    std::optional<std::string> definition;
    std::string why;
    if (format != "cdr") {
      why = "its messages are serialised as " + format + ", not cdr";
    } else if (const auto d = definitions.find(type); d != definitions.end()) {
      if (d->second.first == "ros2msg") {
        definition = d->second.second;
      } else {
        why = "its definition is " + d->second.first + ", not ros2msg";
      }
    } else if (const std::string_view known = KnownRos2Definition(type); !known.empty()) {
      definition = std::string(known);
    } else {
      why =
          "the bag does not carry its definition (rosbag2 before Iron stores none), and "
          "accelcal knows only sensor_msgs/msg/Imu, Temperature and MagneticField";
    }
    std::string problem;
    stream_of[id] = streams.Add(topic, type, definition, RosVersion::kRos2, why, &problem);
    if (!problem.empty()) Fail(name, problem);
  }
  if (rc != SQLITE_DONE) error("its topics cannot be read");
  Statement messages =
      prepare("SELECT id, topic_id, timestamp, data FROM messages ORDER BY timestamp, id");
  if (!messages) error("a ROS 2 bag without its table messages (topic_id, timestamp, data)");
  while ((rc = sqlite3_step(messages.get())) == SQLITE_ROW) {
    const sqlite3_int64 row = sqlite3_column_int64(messages.get(), 0);
    const auto stream = stream_of.find(sqlite3_column_int64(messages.get(), 1));
    if (stream == stream_of.end()) {
      Fail(name, Format("row %lld of messages belongs to topic %lld, which the bag does not list",
                        static_cast<long long>(row),
                        static_cast<long long>(sqlite3_column_int64(messages.get(), 1))));
    }
    const sqlite3_int64 ns = sqlite3_column_int64(messages.get(), 2);
    const auto* data = static_cast<const unsigned char*>(sqlite3_column_blob(messages.get(), 3));
    const auto n = static_cast<std::size_t>(sqlite3_column_bytes(messages.get(), 3));
    if (const std::optional<std::string> why =
            streams.Message(stream->second, ns > 0 ? std::uint64_t(ns) / 1000 : 0,
                            data != nullptr ? data : reinterpret_cast<const unsigned char*>(""), n,
                            std::uint64_t(row))) {
      Fail(name, Format("row %lld: ", static_cast<long long>(row)) + *why);
    }
  }
  if (rc != SQLITE_DONE) error("its messages cannot be read whole");
  return out;
}

}  // namespace accelcal::internal
