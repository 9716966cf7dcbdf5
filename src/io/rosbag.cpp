// ROS 1 bag reader (rosbag.hpp).
#include "io/rosbag.hpp"

#include <array>
#include <cstring>
#include <map>
#include <memory>
#include <unordered_map>

#include "accelcal/error.hpp"
#include "core/text_format.hpp"
#include "io/decompress.hpp"
#include "io/ros_topics.hpp"

namespace accelcal::internal {

namespace {

constexpr char kMagic[] = "#ROSBAG V";
constexpr char kMagic20[] = "#ROSBAG V2.0\n";
constexpr std::size_t kMagic20Size = sizeof(kMagic20) - 1;

enum Op : unsigned char {
  kMessage = 0x02,
  kBagHeader = 0x03,
  kIndex = 0x04,
  kChunk = 0x05,
  kChunkInfo = 0x06,
  kConnection = 0x07,
};

// A connection's header (its topic, type and the type's definition with the types it uses) is
// small: ROS's largest definitions are tens of kilobytes.
constexpr std::size_t kMaxConnectionBytes = std::size_t{1} << 20;
// A record's header is small (a connection's is its topic); its data at most a chunk.
constexpr std::size_t kMaxHeaderBytes = std::size_t{1} << 20;
constexpr std::size_t kMaxDataBytes = kMaxDecompressedBytes + (std::size_t{1} << 20);

// A record header's fields, as views into its bytes (a few: a message's are op, conn, time).
class Fields {
 public:
  static constexpr std::size_t kMax = 32;
  bool Add(std::string_view name, std::string_view value) {
    for (std::size_t i = 0; i < n_; ++i) {
      if (field_[i].first == name) {
        field_[i].second = value;
        return true;
      }
    }
    if (n_ == kMax) return false;
    field_[n_++] = {name, value};
    return true;
  }
  const std::string_view* Find(std::string_view name) const {
    for (std::size_t i = 0; i < n_; ++i) {
      if (field_[i].first == name) return &field_[i].second;
    }
    return nullptr;
  }

 private:
  std::array<std::pair<std::string_view, std::string_view>, kMax> field_;
  std::size_t n_ = 0;
};

// A bag's connections (a topic's publisher each) are read up to this many: a real bag's are
// its topics times their publishers, hundreds. Past it a small compressed bag could ask for
// gigabytes (a 3 MB bz2 chunk held a million connection records).
constexpr std::size_t kMaxConnections = std::size_t{1} << 16;

class Reader {
 public:
  Reader(BinaryStream& in, const KeepStream& keep, const StoreColumns& store)
      : in_(in), keep_(keep), store_(store) {}
  DecodedLog Read();

 private:
  // One record at the input's position: false at the end of what can be read.
  bool Next();
  [[noreturn]] void Fail(std::uint64_t at, const std::string& why) const { in_.Fail(at, why); }
  // The fields of the header of `n` bytes at p (a record's header or a connection's data).
  Fields Parse(const unsigned char* p, std::size_t n, std::uint64_t at) const;
  // A field of exactly sizeof(T) bytes.
  template <typename T>
  T Number(const Fields& f, std::string_view name, std::uint64_t at) const {
    const std::string_view* v = f.Find(name);
    if (v == nullptr || v->size() != sizeof(T)) {
      Fail(at, Format("a record without its %zu-byte field %.*s", sizeof(T),
                      static_cast<int>(name.size()), name.data()));
    }
    return LoadLittle<T>(reinterpret_cast<const unsigned char*>(v->data()));
  }
  std::string_view Text(const Fields& f, std::string_view name, std::uint64_t at) const {
    const std::string_view* v = f.Find(name);
    if (v == nullptr) Fail(at, "a record without its field " + std::string(name));
    return *v;
  }
  // One record of the bag, or of a chunk (`in_chunk`): `at` its offset for messages, `message_at`
  // the offset its messages are reported at.
  void Record(const Fields& header, const unsigned char* data, std::size_t n, std::uint64_t at,
              bool in_chunk);
  // The records of a chunk's data (decompressed): whole ones only when `partial` (the file ends
  // inside it), at `base` in the file when it was not compressed (else at the chunk's offset).
  std::size_t Records(const unsigned char* p, std::size_t n, std::uint64_t chunk_at, bool exact,
                      bool partial);
  void Connect(const Fields& header, const unsigned char* data, std::size_t n, std::uint64_t at);
  void Message(const Fields& header, const unsigned char* data, std::size_t n, std::uint64_t at);

  BinaryStream& in_;
  const KeepStream& keep_;
  const StoreColumns& store_;
  DecodedLog out_;
  std::unordered_map<std::uint32_t, std::size_t> connections_;  // connection -> its stream
  RosTopics topics_{&out_, keep_, store_};
  std::vector<unsigned char> chunk_;
  InflatedTotal inflated_;  // by the compressed chunks so far
  std::size_t whole_ = 0;   // messages read whole
  std::uint64_t index_pos_ = 0;
};

Fields Reader::Parse(const unsigned char* p, std::size_t n, std::uint64_t at) const {
  Fields out;
  for (std::size_t i = 0; i < n;) {
    if (n - i < 4) Fail(at, "a record header whose last field is cut");
    const std::uint32_t len = LoadLittle<std::uint32_t>(p + i);
    if (len > n - i - 4) Fail(at, "a record header field that runs past the header's end");
    const std::string_view field(reinterpret_cast<const char*>(p + i + 4), len);
    const std::size_t eq = field.find('=');
    if (eq == std::string_view::npos) Fail(at, "a record header field without '='");
    if (!out.Add(field.substr(0, eq), field.substr(eq + 1))) {
      Fail(at, Format("a record header of more than %zu fields", Fields::kMax));
    }
    i += 4 + len;
  }
  return out;
}

void Reader::Connect(const Fields& header, const unsigned char* data, std::size_t n,
                     std::uint64_t at) {
  const std::uint32_t id = Number<std::uint32_t>(header, "conn", at);
  const std::string topic(Text(header, "topic", at));
  if (const auto known = connections_.find(id); known != connections_.end()) {
    // The index repeats each connection after the chunks.
    const std::string& before = out_.streams[known->second].topic;
    if (before != topic) {
      Fail(at, Format("connection %u is %s here, %s before", id, topic.c_str(), before.c_str()));
    }
    return;
  }

  if (n > kMaxConnectionBytes) {
    Fail(at, Format("a connection header of %zu bytes: no message definition is that long", n));
  }
  const Fields c = Parse(data, n, at);
  const std::string type(Text(c, "type", at));
  std::string error;
  const std::string_view* callerid = c.Find("callerid");
  const std::size_t stream =
      topics_.Add(topic, type, std::string(Text(c, "message_definition", at)), RosVersion::kRos1,
                  "", &error, callerid != nullptr ? std::string(*callerid) : std::string());
  if (!error.empty()) Fail(at, error);
  if (connections_.size() == kMaxConnections) {
    Fail(at, Format("a bag of more than %zu connections (a topic's publisher each): no "
                    "recording has that many",
                    kMaxConnections));
  }
  connections_.emplace(id, stream);
}

void Reader::Message(const Fields& header, const unsigned char* data, std::size_t n,
                     std::uint64_t at) {
  const std::uint32_t id = Number<std::uint32_t>(header, "conn", at);
  const std::uint64_t time = Number<std::uint64_t>(header, "time", at);
  const auto c = connections_.find(id);
  if (c == connections_.end()) {
    Fail(at,
         Format("a message of connection %u, which no connection record defined before it", id));
  }
  // The record's time: seconds and nanoseconds, in µs.
  const std::uint64_t t_us = (time & 0xffffffffu) * 1000000u + (time >> 32) / 1000u;
  ++whole_;
  if (const std::optional<std::string> why = topics_.Message(c->second, t_us, data, n, at)) {
    Fail(at, *why);
  }
}

void Reader::Record(const Fields& header, const unsigned char* data, std::size_t n,
                    std::uint64_t at, bool in_chunk) {
  const std::string_view op = Text(header, "op", at);
  if (op.size() != 1) Fail(at, "a record whose op is not one byte");
  switch (static_cast<unsigned char>(op[0])) {
    case kConnection:
      Connect(header, data, n, at);
      break;
    case kMessage:
      Message(header, data, n, at);
      break;
    case kBagHeader:
      if (!in_chunk) {
        // Where the index begins: a closed bag's chunks all end before it (0: never closed).
        if (const std::string_view* v = header.Find("index_pos"); v != nullptr && v->size() == 8) {
          index_pos_ = LoadLittle<std::uint64_t>(reinterpret_cast<const unsigned char*>(v->data()));
        }
      }
      break;
    case kIndex:
    case kChunkInfo:
      if (in_chunk) Fail(at, Format("a chunk holds a record of op 0x%02x", op[0]));
      break;
    default:
      Fail(at, Format("a record of op 0x%02x, which ROS bag 2.0 does not define",
                      static_cast<unsigned char>(op[0])));
  }
}

std::size_t Reader::Records(const unsigned char* p, std::size_t n, std::uint64_t chunk_at,
                            bool exact, bool partial) {
  std::size_t i = 0;
  while (i < n) {
    const std::uint64_t at = exact ? chunk_at + i : chunk_at;
    if (n - i < 4) break;
    const std::uint32_t header_len = LoadLittle<std::uint32_t>(p + i);
    if (header_len > n - i - 4 || n - i - 4 - header_len < 4) break;
    const std::uint32_t data_len = LoadLittle<std::uint32_t>(p + i + 4 + header_len);
    if (data_len > n - i - 8 - header_len) break;
    const Fields header = Parse(p + i + 4, header_len, at);
    const std::string_view op = Text(header, "op", at);
    if (op.size() == 1 && op[0] == kChunk) Fail(at, "a chunk inside a chunk");
    Record(header, p + i + 8 + header_len, data_len, at, true);
    i += 8 + header_len + data_len;
  }
  if (i != n && !partial) {
    Fail(exact ? chunk_at + i : chunk_at,
         Format("a chunk whose records do not fill it (a record runs past its end, %zu bytes "
                "into its %zu)",
                i, n));
  }
  return i;
}

bool Reader::Next() {
  const std::uint64_t at = in_.offset();
  if (!in_.Need(4)) {
    if (in_.available() > 0) {
      out_.truncated =
          Format("the bag ends inside a record at byte %llu", static_cast<unsigned long long>(at));
      in_.Skip(in_.available());
    }
    return false;
  }
  const std::uint32_t header_len = LoadLittle<std::uint32_t>(in_.data());
  if (header_len == 0) {
    // Zeros to the end: space never written (a recorder killed, a disk full).
    std::uint64_t nonzero = 0;
    if (!in_.ZerosToEnd(&nonzero)) {
      Fail(at, Format("a record with an empty header where zeros to the end would mean space "
                      "never written, but byte %llu is not zero: the file is corrupt here",
                      static_cast<unsigned long long>(nonzero)));
    }
    out_.truncated = BinaryStream::ZerosMessage(at);
    return false;
  }
  if (header_len > kMaxHeaderBytes) {
    Fail(at, Format("a record header of %u bytes: the file is corrupt here", header_len));
  }
  if (!in_.Need(8 + std::size_t(header_len))) {
    out_.truncated = Format("the bag ends inside a record header at byte %llu",
                            static_cast<unsigned long long>(at));
    in_.Skip(in_.available());
    return false;
  }
  bool chunk = false;
  {
    const Fields header = Parse(in_.data() + 4, header_len, at);
    const std::string_view op = Text(header, "op", at);
    chunk = op.size() == 1 && op[0] == kChunk;
  }  // its views end here: Need below may move the bytes
  const std::size_t data_len = LoadLittle<std::uint32_t>(in_.data() + 4 + header_len);
  if (data_len > kMaxDataBytes) {
    Fail(at, Format("a record of %zu bytes, more than the %zu MiB accelcal reads in one "
                    "(rosbag writes 768 kB chunks; `rosbag filter IN.bag OUT.bag True` rewrites "
                    "a bag recorded with larger ones)",
                    data_len, kMaxDataBytes >> 20));
  }
  const std::size_t length = 8 + header_len + data_len;
  const bool whole = in_.Need(length);
  if (!whole && !chunk) {
    out_.truncated = Format(
        "the bag ends inside a record at byte %llu (%zu of its %zu bytes "
        "there)",
        static_cast<unsigned long long>(at), in_.available(), length);
    in_.Skip(in_.available());
    return false;
  }
  const Fields fields = Parse(in_.data() + 4, header_len, at);
  const unsigned char* data = in_.data() + 8 + header_len;
  if (chunk) {
    const std::string_view compression = Text(fields, "compression", at);
    const std::size_t size = Number<std::uint32_t>(fields, "size", at);
    Compression c = Compression::kNone;
    if (compression == "bz2") {
      c = Compression::kBz2;
    } else if (compression == "lz4") {
      c = Compression::kLz4Frame;
    } else if (compression != "none") {
      Fail(at, "a chunk compressed as " + std::string(compression) +
                   ", which ROS bags do not use (none, bz2, lz4)");
    }
    if (c != Compression::kNone && data_len == 0 && size == 0) {
      // A compressed chunk its recorder opened and never closed (killed): the header's lengths
      // are still the placeholders, and what follows cannot be delimited.
      out_.truncated = Format(
          "the bag ends with a compressed chunk its recorder never closed "
          "(at byte %llu): its messages are not read",
          static_cast<unsigned long long>(at));
      in_.Skip(in_.available());
      return false;
    }
    if (!whole) {
      // The bag ends inside it: an uncompressed chunk's whole records are read.
      const std::size_t there = in_.available() - (8 + header_len);
      const std::size_t read =
          c == Compression::kNone ? Records(data, there, at + 8 + header_len, true, true) : 0;
      out_.truncated = Format(
          "the bag ends inside a chunk at byte %llu (%zu of its %zu bytes "
          "there%s)",
          static_cast<unsigned long long>(at), there, data_len,
          c == Compression::kNone ? Format("; its first %zu bytes of records read", read).c_str()
                                  : ", compressed: none of its messages read");
      in_.Skip(in_.available());
      return false;
    }
    if (c == Compression::kNone) {
      if (size != data_len)
        Fail(at, Format("an uncompressed chunk of %zu bytes that says %zu", data_len, size));
      Records(data, data_len, at + 8 + header_len, true, false);
    } else {
      // Counted before it is inflated: a bomb of many chunks is refused at the first past the
      // bound.
      if (const std::optional<std::string> why = inflated_.Add(size, at + length, "chunks")) {
        Fail(at, *why);
      }
      if (const std::optional<std::string> why = Decompress(c, data, data_len, size, &chunk_)) {
        Fail(at, "a chunk that does not decompress: " + *why);
      }
      Records(chunk_.data(), chunk_.size(), at, false, false);
    }
  } else {
    Record(fields, data, data_len, at, false);
  }
  in_.Skip(length);
  return true;
}

DecodedLog Reader::Read() {
  if (!in_.Need(kMagic20Size) || std::memcmp(in_.data(), kMagic20, kMagic20Size) != 0) {
    std::string version;
    for (std::size_t i = sizeof(kMagic) - 1; i < in_.available() && in_.data()[i] != '\n'; ++i) {
      version += static_cast<char>(in_.data()[i]);
      if (version.size() > 8) break;
    }
    Fail(0, "a ROS bag of version " + version +
                ": accelcal reads version 2.0, which ROS 1 writes since 2010 (rosbag fix "
                "migrates an older one)");
  }
  in_.Skip(kMagic20Size);
  while (true) {
    const std::uint64_t at = in_.offset();
    if (index_pos_ == 0 || at < index_pos_) {
      if (!Next()) break;
      continue;
    }
    // The index after the chunks (connections, chunk infos): every message has been read, so
    // an index that cannot be read ends the reading with a warning, not an error.
    try {
      if (!Next()) break;
    } catch (const InputError& e) {
      out_.truncated = Format("the bag's index (from byte %llu) cannot be read: %s",
                              static_cast<unsigned long long>(index_pos_), e.reason().c_str());
      in_.Skip(in_.available());
      break;
    }
  }
  if (!out_.truncated && index_pos_ > in_.offset()) {
    // Cut where a chunk ended: nothing is cut inside a record, but the index is missing.
    out_.truncated = Format(
        "the bag ends at byte %llu, before its index at byte %llu: a bag cut "
        "short",
        static_cast<unsigned long long>(in_.offset()), static_cast<unsigned long long>(index_pos_));
  }
  if (out_.truncated) *out_.truncated += Format(", after %zu whole messages", whole_);
  out_.bytes = in_.offset();
  return std::move(out_);
}

}  // namespace

bool IsRosBag(std::string_view first_bytes) {
  return first_bytes.substr(0, sizeof(kMagic) - 1) == kMagic;
}

DecodedLog ReadRosBag(BinaryStream& in, const KeepStream& keep, const StoreColumns& store) {
  return Reader(in, keep, store).Read();
}

}  // namespace accelcal::internal
