// YAML as the exports write it: accelcal's calibration file as YAML (JsonToYaml), and the
// numbers and strings of the YAML formats (Kalibr, OpenVINS, ROS), which YAML 1.1 readers take
// as the same values.
#include <algorithm>

#include "output/export_common.hpp"

namespace accelcal::exports {

// A YAML double-quoted scalar holding exactly `text` (UTF-8) in YAML 1.1 and 1.2 readers: '"' and
// '\\' escaped, tab, line feed and carriage return as \t, \n, \r, the other characters of
// internal::IsInvisible (which readers refuse, or read as line breaks and fold) as \xHH or \uHHHH;
// printable Unicode as it is. A byte that is no UTF-8 (a JSON document holds none) is U+FFFD.
std::string YamlQuoted(std::string_view text) {
  return "\"" + internal::EscapeText(text, internal::Escaping::kYamlDoubleQuoted) + "\"";
}
namespace {

// YAML emission of a JSON value at an indentation.
bool IsScalar(const ordered_json& j) { return !j.is_object() && !j.is_array(); }
bool IsFlowArray(const ordered_json& j) {
  if (!j.is_array()) return false;
  for (const auto& e : j) {
    if (!(IsScalar(e) || (e.is_array() && std::all_of(e.begin(), e.end(), IsScalar)))) {
      return false;
    }
  }
  return true;
}
// A key plain when it is an identifier that no YAML 1.1 reader takes for a boolean or null.
std::string YamlKey(const std::string& key) {
  bool plain = !key.empty() && (IsAsciiLetter(key[0]) || key[0] == '_');
  for (const char c : key) plain = plain && IsIdentifierChar(c);
  std::string lower;
  for (const char c : key) lower += internal::AsciiLower(c);
  for (const char* word : {"null", "true", "false", "yes", "no", "on", "off", "y", "n"}) {
    plain = plain && lower != word;
  }
  return plain ? key : YamlQuoted(key);
}
// JSON's spelling of a scalar, except that a float always has a '.' in its mantissa: YAML 1.1
// readers (PyYAML) take 1e-05 for a string, 1.0e-05 for a number.
std::string YamlFlow(const ordered_json& j) {
  if (j.is_array()) {
    std::string text = "[";
    for (std::size_t i = 0; i < j.size(); ++i) text += (i ? ", " : "") + YamlFlow(j[i]);
    return text + "]";
  }
  if (j.is_string()) return YamlQuoted(j.get_ref<const std::string&>());
  std::string text = j.dump();
  if (j.is_number_float() && text.find('.') == std::string::npos) {
    const std::size_t e = text.find_first_of("eE");
    text.insert(e == std::string::npos ? text.size() : e, ".0");
  }
  return text;
}
void EmitYaml(const ordered_json& j, int indent, std::string* out);
void EmitYamlValue(const ordered_json& j, int indent, std::string* out) {
  if (IsScalar(j) || IsFlowArray(j) || j.empty()) {
    *out += " " + YamlFlow(j) + "\n";  // JSON scalars and flow arrays are valid YAML
  } else {
    *out += "\n";
    EmitYaml(j, indent + 2, out);
  }
}
void EmitYaml(const ordered_json& j, int indent, std::string* out) {
  const std::string pad(static_cast<std::size_t>(indent), ' ');
  if (j.is_object()) {
    for (const auto& [key, value] : j.items()) {
      *out += pad + YamlKey(key) + ":";
      EmitYamlValue(value, indent, out);
    }
  } else {
    for (const auto& value : j) {
      if (value.is_object() && !value.empty()) {
        std::string item;
        EmitYaml(value, indent + 2, &item);
        *out += pad + "- " + item.substr(static_cast<std::size_t>(indent) + 2);
      } else {
        *out += pad + "-";
        EmitYamlValue(value, indent, out);
      }
    }
  }
}

}  // namespace

// A number for a YAML file: as Number, with a '.' in every float's mantissa, so that YAML 1.1
// readers (PyYAML, Kalibr's) read 5e-05 as a number, not a string.
std::string YamlNumber(double value) { return YamlFlow(ordered_json(Finite(value))); }

}  // namespace accelcal::exports

namespace accelcal {

std::string JsonToYaml(const std::string& json_text) {
  const nlohmann::ordered_json doc = nlohmann::ordered_json::parse(json_text);
  std::string out = "%YAML 1.2\n---\n";
  exports::EmitYaml(doc, 0, &out);
  return out;
}

}  // namespace accelcal
