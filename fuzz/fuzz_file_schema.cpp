// libFuzzer harness: the files read through a library (ROS 2 SQLite bags through libsqlite3,
// MAT-files through libmatio) built from the fuzzer's bytes as their schema objects, where
// fuzz_file_log mutates their bytes (which seldom survives SQLite's checks of its pages or
// zlib's of its streams). A bag: each of topics, messages and message_definitions absent, a
// table (its columns kept or dropped, typed, generated, WITHOUT ROWID), a view over a table or
// over an endless recursive query, with or without the timestamps' index and a trigger; its rows
// (Imu messages, others, raw bytes); in WAL mode with the last rows in FILE-wal, some of its
// bytes damaged. A MAT-file: up to three variables, each of any class, flags, rank and
// dimensions, its data of any type and length (as claimed or not), cells and structs nested,
// compressed or not. Then inspected and read as fuzz_file_log reads.
// The only accepted failure is InputError; anything else is a finding, and so is a read that
// does not end (-timeout) or takes memory past -rss_limit_mb.
#include <fcntl.h>
#include <fuzzer/FuzzedDataProvider.h>
#include <sqlite3.h>
#include <unistd.h>
#include <zlib.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "accelcal/error.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/native_log.hpp"
#include "input_check.hpp"

namespace {

// One directory for the whole run: the file, and its -wal and -shm. Never destroyed: the exit
// handler that removes it runs after the statics' destructors.
const std::string& Dir() {
  static const std::string* dir = [] {
    const char* tmp = std::getenv("TMPDIR");
    auto* d = new std::string(std::string(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp") +
                              "/fuzz_file_schema.XXXXXX");
    if (::mkdtemp(d->data()) == nullptr) std::abort();
    std::atexit([] {
      for (const char* f :
           {"/in.db3", "/in.db3-wal", "/in.db3-shm", "/in.db3-journal", "/in.mat"}) {
        ::unlink((Dir() + f).c_str());
      }
      ::rmdir(Dir().c_str());
    });
    return d;
  }();
  return *dir;
}

template <typename T>
T Pick(FuzzedDataProvider& in, const std::vector<T>& choices) {
  return choices[in.ConsumeIntegralInRange<std::size_t>(0, choices.size() - 1)];
}

void Exec(sqlite3* db, const std::string& sql) {
  sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr);
}

// A column of a table: dropped, typed, or computed.
std::string Column(FuzzedDataProvider& in, const std::string& name, const std::string& type) {
  switch (in.ConsumeIntegralInRange(0, 9)) {
    case 0:
      return "";
    case 1:
      return name + " " + Pick<std::string>(in, {"INTEGER", "TEXT", "BLOB", "REAL", "ANY", ""});
    case 2:
      return name + " " + type + " GENERATED ALWAYS AS (" +
             Pick<std::string>(in, {"1", "'x'", "zeroblob(1000000)", "randomblob(8)", "id"}) + ")";
    default:
      return name + " " + type;
  }
}

// The CREATE statements of one object: a table of `columns` (the first its id), a view, or none.
void Create(FuzzedDataProvider& in, sqlite3* db, const std::string& name,
            const std::vector<std::pair<std::string, std::string>>& columns) {
  const int kind = in.ConsumeIntegralInRange(0, 9);
  if (kind == 0) return;  // absent
  std::string table = "CREATE TABLE " + (kind == 1 ? name + "_t" : name) + "(";
  bool first = true;
  for (const auto& [column, type] : columns) {
    std::string c =
        first && in.ConsumeBool() ? column + " INTEGER PRIMARY KEY" : Column(in, column, type);
    if (c.empty()) continue;
    table += (first ? "" : ", ") + c;
    first = false;
  }
  if (first) table += "x";
  table += ")";
  if (kind == 2) table += " WITHOUT ROWID";
  if (kind == 3) {
    // A view over a query without end: read, it never returns.
    std::string select;
    for (const auto& [column, type] : columns) {
      select += (select.empty() ? "" : ", ") +
                std::string(type == "BLOB"   ? "x'0001000000'"
                            : type == "TEXT" ? "'cdr'"
                                             : "n") +
                " AS " + column;
    }
    Exec(db, "CREATE VIEW " + name +
                 " AS WITH RECURSIVE r(n) AS (SELECT 1 UNION ALL SELECT n + 1 FROM r) SELECT " +
                 select + " FROM r" + (in.ConsumeBool() ? " ORDER BY n DESC" : ""));
    return;
  }
  Exec(db, table);
  if (kind == 1) Exec(db, "CREATE VIEW " + name + " AS SELECT * FROM " + name + "_t");
  if (in.ConsumeIntegralInRange(0, 7) == 0) {
    Exec(db,
         "CREATE TRIGGER " + name + "_trigger AFTER INSERT ON " + name + " BEGIN SELECT 1; END");
  }
}

// An Imu message in CDR (little-endian), its values from the fuzzer.
std::string ImuMessage(FuzzedDataProvider& in, std::int64_t ns) {
  std::string m("\x00\x01\x00\x00", 4);
  const auto put = [&](const void* p, std::size_t n) {
    while ((m.size() - 4) % n != 0) m += '\0';
    m.append(static_cast<const char*>(p), n);
  };
  const std::int32_t sec = static_cast<std::int32_t>(ns / 1000000000);
  const std::uint32_t nsec = static_cast<std::uint32_t>(ns % 1000000000);
  put(&sec, 4);
  put(&nsec, 4);
  const std::uint32_t frame_length = 9;
  put(&frame_length, 4);
  m.append("imu_link", 9);
  for (int i = 0; i < 4 + 9 + 3 + 9 + 3 + 9; ++i) {
    const double v = in.ConsumeBool() ? Pick<double>(in, {0.0, 1.0, -1.0, 9.81, 1e308, -0.5})
                                      : in.ConsumeFloatingPoint<double>();
    put(&v, 8);
  }
  return m;
}

const char kImuDefinition[] =
    "std_msgs/Header header\ngeometry_msgs/Quaternion orientation\nfloat64[9] "
    "orientation_covariance\ngeometry_msgs/Vector3 angular_velocity\nfloat64[9] "
    "angular_velocity_covariance\ngeometry_msgs/Vector3 linear_acceleration\nfloat64[9] "
    "linear_acceleration_covariance\n=============================================================="
    "=="
    "================\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n"
    "================================================================================\nMSG: "
    "builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n=========================================="
    "======================================\nMSG: geometry_msgs/Quaternion\nfloat64 x 0\nfloat64 "
    "y 0\nfloat64 z 0\nfloat64 w 1\n========================================================"
    "========================\nMSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n";

void Damage(FuzzedDataProvider& in, const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
  if (fd < 0) return;
  const off_t size = ::lseek(fd, 0, SEEK_END);
  for (int i = in.ConsumeIntegralInRange(0, 2); i > 0 && size > 0; --i) {
    const auto at = static_cast<off_t>(
        in.ConsumeIntegralInRange<std::uint64_t>(0, static_cast<std::uint64_t>(size - 1)));
    const auto byte = in.ConsumeIntegral<unsigned char>();
    if (::pwrite(fd, &byte, 1, at) != 1) std::abort();
  }
  ::close(fd);
}

std::string BuildBag(FuzzedDataProvider& in) {
  const std::string path = Dir() + "/in.db3";
  for (const char* suffix : {"", "-wal", "-shm"}) ::unlink((path + suffix).c_str());
  sqlite3* db = nullptr;
  if (sqlite3_open(path.c_str(), &db) != SQLITE_OK) std::abort();
  Exec(db, "PRAGMA synchronous = OFF");  // thousands of files a minute, none kept
  Exec(db, "PRAGMA page_size = " + std::to_string(Pick<int>(in, {512, 1024, 4096, 65536})));
  const bool wal = in.ConsumeBool();
  if (wal) {
    Exec(db, "PRAGMA journal_mode = WAL");
    Exec(db, "PRAGMA wal_autocheckpoint = 0");
    sqlite3_db_config(db, SQLITE_DBCONFIG_NO_CKPT_ON_CLOSE, 1, nullptr);
  }
  Create(in, db, "topics",
         {{"id", "INTEGER"}, {"name", "TEXT"}, {"type", "TEXT"}, {"serialization_format", "TEXT"}});
  Create(in, db, "message_definitions",
         {{"id", "INTEGER"},
          {"topic_type", "TEXT"},
          {"encoding", "TEXT"},
          {"encoded_message_definition", "TEXT"}});
  Create(in, db, "messages",
         {{"id", "INTEGER"}, {"topic_id", "INTEGER"}, {"timestamp", "INTEGER"}, {"data", "BLOB"}});
  if (in.ConsumeBool()) Exec(db, "CREATE INDEX timestamp_idx ON messages (timestamp ASC)");
  const auto insert = [&](const char* sql, const std::vector<std::string>& text,
                          const std::vector<std::int64_t>& numbers, const std::string* blob) {
    sqlite3_stmt* s = nullptr;
    if (sqlite3_prepare_v2(db, sql, -1, &s, nullptr) == SQLITE_OK) {
      int i = 1;
      for (const std::int64_t n : numbers) sqlite3_bind_int64(s, i++, n);
      for (const std::string& t : text) sqlite3_bind_text(s, i++, t.c_str(), -1, SQLITE_TRANSIENT);
      if (blob != nullptr) {
        sqlite3_bind_blob(s, i, blob->data(), static_cast<int>(blob->size()), SQLITE_TRANSIENT);
      }
      sqlite3_step(s);
    }
    sqlite3_finalize(s);
  };
  Exec(db, "BEGIN");
  for (int i = in.ConsumeIntegralInRange(0, 4); i > 0; --i) {
    insert("INSERT INTO topics (id, name, type, serialization_format) VALUES (?1, ?2, ?3, ?4)",
           {Pick<std::string>(in, {"/imu/data", "/imu/temperature", "/x", ""}),
            Pick<std::string>(in, {"sensor_msgs/msg/Imu", "sensor_msgs/msg/Temperature",
                                   "sensor_msgs/msg/MagneticField", "vendor/msg/X"}),
            Pick<std::string>(in, {"cdr", "cdr", "json"})},
           {in.ConsumeIntegralInRange<std::int64_t>(0, 4)}, nullptr);
  }
  if (in.ConsumeBool()) {
    insert(
        "INSERT INTO message_definitions (topic_type, encoding, encoded_message_definition) VALUES "
        "(?1, ?2, ?3)",
        {"sensor_msgs/msg/Imu", Pick<std::string>(in, {"ros2msg", "ros2idl"}),
         in.ConsumeBool() ? std::string(kImuDefinition) : in.ConsumeRandomLengthString(256)},
        {}, nullptr);
  }
  std::int64_t ns = 1700000000000000000;
  const int messages = in.ConsumeIntegralInRange(0, 48),
            committed = in.ConsumeIntegralInRange(0, 48);
  for (int i = 0; i < messages; ++i) {
    if (i == committed) {
      Exec(db, "COMMIT");
      if (in.ConsumeBool()) Exec(db, "PRAGMA wal_checkpoint(TRUNCATE)");
      Exec(db, "BEGIN");
    }
    ns += in.ConsumeBool() ? 10000000
                           : in.ConsumeIntegralInRange<std::int64_t>(-1000000000, 1000000000);
    const std::string data =
        in.ConsumeBool() ? ImuMessage(in, ns) : in.ConsumeRandomLengthString(64);
    insert("INSERT INTO messages (topic_id, timestamp, data) VALUES (?1, ?2, ?3)", {},
           {in.ConsumeIntegralInRange<std::int64_t>(0, 4), ns}, &data);
  }
  Exec(db, "COMMIT");
  sqlite3_close(db);
  if (wal && in.ConsumeBool()) Damage(in, path + "-wal");
  if (in.ConsumeIntegralInRange(0, 3) == 0) Damage(in, path);
  return path;
}

// MAT-file Level 5 (MathWorks, "MAT-File Format"): elements of a type and a byte count.
constexpr std::uint32_t kMiInt8 = 1, kMiUint8 = 2, kMiInt32 = 5, kMiUint32 = 6, kMiDouble = 9,
                        kMiMatrix = 14, kMiCompressed = 15;

void Put32(std::string* out, std::uint32_t v) { out->append(reinterpret_cast<const char*>(&v), 4); }

std::string Element(std::uint32_t type, const std::string& data, bool small_allowed) {
  std::string out;
  if (small_allowed && data.size() <= 4) {
    Put32(&out, static_cast<std::uint32_t>(data.size()) << 16 | type);
    return out + data + std::string(4 - data.size(), '\0');
  }
  Put32(&out, type);
  Put32(&out, static_cast<std::uint32_t>(data.size()));
  return out + data + std::string((8 - data.size() % 8) % 8, '\0');
}

// One matrix element (a variable, or a cell's or struct's element at `depth`).
std::string Matrix(FuzzedDataProvider& in, const std::string& name, int depth) {
  // Classes 1-15: cell, struct, object, char, sparse, double, single, int8 ... uint64, function.
  const auto cls = depth < 2 && in.ConsumeIntegralInRange(0, 3) == 0
                       ? in.ConsumeIntegralInRange<std::uint32_t>(1, 16)
                       : Pick<std::uint32_t>(in, {6, 6, 6, 7, 9, 10, 4});
  const auto flags = in.ConsumeIntegralInRange(0, 5) == 0 ? in.ConsumeIntegral<std::uint8_t>() : 0;
  std::string out = Element(
      kMiUint32,
      [&] {
        std::string f;
        Put32(&f, static_cast<std::uint32_t>(flags) << 8 | cls);
        Put32(&f, in.ConsumeIntegralInRange<std::uint32_t>(0, 16));
        return f;
      }(),
      false);
  std::vector<std::uint32_t> dims(
      in.ConsumeIntegralInRange(0, 9) == 0 ? in.ConsumeIntegralInRange<std::size_t>(1, 4) : 2);
  std::uint64_t values = 1;
  for (auto& d : dims) {
    d = in.ConsumeIntegralInRange(0, 7) == 0 ? in.ConsumeIntegral<std::uint32_t>()
                                             : Pick<std::uint32_t>(in, {0, 1, 3, 4, 7, 17, 40});
    values *= d;
  }
  std::string dim_bytes;
  for (auto d : dims) Put32(&dim_bytes, d);
  out += Element(kMiInt32, dim_bytes, false);
  out += Element(kMiInt8, name, in.ConsumeBool());
  // As many values as claimed (small matrices), or as many as the fuzzer says.
  const std::uint64_t count = values <= 2048 && in.ConsumeIntegralInRange(0, 7) != 0
                                  ? values
                                  : in.ConsumeIntegralInRange<std::uint64_t>(0, 64);
  if (cls == 1 || cls == 2) {
    if (cls == 2) {
      out += Element(kMiInt32, std::string("\x08\x00\x00\x00", 4), true);  // field names' length
      const std::size_t fields = in.ConsumeIntegralInRange<std::size_t>(0, 3);
      std::string names;
      for (std::size_t f = 0; f < fields; ++f) {
        std::string n = "f" + std::to_string(f);
        names += n + std::string(8 - n.size(), '\0');
      }
      out += Element(kMiInt8, names, false);
      for (std::uint64_t i = 0; i < count * fields && i < 8; ++i) {
        out += Element(kMiMatrix, depth < 3 ? Matrix(in, "", depth + 1) : "", false);
      }
    } else {
      for (std::uint64_t i = 0; i < count && i < 8; ++i) {
        out += Element(kMiMatrix, depth < 3 ? Matrix(in, "", depth + 1) : "", false);
      }
    }
    return out;
  }
  const auto type = in.ConsumeIntegralInRange(0, 5) == 0
                        ? in.ConsumeIntegralInRange<std::uint32_t>(1, 18)
                        : Pick<std::uint32_t>(in, {kMiDouble, kMiDouble, kMiUint8, kMiInt32});
  std::string data;
  const bool session = in.ConsumeBool();  // time, then readings near 1 g
  for (std::uint64_t i = 0; i < count; ++i) {
    if (type == kMiDouble) {
      const double v =
          session ? (i % 4 == 0 ? 0.01 * static_cast<double>(i / 4) : 9.81 - 0.01 * (i % 3))
                  : in.ConsumeFloatingPoint<double>();
      data.append(reinterpret_cast<const char*>(&v), 8);
    } else {
      data += static_cast<char>(in.ConsumeIntegral<std::uint8_t>());
    }
  }
  out += Element(type, data, in.ConsumeBool());
  if ((flags & 0x08) != 0) out += Element(type, data, false);  // the imaginary part
  return out;
}

std::string BuildMat(FuzzedDataProvider& in) {
  std::string file = "MATLAB 5.0 MAT-file, fuzz_file_schema";
  file.resize(116, ' ');
  file += std::string(8, '\0');
  file += std::string("\x00\x01IM", 4);
  for (int v = in.ConsumeIntegralInRange(1, 3); v > 0; --v) {
    const std::string element =
        Element(kMiMatrix, Matrix(in, Pick<std::string>(in, {"imu", "acc", "x", ""}), 0), false);
    if (in.ConsumeBool()) {
      uLongf n = compressBound(static_cast<uLong>(element.size()));
      std::string z(n, '\0');
      if (compress(reinterpret_cast<Bytef*>(z.data()), &n,
                   reinterpret_cast<const Bytef*>(element.data()),
                   static_cast<uLong>(element.size())) != Z_OK) {
        std::abort();
      }
      z.resize(n);
      Put32(&file, kMiCompressed);
      Put32(&file, static_cast<std::uint32_t>(z.size()));
      file += z;
    } else {
      file += element;
    }
  }
  const std::string path = Dir() + "/in.mat";
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0 || ::write(fd, file.data(), file.size()) != static_cast<ssize_t>(file.size())) {
    std::abort();
  }
  ::close(fd);
  if (in.ConsumeIntegralInRange(0, 3) == 0) Damage(in, path);
  return path;
}

void Read(const std::string& path, const accelcal::ReadOptions& options) {
  try {
    accelcal::fuzz::CheckInput(accelcal::ReadInput(path, options), true);
  } catch (const accelcal::InputError&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  FuzzedDataProvider in(data, size);
  const bool bag = in.ConsumeBool();
  const std::string path = bag ? BuildBag(in) : BuildMat(in);
  try {
    accelcal::InspectLog(path);
  } catch (const accelcal::InputError&) {
  }
  accelcal::ReadOptions options;
  Read(path, options);
  options.topic = bag ? "/imu/data" : "imu";
  Read(path, options);
  options.sensor = accelcal::SensorKind::kGyroscope;
  Read(path, options);
  return 0;
}
