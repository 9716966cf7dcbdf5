#pragma once
// ROS 2 bags stored in SQLite (rosbag2's sqlite3 storage, `.db3`; ROS 2's default before Iron),
// read with libsqlite3, the database's own library: the table `topics` (id, name, type,
// serialization_format) and `messages` (topic_id, timestamp [ns], data: a CDR message), with the
// message definitions in `message_definitions` (rosbag2 since Iron) or, for an older bag that has
// none, accelcal's own of the sensor types (sensor_msgs/msg/Imu, Temperature, MagneticField).

#include <string>
#include <string_view>

#include "io/decoded_log.hpp"

namespace accelcal::internal {

/// A file that begins as an SQLite 3 database ("SQLite format 3" and a NUL).
bool IsSqlite(std::string_view first_bytes);

/// Reads the ROS 2 bag at `path` (named `name` in messages) as committed, its write-ahead log
/// included, with nothing written in or beside it (sqlite_wal.hpp), decoding the messages of the
/// topics `keep` accepts, in the order of their time. A stream is a topic (instance 0), its time
/// [µs] the messages' timestamps; a message's offset is its row id (DecodedLog::offset_name).
/// Throws InputError naming the file for a database that cannot be read or is not a rosbag2 bag,
/// and naming the row for a message that does not decode. Only tables are read, each checked first:
/// a `topics`, `messages` or `message_definitions` that is a view, a virtual table, or has a
/// generated column is refused, and so is a query that runs 2^27 steps without a row.
DecodedLog ReadRosbag2Sqlite(const std::string& path, const std::string& name,
                             const KeepStream& keep, const StoreColumns& store = {});

}  // namespace accelcal::internal
