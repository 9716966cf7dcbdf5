#pragma once
// Mutations of a valid JSON document at one place: every value replaced by a value of every
// other type (and by hostile numbers), removed, or its key duplicated. Shared by the exhaustive
// test of the calibration-file reader (test_calibration_keys.cpp) and its fuzzer
// (fuzz/fuzz_calibration_keys.cpp), which chains random ones.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace accelcal::test {

/// Every place in `doc`: objects' members and arrays' elements, depth first (not the root).
inline void CollectPointers(const nlohmann::json& doc, const nlohmann::json::json_pointer& at,
                            std::vector<nlohmann::json::json_pointer>* out) {
  if (doc.is_object()) {
    for (auto it = doc.begin(); it != doc.end(); ++it) {
      const nlohmann::json::json_pointer child = at / it.key();
      out->push_back(child);
      CollectPointers(it.value(), child, out);
    }
  } else if (doc.is_array()) {
    for (std::size_t i = 0; i < doc.size(); ++i) {
      const nlohmann::json::json_pointer child = at / i;
      out->push_back(child);
      CollectPointers(doc[i], child, out);
    }
  }
}

/// The values a mutation puts in a place: each JSON type, and numbers a reader must check
/// (negative, zero, fractional where a whole number or an enum code is expected, beyond int and
/// 2^53, the largest doubles).
inline std::vector<nlohmann::json> HostileValues() {
  return {nullptr,
          true,
          "text",
          "",
          -0.7069,
          0,
          -1,
          2,
          1e308,
          -1e308,
          4294967296.0,
          9007199254740993ULL,
          nlohmann::json::array(),
          nlohmann::json::object(),
          nlohmann::json::array({1, 2, 3}),
          nlohmann::json::object({{"a", 1}})};
}

enum class Mutation { kReplace, kErase, kDuplicateKey };

/// The text of `doc` with the value at `at` replaced by `value` (kReplace), removed (kErase), or,
/// for an object member, its key given twice, the second time with `value` (kDuplicateKey: text
/// only, as nlohmann::json holds no duplicate keys). Empty when the mutation does not apply.
inline std::string Mutate(nlohmann::json doc, const nlohmann::json::json_pointer& at,
                          Mutation mutation, const nlohmann::json& value) {
  if (!doc.contains(at)) return {};
  const nlohmann::json::json_pointer parent = at.parent_pointer();
  nlohmann::json& container = doc.at(parent);
  const std::string key = at.back();
  switch (mutation) {
    case Mutation::kReplace:
      doc.at(at) = value;
      return doc.dump();
    case Mutation::kErase:
      if (container.is_object()) {
        container.erase(key);
      } else {
        container.erase(std::stoul(key));
      }
      return doc.dump();
    case Mutation::kDuplicateKey: {
      if (!container.is_object()) return {};
      const std::string original = doc.at(at).dump();
      const std::string marker = "@@accelcal-duplicate@@";
      doc.at(at) = marker;
      std::string text = doc.dump();
      const std::string placed = nlohmann::json(key).dump() + ":" + nlohmann::json(marker).dump();
      const std::size_t pos = text.find(placed);
      if (pos == std::string::npos) return {};
      text.replace(pos, placed.size(),
                   nlohmann::json(key).dump() + ":" + original + "," + nlohmann::json(key).dump() +
                       ":" + value.dump());
      return text;
    }
  }
  return {};
}

}  // namespace accelcal::test
