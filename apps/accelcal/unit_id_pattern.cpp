// batch --unit-id's regular expression, searched in bounded time. The only file of the tool that
// uses <regex>, which it configures: the bound below holds for every std::regex of the program.
//
// libstdc++'s std::regex backtracks by default: "^(a|aa)*c" on a name of 200 a's takes longer than
// a day. Compiled __polynomial it runs breadth-first over the automaton's states instead (no
// back-references then), in time ∝ states × the name's length × the positions a search starts
// from; names are at most 255 bytes, so bounding the states bounds the time: at 1000 states the
// worst patterns measured ("(a{1,20}){1,20}c", "(a*){1,99}c") search a 251-byte name in 0.3-0.35 s,
// where the state count libstdc++ allows by default (100,000) lets one take minutes.
#define _GLIBCXX_REGEX_STATE_LIMIT 1000
#include "unit_id_pattern.hpp"

#include <regex>

#include "commands.hpp"

namespace accelcal::cli {

struct UnitIdPattern::Compiled {
  std::regex regex;
};

UnitIdPattern::UnitIdPattern(const std::string& pattern) {
  auto flags = std::regex::ECMAScript;
#ifdef __GLIBCXX__
  flags |= std::regex_constants::__polynomial;
#endif
  try {
    compiled_ = std::make_unique<Compiled>(Compiled{std::regex(pattern, flags)});
  } catch (const std::regex_error& e) {
    const std::string shown = "--unit-id '" + pattern + "'";
    if (e.code() == std::regex_constants::error_complexity) {
      throw UsageError(shown +
                       " refers back to a group (\\1): such a pattern can take time exponential "
                       "in the name's length to search; write it without");
    }
    if (e.code() == std::regex_constants::error_space) {
      throw UsageError(shown +
                       " is too large to search in bounded time: write its repetitions with "
                       "smaller counts, and alternatives of single characters as a class ([a-z])");
    }
    throw UsageError(shown + " is not a regular expression: " + e.what());
  }
}

UnitIdPattern::~UnitIdPattern() = default;
UnitIdPattern::UnitIdPattern(UnitIdPattern&&) noexcept = default;

std::optional<std::string> UnitIdPattern::Search(const std::string& name) const {
  std::smatch m;
  if (!std::regex_search(name, m, compiled_->regex)) return std::nullopt;
  return m.size() > 1 ? m[1].str() : m[0].str();
}

}  // namespace accelcal::cli
