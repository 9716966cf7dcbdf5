#pragma once
// A quantile of a sample, by partial sorting: the element of rank floor(p n) (0-based), so the
// median is the upper one of an even count.
#include <algorithm>
#include <cstddef>
#include <utility>
#include <vector>

namespace accelcal::internal {

/// p in [0, 1); `v` non-empty.
inline double Quantile(std::vector<double> v, double p) {
  const auto at = v.begin() + static_cast<std::ptrdiff_t>(static_cast<double>(v.size()) * p);
  std::nth_element(v.begin(), at, v.end());
  return *at;
}

inline double Median(std::vector<double> v) { return Quantile(std::move(v), 0.5); }

}  // namespace accelcal::internal
