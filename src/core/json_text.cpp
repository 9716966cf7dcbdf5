#include "accelcal/json_text.hpp"

#include <charconv>
#include <cmath>

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

void AppendScalar(const Json& value, std::string* out) {
  if (value.is_number_float()) {
    const double v = value.get<double>();
    if (!std::isfinite(v)) {
      *out += "null";
      return;
    }
    char buf[32];
    const auto result = std::to_chars(buf, buf + sizeof buf, v);
    out->append(buf, result.ptr);
    return;
  }
  // Strings (escaped, invalid UTF-8 replaced), integers, booleans, null: nlohmann's own text.
  *out += value.dump(-1, ' ', false, Json::error_handler_t::replace);
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
  for (const auto& member : value.items()) {
    if (!first) *out += ',';
    if (one_line) {
      if (!first) *out += ' ';
    } else {
      *out += '\n';
      *out += indent;
    }
    first = false;
    if (!array) {
      AppendScalar(Json(member.key()), out);
      *out += ": ";
    }
    Append(member.value(), depth + 1, one_line, out);
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
