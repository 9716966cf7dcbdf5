#include "accelcal/error.hpp"

#include <algorithm>

namespace accelcal {

InputError::InputError(std::string file, std::size_t line, std::string reason)
    : std::runtime_error(file + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": " +
                         reason),
      file_(std::move(file)),
      line_(line),
      reason_(std::move(reason)) {}

namespace {

// The library's own name of an option: its keyword, but for the flag that turns a default off.
std::string PlainName(const std::string& name) {
  return name == "no_crossval" ? "cross_validate false" : name;
}

}  // namespace

OptionError::OptionError(const std::string& marked)
    : std::invalid_argument(RenderOptionNames(marked, PlainName)), marked_(marked) {}

std::string RenderOptionNames(const std::string& marked,
                              const std::function<std::string(const std::string&)>& name_of) {
  std::string out;
  std::size_t at = 0;
  while (true) {
    const std::size_t open = marked.find("{{", at);
    if (open == std::string::npos) break;
    const std::size_t close = marked.find("}}", open + 2);
    if (close == std::string::npos) break;
    const std::string name = marked.substr(open + 2, close - open - 2);
    const bool word = !name.empty() && std::all_of(name.begin(), name.end(), [](char c) {
      return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
    });
    out.append(marked, at, open - at);
    out += word ? name_of(name) : marked.substr(open, close + 2 - open);
    at = close + 2;
  }
  out.append(marked, at, std::string::npos);
  return out;
}

}  // namespace accelcal
