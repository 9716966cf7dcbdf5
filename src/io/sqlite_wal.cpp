// An SQLite database and its write-ahead log, read as committed, nothing written (sqlite_wal.hpp).
#include "io/sqlite_wal.hpp"

#include <fcntl.h>
#include <sqlite3.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <vector>

#include "accelcal/error.hpp"
#include "core/text_format.hpp"

namespace accelcal::internal {

namespace {

// The log's format (SQLite's "Database File Format", section 4: the write-ahead log).
constexpr std::uint32_t kWalMagic = 0x377f0682;  // | 1: checksums of big-endian words
constexpr std::uint32_t kWalVersion = 3007000;
constexpr std::size_t kWalHeaderBytes = 32, kFrameHeaderBytes = 24;
// What the connection may keep in memory of its pages and temporary tables and sorts (the VFS
// opens no temporary file, so this bounds them): negative means KiB.
constexpr char kCacheSize[] = "PRAGMA cache_size = -32768";  // 32 MiB

std::uint32_t Big32(const unsigned char* p) {
  return std::uint32_t{p[0]} << 24 | std::uint32_t{p[1]} << 16 | std::uint32_t{p[2]} << 8 | p[3];
}

// SQLite's checksum of `n` bytes (a multiple of 8) continuing `sum`: its 32-bit words in the
// byte order the log's magic says.
void Checksum(bool big_endian_words, const unsigned char* p, std::size_t n, std::uint32_t sum[2]) {
  std::uint32_t s1 = sum[0], s2 = sum[1];
  for (std::size_t i = 0; i + 8 <= n; i += 8) {
    std::uint32_t a, b;
    if (big_endian_words) {
      a = Big32(p + i);
      b = Big32(p + i + 4);
    } else {
      std::memcpy(&a, p + i, 4);
      std::memcpy(&b, p + i + 4, 4);
    }
    s1 += a + s2;
    s2 += b + s1;
  }
  sum[0] = s1;
  sum[1] = s2;
}

[[noreturn]] void Fail(const std::string& name, const std::string& why) {
  throw InputError(name, 0, VisibleLine(why));
}

// The page size the database's header states (0: a file too short to have a header).
std::uint32_t DatabasePageBytes(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return 0;
  unsigned char header[18];
  const ssize_t n = ::pread(fd, header, sizeof header, 0);
  ::close(fd);
  if (n != static_cast<ssize_t>(sizeof header)) return 0;
  const std::uint32_t size = std::uint32_t{header[16]} << 8 | header[17];
  return size == 1 ? 65536 : size;
}

}  // namespace

SqliteWal::~SqliteWal() {
  if (fd >= 0) ::close(fd);
}

std::unique_ptr<SqliteWal> ReadSqliteWal(const std::string& path, const std::string& name) {
  auto wal = std::make_unique<SqliteWal>();
  wal->path = path + "-wal";
  wal->fd = ::open(wal->path.c_str(), O_RDONLY | O_CLOEXEC);
  if (wal->fd < 0) {
    if (errno == ENOENT) return wal;  // no log: the file is the database
    Fail(name,
         "its write-ahead log " + wal->path + " cannot be opened (" + std::strerror(errno) + ")");
  }
  struct stat st {};
  if (::fstat(wal->fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    Fail(name, "its write-ahead log " + wal->path + " is not a regular file");
  }
  const auto size = static_cast<std::uint64_t>(st.st_size);
  if (size == 0) return wal;  // emptied by a checkpoint: the file is the database
  unsigned char header[kWalHeaderBytes];
  if (size < kWalHeaderBytes ||
      ::pread(wal->fd, header, sizeof header, 0) != static_cast<ssize_t>(sizeof header)) {
    Fail(name, Format("its write-ahead log %s has %llu bytes, less than its header's 32",
                      wal->path.c_str(), static_cast<unsigned long long>(size)));
  }
  const std::uint32_t magic = Big32(header), page = Big32(header + 8);
  const bool big_endian_words = (magic & 1) != 0;
  std::uint32_t sum[2] = {0, 0};
  Checksum(big_endian_words, header, 24, sum);
  if ((magic & ~1u) != kWalMagic || Big32(header + 4) != kWalVersion || page < 512 ||
      page > 65536 || (page & (page - 1)) != 0 || sum[0] != Big32(header + 24) ||
      sum[1] != Big32(header + 28)) {
    Fail(name, "its write-ahead log " + wal->path +
                   " is not one SQLite wrote (its header's magic, version, page size or "
                   "checksum)");
  }
  const std::uint32_t database_page = DatabasePageBytes(path);
  if (database_page != 0 && database_page != page) {
    Fail(name, Format("its write-ahead log %s has pages of %u bytes, the database %u",
                      wal->path.c_str(), page, database_page));
  }
  wal->page_bytes = page;
  // The frames in order: each continues the checksum of those before it, and a frame that does
  // not (or has another salt: left from before the log restarted) ends the log. A commit frame
  // (the database's size after it, not 0) makes its transaction's pages the database's.
  std::vector<unsigned char> frame(kFrameHeaderBytes + page);
  std::unordered_map<std::uint32_t, std::uint64_t> pending;
  std::uint64_t pending_frames = 0;
  for (std::uint64_t at = kWalHeaderBytes; size - at >= frame.size(); at += frame.size()) {
    if (::pread(wal->fd, frame.data(), frame.size(), static_cast<off_t>(at)) !=
        static_cast<ssize_t>(frame.size())) {
      Fail(name,
           "its write-ahead log " + wal->path + " cannot be read (" + std::strerror(errno) + ")");
    }
    const std::uint32_t page_number = Big32(frame.data()), commit_pages = Big32(frame.data() + 4);
    if (page_number == 0 || std::memcmp(frame.data() + 8, header + 16, 8) != 0) break;
    std::uint32_t next[2] = {sum[0], sum[1]};
    Checksum(big_endian_words, frame.data(), 8, next);
    Checksum(big_endian_words, frame.data() + kFrameHeaderBytes, page, next);
    if (next[0] != Big32(frame.data() + 16) || next[1] != Big32(frame.data() + 20)) break;
    sum[0] = next[0];
    sum[1] = next[1];
    pending[page_number] = at + kFrameHeaderBytes;
    ++pending_frames;
    if (commit_pages != 0) {
      for (const auto& [p, offset] : pending) wal->frame_of[p] = offset;
      pending.clear();
      wal->frames += pending_frames;
      pending_frames = 0;
      wal->database_pages = commit_pages;
    }
  }
  return wal;
}

// The VFS: SQLite's default for the database file, with the log's pages over it; nothing else
// opened, nothing written or deleted.
struct SqliteSnapshot::Vfs {
  sqlite3_vfs vfs{};
  sqlite3_vfs* base = nullptr;
  std::string name;
  const SqliteWal* wal = nullptr;
  bool registered = false;
};

namespace {

struct File {
  sqlite3_file base;  // first: SQLite's view of it
  const SqliteWal* wal;
  sqlite3_file* real;  // the default VFS's file, in the storage after this
};
constexpr int kRealOffset = static_cast<int>((sizeof(File) + 7) / 8 * 8);

File* Of(sqlite3_file* f) { return reinterpret_cast<File*>(f); }

int Close(sqlite3_file* f) { return Of(f)->real->pMethods->xClose(Of(f)->real); }

int Read(sqlite3_file* f, void* out, int amount, sqlite3_int64 offset) {
  const File& file = *Of(f);
  const SqliteWal* wal = file.wal;
  if (wal->database_pages == 0) return file.real->pMethods->xRead(file.real, out, amount, offset);
  auto* to = static_cast<unsigned char*>(out);
  bool short_read = false;
  // Page by page: SQLite reads whole pages (and the header's first 100 bytes).
  while (amount > 0) {
    const auto page = static_cast<std::uint64_t>(offset) / wal->page_bytes + 1;
    const auto within = static_cast<std::uint64_t>(offset) % wal->page_bytes;
    const int n = static_cast<int>(
        std::min<std::uint64_t>(static_cast<std::uint64_t>(amount), wal->page_bytes - within));
    const auto frame = page <= 0xffffffffu ? wal->frame_of.find(static_cast<std::uint32_t>(page))
                                           : wal->frame_of.end();
    if (page > wal->database_pages) {
      // Past the database's end once checkpointed: SQLite's short read (zeros).
      std::memset(to, 0, static_cast<std::size_t>(n));
      short_read = true;
    } else if (frame != wal->frame_of.end()) {
      if (::pread(wal->fd, to, static_cast<std::size_t>(n),
                  static_cast<off_t>(frame->second + within)) != n) {
        return SQLITE_IOERR_READ;
      }
    } else {
      const int rc = file.real->pMethods->xRead(file.real, to, n, offset);
      if (rc == SQLITE_IOERR_SHORT_READ) {
        short_read = true;
      } else if (rc != SQLITE_OK) {
        return rc;
      }
    }
    to += n;
    offset += n;
    amount -= n;
  }
  return short_read ? SQLITE_IOERR_SHORT_READ : SQLITE_OK;
}

int Write(sqlite3_file*, const void*, int, sqlite3_int64) { return SQLITE_IOERR_WRITE; }
int Truncate(sqlite3_file*, sqlite3_int64) { return SQLITE_IOERR_TRUNCATE; }
int Sync(sqlite3_file*, int) { return SQLITE_OK; }
int FileSize(sqlite3_file* f, sqlite3_int64* size) {
  const File& file = *Of(f);
  if (file.wal->database_pages == 0) return file.real->pMethods->xFileSize(file.real, size);
  *size = static_cast<sqlite3_int64>(file.wal->database_pages * file.wal->page_bytes);
  return SQLITE_OK;
}
int Lock(sqlite3_file*, int) { return SQLITE_OK; }
int CheckReservedLock(sqlite3_file*, int* out) {
  *out = 0;
  return SQLITE_OK;
}
int FileControl(sqlite3_file*, int, void*) { return SQLITE_NOTFOUND; }
int SectorSize(sqlite3_file* f) { return Of(f)->real->pMethods->xSectorSize(Of(f)->real); }
int DeviceCharacteristics(sqlite3_file*) { return SQLITE_IOCAP_IMMUTABLE; }

const sqlite3_io_methods kMethods = {1,
                                     Close,
                                     Read,
                                     Write,
                                     Truncate,
                                     Sync,
                                     FileSize,
                                     Lock,
                                     Lock,
                                     CheckReservedLock,
                                     FileControl,
                                     SectorSize,
                                     DeviceCharacteristics,
                                     nullptr,
                                     nullptr,
                                     nullptr,
                                     nullptr,
                                     nullptr,
                                     nullptr};

sqlite3_vfs* Base(sqlite3_vfs* vfs) {
  return static_cast<SqliteSnapshot::Vfs*>(vfs->pAppData)->base;
}

int Open(sqlite3_vfs* vfs, const char* name, sqlite3_file* f, int flags, int* out_flags) {
  f->pMethods = nullptr;
  // The database only, read-only: a journal, a log, a temporary file are never made.
  if (name == nullptr || (flags & SQLITE_OPEN_MAIN_DB) == 0 ||
      (flags & SQLITE_OPEN_READONLY) == 0) {
    return SQLITE_CANTOPEN;
  }
  File* file = Of(f);
  file->wal = static_cast<SqliteSnapshot::Vfs*>(vfs->pAppData)->wal;
  file->real = reinterpret_cast<sqlite3_file*>(reinterpret_cast<char*>(f) + kRealOffset);
  const int rc = Base(vfs)->xOpen(Base(vfs), name, file->real, flags, out_flags);
  if (rc != SQLITE_OK) {
    if (file->real->pMethods != nullptr) file->real->pMethods->xClose(file->real);
    return rc;
  }
  f->pMethods = &kMethods;
  return SQLITE_OK;
}

int Delete(sqlite3_vfs*, const char*, int) { return SQLITE_IOERR_DELETE; }
int Access(sqlite3_vfs* vfs, const char* name, int flags, int* out) {
  return Base(vfs)->xAccess(Base(vfs), name, flags, out);
}
int FullPathname(sqlite3_vfs* vfs, const char* name, int n, char* out) {
  return Base(vfs)->xFullPathname(Base(vfs), name, n, out);
}
void* DlOpen(sqlite3_vfs*, const char*) { return nullptr; }  // no extension is loaded
void DlError(sqlite3_vfs*, int n, char* out) {
  if (n > 0) std::snprintf(out, static_cast<std::size_t>(n), "%s", "no extensions");
}
void (*DlSym(sqlite3_vfs*, void*, const char*))(void) { return nullptr; }
void DlClose(sqlite3_vfs*, void*) {}
int Randomness(sqlite3_vfs* vfs, int n, char* out) {
  return Base(vfs)->xRandomness(Base(vfs), n, out);
}
int Sleep(sqlite3_vfs* vfs, int us) { return Base(vfs)->xSleep(Base(vfs), us); }
int CurrentTime(sqlite3_vfs* vfs, double* out) { return Base(vfs)->xCurrentTime(Base(vfs), out); }
int GetLastError(sqlite3_vfs* vfs, int n, char* out) {
  return Base(vfs)->xGetLastError(Base(vfs), n, out);
}
int CurrentTimeInt64(sqlite3_vfs* vfs, sqlite3_int64* out) {
  return Base(vfs)->xCurrentTimeInt64(Base(vfs), out);
}

// The database's URI for `path`: read-only and immutable (no journal, no lock, no log of
// SQLite's own), its characters escaped as a URI needs.
std::string Uri(const std::string& path) {
  std::string out = "file:";
  for (unsigned char c : path) {
    if (c == '%' || c == '?' || c == '#' || c < 0x20 || c >= 0x7f) {
      out += Format("%%%02X", c);
    } else {
      out += static_cast<char>(c);
    }
  }
  return out + "?mode=ro&immutable=1";
}

}  // namespace

SqliteSnapshot::SqliteSnapshot(const std::string& path, const std::string& name)
    : wal_(ReadSqliteWal(path, name)), vfs_(std::make_unique<Vfs>()) {
  Vfs& v = *vfs_;
  v.base = sqlite3_vfs_find(nullptr);
  if (v.base == nullptr || v.base->iVersion < 2) {
    Fail(name, "an SQLite database, but SQLite has no file system to open it with");
  }
  v.wal = wal_.get();
  v.name = Format("accelcal-snapshot-%p", static_cast<void*>(this));
  v.vfs.iVersion = 2;
  v.vfs.szOsFile = kRealOffset + v.base->szOsFile;
  v.vfs.mxPathname = v.base->mxPathname;
  v.vfs.zName = v.name.c_str();
  v.vfs.pAppData = &v;
  v.vfs.xOpen = Open;
  v.vfs.xDelete = Delete;
  v.vfs.xAccess = Access;
  v.vfs.xFullPathname = FullPathname;
  v.vfs.xDlOpen = DlOpen;
  v.vfs.xDlError = DlError;
  v.vfs.xDlSym = DlSym;
  v.vfs.xDlClose = DlClose;
  v.vfs.xRandomness = Randomness;
  v.vfs.xSleep = Sleep;
  v.vfs.xCurrentTime = CurrentTime;
  v.vfs.xGetLastError = GetLastError;
  v.vfs.xCurrentTimeInt64 = CurrentTimeInt64;
  if (sqlite3_vfs_register(&v.vfs, 0) != SQLITE_OK) {
    Fail(name, "an SQLite database, but SQLite could not take accelcal's file system");
  }
  v.registered = true;
  const int opened = sqlite3_open_v2(Uri(path).c_str(), &db_,
                                     SQLITE_OPEN_READONLY | SQLITE_OPEN_URI, v.name.c_str());
  const auto fail = [&](int rc) {
    const std::string why = db_ != nullptr ? sqlite3_errmsg(db_) : sqlite3_errstr(rc);
    sqlite3_close(db_);
    db_ = nullptr;
    sqlite3_vfs_unregister(&v.vfs);
    v.registered = false;
    Fail(name, "an SQLite database that cannot be opened (" + why + ")");
  };
  if (opened != SQLITE_OK) fail(opened);
  // The schema is the file's: its views, triggers and defaults run no function that is not
  // harmless, and it cannot be changed by a statement (the connection is read-only besides).
  int rc = sqlite3_db_config(db_, SQLITE_DBCONFIG_TRUSTED_SCHEMA, 0, nullptr);
  if (rc == SQLITE_OK) rc = sqlite3_db_config(db_, SQLITE_DBCONFIG_DEFENSIVE, 1, nullptr);
  if (rc == SQLITE_OK) rc = sqlite3_exec(db_, kCacheSize, nullptr, nullptr, nullptr);
  if (rc != SQLITE_OK) fail(rc);
}

SqliteSnapshot::~SqliteSnapshot() {
  sqlite3_close(db_);
  if (vfs_ && vfs_->registered) sqlite3_vfs_unregister(&vfs_->vfs);
}

}  // namespace accelcal::internal
