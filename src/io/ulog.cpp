// PX4 ULog reader (ulog.hpp).
#include "io/ulog.hpp"

#include <algorithm>
#include <cstring>
#include <memory>
#include <unordered_map>
#include <unordered_set>

#include "accelcal/error.hpp"
#include "core/text_format.hpp"

namespace accelcal::internal {

bool IsULog(std::string_view first_bytes) {
  return first_bytes.size() >= sizeof(kULogMagic) &&
         std::memcmp(first_bytes.data(), kULogMagic, sizeof(kULogMagic)) == 0;
}

namespace {

// A name in a format (of a field, a type, the format) is at most this long (PX4's are under 64),
// and all the columns' flattened names of a log at most kMaxLogNameBytes: nested formats repeat
// their parents' names in every column's.
constexpr std::size_t kMaxNameBytes = 255;
constexpr std::size_t kMaxLogNameBytes = std::size_t{64} << 20;

enum class Scalar { kI8, kU8, kI16, kU16, kI32, kU32, kI64, kU64, kF32, kF64, kBool, kChar };

struct ScalarName {
  const char* name;
  Scalar type;
  std::size_t size;
};
constexpr ScalarName kScalars[] = {
    {"int8_t", Scalar::kI8, 1},    {"uint8_t", Scalar::kU8, 1},   {"int16_t", Scalar::kI16, 2},
    {"uint16_t", Scalar::kU16, 2}, {"int32_t", Scalar::kI32, 4},  {"uint32_t", Scalar::kU32, 4},
    {"int64_t", Scalar::kI64, 8},  {"uint64_t", Scalar::kU64, 8}, {"float", Scalar::kF32, 4},
    {"double", Scalar::kF64, 8},   {"bool", Scalar::kBool, 1},    {"char", Scalar::kChar, 1}};

const ScalarName* FindScalar(std::string_view name) {
  for (const ScalarName& s : kScalars) {
    if (name == s.name) return &s;
  }
  return nullptr;
}

// One field of a format as written: `type[count] name`.
struct Field {
  std::string type;  // a scalar's name or another format's
  std::size_t count = 1;
  bool array = false;
  std::string name;
};

// A numeric value of a flattened format: where it is in the message and what it is.
struct Leaf {
  std::string name;
  Scalar type;
  std::size_t offset;
};

struct Layout {
  std::vector<Leaf> leaves;  // numeric, padding and chars left out, at most kMaxFormatColumns
  std::shared_ptr<const std::vector<std::string>> names;  // the leaves' names
  std::size_t size = 0;                                   // all fields, packed
  std::size_t used = 0;  // the end of the last leaf: trailing padding may be left out
  int timestamp = -1;    // the leaf `timestamp` (uint64), if any
  int device_id = -1;    // the leaf `device_id`, if any
};

double Decode(Scalar type, const unsigned char* p) {
  switch (type) {
    case Scalar::kI8:
      return LoadLittle<std::int8_t>(p);
    case Scalar::kU8:
    case Scalar::kBool:
      return LoadLittle<std::uint8_t>(p);
    case Scalar::kI16:
      return LoadLittle<std::int16_t>(p);
    case Scalar::kU16:
      return LoadLittle<std::uint16_t>(p);
    case Scalar::kI32:
      return LoadLittle<std::int32_t>(p);
    case Scalar::kU32:
      return LoadLittle<std::uint32_t>(p);
    case Scalar::kI64:
      return static_cast<double>(LoadLittle<std::int64_t>(p));
    case Scalar::kU64:
      return static_cast<double>(LoadLittle<std::uint64_t>(p));
    case Scalar::kF32:
      return LoadLittle<float>(p);
    case Scalar::kF64:
      return LoadLittle<double>(p);
    case Scalar::kChar:
      return LoadLittle<std::int8_t>(p);
  }
  return 0;
}

class Reader {
 public:
  Reader(BinaryStream& in, const KeepStream& keep, const StoreColumns& store)
      : in_(in), keep_(keep), store_(store), subscribed_(65536, -1) {}

  DecodedLog Read();

 private:
  [[noreturn]] void Fail(std::uint64_t at, const std::string& why) const { in_.Fail(at, why); }
  void ParseFormat(std::string_view text, std::uint64_t at);
  const Layout& LayoutOf(const std::string& name, std::uint64_t at);
  // Appends the leaves of `format` at `base` (names after `prefix`) to `out`; its end offset.
  std::size_t Flatten(const std::string& format, const std::string& prefix, std::size_t base,
                      Layout* out, std::uint64_t at, int depth);
  void Subscribe(const unsigned char* p, std::size_t size, std::uint64_t at);
  void Data(const unsigned char* p, std::size_t size, std::uint64_t at);
  void KeyValue(const unsigned char* p, std::size_t size, bool parameter, std::uint64_t at);

  BinaryStream& in_;
  const KeepStream& keep_;
  const StoreColumns& store_;
  std::size_t total_columns_ = 0;
  std::size_t name_bytes_ = 0;  // of every column's name, all formats
  DecodedLog out_;
  std::unordered_map<std::string, std::vector<Field>> formats_;
  std::unordered_map<std::string, Layout> layouts_;
  std::vector<int> subscribed_;               // message id -> stream, -1 when none
  std::vector<const Layout*> stream_layout_;  // per stream
  std::map<std::pair<std::string, int>, int> stream_of_;
  bool data_section_ = false;
  std::uint64_t last_us_ = 0;  // the timestamp of the last data message read
};

void Reader::ParseFormat(std::string_view text, std::uint64_t at) {
  const std::size_t colon = text.find(':');
  if (colon == std::string_view::npos || colon == 0) {
    Fail(at, "a format definition without a name (\"name:type field;...\")");
  }
  const std::string name(text.substr(0, colon));
  if (name.size() > kMaxNameBytes) {
    Fail(at, "a format name longer than " + std::to_string(kMaxNameBytes) + " bytes");
  }
  std::vector<Field> fields;
  std::unordered_set<std::string> seen;
  std::string_view rest = text.substr(colon + 1);
  while (!rest.empty()) {
    const std::size_t end = std::min(rest.find(';'), rest.size());
    const std::string_view item = rest.substr(0, end);
    rest.remove_prefix(std::min(end + 1, rest.size()));
    if (item.empty()) continue;
    const std::size_t space = item.find(' ');
    if (space == std::string_view::npos || space == 0 || space + 1 == item.size()) {
      Fail(at, "format " + name + ": the field \"" + std::string(item) + "\" is not \"type name\"");
    }
    Field f;
    std::string_view type = item.substr(0, space);
    f.name = std::string(item.substr(space + 1));
    if (const std::size_t open = type.find('['); open != std::string_view::npos) {
      const std::size_t close = type.find(']', open);
      std::size_t count = 0;
      bool digits = close != std::string_view::npos && close == type.size() - 1 && close > open + 1;
      for (std::size_t i = open + 1; digits && i < close; ++i) {
        if (type[i] < '0' || type[i] > '9' || count > 65535)
          digits = false;
        else
          count = count * 10 + std::size_t(type[i] - '0');
      }
      if (!digits || count == 0 || count > 65535) {
        Fail(at, "format " + name + ": the array type \"" + std::string(type) +
                     "\" is not \"type[count]\"");
      }
      f.count = count;
      f.array = true;
      type = type.substr(0, open);
    }
    f.type = std::string(type);
    if (f.name.size() > kMaxNameBytes || f.type.size() > kMaxNameBytes) {
      Fail(at, "format " + name + ": a field or type name longer than " +
                   std::to_string(kMaxNameBytes) + " bytes");
    }
    if (!seen.insert(f.name).second) {
      Fail(at, "format " + name + " names the field " + f.name + " twice");
    }
    fields.push_back(std::move(f));
  }
  if (fields.empty()) Fail(at, "format " + name + " has no fields");
  formats_[name] = std::move(fields);
}

std::size_t Reader::Flatten(const std::string& format, const std::string& prefix, std::size_t base,
                            Layout* out, std::uint64_t at, int depth) {
  if (depth > 16) Fail(at, "format " + format + ": nested more than 16 deep (a cycle?)");
  const auto it = formats_.find(format);
  if (it == formats_.end()) Fail(at, "the format " + format + " is used but never defined");
  std::size_t offset = base;
  for (const Field& f : it->second) {
    const bool padding = f.name.rfind("_padding", 0) == 0;
    for (std::size_t i = 0; i < f.count; ++i) {
      // Past the format's last column only the offsets count: no names are made.
      const bool naming = out->leaves.size() < kMaxFormatColumns;
      const std::string name =
          naming ? prefix + f.name + (f.array ? "[" + std::to_string(i) + "]" : std::string())
                 : std::string();
      if (const ScalarName* s = FindScalar(f.type)) {
        if (!padding && s->type != Scalar::kChar) {
          if (naming) {
            out->leaves.push_back({name, s->type, offset});
            name_bytes_ += name.size();
            if (name_bytes_ > kMaxLogNameBytes) {
              Fail(at, Format("the formats subscribed name their fields in more than %zu bytes",
                              kMaxLogNameBytes));
            }
          }
          out->used = offset + s->size;
        }
        offset += s->size;
      } else {
        offset = Flatten(f.type, naming ? name + "." : std::string(), offset, out, at, depth + 1);
      }
      if (offset > 65535) Fail(at, "format " + format + " is larger than a message can be");
    }
  }
  return offset;
}

const Layout& Reader::LayoutOf(const std::string& name, std::uint64_t at) {
  if (const auto it = layouts_.find(name); it != layouts_.end()) return it->second;
  Layout layout;
  layout.size = Flatten(name, "", 0, &layout, at, 0);
  total_columns_ += layout.leaves.size();
  if (total_columns_ > kMaxLogColumns) {
    Fail(at, Format("the formats subscribed define more than %zu numeric fields in all",
                    kMaxLogColumns));
  }
  auto names = std::make_shared<std::vector<std::string>>();
  for (std::size_t i = 0; i < layout.leaves.size(); ++i) {
    const Leaf& l = layout.leaves[i];
    names->push_back(l.name);
    if (l.name == "timestamp" && l.type == Scalar::kU64) layout.timestamp = static_cast<int>(i);
    // An identifier: an integer type only (a float's NaN is no device).
    if (l.name == "device_id" && l.type != Scalar::kF32 && l.type != Scalar::kF64) {
      layout.device_id = static_cast<int>(i);
    }
  }
  // vehicle_imu names its accelerometer's id accel_device_id.
  for (std::size_t i = 0; i < layout.leaves.size() && layout.device_id < 0; ++i) {
    const Leaf& l = layout.leaves[i];
    if (l.name == "accel_device_id" && l.type != Scalar::kF32 && l.type != Scalar::kF64) {
      layout.device_id = static_cast<int>(i);
    }
  }
  layout.names = std::move(names);
  return layouts_.emplace(name, std::move(layout)).first->second;
}

void Reader::Subscribe(const unsigned char* p, std::size_t size, std::uint64_t at) {
  if (size < 4) Fail(at, "a subscription (A) message shorter than its fields");
  const int multi_id = p[0];
  const std::uint16_t id = LoadLittle<std::uint16_t>(p + 1);
  const std::string topic(reinterpret_cast<const char*>(p + 3), size - 3);
  if (formats_.find(topic) == formats_.end()) {
    Fail(at, "message id " + std::to_string(id) + " subscribes " + topic +
                 ", whose format was never defined");
  }
  const Layout& layout = LayoutOf(topic, at);
  const auto key = std::make_pair(topic, multi_id);
  auto [it, added] = stream_of_.emplace(key, static_cast<int>(out_.streams.size()));
  if (added) {
    DecodedStream s;
    s.topic = topic;
    s.type = topic;
    s.instance = multi_id;
    s.columns = layout.names;
    s.kept = keep_(s);
    if (s.kept) {
      if (store_) {
        s.stored = store_(s);
        for (std::size_t c : s.stored) {
          if (c >= layout.leaves.size()) Fail(at, "internal: a stored column beyond the format's");
        }
      } else {
        for (std::size_t c = 0; c < layout.leaves.size(); ++c) s.stored.push_back(c);
      }
    }
    out_.streams.push_back(std::move(s));
    stream_layout_.push_back(&layout);
  }
  subscribed_[id] = it->second;
}

void Reader::Data(const unsigned char* p, std::size_t size, std::uint64_t at) {
  if (size < 2) Fail(at, "a data (D) message shorter than its message id");
  const std::uint16_t id = LoadLittle<std::uint16_t>(p);
  const int index = subscribed_[id];
  if (index < 0) {
    Fail(at, "a data message of message id " + std::to_string(id) +
                 ", which no A message "
                 "subscribed");
  }
  DecodedStream& s = out_.streams[std::size_t(index)];
  const Layout& layout = *stream_layout_[std::size_t(index)];
  const std::size_t bytes = size - 2;
  if (bytes < layout.used || bytes > layout.size) {
    Fail(at, Format("a data message of %s holds %zu bytes where its format has %zu",
                    s.topic.c_str(), bytes, layout.size));
  }
  const unsigned char* d = p + 2;
  const std::uint64_t t =
      layout.timestamp >= 0
          ? LoadLittle<std::uint64_t>(d + layout.leaves[std::size_t(layout.timestamp)].offset)
          : 0;
  if (s.messages == 0) s.first_us = t;
  if (layout.device_id >= 0) {
    const Leaf& l = layout.leaves[std::size_t(layout.device_id)];
    const auto device_id = static_cast<std::uint64_t>(Decode(l.type, d + l.offset));
    if (s.messages == 0) {
      s.device_id = device_id;
    } else if (device_id != *s.device_id && s.unreadable.empty()) {
      // Another sensor in the same instance (a driver restarted on another bus, two logs
      // joined): its samples would be calibrated and exported as the first sensor's. Read, it is
      // refused here; listed (inspect), it is named as a stream accelcal cannot read.
      s.unreadable = Format(
          "its device_id changes from %llu to %llu at its message %zu (timestamp %llu us): two "
          "sensors' samples in one instance, which accelcal cannot calibrate as one (it reads no "
          "part of a log by device id)",
          static_cast<unsigned long long>(*s.device_id), static_cast<unsigned long long>(device_id),
          s.messages + 1, static_cast<unsigned long long>(t));
      if (s.kept) Fail(at, Format("%s instance %d: ", s.topic.c_str(), s.instance) + s.unreadable);
    }
  }
  s.last_us = t;
  if (layout.timestamp >= 0) last_us_ = std::max(last_us_, t);
  ++s.messages;
  if (s.kept) {
    for (std::size_t c : s.stored) {
      const Leaf& l = layout.leaves[c];
      s.values.push_back(Decode(l.type, d + l.offset));
    }
    s.offset.push_back(at);
  }
}

void Reader::KeyValue(const unsigned char* p, std::size_t size, bool parameter, std::uint64_t at) {
  if (size < 1 || std::size_t(p[0]) + 1 > size)
    Fail(at, "an information or parameter message whose key runs past its end");
  const std::string_view key(reinterpret_cast<const char*>(p + 1), p[0]);
  const unsigned char* value = p + 1 + p[0];
  const std::size_t value_size = size - 1 - p[0];
  const std::size_t space = key.find(' ');
  if (space == std::string_view::npos)
    Fail(at, "the key \"" + std::string(key) + "\" is not \"type name\"");
  const std::string_view type = key.substr(0, space);
  const std::string name(key.substr(space + 1));
  if (parameter) {
    double v = 0;
    if (type == "float" && value_size == 4) {
      v = LoadLittle<float>(value);
    } else if (type == "int32_t" && value_size == 4) {
      v = LoadLittle<std::int32_t>(value);
    } else {
      Fail(at, "the parameter " + name + " is of type " + std::string(type) + " with " +
                   std::to_string(value_size) + " bytes (float or int32_t expected)");
    }
    // A change among the data has no time of its own: it was set after the last message logged.
    // The definitions' value (the log's start) is the first, and there the value in force.
    if (!data_section_) out_.parameters[name] = v;
    out_.parameters.emplace(name, v);
    out_.parameter_history[name].emplace_back(data_section_ ? last_us_ : 0, v);
  } else if (type.rfind("char[", 0) == 0) {
    out_.info[name] = std::string(reinterpret_cast<const char*>(value), value_size);
  }
}

DecodedLog Reader::Read() {
  if (!in_.Need(16) || !IsULog(std::string_view(reinterpret_cast<const char*>(in_.data()), 16))) {
    Fail(0, "not a ULog file (its header is not \"ULog\" 01 12 35, version, time)");
  }
  out_.start_us = LoadLittle<std::uint64_t>(in_.data() + 8);
  in_.Skip(16);
  std::uint64_t appended = 0;  // where appended data begin (0: none)
  std::size_t whole = 0;       // messages read whole
  bool first = true;
  while (true) {
    const std::uint64_t at = in_.offset();
    if (!in_.Need(3)) {
      if (in_.available() > 0) {
        out_.truncated = Format("the log ends inside a message header at byte %llu",
                                static_cast<unsigned long long>(at));
        in_.Skip(in_.available());
      }
      break;
    }
    const std::size_t size = LoadLittle<std::uint16_t>(in_.data());
    const unsigned char type = in_.data()[2];
    if (appended > at && at + 3 + size > appended) {
      // The main part ends inside a message the logger never finished (it crashed, or the log
      // was closed): the appended data follow at their offset.
      while (in_.offset() < appended && in_.Need(1)) {
        in_.Skip(std::min<std::uint64_t>(in_.available(), appended - in_.offset()));
      }
      continue;
    }
    if (type == 0 && size == 0) {
      // Zeros to the end: space the logger had reserved and never wrote.
      std::uint64_t nonzero = 0;
      if (!in_.ZerosToEnd(&nonzero)) {
        Fail(at, Format("a message of type 0 where zeros to the end would mean space never "
                        "written, but byte %llu is not zero: the file is corrupt here",
                        static_cast<unsigned long long>(nonzero)));
      }
      out_.truncated = BinaryStream::ZerosMessage(at);
      break;
    }
    if (!in_.Need(3 + size)) {
      out_.truncated = Format(
          "the log ends inside a message at byte %llu (%zu of its %zu bytes "
          "there)",
          static_cast<unsigned long long>(at), in_.available(), size + 3);
      in_.Skip(in_.available());
      break;
    }
    const unsigned char* p = in_.data() + 3;
    switch (type) {
      case 'B': {
        if (!first) Fail(at, "a flag bits (B) message after the first message");
        if (size < 40) Fail(at, "a flag bits (B) message shorter than 40 bytes");
        const unsigned char* incompat = p + 8;
        if ((incompat[0] & ~1u) != 0 ||
            std::any_of(incompat + 1, incompat + 8, [](unsigned char c) { return c != 0; })) {
          Fail(at, "the log sets an incompatible flag this reader does not know (a newer ULog)");
        }
        if (incompat[0] & 1u) appended = LoadLittle<std::uint64_t>(p + 16);
        break;
      }
      case 'F':
        if (data_section_) Fail(at, "a format (F) message among the data");
        ParseFormat(std::string_view(reinterpret_cast<const char*>(p), size), at);
        break;
      case 'I':
        KeyValue(p, size, false, at);
        break;
      case 'P':
        // Among the data: a parameter changed while the log ran.
        KeyValue(p, size, true, at);
        break;
      case 'M':
      case 'Q':
      case 'L':
      case 'C':
      case 'S':
      case 'O':
      case 'R':
        break;
      case 'A':
        data_section_ = true;
        Subscribe(p, size, at);
        break;
      case 'D':
        if (!data_section_) Fail(at, "a data (D) message before any subscription");
        Data(p, size, at);
        break;
      default:
        Fail(at, Format("an unknown message type 0x%02x (%zu bytes): the file is corrupt here, or "
                        "of a ULog version this reader does not know",
                        type, size));
    }
    if (type == 'R') {
      if (size < 2) Fail(at, "an unsubscribe (R) message shorter than its message id");
      subscribed_[LoadLittle<std::uint16_t>(p)] = -1;
    }
    first = false;
    in_.Skip(3 + size);
    ++whole;
  }
  if (out_.truncated) *out_.truncated += Format(", after %zu whole messages", whole);
  out_.bytes = in_.offset();
  return std::move(out_);
}

}  // namespace

DecodedLog ReadULog(BinaryStream& in, const KeepStream& keep, const StoreColumns& store) {
  return Reader(in, keep, store).Read();
}

}  // namespace accelcal::internal
