#pragma once
/// @file names.hpp
/// The names of an enum's values: one table per enum, specialised beside the enum's definition
/// (`template <> struct EnumNames<SolverMethod>`), read by its ToString and FromString functions
/// and by every list of choices the command line and Python show, so that they cannot drift
/// apart. A table lists the values in the order the documentation gives them; the first entry of
/// a value is its name, later entries for the same value are accepted spellings.

#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>
#include <utility>

namespace accelcal {

/// Specialised per enum: `static constexpr std::pair<E, std::string_view> kTable[] = {...};`.
template <typename E>
struct EnumNames;

/// The name of `value` (empty when the table lacks it).
template <typename E>
constexpr std::string_view NameOf(E value) {
  for (const auto& [v, name] : EnumNames<E>::kTable) {
    if (v == value) return name;
  }
  return {};
}

/// The value named `text` (a name or an accepted spelling), or std::nullopt.
template <typename E>
constexpr std::optional<E> FromName(std::string_view text) {
  for (const auto& [v, name] : EnumNames<E>::kTable) {
    if (name == text) return v;
  }
  return std::nullopt;
}

/// "a, b, c": the names of every value, or of `subset` only, in the table's order.
template <typename E>
std::string NameList(std::initializer_list<E> subset = {}) {
  std::string list;
  const auto* table = EnumNames<E>::kTable;
  const std::size_t n = std::size(EnumNames<E>::kTable);
  for (std::size_t i = 0; i < n; ++i) {
    const auto& [value, name] = table[i];
    if (NameOf(value) != name) continue;  // an accepted spelling, not the name
    bool wanted = subset.size() == 0;
    for (E e : subset) wanted = wanted || e == value;
    if (!wanted) continue;
    if (!list.empty()) list += ", ";
    list += name;
  }
  return list;
}

}  // namespace accelcal
