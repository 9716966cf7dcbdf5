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

/// Whether the sensor stayed still: the means of consecutive blocks of kStillBlockSamples
/// samples then differ by noise and drift alone, each change about as large as the others (for
/// white noise, random walk, bias instability alike, the largest of 10⁵ changes is some 7
/// median ones). A turn or a knock changes the mean by a part of g in one block. A log that
/// turns all the time (a calibration session of short positions) has no quiet median change to
/// stand out from: there the largest change is also held against the quietest block's mean step
/// between neighbouring samples (as Spikes::typical_step), which a block mean of a still sensor
/// does not reach by kStillStepRatio (white noise: some 0.4 of it; a sensor low-passed to a lag-1
/// correlation of 0.99: some 50), and a turn of a part of g does by hundreds.
struct Stillness {
  bool checked = false;  ///< at least kStillMinBlocks blocks
  bool still = true;     ///< largest_change ≤ kStillChangeRatio · typical_change on every axis
  int axis = 0;          ///< the axis of the largest change relative to its typical one
  double largest_change = 0;  ///< |mean_{j+1} − mean_j| there [sample unit]
  double typical_change = 0;  ///< the median change there, floored by the quantum / block
  std::size_t at_sample = 0;  ///< the first sample of the block after the largest change
  /// Refused by the step criterion: typical_change is then the typical step between
  /// neighbouring samples.
  bool beyond_steps = false;
};
/// Single-sample glitches (a bus error, a saturated reading): a step between neighbouring
/// samples far beyond the typical one adds its square to every short averaging time's variance
/// and biases the white noise high (ten steps of 70σ in 20000 samples: +50 %). The typical step
/// is the median over blocks of kStillBlockSamples of their mean |x_k − x_{k−1}| (0.8 σ_Δ for
/// Gaussian noise; the largest of 35 M such steps is some 6 σ_Δ, 8 typical ones), floored by
/// the quantum.
struct Spikes {
  bool checked = false;       ///< at least kStillMinBlocks blocks
  bool clean = true;          ///< largest_step ≤ kSpikeRatio · typical_step on every axis
  int axis = 0;               ///< the axis of the largest step relative to its typical one
  double largest_step = 0;    ///< |x_k − x_{k−1}| there [sample unit]
  double typical_step = 0;    ///< there
  std::size_t at_sample = 0;  ///< k
};
inline constexpr double kSpikeRatio = 20;

inline constexpr std::size_t kStillBlockSamples = 256;
inline constexpr std::size_t kStillMinBlocks = 8;
inline constexpr double kStillChangeRatio = 30;
inline constexpr double kStillStepRatio = 100;

/// Samples whose squares double precision holds (sums of them, in the Allan variance): an axis
/// whose readings reach beyond kMaxNoiseMagnitude, or vary by less than kMinNoiseSpread, is
/// refused.
inline constexpr double kMaxNoiseMagnitude = 1e100;
inline constexpr double kMinNoiseSpread = 1e-100;

/// An axis whose reading changes in fewer than this fraction of its steps is refused: it holds
/// one value nearly throughout (a stuck column with a glitch, or a quantum so coarse that the
/// noise is below a hundredth of it: white noise of σ changes a reading of quantum q in about
/// 1.13 σ/q of the steps), and what its Allan variance shows is those few changes, not noise.
inline constexpr double kMinChangingSteps = 0.01;

struct NoiseAnalysis {
  std::size_t samples = 0;
  double sample_period_s = 0;
  std::array<AxisNoise, 3> axes;  ///< x, y, z
  Vec3 mean = Vec3::Zero();       ///< of the samples
  Stillness stillness;
  Spikes spikes;
};

/// The same, fed in pieces (a log too long to hold, StreamRawLog): memory does not grow with the
/// samples.
class NoiseAccumulator {
 public:
  /// Throws std::invalid_argument for a period not finite and positive, or fit options out of
  /// range (FitNoiseModel's).
  NoiseAccumulator(double sample_period_s, const NoiseOptions& options = {});
  /// Appends samples (finite: std::invalid_argument naming the sample otherwise).
  void Add(const Vec3* samples, std::size_t count);
  std::size_t samples() const { return samples_; }
  /// The sample after the largest step of `axis` so far (0: none): a streamed log's reader takes
  /// its line when it changes, for the message that names a spike.
  std::size_t largest_step_sample(int axis) const { return largest_step_at_[std::size_t(axis)]; }
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
  Vec3 sum_ = Vec3::Zero();  // of the samples less the first (their mean, exactly enough)
  Vec3 first_ = Vec3::Zero();
  Vec3 previous_ = Vec3::Zero();                   // the last sample of the previous piece
  Vec3 low_ = Vec3::Zero(), high_ = Vec3::Zero();  // per axis, of the samples
  Vec3 quantum_ = Vec3::Zero();           // per axis, the smallest nonzero change between samples
  std::array<std::size_t, 3> changes_{};  // per axis, steps with a nonzero change
  Vec3 block_sum_ = Vec3::Zero();
  std::vector<Vec3> block_means_;
  Vec3 largest_step_ = Vec3::Zero();
  std::array<std::size_t, 3> largest_step_at_{};
  Vec3 block_abs_steps_ = Vec3::Zero();
  std::vector<Vec3> block_mean_abs_steps_;
};

/// Each axis of `samples` (taken every `sample_period_s`, in the unit the terms come out in).
/// Throws DataError when there are too few samples for the terms fitted (4 m ≤ n must hold for
/// one more octave than terms: 128 samples for all five), an axis is constant (no noise to
/// characterise) or beyond the magnitudes above; std::invalid_argument for a period not finite
/// and positive or a sample not finite.
NoiseAnalysis AnalyseNoise(const std::vector<Vec3>& samples, double sample_period_s,
                           const NoiseOptions& options = {});

}  // namespace accelcal
