#pragma once
/// @file position_noise.hpp
/// The noise of still positions' mean readings, measured from their samples with the samples'
/// correlation included: a sensor that filters its output before sampling (the Xsens MTi and the
/// RealSense T265 both do: their shortest Allan averaging times fall below white noise) has
/// samples that are not independent, and the sample standard deviation over √n then puts a
/// mean's noise low. Each position's samples are cut into kPositionNoiseBatches batches; the
/// scatter of their means (by their median absolute deviation: a batch reaching into a turn is
/// far off) over √batches is its mean's σ. The sensor's noise is the same in every position: that
/// variance times the position's samples (a variance per sample, correlation included: the white
/// noise density squared times the rate) is pooled by the median over the positions, and each
/// position's σ is the pooled variance over its samples. One position's batches alone have 15
/// degrees of freedom (by their MAD, fewer).

#include <cstddef>
#include <optional>
#include <vector>

#include "accelcal/load_positions.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/positions.hpp"
#include "accelcal/types.hpp"

namespace accelcal {

/// Batches a position's mean noise is measured over (15 degrees of freedom per axis), each of
/// at least kPositionNoiseMinBatchSamples samples (shorter would not hold a filtered sensor's
/// correlation).
inline constexpr std::size_t kPositionNoiseBatches = 16;
inline constexpr std::size_t kPositionNoiseMinBatchSamples = 8;

/// The variance of `position`'s mean reading (per axis, raw²), from `log`, the raw log its
/// interval is of: its batch means' scatter over kPositionNoiseBatches; σ²/n of the samples for a
/// position too short to batch or joined across a disturbance (its samples are not one run).
/// Throws std::invalid_argument for a position without an interval or one beyond the log.
Vec3 PositionMeanVariance(const RawLog& log, const Position& position);

/// The positions' noise, pooled.
struct PositionNoise {
  /// Each position's mean variance times its samples, the median over the positions, per axis
  /// [raw²]: the noise of one sample as it averages (the white noise density² × the rate).
  Vec3 per_sample_variance = Vec3::Zero();
  /// Per position: √(per_sample_variance / its samples) [raw], the 1σ of its mean.
  std::vector<Vec3> sigmas;
  /// Positions whose mean variance came from batch means (the others from σ²/n).
  std::size_t batched = 0;
};

/// Pools the mean variances of `positions` (PositionMeanVariance of each, in order).
PositionNoise PoolPositionNoise(const std::vector<Position>& positions,
                                const std::vector<Vec3>& mean_variances);

/// The noise of every position of `input`, each from its raw log, pooled over the positions of
/// each file (sessions may differ in noise and rate; `per_sample_variance` is the last file's),
/// each mean's variance at least what rounding to the file's quantisation step leaves in it
/// (internal::RoundingFloorVariance: readings that do not dither are not averaged down);
/// nullopt when some position is not from a raw log (a positions file: its own columns give its
/// noise, SigmasOfMeans) or a file's pooled noise is not positive on every axis (a quantised
/// sensor that reads one value).
std::optional<PositionNoise> MeasurePositionNoise(const LoadedInput& input);

/// The 1σ of each position's mean (CalibrationOptions::reading_sigmas): MeasurePositionNoise's,
/// or for positions not from raw logs their own (SigmasOfMeans: empty when they have none, and
/// the noise then comes from the fit's residuals).
std::vector<Vec3> ReadingSigmas(const LoadedInput& input);

}  // namespace accelcal
