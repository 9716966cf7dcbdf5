// The overlapping Allan variance, streamed (allan.hpp).
#include "accelcal/allan.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "statistics/student_t.hpp"

namespace accelcal {

namespace {

constexpr std::uint64_t kMaxFullOverlap = std::uint64_t{1} << 20;

bool PowerOfTwo(std::uint64_t v) { return v != 0 && (v & (v - 1)) == 0; }

int Log2(std::uint64_t v) {
  int j = 0;
  while (v > 1) v >>= 1, ++j;
  return j;
}

}  // namespace

AllanAccumulator::AllanAccumulator(const AllanOptions& options) : options_(options) {
  if (!(std::isfinite(options.sample_period_s) && options.sample_period_s > 0)) {
    throw std::invalid_argument("AllanAccumulator: the sample period must be finite and positive");
  }
  const std::uint64_t R = options.full_overlap_up_to;
  if (!PowerOfTwo(R) || R > kMaxFullOverlap) {
    throw std::invalid_argument(
        "AllanAccumulator: the longest fully overlapped average must be a power of two up to "
        "2^20 samples");
  }
  // Level 0 holds every phase point for the averages of 1, 2, …, R samples; level l ≥ 1 every
  // 2^l-th for the average of R 2^l. Each keeps the last 2R + 1 (a power of two above it: a mask
  // indexes the ring).
  Level first;
  first.m = 1;
  first.stride = 1;
  first.ring.assign(4 * R, 0.0);
  first.count = 1;  // θ_0 = 0
  levels_.push_back(std::move(first));
  sums_.assign(static_cast<std::size_t>(Log2(R)) + 1, 0.0);
  terms_.assign(sums_.size(), 0);
}

void AllanAccumulator::Add(const double* y, std::size_t count) {
  const std::uint64_t R = options_.full_overlap_up_to;
  const std::uint64_t mask = 4 * R - 1;
  // Level 0 octave by octave over chunks of the samples: θ at each chunk's phase points in one
  // array, so that each octave's sum is one loop without the ring's masks once its terms reach
  // back no further than the chunk (those before read the ring); each sum takes the same terms
  // in the same order as a sample at a time would. The ring takes the chunk's θ at its end.
  constexpr std::size_t kChunk = 4096;
  history_.resize(std::min(count, kChunk));
  double* const history = history_.data();
  for (std::size_t begin = 0; begin < count; begin += kChunk) {
    const std::size_t size = std::min(kChunk, count - begin);
    const std::uint64_t i0 = samples_ + 1;  // the chunk's first phase point
    std::size_t added = size;
    for (std::size_t k = 0; k < size; ++k) {
      const double v = y[begin + k];
      if (!std::isfinite(v)) {
        added = k;
        break;
      }
      if (samples_ == 0) origin_ = v;
      theta_ += v - origin_;
      ++samples_;
      const std::uint64_t i = samples_;  // the phase point's index
      history[k] = theta_;
      // Level l ≥ 1 at every index divisible by 2^l; created at its first (i = 2^l), with θ_0.
      for (std::size_t l = 1; (i & ((std::uint64_t{1} << l) - 1)) == 0; ++l) {
        if (l == levels_.size()) {
          Level level;
          level.stride = std::uint64_t{1} << l;
          level.m = R * level.stride;
          level.ring.assign(4 * R, 0.0);
          level.count = 1;  // θ_0 = 0 at its slot 0
          levels_.push_back(std::move(level));
        }
        Level& level = levels_[l];
        const std::uint64_t p = level.count++;  // this point's index in the level's sequence
        level.ring[p & mask] = theta_;
        if (p >= 2 * R) {
          const double d = theta_ - 2 * level.ring[(p - R) & mask] + level.ring[(p - 2 * R) & mask];
          level.sum += d * d;
          ++level.terms;
        }
      }
    }
    // Level 0: every m = 1, 2, 4, …, R at each phase point i ≥ 2m.
    double* const ring = levels_[0].ring.data();
    const std::uint64_t end = i0 + added;
    const auto theta_at = [&](std::uint64_t p) {
      return p >= i0 ? history[p - i0] : ring[p & mask];
    };
    std::size_t j = 0;
    for (std::uint64_t m = 1; m <= R; m <<= 1, ++j) {
      const std::uint64_t first = std::max(i0, 2 * m);
      if (first >= end) continue;
      double sum = sums_[j];
      const std::uint64_t within = std::min(end, std::max(first, i0 + 2 * m));
      for (std::uint64_t i = first; i < within; ++i) {
        const double d = theta_at(i) - 2 * theta_at(i - m) + theta_at(i - 2 * m);
        sum += d * d;
      }
      if (within < end) {  // within ≥ i0 + 2m: all three in the chunk
        const double* const theta = history + (within - i0);
        const double* const back = theta - m;
        const double* const back2 = theta - 2 * m;
        const auto n = static_cast<std::size_t>(end - within);
        for (std::size_t q = 0; q < n; ++q) {
          const double d = theta[q] - 2 * back[q] + back2[q];
          sum += d * d;
        }
      }
      sums_[j] = sum;
      terms_[j] += end - first;
    }
    for (std::uint64_t p = std::max(i0, end > 4 * R ? end - 4 * R : 0); p < end; ++p) {
      ring[p & mask] = history[p - i0];
    }
    levels_[0].count = samples_ + 1;
    if (added < size) {
      throw std::invalid_argument("AllanAccumulator: sample " + std::to_string(samples_ + 1) +
                                  " is not a finite number");
    }
  }
}

std::vector<AllanPoint> AllanAccumulator::Points() const {
  return Points(options_.sample_period_s);
}

std::vector<AllanPoint> AllanAccumulator::Points(double sample_period_s) const {
  if (!(std::isfinite(sample_period_s) && sample_period_s > 0)) {
    throw std::invalid_argument("AllanAccumulator: the sample period must be finite and positive");
  }
  std::vector<AllanPoint> out;
  const double tau0 = sample_period_s;
  const auto add = [&](std::uint64_t m, std::uint64_t stride, double sum, std::uint64_t terms) {
    if (terms == 0 || 4 * m > samples_) return;
    AllanPoint p;
    p.m = m;
    p.tau_s = static_cast<double>(m) * tau0;
    p.stride = stride;
    p.terms = terms;
    p.phase_points = samples_ + 1;
    // θ was summed in samples: the second difference in τ₀ units, over 2 (m τ₀)² — τ₀ cancels.
    p.avar =
        sum / (2.0 * static_cast<double>(m) * static_cast<double>(m) * static_cast<double>(terms));
    out.push_back(p);
  };
  std::uint64_t m = 1;
  for (std::size_t j = 0; j < sums_.size(); ++j, m <<= 1) add(m, 1, sums_[j], terms_[j]);
  for (std::size_t l = 1; l < levels_.size(); ++l) {
    add(levels_[l].m, levels_[l].stride, levels_[l].sum, levels_[l].terms);
  }
  return out;
}

std::vector<AllanPoint> AllanVariance(const std::vector<double>& y, const AllanOptions& options) {
  AllanAccumulator accumulator(options);
  accumulator.Add(y.data(), y.size());
  return accumulator.Points();
}

double AllanEdf(PowerLawNoise noise, double N, double m) {
  switch (noise) {
    case PowerLawNoise::kQuantization:
      return (N + 1) * (N - 2 * m) / (2 * (N - m));
    case PowerLawNoise::kWhite:
      return (3 * (N - 1) / (2 * m) - 2 * (N - 2) / N) * 4 * m * m / (4 * m * m + 5);
    case PowerLawNoise::kFlicker:
      return m == 1 ? 2 * (N - 2) / (2.3 * N - 4.9) : 5 * N * N / (4 * m * (N + 3 * m));
    case PowerLawNoise::kRandomWalk:
      return (N - 2) / m * ((N - 1) * (N - 1) - 3 * m * (N - 1) + 4 * m * m) / ((N - 3) * (N - 3));
  }
  return 0;
}

double AllanEdf(PowerLawNoise noise, const AllanPoint& point) {
  if (point.stride == 0 || point.m % point.stride != 0 || point.phase_points < 1) {
    throw std::invalid_argument("AllanEdf: a point whose stride does not divide its m");
  }
  const std::uint64_t decimated = (point.phase_points - 1) / point.stride + 1;
  return AllanEdf(noise, static_cast<double>(decimated),
                  static_cast<double>(point.m / point.stride));
}

AllanInterval AllanDeviationInterval(double avar, double edf, double confidence) {
  if (!(confidence > 0 && confidence < 1) || !(edf > 0) || !(avar >= 0)) {
    throw std::invalid_argument(
        "AllanDeviationInterval: the confidence must lie in (0, 1), the degrees of freedom be "
        "positive and the variance not negative");
  }
  const double tail = 0.5 * (1 - confidence);
  AllanInterval out;
  out.low = std::sqrt(edf * avar / internal::ChiSquareQuantile(tail, edf));
  out.high = std::sqrt(edf * avar / internal::ChiSquareQuantile(1 - tail, edf));
  return out;
}

}  // namespace accelcal
