#pragma once
// A quantile of a sample, by partial sorting: the element of rank floor(p n) (0-based), so the
// median is the upper one of an even count.
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

namespace accelcal::internal {

/// An unsigned key in the order of the doubles (not NaN): negative values' bits reversed, the
/// others' sign bit set.
inline std::uint64_t OrderKey(double x) {
  std::uint64_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  return (bits >> 63) != 0 ? ~bits : bits | (std::uint64_t{1} << 63);
}

/// p in [0, 1); `v` non-empty, without NaN.
inline double Quantile(std::vector<double> v, double p) {
  std::size_t rank = static_cast<std::size_t>(static_cast<double>(v.size()) * p);
  // A long sample is first narrowed by one counting pass over its keys' top 16 bits (sign,
  // exponent and 4 bits of mantissa: a sixteenth of an octave) to the bucket that holds the
  // element of that rank; the partial sort then runs on that bucket only. The element is the same;
  // std::nth_element alone spends several branchy passes over all of them (on 30 000 window
  // means, most of the gyroscope's still-span search).
  // The counts are kept between calls (per thread) and only the buckets between the lowest and
  // the highest key's are read and cleared: a sample of one sign spans a few hundred buckets of
  // the 65,536 (the non-negative ones start at the 32,768th).
  constexpr std::size_t kNarrowFrom = 4096;
  if (v.size() >= kNarrowFrom) {
    // On the heap (a thread's first long sample), not in every thread's static TLS block.
    thread_local std::vector<std::uint32_t> count(std::size_t{1} << 16, 0);  // 0 between calls
    std::size_t lowest = count.size(), highest = 0;
    for (double x : v) {
      const auto b = static_cast<std::size_t>(OrderKey(x) >> 48);
      ++count[b];
      lowest = std::min(lowest, b);
      highest = std::max(highest, b);
    }
    std::size_t below = 0, bucket = lowest;
    while (below + count[bucket] <= rank) below += count[bucket++];
    std::fill(count.begin() + static_cast<std::ptrdiff_t>(lowest),
              count.begin() + static_cast<std::ptrdiff_t>(highest) + 1, 0u);
    std::size_t kept = 0;
    for (double x : v) {
      if ((OrderKey(x) >> 48) == bucket) v[kept++] = x;
    }
    v.resize(kept);
    rank -= below;
  }
  const auto at = v.begin() + static_cast<std::ptrdiff_t>(rank);
  std::nth_element(v.begin(), at, v.end());
  return *at;
}

inline double Median(std::vector<double> v) { return Quantile(std::move(v), 0.5); }

}  // namespace accelcal::internal
