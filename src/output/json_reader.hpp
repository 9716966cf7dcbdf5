#pragma once
// Reading a JSON document accelcal wrote (a calibration file, a noise analysis): every key
// checked once, each error naming the file and the key's path.
#include <cmath>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "accelcal/error.hpp"
#include "accelcal/types.hpp"

namespace accelcal::internal {

using nlohmann::ordered_json;

// The checks of one document's keys, with the file's name for the errors and the path of the
// object being read ("" at the top; "sensors.accelerometer." in version 2) for their key names.
class Reader {
 public:
  Reader(const std::string& source, std::string path) : source_(source), path_(std::move(path)) {}

  [[noreturn]] void Fail(const std::string& reason) const { throw InputError(source_, 0, reason); }
  std::string Key(const std::string& key) const { return "'" + path_ + key + "'"; }

  double Number(const ordered_json& j, const std::string& what) const {
    if (!j.is_number()) Fail(what + " must be a number");
    const double v = j.get<double>();
    if (!std::isfinite(v)) Fail(what + " is not finite");
    return v;
  }
  // A number, or null (written for a value that does not exist), or absent.
  std::optional<double> Nullable(const ordered_json& doc, const char* key) const {
    if (!doc.contains(key) || doc[key].is_null()) return std::nullopt;
    return Number(doc[key], Key(key));
  }
  Vec3 Vector3(const ordered_json& doc, const char* key) const {
    if (!doc.contains(key) || !doc[key].is_array() || doc[key].size() != 3) {
      Fail(Key(key) + " must be an array of 3 numbers");
    }
    Vec3 v;
    for (int i = 0; i < 3; ++i)
      v(i) = Number(doc[key][i], path_ + key + "[" + std::to_string(i) + "]");
    return v;
  }
  std::optional<Vec3> OptionalVector3(const ordered_json& doc, const char* key) const {
    if (!doc.contains(key)) return std::nullopt;
    return Vector3(doc, key);
  }
  std::string Text(const ordered_json& doc, const char* key) const {
    if (!doc.contains(key) || !doc[key].is_string()) Fail(Key(key) + " must be text");
    return doc[key].get<std::string>();
  }
  const ordered_json& Object(const ordered_json& doc, const char* key) const {
    if (!doc.contains(key) || !doc[key].is_object()) Fail(Key(key) + " must be an object");
    return doc[key];
  }
  Reader Inside(const std::string& key) const { return Reader(source_, path_ + key + "."); }

 private:
  const std::string& source_;
  std::string path_;
};

/// Parses JSON refusing a key that appears twice in one object (the last one would silently
/// win), in any locale. InputError naming `source` for bad JSON.
ordered_json ParseWithoutDuplicateKeys(const std::string& text, const std::string& source);

}  // namespace accelcal::internal
