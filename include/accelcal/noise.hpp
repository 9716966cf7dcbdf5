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

/// The same, fed in pieces (a log too long to hold, StreamRawLog): memory does not grow with the
/// samples.
class NoiseAccumulator {
 public:
  /// Throws std::invalid_argument for a period not finite and positive.
  NoiseAccumulator(double sample_period_s, const NoiseOptions& options = {});
  /// Appends samples (finite: std::invalid_argument naming the sample otherwise).
  void Add(const Vec3* samples, std::size_t count);
  std::size_t samples() const { return samples_; }
  /// The analysis of everything added (AnalyseNoise's errors).
  NoiseAnalysis Finish() const { return Finish(sample_period_s_); }
  /// The same at another sample period (a stream's rate, known at its end).
  NoiseAnalysis Finish(double sample_period_s) const;

 private:
  double sample_period_s_;
  NoiseOptions options_;
  std::vector<AllanAccumulator> axes_;
  std::vector<double> buffer_;
  std::size_t samples_ = 0;
};

/// Each axis of `samples` (taken every `sample_period_s`, in the unit the terms come out in).
/// Throws DataError when there are too few samples for the terms fitted (4 m ≤ n must hold for
/// one more octave than terms: 128 samples for all five), or an axis is constant (no noise to
/// characterise); std::invalid_argument for a period not finite and positive or a sample not
/// finite.
NoiseAnalysis AnalyseNoise(const std::vector<Vec3>& samples, double sample_period_s,
                           const NoiseOptions& options = {});

}  // namespace accelcal
