// MCAP reader (mcap.hpp).
#include "io/mcap.hpp"

#include <cstring>
#include <map>
#include <optional>
#include <unordered_map>

#include "accelcal/error.hpp"
#include "core/crc32.hpp"
#include "core/text_format.hpp"
#include "io/decompress.hpp"
#include "io/ros_topics.hpp"

namespace accelcal::internal {

bool IsMcap(std::string_view first_bytes) {
  return first_bytes.size() >= sizeof(kMcapMagic) &&
         std::memcmp(first_bytes.data(), kMcapMagic, sizeof(kMcapMagic)) == 0;
}

namespace {

enum Op : unsigned char {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kDataEnd = 0x0F,
};

// The records read whole: a chunk at most as large as a decompressed block may be, the others
// (a schema, a channel, a message) far smaller. Larger records (attachments) are skipped unread.
constexpr std::uint64_t kMaxRecordBytes = kMaxDecompressedBytes + (std::uint64_t{1} << 20);

// The fields of a record's content, read in order; false when a field runs past its end.
class Fields {
 public:
  Fields(const unsigned char* p, std::size_t n) : p_(p), end_(p + n) {}
  template <typename T>
  bool Number(T* v) {
    if (std::size_t(end_ - p_) < sizeof(T)) return false;
    *v = LoadLittle<T>(p_);
    p_ += sizeof(T);
    return true;
  }
  // Bytes preceded by their length as a uint32 (a String) or a uint64.
  template <typename Length>
  bool Prefixed(std::string_view* v) {
    Length n = 0;
    if (!Number(&n) || std::uint64_t(end_ - p_) < n) return false;
    *v = std::string_view(reinterpret_cast<const char*>(p_), std::size_t(n));
    p_ += n;
    return true;
  }
  bool String(std::string_view* v) { return Prefixed<std::uint32_t>(v); }
  const unsigned char* at() const { return p_; }
  std::size_t left() const { return std::size_t(end_ - p_); }

 private:
  const unsigned char* p_;
  const unsigned char* end_;
};

struct Schema {
  std::string name, encoding, data;
};

class Reader {
 public:
  Reader(BinaryStream& in, const KeepStream& keep, const StoreColumns& store)
      : in_(in), topics_(&out_, keep, store) {}
  DecodedLog Read();

 private:
  [[noreturn]] void Fail(std::uint64_t at, const std::string& why) const { in_.Fail(at, why); }
  // A record of `op` with `n` bytes of content at p, at byte `at` of the file (a record in a
  // compressed chunk: the chunk's).
  void Record(unsigned char op, const unsigned char* p, std::size_t n, std::uint64_t at,
              bool in_chunk);
  void Chunk(const unsigned char* p, std::size_t n, std::uint64_t at);
  void Channel(const unsigned char* p, std::size_t n, std::uint64_t at);

  BinaryStream& in_;
  DecodedLog out_;
  RosTopics topics_;
  std::unordered_map<std::uint16_t, Schema> schemas_;
  std::unordered_map<std::uint16_t, std::size_t> channels_;  // channel -> stream
  std::vector<unsigned char> chunk_;
  InflatedTotal inflated_;  // by the compressed chunks so far
  std::size_t whole_ = 0;   // messages read whole
};

void Reader::Channel(const unsigned char* p, std::size_t n, std::uint64_t at) {
  Fields f(p, n);
  std::uint16_t id = 0, schema_id = 0;
  std::string_view topic, encoding;
  if (!f.Number(&id) || !f.Number(&schema_id) || !f.String(&topic) || !f.String(&encoding)) {
    Fail(at, "a Channel record shorter than its fields");
  }
  if (channels_.count(id) != 0) return;  // the summary repeats each channel
  std::string type = "(no schema)", why;
  std::optional<std::string> definition;
  RosVersion version = RosVersion::kRos2;
  if (schema_id != 0) {
    const auto s = schemas_.find(schema_id);
    if (s == schemas_.end()) {
      Fail(at, Format("channel %u (%s) refers to schema %u, which no Schema record defined "
                      "before it",
                      id, std::string(topic).c_str(), schema_id));
    }
    type = s->second.name;
    if (encoding == "cdr" && s->second.encoding == "ros2msg") {
      definition = s->second.data;
    } else if (encoding == "ros1" && s->second.encoding == "ros1msg") {
      definition = s->second.data;
      version = RosVersion::kRos1;
    } else {
      why = "its messages are " + std::string(encoding) + " of a " + s->second.encoding +
            " schema; accelcal decodes ROS 2's cdr (ros2msg) and ROS 1's ros1 (ros1msg)";
    }
  } else {
    why = "its channel has no schema";
  }
  std::string error;
  const std::size_t stream =
      topics_.Add(std::string(topic), type, definition, version, why, &error);
  if (!error.empty()) Fail(at, error);
  channels_.emplace(id, stream);
}

void Reader::Record(unsigned char op, const unsigned char* p, std::size_t n, std::uint64_t at,
                    bool in_chunk) {
  switch (op) {
    case kSchema: {
      Fields f(p, n);
      std::uint16_t id = 0;
      std::string_view name, encoding, data;
      if (!f.Number(&id) || !f.String(&name) || !f.String(&encoding) || !f.String(&data)) {
        Fail(at, "a Schema record shorter than its fields");
      }
      if (id != 0) {  // id 0 is invalid, to be ignored
        schemas_.emplace(id, Schema{std::string(name), std::string(encoding), std::string(data)});
      }
      break;
    }
    case kChannel:
      Channel(p, n, at);
      break;
    case kMessage: {
      Fields f(p, n);
      std::uint16_t channel = 0;
      std::uint32_t sequence = 0;
      std::uint64_t log_time = 0, publish_time = 0;
      if (!f.Number(&channel) || !f.Number(&sequence) || !f.Number(&log_time) ||
          !f.Number(&publish_time)) {
        Fail(at, "a Message record shorter than its fields");
      }
      const auto c = channels_.find(channel);
      if (c == channels_.end()) {
        Fail(at,
             Format("a message of channel %u, which no Channel record defined before it", channel));
      }
      ++whole_;
      if (const std::optional<std::string> why =
              topics_.Message(c->second, log_time / 1000, f.at(), f.left(), at)) {
        Fail(at, *why);
      }
      break;
    }
    case kChunk:
      if (in_chunk) Fail(at, "a chunk inside a chunk");
      Chunk(p, n, at);
      break;
    case kHeader: {
      Fields f(p, n);
      std::string_view profile, library;
      if (!f.String(&profile) || !f.String(&library)) {
        Fail(at, "a Header record shorter than its fields");
      }
      out_.info["profile"] = std::string(profile);
      out_.info["library"] = std::string(library);
      break;
    }
    default:
      // The index, summary, attachment and metadata records, and private ones: not needed.
      break;
  }
}

void Reader::Chunk(const unsigned char* p, std::size_t n, std::uint64_t at) {
  Fields f(p, n);
  std::uint64_t start = 0, end = 0, size = 0;
  std::uint32_t crc = 0;
  std::string_view compression, records;
  if (!f.Number(&start) || !f.Number(&end) || !f.Number(&size) || !f.Number(&crc) ||
      !f.String(&compression) || !f.Prefixed<std::uint64_t>(&records)) {
    Fail(at, "a Chunk record shorter than its fields");
  }
  const auto* data = reinterpret_cast<const unsigned char*>(records.data());
  const unsigned char* content = data;
  std::size_t length = records.size();
  const bool exact = compression.empty();
  if (!exact) {
    Compression c = Compression::kLz4Frame;
    if (compression == "zstd") {
      c = Compression::kZstd;
    } else if (compression != "lz4") {
      Fail(at, "a chunk compressed as " + std::string(compression) +
                   ", which MCAP does not define (lz4, zstd, or none)");
    }
    if (size > kMaxDecompressedBytes) {
      Fail(at, Format("a chunk of %llu bytes once decompressed, more than the %zu MiB accelcal "
                      "reads in one (ROS 2 writes 768 kB to 4 MiB chunks; the mcap tool's "
                      "compress --chunk-size rewrites a file recorded with larger ones)",
                      static_cast<unsigned long long>(size), kMaxDecompressedBytes >> 20));
    }
    // Counted before it is inflated: a bomb of many chunks is refused at the first past the bound.
    if (const std::optional<std::string> why = inflated_.Add(size, at + 9 + n, "chunks")) {
      Fail(at, *why);
    }
    if (const std::optional<std::string> why =
            Decompress(c, data, records.size(), std::size_t(size), &chunk_)) {
      Fail(at, "a chunk that does not decompress: " + *why);
    }
    content = chunk_.data();
    length = chunk_.size();
  } else if (size != records.size()) {
    Fail(at, Format("an uncompressed chunk of %zu bytes that says %llu", records.size(),
                    static_cast<unsigned long long>(size)));
  }
  if (crc != 0 && Crc32(content, length) != crc) {
    Fail(at, Format("a chunk whose records fail their CRC-32 (%08x, where the chunk says %08x): "
                    "the file is corrupt here",
                    Crc32(content, length), crc));
  }
  // Its records: in an uncompressed chunk each at its own byte, else at the chunk's.
  const std::uint64_t base =
      at + 1 + 8 + std::uint64_t(records.data() - reinterpret_cast<const char*>(p));
  for (std::size_t i = 0; i < length;) {
    const std::uint64_t record_at = exact ? base + i : at;
    if (length - i < 9) Fail(record_at, "a chunk whose last record is cut");
    const unsigned char op = content[i];
    const std::uint64_t record_length = LoadLittle<std::uint64_t>(content + i + 1);
    if (record_length > length - i - 9) Fail(record_at, "a record that runs past its chunk's end");
    Record(op, content + i + 9, std::size_t(record_length), record_at, true);
    i += 9 + std::size_t(record_length);
  }
}

DecodedLog Reader::Read() {
  if (!in_.Need(sizeof(kMcapMagic)) ||
      !IsMcap(std::string_view(reinterpret_cast<const char*>(in_.data()), sizeof(kMcapMagic)))) {
    Fail(0, "not an MCAP file (its magic is not 89 \"MCAP0\" 0D 0A)");
  }
  in_.Skip(sizeof(kMcapMagic));
  bool footer = false, data_end = false;
  while (true) {
    const std::uint64_t at = in_.offset();
    if (!in_.Need(9)) {
      if (in_.available() > 0) {
        out_.truncated = Format("the file ends inside a record at byte %llu",
                                static_cast<unsigned long long>(at));
        in_.Skip(in_.available());
      }
      break;
    }
    const unsigned char op = in_.data()[0];
    const std::uint64_t length = LoadLittle<std::uint64_t>(in_.data() + 1);
    if (op == 0) {
      // Zeros to the end: space never written (a recorder killed, a disk full).
      std::uint64_t nonzero = 0;
      if (!in_.ZerosToEnd(&nonzero)) {
        Fail(at, Format("a record of opcode 0, which MCAP does not define; byte %llu after it is "
                        "not zero: the file is corrupt here",
                        static_cast<unsigned long long>(nonzero)));
      }
      out_.truncated = BinaryStream::ZerosMessage(at);
      break;
    }
    const bool needed = op == kHeader || op == kSchema || op == kChannel || op == kMessage ||
                        op == kChunk || op == kFooter || op == kDataEnd;
    if (!needed) {
      // Not needed, however large (an attachment): skipped as it is read.
      in_.Skip(9);
      if (!in_.SkipAhead(length)) {
        out_.truncated = Format("the file ends inside a record at byte %llu",
                                static_cast<unsigned long long>(at));
        break;
      }
      continue;
    }
    if (length > kMaxRecordBytes) {
      Fail(at, Format("a record of opcode 0x%02x and %llu bytes, more than the %llu MiB accelcal "
                      "reads in one",
                      op, static_cast<unsigned long long>(length),
                      static_cast<unsigned long long>(kMaxRecordBytes >> 20)));
    }
    if (!in_.Need(9 + std::size_t(length))) {
      out_.truncated = Format(
          "the file ends inside a record at byte %llu (%zu of its %llu bytes "
          "there)",
          static_cast<unsigned long long>(at), in_.available(),
          static_cast<unsigned long long>(9 + length));
      in_.Skip(in_.available());
      break;
    }
    if (op == kFooter) {
      in_.Skip(9 + std::size_t(length));
      footer = true;
      if (!in_.Need(sizeof(kMcapMagic)) ||
          !IsMcap(std::string_view(reinterpret_cast<const char*>(in_.data()), 8))) {
        Fail(in_.offset(), "the Footer record is not followed by the closing magic");
      }
      in_.Skip(sizeof(kMcapMagic));
      if (in_.Need(1)) Fail(in_.offset(), "bytes after the closing magic");
      break;
    }
    if (op == kDataEnd) data_end = true;
    Record(op, in_.data() + 9, std::size_t(length), at, false);
    in_.Skip(9 + std::size_t(length));
  }
  if (!footer && !out_.truncated) {
    out_.truncated = Format("the file ends at byte %llu without its %s (a recording never closed)",
                            static_cast<unsigned long long>(in_.offset()),
                            data_end ? "Footer" : "Data End and Footer records");
  }
  if (out_.truncated) *out_.truncated += Format(", after %zu whole messages", whole_);
  out_.bytes = in_.offset();
  return std::move(out_);
}

}  // namespace

DecodedLog ReadMcap(BinaryStream& in, const KeepStream& keep, const StoreColumns& store) {
  return Reader(in, keep, store).Read();
}

}  // namespace accelcal::internal
