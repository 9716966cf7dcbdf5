// ROS message types from their definitions, and ROS 1 serialisation (ros_message.hpp).
#include "io/ros_message.hpp"

#include <algorithm>
#include <map>
#include <set>

#include "accelcal/error.hpp"
#include "core/text_format.hpp"
#include "io/binary_stream.hpp"
#include "io/decoded_log.hpp"

namespace accelcal::internal {

namespace {

enum class Kind {
  kBool,
  kI8,
  kU8,
  kI16,
  kU16,
  kI32,
  kU32,
  kI64,
  kU64,
  kF32,
  kF64,
  kString,
  kTime,      // ROS 1 time: uint32 seconds, uint32 nanoseconds
  kDuration,  // ROS 1 duration: int32, int32
  kStamp2,    // ROS 2 builtin_interfaces/Time and Duration: int32 sec, uint32 nanosec
  kStruct
};

struct Builtin {
  const char* name;
  Kind kind;
  std::size_t size;  // serialised; a string's least (its count)
};
// ROS 1's built-in types; byte and char are its deprecated aliases of int8 and uint8.
constexpr Builtin kBuiltins1[] = {
    {"bool", Kind::kBool, 1},        {"int8", Kind::kI8, 1},       {"byte", Kind::kI8, 1},
    {"uint8", Kind::kU8, 1},         {"char", Kind::kU8, 1},       {"int16", Kind::kI16, 2},
    {"uint16", Kind::kU16, 2},       {"int32", Kind::kI32, 4},     {"uint32", Kind::kU32, 4},
    {"int64", Kind::kI64, 8},        {"uint64", Kind::kU64, 8},    {"float32", Kind::kF32, 4},
    {"float64", Kind::kF64, 8},      {"string", Kind::kString, 4}, {"time", Kind::kTime, 8},
    {"duration", Kind::kDuration, 8}};
// ROS 2's (byte and char are octets there); its times are the builtin_interfaces types.
constexpr Builtin kBuiltins2[] = {{"bool", Kind::kBool, 1},
                                  {"byte", Kind::kU8, 1},
                                  {"char", Kind::kU8, 1},
                                  {"int8", Kind::kI8, 1},
                                  {"uint8", Kind::kU8, 1},
                                  {"int16", Kind::kI16, 2},
                                  {"uint16", Kind::kU16, 2},
                                  {"int32", Kind::kI32, 4},
                                  {"uint32", Kind::kU32, 4},
                                  {"int64", Kind::kI64, 8},
                                  {"uint64", Kind::kU64, 8},
                                  {"float32", Kind::kF32, 4},
                                  {"float64", Kind::kF64, 8},
                                  {"string", Kind::kString, 4},
                                  {"builtin_interfaces/Time", Kind::kStamp2, 8},
                                  {"builtin_interfaces/Duration", Kind::kStamp2, 8}};

// A type's name without ROS 2's "/msg/" ("sensor_msgs/msg/Imu" is "sensor_msgs/Imu").
std::string Normal(std::string_view name) {
  std::string out(name);
  if (const std::size_t at = out.find("/msg/"); at != std::string::npos) out.erase(at, 4);
  return out;
}

// Nesting deeper than this is refused (a real message nests a handful of levels).
constexpr int kMaxDepth = 32;
// A count that saturates: a type's least size and its number of columns, which a hostile
// definition could make overflow with nested fixed arrays.
constexpr std::size_t kHuge = std::size_t{1} << 40;
std::size_t Times(std::size_t a, std::size_t b) {
  if (a == 0 || b == 0) return 0;
  return a > kHuge / b ? kHuge : a * b;
}
std::size_t Plus(std::size_t a, std::size_t b) { return std::min(kHuge, a + b); }

enum class Array { kNone, kFixed, kVariable };

struct Member {
  Kind kind;
  int type = -1;  // kStruct: index of its type
  std::string name;
  Array array = Array::kNone;
  std::size_t count = 1;  // kFixed
  // A scalar's serialised size (a string's least: its count) and CDR alignment, looked up once.
  std::size_t size = 0, align = 1;
};

struct Type {
  std::string name;
  std::vector<Member> members;
  std::size_t least = 0;    // bytes of its smallest message
  std::size_t columns = 0;  // its columns, saturating
};

std::string_view Trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t' || s.front() == '\r')) {
    s.remove_prefix(1);
  }
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) {
    s.remove_suffix(1);
  }
  return s;
}

bool IsName(std::string_view s, bool slash) {
  if (s.empty()) return false;
  for (char c : s) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '_' || (slash && c == '/');
    if (!ok) return false;
  }
  return true;
}

}  // namespace

// Where a message is being read: its bytes, and for CDR the origin its alignment counts from.
struct Cursor {
  const unsigned char* p = nullptr;
  const unsigned char* end = nullptr;
  const unsigned char* origin = nullptr;
  bool cdr = false;
  std::size_t column = 0;   // the next column's index
  std::size_t columns = 0;  // how many are stored
  // Skips CDR's padding before a value of `size` bytes (its alignment, at most 8).
  bool Align(std::size_t size) {
    if (!cdr || size <= 1) return true;
    const std::size_t pad = (size - std::size_t(p - origin) % size) % size;
    if (std::size_t(end - p) < pad) return false;
    p += pad;
    return true;
  }
};

struct RosMessageType::Impl {
  RosVersion version = RosVersion::kRos1;
  std::vector<Type> types;  // [0] the message's own
  std::shared_ptr<const std::vector<std::string>> columns;
  std::vector<std::size_t> microseconds;  // the time and duration columns
  std::optional<std::size_t> stamp;

  std::map<std::string, std::string_view> sections;  // a used type's definition text

  int Resolve(const std::string& name, std::vector<std::string>* stack);
  void Name(const Type& t, const std::string& prefix, std::vector<std::string>* out);
  // Reads a `t` at c (values into `values` when not null: outside variable-length arrays).
  bool Walk(const Type& t, Cursor& c, double* values) const;
  bool Element(const Member& m, Cursor& c, double* values) const;
  // A cursor at the first field of the message of `n` bytes at `p` (after ROS 2's CDR
  // encapsulation), or the reason it is not one.
  std::optional<std::string> Open(const unsigned char* p, std::size_t n, Cursor* c) const;
};

namespace {

// Reads a string at the cursor (its uint32 count, then its bytes), its bytes in `text`.
bool ReadString(Cursor& c, std::string_view* text) {
  if (!c.Align(4) || c.end - c.p < 4) return false;
  const std::uint32_t n = LoadLittle<std::uint32_t>(c.p);
  if (std::size_t(c.end - c.p) - 4 < n) return false;
  *text = std::string_view(reinterpret_cast<const char*>(c.p + 4), n);
  c.p += 4 + n;
  return true;
}

}  // namespace

// The index of type `name`'s resolved Type, parsed from its section (recursively).
int RosMessageType::Impl::Resolve(const std::string& name, std::vector<std::string>* stack) {
  for (std::size_t i = 0; i < types.size(); ++i) {
    if (types[i].name == name) return static_cast<int>(i);
  }
  if (std::find(stack->begin(), stack->end(), name) != stack->end()) {
    throw DataError("the message type " + name + " contains itself");
  }
  if (stack->size() >= std::size_t(kMaxDepth)) {
    throw DataError(Format("message types nested more than %d deep", kMaxDepth));
  }
  const auto section = sections.find(name);
  if (section == sections.end()) {
    throw DataError("the definition does not define the type " + name + " it uses");
  }
  const std::string package = name.substr(0, name.rfind('/') + 1);  // "pkg/" or ""
  stack->push_back(name);
  Type t;
  t.name = name;
  std::set<std::string> fields;
  std::string_view text = section->second;
  while (!text.empty()) {
    const std::size_t eol = text.find('\n');
    std::string_view line = text.substr(0, eol);
    text.remove_prefix(eol == std::string_view::npos ? text.size() : eol + 1);
    line = Trim(line.substr(0, line.find('#')));
    if (line.empty()) continue;
    const std::size_t space = line.find_first_of(" \t");
    if (space == std::string_view::npos) {
      throw DataError("the definition of " + name + " has the line \"" + std::string(line) +
                      "\", not a type and a name");
    }
    std::string_view type_text = line.substr(0, space);
    const std::string_view rest = Trim(line.substr(space));
    // "type NAME=value" (or "NAME = value") is a constant; ROS 2's "type name value" a field
    // with its default.
    const std::string_view field = rest.substr(0, rest.find_first_of(" \t="));
    if (Trim(rest.substr(field.size())).substr(0, 1) == "=") continue;
    if (!IsName(field, false)) {
      throw DataError("the definition of " + name + " names a field \"" + std::string(field) +
                      "\"");
    }
    Member m;
    m.name = std::string(field);
    if (const std::size_t bracket = type_text.find('['); bracket != std::string_view::npos) {
      const std::string_view inside = type_text.substr(bracket + 1);
      if (inside.empty() || inside.back() != ']') {
        throw DataError("the definition of " + name + " has the type \"" + std::string(type_text) +
                        "\"");
      }
      const std::string_view count = inside.substr(0, inside.size() - 1);
      if (count.empty() || (version == RosVersion::kRos2 && count.substr(0, 2) == "<=")) {
        // ROS 2's bounded sequence "T[<=N]" is serialised as an unbounded one.
        m.array = Array::kVariable;
      } else {
        m.array = Array::kFixed;
        std::size_t n = 0;
        for (char c : count) {
          if (c < '0' || c > '9' || n > kHuge) {
            throw DataError("the definition of " + name + " has the array type \"" +
                            std::string(type_text) + "\"");
          }
          n = n * 10 + std::size_t(c - '0');
        }
        m.count = n;
      }
      type_text = type_text.substr(0, bracket);
    }
    if (version == RosVersion::kRos2) {
      // ROS 2's bounded string "string<=N" is serialised as a string.
      type_text = type_text.substr(0, type_text.find("<="));
      if (type_text == "wstring") {
        throw DataError("the definition of " + name + " has a wstring field " + m.name +
                        ", which accelcal does not read");
      }
    }
    const std::string normal = Normal(type_text);
    const Builtin* builtin = nullptr;
    if (version == RosVersion::kRos1) {
      for (const Builtin& b : kBuiltins1) {
        if (normal == b.name) builtin = &b;
      }
    } else {
      for (const Builtin& b : kBuiltins2) {
        if (normal == b.name) builtin = &b;
      }
    }
    std::size_t least = 0, width = 0;
    if (builtin != nullptr) {
      m.kind = builtin->kind;
      least = builtin->size;
      m.size = builtin->size;
      m.align = m.kind == Kind::kTime || m.kind == Kind::kDuration || m.kind == Kind::kStamp2 ||
                        m.kind == Kind::kString
                    ? 4
                    : builtin->size;
      width = m.kind == Kind::kString ? 0 : 1;
    } else {
      if (!IsName(type_text, true)) {
        throw DataError("the definition of " + name + " uses the type \"" + std::string(type_text) +
                        "\"");
      }
      std::string full = normal == "Header"                      ? "std_msgs/Header"
                         : normal.find('/') != std::string::npos ? normal
                                                                 : package + normal;
      m.kind = Kind::kStruct;
      m.type = Resolve(full, stack);
      least = types[std::size_t(m.type)].least;
      width = types[std::size_t(m.type)].columns;
    }
    if (m.array == Array::kVariable) {
      t.least = Plus(t.least, 4);
    } else if (m.array == Array::kFixed) {
      t.least = Plus(t.least, Times(least, m.count));
      t.columns = Plus(t.columns, Times(width, m.count));
    } else {
      t.least = Plus(t.least, least);
      t.columns = Plus(t.columns, width);
    }
    if (!fields.insert(m.name).second) {
      throw DataError("the definition of " + name + " has two fields " + m.name);
    }
    t.members.push_back(std::move(m));
  }
  stack->pop_back();
  types.push_back(std::move(t));
  return static_cast<int>(types.size() - 1);
}

// The columns' names of `t` after `prefix`, up to kMaxFormatColumns in all.
void RosMessageType::Impl::Name(const Type& t, const std::string& prefix,
                                std::vector<std::string>* out) {
  for (const Member& m : t.members) {
    if (out->size() >= kMaxFormatColumns) return;
    if (m.kind == Kind::kString || m.array == Array::kVariable) continue;
    const std::string base = prefix + m.name;
    const std::size_t n = m.array == Array::kFixed ? m.count : 1;
    if (m.kind == Kind::kStruct && types[std::size_t(m.type)].columns == 0) continue;
    for (std::size_t i = 0; i < n && out->size() < kMaxFormatColumns; ++i) {
      const std::string name = m.array == Array::kFixed ? base + Format("[%zu]", i) : base;
      if (m.kind == Kind::kStruct) {
        Name(types[std::size_t(m.type)], name + ".", out);
      } else {
        if (m.kind == Kind::kTime || m.kind == Kind::kDuration || m.kind == Kind::kStamp2) {
          microseconds.push_back(out->size());
        }
        out->push_back(name);
      }
    }
  }
}

namespace {

double Scalar(Kind kind, const unsigned char* p) {
  switch (kind) {
    case Kind::kBool:
    case Kind::kU8:
      return LoadLittle<std::uint8_t>(p);
    case Kind::kI8:
      return LoadLittle<std::int8_t>(p);
    case Kind::kI16:
      return LoadLittle<std::int16_t>(p);
    case Kind::kU16:
      return LoadLittle<std::uint16_t>(p);
    case Kind::kI32:
      return LoadLittle<std::int32_t>(p);
    case Kind::kU32:
      return LoadLittle<std::uint32_t>(p);
    case Kind::kI64:
      return static_cast<double>(LoadLittle<std::int64_t>(p));
    case Kind::kU64:
      return static_cast<double>(LoadLittle<std::uint64_t>(p));
    case Kind::kF32:
      return LoadLittle<float>(p);
    case Kind::kF64:
      return LoadLittle<double>(p);
    case Kind::kTime:  // seconds and nanoseconds, in µs
      return static_cast<double>(LoadLittle<std::uint32_t>(p)) * 1e6 +
             static_cast<double>(LoadLittle<std::uint32_t>(p + 4)) * 1e-3;
    case Kind::kDuration:
      return static_cast<double>(LoadLittle<std::int32_t>(p)) * 1e6 +
             static_cast<double>(LoadLittle<std::int32_t>(p + 4)) * 1e-3;
    case Kind::kStamp2:
      return static_cast<double>(LoadLittle<std::int32_t>(p)) * 1e6 +
             static_cast<double>(LoadLittle<std::uint32_t>(p + 4)) * 1e-3;
    default:
      return 0;
  }
}

}  // namespace

// One element of member `m` (a scalar, a string, a struct) at the cursor; values beyond the
// cursor's columns (or with `values` null: inside a variable-length array) are not stored.
bool RosMessageType::Impl::Element(const Member& m, Cursor& c, double* values) const {
  if (m.kind == Kind::kStruct) return Walk(types[std::size_t(m.type)], c, values);
  if (m.kind == Kind::kString) {
    std::string_view skipped;
    return ReadString(c, &skipped);
  }
  if (!c.Align(m.align) || std::size_t(c.end - c.p) < m.size) return false;
  if (values != nullptr) {
    if (c.column < c.columns) values[c.column] = Scalar(m.kind, c.p);
    ++c.column;
  }
  c.p += m.size;
  return true;
}

bool RosMessageType::Impl::Walk(const Type& t, Cursor& c, double* values) const {
  for (const Member& m : t.members) {
    const std::size_t least = m.kind == Kind::kStruct ? types[std::size_t(m.type)].least : m.size;
    if (m.array == Array::kNone) {
      if (!Element(m, c, values)) return false;
      continue;
    }
    std::size_t n = m.count;
    double* into = values;
    if (m.array == Array::kVariable) {
      if (!c.Align(4) || c.end - c.p < 4) return false;
      n = LoadLittle<std::uint32_t>(c.p);
      c.p += 4;
      into = nullptr;  // not columns
    }
    if (least == 0) continue;  // elements of nothing (an empty type)
    if (n > std::size_t(c.end - c.p) / least) return false;
    if (m.kind != Kind::kStruct && m.kind != Kind::kString) {
      // Fixed-size scalars: aligned as their first, then packed (their size is their alignment's
      // multiple); skipped whole inside a variable-length array, else each a column.
      if (n > 0 && !c.Align(m.align)) return false;
      if (n > std::size_t(c.end - c.p) / least) return false;
      if (into != nullptr) {
        for (std::size_t i = 0; i < n; ++i, ++c.column) {
          if (c.column < c.columns) into[c.column] = Scalar(m.kind, c.p + i * least);
        }
      }
      c.p += n * least;
      continue;
    }
    for (std::size_t i = 0; i < n; ++i) {
      if (!Element(m, c, into)) return false;
    }
  }
  return true;
}

std::string_view KnownRos2Definition(std::string_view type) {
#define ACCELCAL_RULE \
  "================================================================================\n"
  // The types they use, as ROS 2 writes them after a rule.
  static constexpr char kHeader[] = ACCELCAL_RULE
      "MSG: std_msgs/Header\n"
      "builtin_interfaces/Time stamp\n"
      "string frame_id\n" ACCELCAL_RULE
      "MSG: builtin_interfaces/Time\n"
      "int32 sec\n"
      "uint32 nanosec\n";
  static constexpr char kVector3[] = ACCELCAL_RULE
      "MSG: geometry_msgs/Vector3\n"
      "float64 x\n"
      "float64 y\n"
      "float64 z\n";
  static const std::string kImu = std::string(
                                      "std_msgs/Header header\n"
                                      "geometry_msgs/Quaternion orientation\n"
                                      "float64[9] orientation_covariance\n"
                                      "geometry_msgs/Vector3 angular_velocity\n"
                                      "float64[9] angular_velocity_covariance\n"
                                      "geometry_msgs/Vector3 linear_acceleration\n"
                                      "float64[9] linear_acceleration_covariance\n") +
                                  kHeader +
                                  ACCELCAL_RULE
                                  "MSG: geometry_msgs/Quaternion\n"
                                  "float64 x 0\n"
                                  "float64 y 0\n"
                                  "float64 z 0\n"
                                  "float64 w 1\n" +
                                  kVector3;
  static const std::string kTemperature = std::string(
                                              "std_msgs/Header header\n"
                                              "float64 temperature\n"
                                              "float64 variance\n") +
                                          kHeader;
  static const std::string kMagneticField = std::string(
                                                "std_msgs/Header header\n"
                                                "geometry_msgs/Vector3 magnetic_field\n"
                                                "float64[9] magnetic_field_covariance\n") +
                                            kHeader + kVector3;
#undef ACCELCAL_RULE
  const std::string name = Normal(type);
  if (name == "sensor_msgs/Imu") return kImu;
  if (name == "sensor_msgs/Temperature") return kTemperature;
  if (name == "sensor_msgs/MagneticField") return kMagneticField;
  return {};
}

RosMessageType::RosMessageType(std::string_view type, std::string_view definition,
                               RosVersion version)
    : impl_(std::make_unique<Impl>()) {
  impl_->version = version;
  // Sections: the type's own, then one per "MSG: name" after a line of '='.
  std::string current = Normal(type);
  std::size_t begin = 0;
  bool separator = false;
  for (std::size_t at = 0; at <= definition.size();) {
    const std::size_t eol = std::min(definition.find('\n', at), definition.size());
    const std::string_view line = Trim(definition.substr(at, eol - at));
    const bool rule = line.size() >= 3 && line.find_first_not_of('=') == std::string_view::npos;
    if (rule || eol == definition.size()) {
      const std::size_t stop = rule ? at : definition.size();
      if (!separator) impl_->sections.emplace(current, definition.substr(begin, stop - begin));
      separator = rule;
    } else if (separator && line.substr(0, 4) == "MSG:") {
      current = Normal(Trim(line.substr(4)));
      begin = eol + 1;
      separator = false;
    } else if (separator && !line.empty()) {
      throw DataError("the definition of " + std::string(type) +
                      " has a section that does not begin \"MSG: package/Type\"");
    }
    at = eol + 1;
  }
  std::vector<std::string> stack;
  impl_->types.reserve(16);
  const int own = impl_->Resolve(Normal(type), &stack);
  // The message's own type first: Resolve appends each type after those it uses.
  std::swap(impl_->types[0], impl_->types[std::size_t(own)]);
  for (Type& t : impl_->types) {
    for (Member& m : t.members) {
      if (m.type == 0) {
        m.type = own;
      } else if (m.type == own) {
        m.type = 0;
      }
    }
  }
  auto names = std::make_shared<std::vector<std::string>>();
  impl_->Name(impl_->types[0], "", names.get());
  const auto stamp = std::find(names->begin(), names->end(), "header.stamp");
  const Type& own_type = impl_->types[0];
  if (stamp != names->end() && !own_type.members.empty() && own_type.members[0].name == "header" &&
      own_type.members[0].kind == Kind::kStruct &&
      impl_->types[std::size_t(own_type.members[0].type)].name == "std_msgs/Header") {
    impl_->stamp = std::size_t(stamp - names->begin());
  }
  impl_->columns = std::move(names);
  impl_->sections.clear();
}

RosMessageType::~RosMessageType() = default;
RosMessageType::RosMessageType(RosMessageType&&) noexcept = default;

const std::string& RosMessageType::name() const { return impl_->types[0].name; }
const std::shared_ptr<const std::vector<std::string>>& RosMessageType::columns() const {
  return impl_->columns;
}
std::optional<std::size_t> RosMessageType::stamp() const { return impl_->stamp; }
const std::vector<std::size_t>& RosMessageType::microseconds() const { return impl_->microseconds; }

std::optional<std::string> RosMessageType::Impl::Open(const unsigned char* p, std::size_t n,
                                                      Cursor* c) const {
  *c = Cursor{p, p + n, p, false, 0, columns->size()};
  if (version == RosVersion::kRos2) {
    // The RTPS encapsulation: a representation identifier and options; ROS 2 writes CDR,
    // little-endian (00 01), its alignment counted from after these 4 bytes.
    if (n < 4) return Format("a %zu-byte message, shorter than its CDR encapsulation", n);
    if (p[0] != 0 || p[1] != 1) {
      return Format(
          "a message encoded as %02x %02x, not little-endian CDR (00 01), which "
          "accelcal reads",
          p[0], p[1]);
    }
    c->p = c->origin = p + 4;
    c->cdr = true;
  }
  return std::nullopt;
}

std::optional<std::string> RosMessageType::Decode(const unsigned char* p, std::size_t n,
                                                  double* values) const {
  Cursor c;
  if (std::optional<std::string> why = impl_->Open(p, n, &c)) return why;
  // Bytes a whole message may end with after its fields: CDR pads a message to 4 bytes.
  const std::size_t padding = c.cdr ? 3 : 0;
  if (!impl_->Walk(impl_->types[0], c, values)) {
    return Format("a %zu-byte message, shorter than its fields", n);
  }
  if (std::size_t(c.end - c.p) > padding) {
    return Format("a %zu-byte message whose fields end after %zu bytes", n,
                  static_cast<std::size_t>(c.p - p));
  }
  return std::nullopt;
}

std::optional<std::string> RosMessageType::FrameId(const unsigned char* p, std::size_t n) const {
  if (!impl_->stamp) return std::nullopt;  // no std_msgs/Header first
  Cursor c;
  if (impl_->Open(p, n, &c)) return std::nullopt;
  const Type& header = impl_->types[std::size_t(impl_->types[0].members[0].type)];
  for (const Member& m : header.members) {
    if (m.array != Array::kNone) return std::nullopt;  // not a std_msgs/Header as ROS has it
    if (m.kind == Kind::kString && m.name == "frame_id") {
      std::string_view id;
      if (!ReadString(c, &id)) return std::nullopt;
      // CDR counts a string's terminating NUL.
      if (c.cdr && !id.empty() && id.back() == '\0') id.remove_suffix(1);
      return std::string(id);
    }
    if (!impl_->Element(m, c, nullptr)) return std::nullopt;
  }
  return std::nullopt;
}

}  // namespace accelcal::internal
