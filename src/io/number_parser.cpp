#include "io/number_parser.hpp"

#include <system_error>

#include <fast_float/fast_float.h>

namespace accelcal::internal {

bool ParseNumber(const char* first, const char* last, double* value) {
  if (ParseShortDecimal(first, last, value) == last) return true;
  if (first != last && *first == '+') {  // fast_float takes no '+'; nor may a second sign follow
    ++first;
    if (first != last && (*first == '+' || *first == '-')) return false;
  }
  const auto result = fast_float::from_chars(first, last, *value);
  return result.ec == std::errc() && result.ptr == last;
}

}  // namespace accelcal::internal
