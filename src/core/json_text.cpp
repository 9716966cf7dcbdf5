#include "accelcal/json_text.hpp"

#include <charconv>
#include <cmath>
#include <cstdint>

namespace accelcal {

namespace {

using Json = nlohmann::ordered_json;

// Whether a container holds an array with an object in it, at any depth: such a container is
// written one member per line.
bool HoldsArrayOfObjects(const Json& value) {
  if (value.is_array()) {
    for (const Json& element : value) {
      if (element.is_object() || HoldsArrayOfObjects(element)) return true;
    }
  } else if (value.is_object()) {
    for (const auto& member : value.items()) {
      if (HoldsArrayOfObjects(member.value())) return true;
    }
  }
  return false;
}

// A string as JSON: quoted as it is when every byte is printable ASCII other than '"' and '\\'
// (names, numbers' labels, most messages), else through nlohmann's escaping.
void AppendString(const std::string& text, std::string* out) {
  for (const char c : text) {
    if (c < 0x20 || c > 0x7e || c == '"' || c == '\\') {
      *out += Json(text).dump(-1, ' ', false, Json::error_handler_t::replace);
      return;
    }
  }
  *out += '"';
  *out += text;
  *out += '"';
}

template <typename Number>
void AppendNumber(Number v, std::string* out) {
  char buf[32];
  const auto result = std::to_chars(buf, buf + sizeof buf, v);
  out->append(buf, result.ptr);
}

void AppendScalar(const Json& value, std::string* out) {
  switch (value.type()) {
    case Json::value_t::number_float: {
      const double v = value.get<double>();
      if (std::isfinite(v)) {
        AppendNumber(v, out);
      } else {
        *out += "null";
      }
      return;
    }
    case Json::value_t::number_integer:
      AppendNumber(value.get<std::int64_t>(), out);
      return;
    case Json::value_t::number_unsigned:
      AppendNumber(value.get<std::uint64_t>(), out);
      return;
    case Json::value_t::string:
      AppendString(value.get_ref<const std::string&>(), out);
      return;
    default:  // booleans, null (and binary, which no document here holds): nlohmann's own text
      *out += value.dump(-1, ' ', false, Json::error_handler_t::replace);
  }
}

void Append(const Json& value, int depth, bool inline_layout, std::string* out) {
  if (!value.is_structured()) {
    AppendScalar(value, out);
    return;
  }
  const bool array = value.is_array();
  const char open = array ? '[' : '{', close = array ? ']' : '}';
  if (value.empty()) {
    *out += open;
    *out += close;
    return;
  }
  const bool one_line = inline_layout || (depth > 0 && !HoldsArrayOfObjects(value));
  const std::string indent(static_cast<std::size_t>(2 * (depth + 1)), ' ');
  *out += open;
  bool first = true;
  const auto separate = [&] {
    if (!first) *out += ',';
    if (one_line) {
      if (!first) *out += ' ';
    } else {
      *out += '\n';
      *out += indent;
    }
    first = false;
  };
  if (array) {
    for (const Json& element : value) {
      separate();
      Append(element, depth + 1, one_line, out);
    }
  } else {
    for (auto member = value.begin(); member != value.end(); ++member) {
      separate();
      AppendString(member.key(), out);
      *out += ": ";
      Append(member.value(), depth + 1, one_line, out);
    }
  }
  if (!one_line) {
    *out += '\n';
    out->append(static_cast<std::size_t>(2 * depth), ' ');
  }
  *out += close;
}

}  // namespace

std::string JsonText(const nlohmann::ordered_json& doc) {
  std::string out;
  Append(doc, 0, false, &out);
  out += '\n';
  return out;
}

}  // namespace accelcal
