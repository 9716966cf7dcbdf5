#pragma once
// An SQLite database read as it is committed, its write-ahead log included, with nothing written
// anywhere: what a recorder killed in WAL mode leaves (rosbag2's resilient preset: FILE and
// FILE-wal, the last transactions only in the log) reads as the checkpoint SQLite would make.
//
// SQLite itself cannot do this: opened immutable it ignores the log, and opened read-only it
// writes the shared-memory index beside the user's file (FILE-shm, created or rewritten; with
// locking_mode=EXCLUSIVE a read-only connection fails with a disk I/O error). So the log is read
// here (its frames' salts and checksums checked as SQLite checks them, every page of its last
// committed transaction kept) and served to SQLite through a VFS of its own over the immutable
// database: each page SQLite reads comes from the log's last committed frame of it, else from the
// file. The VFS opens the database only: no journal, no -shm, and no temporary file (a sort or
// temporary table larger than the connection's page cache fails instead of spilling to disk).

#include <cstdint>
#include <memory>
#include <string>
#include <unordered_map>

struct sqlite3;

namespace accelcal::internal {

/// The committed frames of the write-ahead log `path` + "-wal".
struct SqliteWal {
  std::string path;                  ///< the log's file
  int fd = -1;                       ///< open for reading while frames are served
  std::uint32_t page_bytes = 0;      ///< the log's page size
  std::uint64_t database_pages = 0;  ///< the database's size once checkpointed; 0: nothing to apply
  std::unordered_map<std::uint32_t, std::uint64_t> frame_of;  ///< page -> its data's offset
  std::uint64_t frames = 0;  ///< committed frames (pages of every transaction) in the log
  ~SqliteWal();
};

/// Reads the log beside the database `path` (absent or empty: nothing to apply). Throws
/// InputError naming `name` when the log is there but cannot be read or is not SQLite's (a
/// header without its magic, its version or a page size; a page size that is not the
/// database's). Frames after the last commit (a transaction the recorder never finished) and
/// frames whose salt or checksum does not follow (left from before the log was restarted) are
/// not applied, as SQLite does not apply them.
std::unique_ptr<SqliteWal> ReadSqliteWal(const std::string& path, const std::string& name);

/// An open database, read-only, its log's pages served over the file's (see above).
class SqliteSnapshot {
 public:
  /// Opens `path` (named `name` in errors). Throws InputError when it cannot be opened.
  SqliteSnapshot(const std::string& path, const std::string& name);
  ~SqliteSnapshot();
  SqliteSnapshot(const SqliteSnapshot&) = delete;
  SqliteSnapshot& operator=(const SqliteSnapshot&) = delete;
  sqlite3* db() const { return db_; }
  /// The committed frames of the log applied (0: none; the database's file alone).
  std::uint64_t wal_frames() const { return wal_ ? wal_->frames : 0; }
  struct Vfs;  ///< the file system SQLite reads it through (sqlite_wal.cpp)

 private:
  std::unique_ptr<SqliteWal> wal_;
  std::unique_ptr<Vfs> vfs_;
  sqlite3* db_ = nullptr;
};

}  // namespace accelcal::internal
