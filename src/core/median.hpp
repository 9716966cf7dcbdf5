#pragma once
// The median of a sample (the upper one of an even count), by partial sorting.
#include <algorithm>
#include <cstddef>
#include <vector>

namespace accelcal::internal {

inline double Median(std::vector<double> v) {
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

}  // namespace accelcal::internal
