// The noise of still positions' mean readings (position_noise.hpp).
#include "accelcal/position_noise.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "core/median.hpp"
#include "statistics/rounding.hpp"

namespace accelcal {

namespace {

// A run of samples long enough for its batch means (not joined across a disturbance).
bool Batched(const StaticInterval& in) {
  return in.averaged == 0 &&
         in.end - in.begin >= kPositionNoiseBatches * kPositionNoiseMinBatchSamples;
}

// The samples a position's mean averages (at least 1).
double Averaged(const Position& p) {
  return static_cast<double>(
      std::max<std::size_t>(1, p.interval ? p.interval->count() : p.samples));
}

}  // namespace

Vec3 PositionMeanVariance(const RawLog& log, const Position& position) {
  if (!position.interval) {
    throw std::invalid_argument("PositionMeanVariance: a position without its interval");
  }
  const StaticInterval& in = *position.interval;
  if (in.begin > in.end || in.end > log.samples.size()) {
    throw std::invalid_argument("PositionMeanVariance: an interval beyond the log");
  }
  const std::size_t n = in.end - in.begin;
  const Vec3 std = position.std.value_or(in.std);
  if (!Batched(in)) return std.cwiseProduct(std) / Averaged(position);
  const std::size_t size = n / kPositionNoiseBatches;
  std::array<Vec3, kPositionNoiseBatches> means;
  for (std::size_t b = 0; b < kPositionNoiseBatches; ++b) {
    means[b] = Vec3::Zero();
    for (std::size_t i = 0; i < size; ++i) means[b] += log.samples[in.begin + b * size + i];
    means[b] /= static_cast<double>(size);
  }
  // The batch means' scatter by their median absolute deviation (× 1.4826, σ for normal
  // scatter): an interval whose ends reach into the turns (a slow turn, a noisy sensor whose
  // detection runs 0.45 s into it) has one or two end batches far off, which would put the
  // mean's noise several times high.
  Vec3 out;
  for (int a = 0; a < 3; ++a) {
    std::vector<double> v;
    for (const Vec3& m : means) v.push_back(m(a));
    const double median = internal::Median(v);
    for (double& x : v) x = std::abs(x - median);
    const double sigma = 1.4826 * internal::Median(v);
    // The variance of one batch mean over the batches in the whole interval: σ² / batches.
    out(a) = sigma * sigma / static_cast<double>(kPositionNoiseBatches);
  }
  return out;
}

PositionNoise PoolPositionNoise(const std::vector<Position>& positions,
                                const std::vector<Vec3>& mean_variances) {
  if (positions.empty() || positions.size() != mean_variances.size()) {
    throw std::invalid_argument("PoolPositionNoise: one mean variance per position, at least one");
  }
  PositionNoise out;
  std::array<std::vector<double>, 3> per_sample;
  for (std::size_t k = 0; k < positions.size(); ++k) {
    const Vec3 v = mean_variances[k] * Averaged(positions[k]);
    for (int a = 0; a < 3; ++a) per_sample[std::size_t(a)].push_back(v(a));
    if (positions[k].interval && Batched(*positions[k].interval)) ++out.batched;
  }
  for (int a = 0; a < 3; ++a) {
    out.per_sample_variance(a) = internal::Median(per_sample[std::size_t(a)]);
  }
  for (const Position& p : positions) {
    out.sigmas.push_back((out.per_sample_variance / Averaged(p)).cwiseSqrt());
  }
  return out;
}

std::optional<PositionNoise> MeasurePositionNoise(const LoadedInput& input) {
  // Pooled file by file: sessions may differ in noise and in rate (a per-sample variance is the
  // density² times the rate), and one pool over both weighed the quiet session's positions as
  // noisy (two sessions, one 10 times noisier: the scatter ratio 5.1 where each alone was 1.1).
  PositionNoise out;
  std::size_t k = 0;
  for (const LoadedFile& file : input.files) {
    if (file.data.kind != InputKind::kRaw || !file.detection) return std::nullopt;
    // The positions of this file: the next ones, one per interval.
    const std::size_t count = file.detection->intervals.size();
    if (count == 0 || k + count > input.positions.size()) return std::nullopt;
    const std::vector<Position> positions(
        input.positions.begin() + static_cast<std::ptrdiff_t>(k),
        input.positions.begin() + static_cast<std::ptrdiff_t>(k + count));
    std::vector<Vec3> variances;
    for (const Position& p : positions) {
      if (!p.interval) return std::nullopt;
      variances.push_back(PositionMeanVariance(file.data.raw, p));
    }
    PositionNoise pooled = PoolPositionNoise(positions, variances);
    // Readings rounded to a step coarser than their noise keep a rounding error in each mean
    // that averaging does not take down (a 12-bit part, a log written with 2 decimals): each
    // mean's variance is at least what that leaves, also where the readings hardly ever change.
    Vec3 floor = Vec3::Zero();
    for (int a = 0; a < 3; ++a) {
      floor(a) = internal::RoundingFloorVariance(file.detection->quantisation_step(a),
                                                 pooled.per_sample_variance(a));
    }
    if (!((pooled.per_sample_variance + floor).minCoeff() > 0) ||
        !pooled.per_sample_variance.allFinite()) {
      return std::nullopt;
    }
    for (Vec3& sigma : pooled.sigmas) sigma = (sigma.cwiseAbs2() + floor).cwiseSqrt();
    out.sigmas.insert(out.sigmas.end(), pooled.sigmas.begin(), pooled.sigmas.end());
    out.batched += pooled.batched;
    out.per_sample_variance = pooled.per_sample_variance;
    k += count;
  }
  if (k != input.positions.size() || k == 0) return std::nullopt;
  return out;
}

std::vector<Vec3> ReadingSigmas(const LoadedInput& input) {
  if (std::optional<PositionNoise> noise = MeasurePositionNoise(input)) return noise->sigmas;
  return SigmasOfMeans(input.positions);
}

}  // namespace accelcal
