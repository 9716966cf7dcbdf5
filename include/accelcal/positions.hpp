#pragma once
/// @file positions.hpp
/// Static positions: the averaged raw reading of one orientation, the input of every calibration.

#include <cstddef>
#include <optional>
#include <vector>

#include "accelcal/types.hpp"

namespace accelcal {

/// A contiguous run of samples during which the sensor was still.
struct StaticInterval {
  std::size_t begin = 0;     ///< first sample index (0-based)
  std::size_t end = 0;       ///< one past the last sample
  double t_begin_s = 0;      ///< time of the first sample [s]
  double t_end_s = 0;        ///< time of the last sample [s]
  Vec3 mean = Vec3::Zero();  ///< raw
  Vec3 std = Vec3::Zero();   ///< per-axis sample standard deviation, raw
  /// Samples in `mean` and `std` when fewer than end − begin: a still period joined across a
  /// short disturbance (StaticDetectionResult::joined) leaves the disturbance out. 0: all.
  std::size_t averaged = 0;
  /// Samples averaged.
  std::size_t count() const { return averaged > 0 ? averaged : end - begin; }
  /// The mean temperature [°C] of its samples that have one (RawLog::temperature_c); unset when
  /// none has.
  std::optional<double> temperature_c;
};

/// One static position: the averaged raw reading.
struct Position {
  Vec3 mean = Vec3::Zero();                ///< averaged raw reading
  std::size_t samples = 1;                 ///< number of samples averaged (1 when unknown)
  std::optional<Vec3> std;                 ///< per-axis sample standard deviation, raw, when known
  std::optional<StaticInterval> interval;  ///< where it came from, for positions from a raw log
  std::optional<double> temperature_c;     ///< the sensor's mean temperature [°C], when known
};

std::vector<Position> PositionsFromIntervals(const std::vector<StaticInterval>& intervals);
std::vector<Vec3> Means(const std::vector<Position>& positions);
/// The 1σ of each averaged reading, std / √samples, when every position has a positive sample
/// standard deviation from at least 2 samples; else empty (CalibrationOptions::reading_sigmas).
std::vector<Vec3> SigmasOfMeans(const std::vector<Position>& positions);

}  // namespace accelcal
