#pragma once
/// @file noise.hpp
/// The noise of a still sensor, axis by axis (issue 19): the overlapping Allan deviation with its
/// intervals (allan.hpp) and the IEEE terms fitted to it (noise_model.hpp).

#include <array>
#include <cstddef>
#include <vector>

#include "accelcal/allan.hpp"
#include "accelcal/noise_model.hpp"
#include "accelcal/types.hpp"

namespace accelcal {

struct NoiseOptions {
  /// Averages of up to this many samples fully overlapped (AllanOptions::full_overlap_up_to).
  std::uint64_t full_overlap_up_to = 32;
  NoiseFitOptions fit;
};

struct AxisNoise {
  std::vector<AllanPoint> points;  ///< every octave with 4 m ≤ n
  NoiseModelFit fit;
};

struct NoiseAnalysis {
  std::size_t samples = 0;
  double sample_period_s = 0;
  std::array<AxisNoise, 3> axes;  ///< x, y, z
};

/// Each axis of `samples` (taken every `sample_period_s`, in the unit the terms come out in).
/// Throws DataError when there are too few samples for the terms fitted (4 m ≤ n must hold for
/// one more octave than terms: 128 samples for all five), or an axis is constant (no noise to
/// characterise); std::invalid_argument for a period not finite and positive or a sample not
/// finite.
NoiseAnalysis AnalyseNoise(const std::vector<Vec3>& samples, double sample_period_s,
                           const NoiseOptions& options = {});

}  // namespace accelcal
