// Autopilot parameter files (parameter_file.hpp).
#include "accelcal/parameter_file.hpp"

#include <cmath>
#include <vector>

#include "accelcal/error.hpp"
#include "core/text_format.hpp"
#include "io/number_parser.hpp"

namespace accelcal {

namespace {

bool IsParameterName(std::string_view s) {
  if (s.empty() || s.size() > 16) return false;  // MAVLink's param_id holds 16 characters
  for (char c : s) {
    if (!((c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_')) {
      return false;
    }
  }
  return true;
}

}  // namespace

std::map<std::string, double> ParseParameterFile(std::string_view text, const std::string& source) {
  std::map<std::string, double> out;
  std::size_t number = 0;
  while (!text.empty()) {
    ++number;
    const std::size_t eol = text.find('\n');
    std::string_view line = text.substr(0, eol);
    text.remove_prefix(eol == std::string_view::npos ? text.size() : eol + 1);
    line = line.substr(0, line.find('#'));
    // Its fields, split at commas, tabs and spaces.
    std::vector<std::string_view> fields;
    for (std::size_t at = 0; at < line.size();) {
      const std::size_t end = line.find_first_of(", \t\r", at);
      const std::size_t stop = end == std::string_view::npos ? line.size() : end;
      if (stop > at) fields.push_back(line.substr(at, stop - at));
      at = stop + 1;
    }
    if (fields.empty()) continue;
    std::string_view name, value;
    if (fields.size() == 2) {
      name = fields[0], value = fields[1];
    } else if (fields.size() == 3 && IsParameterName(fields[0])) {  // MAVProxy: NAME VALUE TYPE
      name = fields[0], value = fields[1];
    } else if (fields.size() == 5) {  // QGroundControl: vehicle component NAME VALUE type
      name = fields[2], value = fields[3];
    } else {
      throw InputError(source, number,
                       "not a parameter: NAME,VALUE (Mission Planner), NAME VALUE (MAVProxy) "
                       "or vehicle, component, NAME, VALUE, type (QGroundControl)");
    }
    if (!IsParameterName(name)) {
      throw InputError(source, number,
                       "\"" + internal::VisibleLine(name) + "\" is not a parameter name");
    }
    double v = 0;
    if (!internal::ParseNumber(value, &v) || !std::isfinite(v)) {
      throw InputError(source, number,
                       "the value of " + std::string(name) + " is not a finite number");
    }
    const auto [it, added] = out.emplace(std::string(name), v);
    if (!added && it->second != v) {
      throw InputError(source, number, std::string(name) + " given twice, with different values");
    }
  }
  if (out.empty()) throw InputError(source, 0, "no parameter in the file");
  return out;
}

}  // namespace accelcal
