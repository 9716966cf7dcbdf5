// ROS 2 bags in SQLite (rosbag2_sqlite.hpp).
#include "io/rosbag2_sqlite.hpp"

#include <sqlite3.h>

#include <algorithm>
#include <cstring>
#include <initializer_list>
#include <map>
#include <memory>
#include <optional>
#include <vector>

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

std::string Lower(std::string text) {
  for (char& c : text) c = AsciiLower(c);
  return text;
}

std::string Text(sqlite3_stmt* s, int column) {
  const unsigned char* t = sqlite3_column_text(s, column);
  return t != nullptr ? std::string(reinterpret_cast<const char*>(t),
                                    static_cast<std::size_t>(sqlite3_column_bytes(s, column)))
                      : std::string();
}

// The virtual machine's steps a statement may take between two rows it returns (checked every
// 1024): a scan of a real table or index returns a row every few dozen, so this is seconds of
// work that produced nothing, which no bag's query needs.
constexpr long long kStepsPerRow = 1LL << 27;
constexpr int kStepsPerCheck = 1024;

// A statement's rows under the budget above.
class Query {
 public:
  Query(sqlite3* db, const std::string& name, const char* sql) : db_(db), name_(name) {
    sqlite3_stmt* s = nullptr;
    if (sqlite3_prepare_v2(db, sql, -1, &s, nullptr) == SQLITE_OK)
      statement_.reset(s);
    else
      sqlite3_finalize(s);
  }
  explicit operator bool() const { return statement_ != nullptr; }
  sqlite3_stmt* get() const { return statement_.get(); }
  // The next row: false after the last; a statement that fails or runs past its budget is an
  // error naming `what`.
  bool Next(const char* what) {
    left_ = kStepsPerRow / kStepsPerCheck;
    sqlite3_progress_handler(db_, kStepsPerCheck, &Query::Progress, &left_);
    const int rc = sqlite3_step(statement_.get());
    sqlite3_progress_handler(db_, 0, nullptr, nullptr);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    if (rc == SQLITE_INTERRUPT && left_ <= 0) {
      Fail(name_, Format("%s: SQLite ran %lld steps without a row (a query that would not end)",
                         what, kStepsPerRow));
    }
    if (rc == SQLITE_CANTOPEN) {
      // The VFS opens no temporary file (sqlite_wal.hpp): a sort or table past the cache.
      Fail(name_, std::string(what) +
                      ": SQLite needed a temporary file beyond its 32 MiB of memory, which "
                      "accelcal does not make");
    }
    Fail(name_, std::string(what) + " (SQLite: " + sqlite3_errmsg(db_) + ")");
  }
  void Reset() { sqlite3_reset(statement_.get()); }

 private:
  static int Progress(void* left) { return --*static_cast<long long*>(left) <= 0 ? 1 : 0; }
  sqlite3* db_;
  const std::string& name_;
  Statement statement_;
  long long left_ = 0;
};

// A table of the bag: `table` must be an ordinary table of the file (a view, a virtual table or
// a table without row ids is refused: a view's query, however long, would run on every read),
// and hold `columns`, none of them computed (a generated column runs its expression on every
// row). Returns false when the file has no such object.
bool CheckTable(sqlite3* db, const std::string& name, const char* table,
                std::initializer_list<const char*> columns) {
  Query object(db, name, "SELECT type, sql FROM sqlite_master WHERE name = ?1 COLLATE NOCASE");
  if (!object)
    Fail(name, std::string("its schema cannot be read (SQLite: ") + sqlite3_errmsg(db) + ")");
  sqlite3_bind_text(object.get(), 1, table, -1, SQLITE_STATIC);
  if (!object.Next("its schema cannot be read")) return false;
  const std::string type = Text(object.get(), 0), sql = Text(object.get(), 1);
  // SQLite writes a table's statement as "CREATE TABLE " and the rest as it was given.
  const std::string statement = Lower(sql);
  if (type != "table" || statement.rfind("create table ", 0) != 0 ||
      statement.find("without rowid") != std::string::npos) {
    Fail(name, Format("an SQLite database whose %s is a %s, not a table as rosbag2 writes: "
                      "accelcal reads tables only",
                      table,
                      type == "table" ? "virtual table or a table without row ids" : type.c_str()));
  }
  Query info(db, name, "SELECT name, hidden FROM pragma_table_xinfo(?1)");
  if (!info)
    Fail(name, std::string("its schema cannot be read (SQLite: ") + sqlite3_errmsg(db) + ")");
  sqlite3_bind_text(info.get(), 1, table, -1, SQLITE_STATIC);
  std::map<std::string, int> hidden;  // column (lower case) -> 0, or how it is computed
  while (info.Next("its schema cannot be read")) {
    hidden[Lower(Text(info.get(), 0))] = sqlite3_column_int(info.get(), 1);
  }
  for (const char* column : columns) {
    const auto c = hidden.find(column);
    if (c == hidden.end()) {
      Fail(name, Format("an SQLite database whose table %s has no column %s: not a ROS 2 bag",
                        table, column));
    }
    if (c->second != 0) {
      Fail(name, Format("an SQLite database whose column %s of %s is computed, not stored (a "
                        "generated column): not a ROS 2 bag as rosbag2 writes it",
                        column, table));
    }
  }
  return true;
}

// Whether SQLite would sort the rows of `sql` itself (its plan uses a temporary B-tree).
bool NeedsSort(sqlite3* db, const std::string& name, const char* sql) {
  const std::string explain = std::string("EXPLAIN QUERY PLAN ") + sql;
  Query plan(db, name, explain.c_str());
  if (!plan)
    Fail(name, std::string("its messages cannot be read (SQLite: ") + sqlite3_errmsg(db) + ")");
  bool sorts = false;
  while (plan.Next("its messages cannot be read")) {
    sorts = sorts || Text(plan.get(), 3).find("TEMP B-TREE") != std::string::npos;
  }
  return sorts;
}

}  // namespace

DecodedLog ReadRosbag2Sqlite(const std::string& path, const std::string& name,
                             const KeepStream& keep, const StoreColumns& store) {
  const SqliteSnapshot snapshot(path, name);
  sqlite3* db = snapshot.db();
  // Every table read is checked first: nothing of the file's schema runs but its tables.
  if (!CheckTable(db, name, "topics", {"id", "name", "type", "serialization_format"})) {
    Fail(name,
         "an SQLite database, but not a ROS 2 bag: it has no table topics (id, name, type, "
         "serialization_format)");
  }
  if (!CheckTable(db, name, "messages", {"id", "topic_id", "timestamp", "data"})) {
    Fail(name, "a ROS 2 bag without its table messages (topic_id, timestamp, data)");
  }
  const bool has_definitions = CheckTable(db, name, "message_definitions",
                                          {"topic_type", "encoding", "encoded_message_definition"});
  Query topics(db, name, "SELECT id, name, type, serialization_format FROM topics ORDER BY id");
  if (!topics)
    Fail(name, std::string("its topics cannot be read (SQLite: ") + sqlite3_errmsg(db) + ")");
  // The definitions a bag since Iron carries.
  std::map<std::string, std::pair<std::string, std::string>> definitions;  // type -> encoding, text
  if (has_definitions) {
    Query d(db, name,
            "SELECT topic_type, encoding, encoded_message_definition FROM message_definitions");
    if (!d)
      Fail(name, std::string("its message definitions cannot be read (SQLite: ") +
                     sqlite3_errmsg(db) + ")");
    while (d.Next("its message definitions cannot be read")) {
      definitions[Text(d.get(), 0)] = {Text(d.get(), 1), Text(d.get(), 2)};
    }
  }
  DecodedLog out;
  out.offset_name = "row";
  RosTopics streams(&out, keep, store);
  std::map<sqlite3_int64, std::size_t> stream_of;  // topic id -> stream
  while (topics.Next("its topics cannot be read")) {
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
  // The messages in the order of their time: through rosbag2's index of the timestamps, which
  // a bag has. Without it, SQLite would sort the rows, their data with them, in temporary files
  // (or, as the VFS opens none, fail past its cache): so the times and ids are read and sorted
  // here (24 bytes a message), and each message then fetched by its row id.
  constexpr char kOrdered[] =
      "SELECT id, topic_id, timestamp, data FROM messages ORDER BY timestamp, id";
  const auto message = [&](sqlite3_stmt* m) {
    const sqlite3_int64 row = sqlite3_column_int64(m, 0);
    const auto stream = stream_of.find(sqlite3_column_int64(m, 1));
    if (stream == stream_of.end()) {
      Fail(name,
           Format("row %lld of messages belongs to topic %lld, which the bag does not list",
                  static_cast<long long>(row), static_cast<long long>(sqlite3_column_int64(m, 1))));
    }
    const sqlite3_int64 ns = sqlite3_column_int64(m, 2);
    const auto* data = static_cast<const unsigned char*>(sqlite3_column_blob(m, 3));
    const auto n = static_cast<std::size_t>(sqlite3_column_bytes(m, 3));
    if (const std::optional<std::string> why =
            streams.Message(stream->second, ns > 0 ? std::uint64_t(ns) / 1000 : 0,
                            data != nullptr ? data : reinterpret_cast<const unsigned char*>(""), n,
                            std::uint64_t(row))) {
      Fail(name, Format("row %lld: ", static_cast<long long>(row)) + *why);
    }
  };
  constexpr char kWhat[] = "its messages cannot be read whole";
  if (!NeedsSort(db, name, kOrdered)) {
    Query messages(db, name, kOrdered);
    if (!messages) Fail(name, std::string(kWhat) + " (SQLite: " + sqlite3_errmsg(db) + ")");
    while (messages.Next(kWhat)) message(messages.get());
    return out;
  }
  struct Key {
    sqlite3_int64 ns, id, row;
  };
  std::vector<Key> keys;
  {
    Query all(db, name, "SELECT timestamp, id, rowid FROM messages");
    if (!all) Fail(name, std::string(kWhat) + " (SQLite: " + sqlite3_errmsg(db) + ")");
    while (all.Next(kWhat)) {
      keys.push_back({sqlite3_column_int64(all.get(), 0), sqlite3_column_int64(all.get(), 1),
                      sqlite3_column_int64(all.get(), 2)});
    }
  }
  std::sort(keys.begin(), keys.end(),
            [](const Key& a, const Key& b) { return a.ns != b.ns ? a.ns < b.ns : a.id < b.id; });
  Query one(db, name, "SELECT id, topic_id, timestamp, data FROM messages WHERE rowid = ?1");
  if (!one) Fail(name, std::string(kWhat) + " (SQLite: " + sqlite3_errmsg(db) + ")");
  for (const Key& k : keys) {
    one.Reset();
    sqlite3_bind_int64(one.get(), 1, k.row);
    if (!one.Next(kWhat))
      Fail(name, Format("row %lld of messages is gone", static_cast<long long>(k.id)));
    message(one.get());
  }
  return out;
}

}  // namespace accelcal::internal
