// Quantile (core/median.hpp): the element of rank floor(p n) of the sorted sample, for short
// samples (partial sort alone) and long ones (narrowed first by a count over the keys' top bits).
#include "core/median.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

namespace accelcal::internal {
namespace {

double Sorted(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(static_cast<double>(v.size()) * p)];
}

TEST(Quantile, IsTheElementOfItsRankInTheSortedSample) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_int_distribution<int> counts(-20, 20);
  const std::vector<std::size_t> sizes = {1, 2, 3, 4095, 4096, 4097, 30011};
  const std::vector<double> ps = {0.0, 0.25, 0.5, 0.75, 0.999};
  for (std::size_t n : sizes) {
    // Gaussian, of both signs; |x| spanning 40 octaves; quantised counts with many ties; one
    // value throughout.
    std::vector<std::vector<double>> samples(4);
    for (std::size_t k = 0; k < n; ++k) {
      const double z = normal(rng);
      samples[0].push_back(z);
      samples[1].push_back(std::abs(z) * std::ldexp(1.0, counts(rng)));
      samples[2].push_back(static_cast<double>(counts(rng)) * 0.25);
      samples[3].push_back(-3.5);
    }
    for (const std::vector<double>& v : samples) {
      for (double p : ps) {
        EXPECT_EQ(Quantile(v, p), Sorted(v, p)) << "n " << n << " p " << p;
      }
    }
  }
}

TEST(Quantile, OrdersSignedZerosAndExtremes) {
  // Keys in the doubles' order across zero, the subnormals and the largest values.
  const std::vector<double> ordered = {-std::numeric_limits<double>::max(),        -1.0,
                                       -std::numeric_limits<double>::denorm_min(), 0.0,
                                       std::numeric_limits<double>::denorm_min(),  1.0,
                                       std::numeric_limits<double>::infinity()};
  for (std::size_t k = 1; k < ordered.size(); ++k) {
    EXPECT_LT(OrderKey(ordered[k - 1]), OrderKey(ordered[k])) << k;
  }
  std::vector<double> v(5000, 1.0);
  for (std::size_t k = 0; k < 2000; ++k) v[k] = k % 2 == 0 ? -0.0 : 0.0;
  EXPECT_EQ(Quantile(v, 0.2), 0.0);
  EXPECT_EQ(Quantile(v, 0.5), 1.0);
}

}  // namespace
}  // namespace accelcal::internal
