#pragma once
// batch --unit-id: a regular expression searched in each file's name, in time bounded whatever
// the pattern (unit_id_pattern.cpp).

#include <memory>
#include <optional>
#include <string>

namespace accelcal::cli {

class UnitIdPattern {
 public:
  /// Compiles `pattern` (ECMAScript); a UsageError naming --unit-id for one that is not a regular
  /// expression, holds a back-reference, or is too large to search in bounded time.
  explicit UnitIdPattern(const std::string& pattern);
  ~UnitIdPattern();
  UnitIdPattern(UnitIdPattern&&) noexcept;
  /// The first group of the leftmost match in `name` (the whole match when there is no group), or
  /// nothing when it does not match.
  std::optional<std::string> Search(const std::string& name) const;

 private:
  struct Compiled;
  std::unique_ptr<Compiled> compiled_;
};

}  // namespace accelcal::cli
