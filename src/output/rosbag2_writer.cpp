// A ROS 2 SQLite bag of one IMU (rosbag2_writer.hpp).
#include "accelcal/rosbag2_writer.hpp"

#include <sqlite3.h>

#include <algorithm>
#include <stdexcept>
#include <utility>

#include "core/text_format.hpp"
#include "io/ros_message.hpp"
#include "output/ros_imu_message.hpp"

namespace accelcal {

namespace {

constexpr char kType[] = "sensor_msgs/msg/Imu";

}  // namespace

struct Rosbag2SqliteImuWriter::Impl {
  std::string path, topic, file;  // file: the name the metadata gives
  sqlite3* db = nullptr;
  sqlite3_stmt* insert = nullptr;
  std::uint64_t messages = 0, first_ns = 0, last_ns = 0;

  [[noreturn]] void Fail(const std::string& what) const {
    throw std::runtime_error(path + ": " + what + " (SQLite: " +
                             (db != nullptr ? sqlite3_errmsg(db) : "out of memory") + ")");
  }
  void Execute(const std::string& sql) const {
    if (sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr) != SQLITE_OK) {
      Fail("cannot write the bag");
    }
  }
  void Insert(std::uint64_t time_ns, const std::string& message);
  void Close() {
    sqlite3_finalize(insert);
    insert = nullptr;
    sqlite3_close(db);
    db = nullptr;
  }
};

Rosbag2SqliteImuWriter::Rosbag2SqliteImuWriter(const std::string& path, std::string topic,
                                               std::string file_name)
    : impl_(std::make_unique<Impl>()) {
  impl_->path = path;
  impl_->topic = std::move(topic);
  impl_->file = std::move(file_name);
  if (impl_->file.empty()) {
    const std::size_t slash = path.rfind('/');
    impl_->file = path.substr(slash == std::string::npos ? 0 : slash + 1);
  }
  if (sqlite3_open_v2(path.c_str(), &impl_->db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE,
                      nullptr) != SQLITE_OK) {
    const std::string why = std::string("cannot create the bag (SQLite: ") +
                            (impl_->db != nullptr ? sqlite3_errmsg(impl_->db) : "out of memory") +
                            ")";
    impl_->Close();
    throw std::runtime_error(path + ": " + why);
  }
  try {
    // No journal beside the file and no syncs of SQLite's own: the caller writes a temporary
    // file, synced and renamed once whole, so an interrupted bag is never left as the output.
    impl_->Execute(
        "PRAGMA journal_mode=OFF; PRAGMA synchronous=OFF; BEGIN;"
        "CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL);"
        "INSERT INTO schema VALUES (4, 'iron');"
        "CREATE TABLE metadata(id INTEGER PRIMARY KEY, metadata_version INTEGER NOT NULL,"
        " metadata TEXT NOT NULL);"
        "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL,"
        " serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL,"
        " type_description_hash TEXT NOT NULL);"
        "CREATE TABLE message_definitions(id INTEGER PRIMARY KEY, topic_type TEXT NOT NULL,"
        " encoding TEXT NOT NULL, encoded_message_definition TEXT NOT NULL,"
        " type_description_hash TEXT NOT NULL);"
        "CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL,"
        " timestamp INTEGER NOT NULL, data BLOB NOT NULL);"
        "CREATE INDEX timestamp_idx ON messages (timestamp ASC);");
    sqlite3_stmt* s = nullptr;
    if (sqlite3_prepare_v2(impl_->db, "INSERT INTO topics VALUES (1, ?, ?, 'cdr', '', '')", -1, &s,
                           nullptr) != SQLITE_OK) {
      impl_->Fail("cannot write the bag");
    }
    sqlite3_bind_text(s, 1, impl_->topic.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(s, 2, kType, -1, SQLITE_STATIC);
    const int topic_done = sqlite3_step(s);
    sqlite3_finalize(s);
    if (topic_done != SQLITE_DONE) impl_->Fail("cannot write the bag");
    s = nullptr;
    if (sqlite3_prepare_v2(impl_->db,
                           "INSERT INTO message_definitions VALUES (1, ?, 'ros2msg', ?, '')", -1,
                           &s, nullptr) != SQLITE_OK) {
      impl_->Fail("cannot write the bag");
    }
    const std::string_view definition = internal::KnownRos2Definition(kType);
    sqlite3_bind_text(s, 1, kType, -1, SQLITE_STATIC);
    sqlite3_bind_text(s, 2, definition.data(), static_cast<int>(definition.size()), SQLITE_STATIC);
    const int definition_done = sqlite3_step(s);
    sqlite3_finalize(s);
    if (definition_done != SQLITE_DONE) impl_->Fail("cannot write the bag");
    if (sqlite3_prepare_v2(impl_->db,
                           "INSERT INTO messages (topic_id, timestamp, data) VALUES (1, ?, ?)", -1,
                           &impl_->insert, nullptr) != SQLITE_OK) {
      impl_->Fail("cannot write the bag");
    }
  } catch (...) {
    impl_->Close();
    throw;
  }
}

Rosbag2SqliteImuWriter::~Rosbag2SqliteImuWriter() { impl_->Close(); }

void Rosbag2SqliteImuWriter::Sample(std::uint64_t time_ns, const Vec3& accel, const Vec3& gyro) {
  impl_->Insert(time_ns, internal::Ros2ImuMessage(time_ns, accel, &gyro));
}

void Rosbag2SqliteImuWriter::Sample(std::uint64_t time_ns, const Vec3& accel) {
  impl_->Insert(time_ns, internal::Ros2ImuMessage(time_ns, accel, nullptr));
}

void Rosbag2SqliteImuWriter::Impl::Insert(std::uint64_t time_ns, const std::string& message) {
  if (db == nullptr) throw std::logic_error("Rosbag2SqliteImuWriter: a sample after Finish");
  sqlite3_stmt* s = insert;
  sqlite3_reset(s);
  sqlite3_bind_int64(s, 1, static_cast<sqlite3_int64>(time_ns));
  sqlite3_bind_blob(s, 2, message.data(), static_cast<int>(message.size()), SQLITE_STATIC);
  if (sqlite3_step(s) != SQLITE_DONE) Fail("cannot write a message");
  if (messages == 0) first_ns = time_ns;
  first_ns = std::min(first_ns, time_ns);
  last_ns = std::max(last_ns, time_ns);
  ++messages;
}

void Rosbag2SqliteImuWriter::Finish() {
  if (impl_->db == nullptr) throw std::logic_error("Rosbag2SqliteImuWriter: Finish twice");
  // Names as YAML double-quoted scalars: any file or topic name reads back as itself.
  const auto quoted = [](const std::string& text) {
    return "\"" + internal::EscapeText(text, internal::Escaping::kYamlDoubleQuoted) + "\"";
  };
  const std::string file = quoted(impl_->file), topic = quoted(impl_->topic);
  const unsigned long long n = impl_->messages;
  const unsigned long long start = n > 0 ? impl_->first_ns : 0;
  const unsigned long long duration = n > 0 ? impl_->last_ns - impl_->first_ns : 0;
  // rosbag2's metadata.yaml (version 8), as it stores it in the database too.
  const std::string metadata = internal::Format(
      "rosbag2_bagfile_information:\n"
      "  version: 8\n"
      "  storage_identifier: sqlite3\n"
      "  duration:\n"
      "    nanoseconds: %llu\n"
      "  starting_time:\n"
      "    nanoseconds_since_epoch: %llu\n"
      "  message_count: %llu\n"
      "  topics_with_message_count:\n"
      "    - topic_metadata:\n"
      "        name: %s\n"
      "        type: %s\n"
      "        serialization_format: cdr\n"
      "        offered_qos_profiles: \"\"\n"
      "        type_description_hash: \"\"\n"
      "      message_count: %llu\n"
      "  compression_format: \"\"\n"
      "  compression_mode: \"\"\n"
      "  relative_file_paths:\n"
      "    - %s\n"
      "  files:\n"
      "    - path: %s\n"
      "      starting_time:\n"
      "        nanoseconds_since_epoch: %llu\n"
      "      duration:\n"
      "        nanoseconds: %llu\n"
      "      message_count: %llu\n"
      "  custom_data: ~\n"
      "  ros_distro: iron\n",
      duration, start, n, topic.c_str(), kType, n, file.c_str(), file.c_str(), start, duration, n);
  sqlite3_stmt* s = nullptr;
  if (sqlite3_prepare_v2(impl_->db, "INSERT INTO metadata VALUES (1, 8, ?)", -1, &s, nullptr) !=
      SQLITE_OK) {
    impl_->Fail("cannot write the bag's metadata");
  }
  sqlite3_bind_text(s, 1, metadata.c_str(), -1, SQLITE_TRANSIENT);
  const int done = sqlite3_step(s);
  sqlite3_finalize(s);
  if (done != SQLITE_DONE) impl_->Fail("cannot write the bag's metadata");
  impl_->Execute("COMMIT;");
  sqlite3_finalize(impl_->insert);
  impl_->insert = nullptr;
  if (sqlite3_close(impl_->db) != SQLITE_OK) impl_->Fail("cannot close the bag");
  impl_->db = nullptr;
}

}  // namespace accelcal
