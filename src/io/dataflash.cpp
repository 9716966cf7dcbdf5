// ArduPilot DataFlash reader (dataflash.hpp).
#include "io/dataflash.hpp"

#include <array>
#include <cstring>
#include <memory>

#include "accelcal/error.hpp"
#include "core/text_format.hpp"

namespace accelcal::internal {

namespace {

constexpr unsigned char kHead1 = 0xA3, kHead2 = 0x95, kFmtType = 128;
constexpr std::size_t kFmtLength = 89;  // header 3, type 1, length 1, name 4, format 16, labels 64

// A field of a record: where it is, how to read it, and what it is worth as a number.
struct Field {
  char code;
  std::size_t offset;  // from the record's first byte (its header included)
  double scale = 1;
  bool numeric = true;
  std::string label;
};

struct Type {
  bool defined = false;
  std::string name;
  std::size_t length = 0;
  std::vector<Field> fields;
  std::vector<std::size_t> numeric;  // indices of the numeric fields: the columns
  std::shared_ptr<const std::vector<std::string>> names;  // their labels
  std::string format;                                     // its format characters
  int time = -1, instance = -1;                           // the TimeUS and I fields
  int param_name = -1, param_value = -1;                  // a PARM record's Name and Value
};

// The size of a format character's field (0: unknown).
std::size_t SizeOf(char c) {
  switch (c) {
    case 'b':
    case 'B':
    case 'M':
      return 1;
    case 'h':
    case 'H':
    case 'c':
    case 'C':
      return 2;
    case 'i':
    case 'I':
    case 'f':
    case 'e':
    case 'E':
    case 'L':
    case 'n':
      return 4;
    case 'd':
    case 'q':
    case 'Q':
      return 8;
    case 'N':
      return 16;
    case 'Z':
    case 'a':
      return 64;
    default:
      return 0;
  }
}

double Decode(char c, const unsigned char* p) {
  switch (c) {
    case 'b':
      return LoadLittle<std::int8_t>(p);
    case 'B':
    case 'M':
      return LoadLittle<std::uint8_t>(p);
    case 'h':
      return LoadLittle<std::int16_t>(p);
    case 'H':
      return LoadLittle<std::uint16_t>(p);
    case 'c':
      return LoadLittle<std::int16_t>(p) * 0.01;
    case 'C':
      return LoadLittle<std::uint16_t>(p) * 0.01;
    case 'i':
      return LoadLittle<std::int32_t>(p);
    case 'I':
      return LoadLittle<std::uint32_t>(p);
    case 'e':
      return LoadLittle<std::int32_t>(p) * 0.01;
    case 'E':
      return LoadLittle<std::uint32_t>(p) * 0.01;
    case 'L':
      return LoadLittle<std::int32_t>(p) * 1e-7;
    case 'f':
      return LoadLittle<float>(p);
    case 'd':
      return LoadLittle<double>(p);
    case 'q':
      return static_cast<double>(LoadLittle<std::int64_t>(p));
    case 'Q':
      return static_cast<double>(LoadLittle<std::uint64_t>(p));
    default:
      return 0;
  }
}

// A fixed-size text field, to its first NUL.
std::string Text(const unsigned char* p, std::size_t n) {
  const char* s = reinterpret_cast<const char*>(p);
  return std::string(s, strnlen(s, n));
}

class Reader {
 public:
  Reader(BinaryStream& in, const KeepStream& keep, const StoreColumns& store)
      : in_(in), keep_(keep), store_(store) {}
  DecodedLog Read();

 private:
  [[noreturn]] void Fail(std::uint64_t at, const std::string& why) const { in_.Fail(at, why); }
  void Define(const unsigned char* r, std::uint64_t at);
  void Record(const Type& type, const unsigned char* r, std::uint64_t at);

  BinaryStream& in_;
  const KeepStream& keep_;
  const StoreColumns& store_;
  DecodedLog out_;
  std::array<Type, 256> types_;
  std::array<bool, 256> used_{};                          // a record of the type was read
  std::map<std::pair<int, int>, std::size_t> stream_of_;  // (type, instance) -> stream
};

void Reader::Define(const unsigned char* r, std::uint64_t at) {
  const int number = r[3];
  const std::size_t length = r[4];
  Type t;
  t.defined = true;
  t.name = Text(r + 5, 4);
  const std::string format = Text(r + 9, 16);
  const std::string labels = Text(r + 25, 64);
  if (number == kFmtType) {
    if (length != kFmtLength || format != "BBnNZ") {
      Fail(at, "a FMT record that redefines FMT otherwise than as 89 bytes of BBnNZ");
    }
    return;
  }
  std::vector<std::string> names;
  for (std::size_t start = 0;;) {
    const std::size_t comma = labels.find(',', start);
    names.push_back(labels.substr(start, comma - start));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (names.size() != format.size()) {
    Fail(at, Format("the FMT of %s has %zu format characters and %zu column labels", t.name.c_str(),
                    format.size(), names.size()));
  }
  std::size_t offset = 3;
  for (std::size_t i = 0; i < format.size(); ++i) {
    const char c = format[i];
    const std::size_t size = SizeOf(c);
    if (size == 0) {
      Fail(at, Format("the FMT of %s has the format character '%c', which DataFlash does not "
                      "define",
                      t.name.c_str(), c));
    }
    Field f{c, offset, 1, !(c == 'n' || c == 'N' || c == 'Z' || c == 'a'), names[i]};
    if (f.numeric) t.numeric.push_back(i);
    if (names[i] == "TimeUS" && c == 'Q') t.time = static_cast<int>(i);
    if (names[i] == "I" && (c == 'B' || c == 'b')) t.instance = static_cast<int>(i);
    if (names[i] == "Name" && c == 'N') t.param_name = static_cast<int>(i);
    if (names[i] == "Value" && c == 'f') t.param_value = static_cast<int>(i);
    for (const Field& before : t.fields) {
      if (before.label == f.label) {
        Fail(at, "the FMT of " + t.name + " labels two columns " + f.label);
      }
    }
    t.fields.push_back(std::move(f));
    offset += size;
  }
  auto labels_kept = std::make_shared<std::vector<std::string>>();
  for (std::size_t i : t.numeric) labels_kept->push_back(t.fields[i].label);
  t.names = std::move(labels_kept);
  if (offset != length) {
    Fail(at, Format("the FMT of %s says %zu bytes, but its fields (%s) take %zu", t.name.c_str(),
                    length, format.c_str(), offset));
  }
  t.length = length;
  Type& before = types_[std::size_t(number)];
  if (before.defined && used_[std::size_t(number)] &&
      (before.name != t.name || before.length != t.length || before.format != format ||
       *before.names != *t.names)) {
    // Its records so far were read by the old layout, and a stream holds one layout.
    Fail(at, Format("a FMT record redefines type %d (%s, %s) as %s, %s%s after records of it: "
                    "the log mixes two layouts of it",
                    number, before.name.c_str(), before.format.c_str(), t.name.c_str(),
                    format.c_str(), *before.names != *t.names ? " with other labels" : ""));
  }
  t.format = format;
  before = std::move(t);
}

void Reader::Record(const Type& type, const unsigned char* r, std::uint64_t at) {
  if (type.param_name >= 0 && type.param_value >= 0 && type.name == "PARM") {
    const std::string name = Text(r + type.fields[std::size_t(type.param_name)].offset, 16);
    const double value = LoadLittle<float>(r + type.fields[std::size_t(type.param_value)].offset);
    out_.parameters.emplace(name, value);
    out_.parameter_history[name].emplace_back(
        type.time >= 0 ? LoadLittle<std::uint64_t>(r + type.fields[std::size_t(type.time)].offset)
                       : 0,
        value);
  }
  const int instance =
      type.instance >= 0
          ? static_cast<int>(Decode(type.fields[std::size_t(type.instance)].code,
                                    r + type.fields[std::size_t(type.instance)].offset))
          : 0;
  const int number = r[2];
  auto [it, added] = stream_of_.emplace(std::make_pair(number, instance), out_.streams.size());
  if (added) {
    DecodedStream s;
    s.topic = type.name;
    s.type = type.name;
    s.instance = instance;
    s.columns = type.names;
    s.kept = keep_(s);
    if (s.kept) {
      if (store_) {
        s.stored = store_(s);
      } else {
        for (std::size_t c = 0; c < type.numeric.size(); ++c) s.stored.push_back(c);
      }
    }
    out_.streams.push_back(std::move(s));
  }
  DecodedStream& s = out_.streams[it->second];
  const std::uint64_t t =
      type.time >= 0 ? LoadLittle<std::uint64_t>(r + type.fields[std::size_t(type.time)].offset)
                     : 0;
  if (s.messages == 0) s.first_us = t;
  s.last_us = t;
  ++s.messages;
  if (s.kept) {
    for (std::size_t c : s.stored) {
      const Field& f = type.fields[type.numeric.at(c)];
      s.values.push_back(Decode(f.code, r + f.offset));
    }
    s.offset.push_back(at);
  }
}

DecodedLog Reader::Read() {
  std::size_t whole = 0;
  while (true) {
    const std::uint64_t at = in_.offset();
    if (!in_.Need(3)) {
      if (in_.available() > 0) {
        out_.truncated = Format("the log ends inside a record header at byte %llu",
                                static_cast<unsigned long long>(at));
        in_.Skip(in_.available());
      }
      break;
    }
    const unsigned char* h = in_.data();
    if (h[0] != kHead1 || h[1] != kHead2) {
      if (h[0] == 0 && h[1] == 0 && h[2] == 0) {
        // Zeros to the end: space the logger had reserved and never wrote.
        std::uint64_t nonzero = 0;
        if (!in_.ZerosToEnd(&nonzero)) {
          Fail(nonzero, "not zero, after zeros from byte " + std::to_string(at) +
                            ": the file is corrupt here");
        }
        out_.truncated = BinaryStream::ZerosMessage(at);
        break;
      }
      Fail(at,
           Format("a record begins %02x %02x, not A3 95: the file is corrupt here", h[0], h[1]));
    }
    const int number = h[2];
    const std::size_t length = number == kFmtType ? kFmtLength : types_[std::size_t(number)].length;
    if (number != kFmtType && !types_[std::size_t(number)].defined) {
      Fail(at, Format("a record of type %d, which no FMT record defined before it", number));
    }
    if (!in_.Need(length)) {
      out_.truncated = Format(
          "the log ends inside a record at byte %llu (%zu of its %zu bytes "
          "there)",
          static_cast<unsigned long long>(at), in_.available(), length);
      in_.Skip(in_.available());
      break;
    }
    if (number == kFmtType) {
      Define(in_.data(), at);
    } else {
      Record(types_[std::size_t(number)], in_.data(), at);
      used_[std::size_t(number)] = true;
    }
    in_.Skip(length);
    ++whole;
  }
  if (out_.truncated) *out_.truncated += Format(", after %zu whole records", whole);
  out_.bytes = in_.offset();
  return std::move(out_);
}

}  // namespace

bool IsDataFlash(std::string_view first_bytes) {
  return first_bytes.size() >= 3 && static_cast<unsigned char>(first_bytes[0]) == kHead1 &&
         static_cast<unsigned char>(first_bytes[1]) == kHead2 &&
         static_cast<unsigned char>(first_bytes[2]) == kFmtType;
}

DecodedLog ReadDataFlash(BinaryStream& in, const KeepStream& keep, const StoreColumns& store) {
  return Reader(in, keep, store).Read();
}

}  // namespace accelcal::internal
