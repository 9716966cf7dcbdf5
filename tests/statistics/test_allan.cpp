// The streamed overlapping Allan variance (allan.hpp): against the defining sum, on simulated
// noise of known Allan variance, and the coverage of its confidence intervals.
#include "accelcal/allan.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "statistics/student_t.hpp"

namespace accelcal {
namespace {

constexpr bool kSanitized = ACCELCAL_TESTS_SANITIZED;
constexpr int kRuns = kSanitized ? 150 : 400;

// The defining sum, from the whole phase: θ_i = Σ_{k<i} y_k (in samples), second differences
// at i = 0, s, 2s, … ≤ N − 1 − 2m, over 2 m² per term.
double DirectAvar(const std::vector<double>& y, std::uint64_t m, std::uint64_t stride) {
  std::vector<long double> theta(y.size() + 1, 0.0L);
  for (std::size_t k = 0; k < y.size(); ++k) theta[k + 1] = theta[k] + y[k];
  long double sum = 0;
  std::uint64_t terms = 0;
  for (std::uint64_t i = 0; i + 2 * m <= y.size(); i += stride) {
    const long double d = theta[i + 2 * m] - 2 * theta[i + m] + theta[i];
    sum += d * d;
    ++terms;
  }
  return static_cast<double>(sum / (2.0L * m * m * terms));
}

std::vector<double> WhiteNoise(std::size_t n, double sigma, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, sigma);
  std::vector<double> y(n);
  for (double& v : y) v = 5.0 + normal(rng);  // an offset, which σ² does not see
  return y;
}

TEST(Allan, EveryPointIsTheDefiningSum) {
  const std::vector<double> y = WhiteNoise(5000, 0.3, 1);
  for (std::uint64_t R : {1u, 4u, 32u, 8192u}) {
    AllanOptions options;
    options.sample_period_s = 0.01;
    options.full_overlap_up_to = R;
    const std::vector<AllanPoint> points = AllanVariance(y, options);
    ASSERT_EQ(points.size(), 11u) << "m = 1 … 1024 (4 m ≤ 5000)";
    for (std::size_t j = 0; j < points.size(); ++j) {
      const AllanPoint& p = points[j];
      EXPECT_EQ(p.m, std::uint64_t{1} << j);
      EXPECT_EQ(p.stride, p.m <= R ? 1 : p.m / R);
      EXPECT_DOUBLE_EQ(p.tau_s, 0.01 * static_cast<double>(p.m));
      EXPECT_EQ(p.terms, (5000 - 2 * p.m) / p.stride + 1);
      EXPECT_NEAR(p.avar, DirectAvar(y, p.m, p.stride), 1e-12 * p.avar)
          << "R " << R << " m " << p.m;
    }
  }
}

TEST(Allan, StreamedInPiecesIsTheSame) {
  const std::vector<double> y = WhiteNoise(3000, 1.0, 2);
  AllanOptions options;
  options.sample_period_s = 0.005;
  options.full_overlap_up_to = 8;
  AllanAccumulator pieces(options);
  for (std::size_t k = 0; k < y.size();) {
    const std::size_t n = std::min<std::size_t>(1 + k % 97, y.size() - k);
    pieces.Add(y.data() + k, n);
    k += n;
  }
  const std::vector<AllanPoint> whole = AllanVariance(y, options), streamed = pieces.Points();
  ASSERT_EQ(whole.size(), streamed.size());
  for (std::size_t j = 0; j < whole.size(); ++j) EXPECT_EQ(whole[j].avar, streamed[j].avar);
}

// Add sums level 0 over chunks of 4096 samples, reading the ring for the terms that reach back
// before a chunk: across chunks, and one sample at a time, the sums are the same to the bit.
TEST(Allan, ChunksAndSingleSamplesGiveTheSameBits) {
  const std::vector<double> y = WhiteNoise(10000, 0.7, 3);
  for (std::uint64_t R : {1u, 32u, 8192u}) {
    AllanOptions options;
    options.sample_period_s = 0.01;
    options.full_overlap_up_to = R;
    AllanAccumulator single(options), pieces(options);
    for (double v : y) single.Add(v);
    for (std::size_t k = 0; k < y.size();) {
      const std::size_t n = std::min<std::size_t>(1 + (k * 7919) % 5000, y.size() - k);
      pieces.Add(y.data() + k, n);
      k += n;
    }
    const std::vector<AllanPoint> whole = AllanVariance(y, options);
    for (const AllanAccumulator* other : {&single, &pieces}) {
      const std::vector<AllanPoint> points = other->Points();
      ASSERT_EQ(points.size(), whole.size()) << "R " << R;
      for (std::size_t j = 0; j < whole.size(); ++j) {
        EXPECT_EQ(points[j].avar, whole[j].avar) << "R " << R << " m " << whole[j].m;
        EXPECT_EQ(points[j].terms, whole[j].terms) << "R " << R << " m " << whole[j].m;
      }
    }
    for (const AllanPoint& p : whole) {
      EXPECT_NEAR(p.avar, DirectAvar(y, p.m, p.stride), 1e-12 * p.avar) << "R " << R;
    }
  }
}

TEST(Allan, RefusesWhatItCannotUse) {
  AllanOptions options;
  for (double period : {0.0, -1.0, std::nan(""), HUGE_VAL}) {
    options.sample_period_s = period;
    EXPECT_THROW(AllanAccumulator{options}, std::invalid_argument) << period;
  }
  options.sample_period_s = 0.01;
  for (std::uint64_t R : {0u, 3u, 48u, (1u << 21)}) {
    options.full_overlap_up_to = R;
    EXPECT_THROW(AllanAccumulator{options}, std::invalid_argument) << R;
  }
  options.full_overlap_up_to = 32;
  AllanAccumulator a(options);
  a.Add(1.0);
  try {
    a.Add(std::nan(""));
    FAIL() << "a NaN sample was taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("sample 2"), std::string::npos) << e.what();
  }
  {
    // A sample not finite within a long block: those before it are taken, as one at a time.
    std::vector<double> y = WhiteNoise(6000, 1.0, 4);
    y[5000] = HUGE_VAL;
    AllanAccumulator block(options), before(options);
    EXPECT_THROW(block.Add(y.data(), y.size()), std::invalid_argument);
    before.Add(y.data(), 5000);
    EXPECT_EQ(block.samples(), 5000u);
    const std::vector<AllanPoint> p = block.Points(), q = before.Points();
    ASSERT_EQ(p.size(), q.size());
    for (std::size_t j = 0; j < p.size(); ++j) EXPECT_EQ(p[j].avar, q[j].avar);
  }
  EXPECT_TRUE(a.Points().empty()) << "one sample: no m with 4 m ≤ n";
}

TEST(ChiSquare, QuantilesMatchKnownValues) {
  // Tables (e.g. NIST/SEMATECH e-Handbook 1.3.6.7.4), to their 3 decimals.
  EXPECT_NEAR(internal::ChiSquareQuantile(0.025, 1), 5.024, 1e-3);
  EXPECT_NEAR(internal::ChiSquareQuantile(0.975, 1), 0.000982, 1e-6);
  EXPECT_NEAR(internal::ChiSquareQuantile(0.025, 10), 20.483, 1e-3);
  EXPECT_NEAR(internal::ChiSquareQuantile(0.975, 10), 3.247, 1e-3);
  EXPECT_NEAR(internal::ChiSquareQuantile(0.05, 100), 124.342, 1e-3);
  // Two degrees of freedom: P(X ≥ x) = e^(−x/2), so the quantile is −2 ln p exactly.
  for (double p : {0.001, 0.025, 0.5, 0.975}) {
    EXPECT_NEAR(internal::ChiSquareQuantile(p, 2), -2 * std::log(p), 1e-10 * (1 - std::log(p)));
  }
}

// Coverage of the 95 % interval over `runs` simulated logs, per averaging time: the truth inside
// in a fraction whose binomial σ is √(0.95 · 0.05 / runs) — 1.1 % for 400 runs (1.8 % for the
// 150 of a sanitized build); the bounds below are 3.5 σ either side of 95 %.
template <typename Simulate, typename Truth>
void ExpectCoverage(PowerLawNoise noise, std::uint64_t R, std::size_t n, int runs,
                    const Simulate& simulate, const Truth& truth) {
  AllanOptions options;
  options.sample_period_s = 0.01;
  options.full_overlap_up_to = R;
  std::vector<int> inside;
  std::vector<std::uint64_t> ms;
  for (int run = 0; run < runs; ++run) {
    const std::vector<double> y = simulate(static_cast<std::uint64_t>(run) + 100);
    const std::vector<AllanPoint> points = AllanVariance(y, options);
    if (inside.empty()) inside.assign(points.size(), 0);
    for (std::size_t j = 0; j < points.size(); ++j) {
      const AllanPoint& p = points[j];
      if (run == 0) ms.push_back(p.m);
      ASSERT_EQ(p.phase_points, n + 1);
      const double edf = AllanEdf(noise, p);
      const AllanInterval ci = AllanDeviationInterval(p.avar, edf, 0.95);
      const double sigma = std::sqrt(truth(static_cast<double>(p.m)));
      inside[j] += ci.low <= sigma && sigma <= ci.high;
    }
  }
  const double half_width = 3.5 * std::sqrt(0.95 * 0.05 / runs);
  for (std::size_t j = 0; j < inside.size(); ++j) {
    const double fraction = static_cast<double>(inside[j]) / runs;
    EXPECT_NEAR(fraction, 0.95, half_width) << "m " << ms[j] << " R " << R;
  }
}

TEST(Allan, WhiteNoiseIntervalsCoverTheTruth) {
  // Discrete white noise of σ: averages of m samples have variance σ²/m, and σ²(τ) = σ²/m.
  const double sigma = 0.7;
  const std::size_t n = 4096;
  for (std::uint64_t R : {std::uint64_t{8}, std::uint64_t{4096}}) {
    ExpectCoverage(
        PowerLawNoise::kWhite, R, n, kRuns,
        [&](std::uint64_t seed) { return WhiteNoise(n, sigma, seed); },
        [&](double m) { return sigma * sigma / m; });
  }
}

TEST(Allan, RandomWalkIntervalsCoverTheTruth) {
  // y_k = y_{k−1} + e_k, e ~ N(0, q²): the difference of adjacent m-averages is Σ c_j e_j / m with
  // c_j = j (j < m), 2m − j (m ≤ j < 2m), Σ c_j² = m (2m² + 1) / 3, so σ²(τ) = q² (2m² + 1) / (6m).
  const double q = 0.05;
  const std::size_t n = 4096;
  const auto walk = [&](std::uint64_t seed) {
    std::vector<double> y = WhiteNoise(n, q, seed);
    double level = 0;
    for (double& v : y) v = level += v - 5.0;
    return y;
  };
  for (std::uint64_t R : {std::uint64_t{8}, std::uint64_t{4096}}) {
    ExpectCoverage(PowerLawNoise::kRandomWalk, R, n, kRuns, walk,
                   [&](double m) { return q * q * (2 * m * m + 1) / (6 * m); });
  }
}

TEST(Allan, QuantizationIntervalsCoverTheTruth) {
  // y_k = (x_{k+1} − x_k) / τ₀ with x white of σ_x: θ is x, so σ²(τ) = 6 σ_x² / (2 m² τ₀²).
  const double sigma_x = 0.002, tau0 = 0.01;
  const std::size_t n = 4096;
  const auto differenced = [&](std::uint64_t seed) {
    const std::vector<double> x = WhiteNoise(n + 1, sigma_x, seed);
    std::vector<double> y(n);
    for (std::size_t k = 0; k < n; ++k) y[k] = (x[k + 1] - x[k]) / tau0;
    return y;
  };
  for (std::uint64_t R : {std::uint64_t{8}, std::uint64_t{4096}}) {
    ExpectCoverage(PowerLawNoise::kQuantization, R, n, kRuns, differenced,
                   [&](double m) { return 3 * sigma_x * sigma_x / (m * m * tau0 * tau0); });
  }
}

}  // namespace
}  // namespace accelcal
