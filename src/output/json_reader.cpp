// Reading a JSON document accelcal wrote (json_reader.hpp).
#include "output/json_reader.hpp"

#include <set>
#include <vector>

#include "core/text_format.hpp"

namespace accelcal::internal {

// Parses JSON refusing a key that appears twice in one object: the last one would silently win
// (a second identity "K" would turn `apply` into a no-op).
ordered_json ParseWithoutDuplicateKeys(const std::string& text, const std::string& source) {
  std::vector<std::set<std::string>> keys;  // of each object being read
  std::string duplicate;
  const auto check = [&](int, nlohmann::json::parse_event_t event, ordered_json& parsed) {
    using Event = nlohmann::json::parse_event_t;
    if (event == Event::object_start) keys.emplace_back();
    if (event == Event::object_end && !keys.empty()) keys.pop_back();
    if (event == Event::key && !keys.empty() &&
        !keys.back().insert(parsed.get<std::string>()).second && duplicate.empty()) {
      duplicate = parsed.get<std::string>();
    }
    return true;
  };
  ordered_json doc;
  // nlohmann's parser reads numbers with strtod, after putting the C locale's decimal point in
  // place of '.': right in any locale, but only while no other thread changes it in between.
  const internal::ClassicLocale c_locale;
  try {
    doc = ordered_json::parse(text, check);
  } catch (const nlohmann::json::exception& e) {  // syntax, or a number beyond double's range
    throw InputError(source, 0, std::string("not valid JSON: ") + e.what());
  }
  if (!duplicate.empty()) {
    throw InputError(source, 0, "the key '" + duplicate + "' appears twice in one object");
  }
  return doc;
}

}  // namespace accelcal::internal
