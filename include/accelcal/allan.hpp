#pragma once
/// @file allan.hpp
/// The overlapping Allan variance of a sampled rate (IEEE Std 952-1997 Annex C; NIST SP 1065
/// §5.2.4) at octave-spaced averaging times, accumulated from a stream of samples in memory that
/// does not grow with the stream, with confidence intervals from its equivalent χ² degrees of
/// freedom.
///
/// With y_k the samples taken every τ₀ and θ_i = τ₀ Σ_{k<i} y_k their integral (N = n + 1 phase
/// points for n samples), at τ = m τ₀:
///
///   σ²(τ) = Σ_i (θ_{i+2m} − 2 θ_{i+m} + θ_i)² / (2 τ² · terms),
///
/// the sum over i = 0, s, 2s, … ≤ N − 1 − 2m. The fully overlapping estimator takes every i
/// (stride s = 1); here averages of up to R samples (AllanOptions::full_overlap_up_to) do, and
/// longer ones take every (m / R)-th, so that each octave keeps 2R + 1 phase points however long
/// the log. Adjacent terms of a long average share all but 1/R of their samples, so the estimate
/// loses almost nothing (tested: its scatter over simulated logs against the fully overlapping
/// one's).

#include <cstddef>
#include <cstdint>
#include <vector>

namespace accelcal {

/// The power-law noise of the rate, S_y(f) ∝ f^α, that an Allan variance point's degrees of
/// freedom are taken for. The inertial names (IEEE Std 952 Annex C) beside the time-and-frequency
/// ones: quantisation noise is white phase noise, white rate noise (the noise density: angle or
/// velocity random walk) white frequency noise, bias instability flicker frequency noise, and
/// rate random walk random-walk frequency noise.
enum class PowerLawNoise {
  kQuantization = 2,  ///< σ² ∝ τ⁻², white phase
  kWhite = 0,         ///< σ² ∝ τ⁻¹, white frequency
  kFlicker = -1,      ///< σ² ∝ τ⁰, flicker frequency (bias instability)
  kRandomWalk = -2,   ///< σ² ∝ τ, random-walk frequency
};

struct AllanOptions {
  /// Sample period τ₀ [s], > 0.
  double sample_period_s = 0;
  /// R, a power of two from 1 to 2^20: averages of up to R samples are compared at every sample,
  /// longer ones at every m/R samples.
  std::uint64_t full_overlap_up_to = 32;
};

/// One averaging time's estimate.
struct AllanPoint {
  std::uint64_t m = 0;             ///< samples per average
  double tau_s = 0;                ///< m τ₀ [s]
  std::uint64_t stride = 1;        ///< s: samples between the starts of the terms compared
  std::uint64_t terms = 0;         ///< second differences averaged
  std::uint64_t phase_points = 0;  ///< N = n + 1 of the n samples it is from
  double avar = 0;                 ///< σ²(τ) [unit²]
};

/// The overlapping Allan variance of a stream, octave by octave (m = 1, 2, 4, …): O(R log n)
/// memory, about log₂ R + 2 updates per sample.
class AllanAccumulator {
 public:
  /// Throws std::invalid_argument for a sample period not finite and positive or an R that is
  /// not a power of two in range.
  explicit AllanAccumulator(const AllanOptions& options);

  /// Appends samples y [unit], finite (throws std::invalid_argument naming the sample's index in
  /// the stream otherwise).
  void Add(const double* y, std::size_t count);
  void Add(double y) { Add(&y, 1); }

  std::uint64_t samples() const { return samples_; }

  /// Every octave with 4 m ≤ n (n the samples so far): at m = n/4 the white-noise estimate still
  /// has about 4 degrees of freedom.
  std::vector<AllanPoint> Points() const;
  /// The same at another sample period (a stream whose rate is known only at its end): the sums
  /// do not depend on it. Throws std::invalid_argument for one not finite and positive.
  std::vector<AllanPoint> Points(double sample_period_s) const;

 private:
  // Level 0 keeps every phase point (for m = 1, 2, …, R: sums_ and terms_ by log₂ m); level
  // l ≥ 1 every 2^l-th, for m = R 2^l. Each ring holds 4R points (the last 2R + 1 are read).
  struct Level {
    std::uint64_t m = 1, stride = 1;
    std::vector<double> ring;
    std::uint64_t count = 0;  // its phase points so far
    double sum = 0;           // Σ of its squared second differences
    std::uint64_t terms = 0;
  };

  AllanOptions options_;
  std::uint64_t samples_ = 0;
  double origin_ = 0;  // the first sample, subtracted (σ² does not see a constant)
  double theta_ = 0;   // θ at the latest phase point, in sample sums (τ₀ cancels in σ²)
  std::vector<Level> levels_;
  std::vector<double> sums_;
  std::vector<std::uint64_t> terms_;
  std::vector<double> history_;  // Add's θ of a chunk's phase points
};

/// The overlapping Allan variance of `y` (AllanAccumulator over the whole vector).
std::vector<AllanPoint> AllanVariance(const std::vector<double>& y, const AllanOptions& options);

/// Equivalent χ² degrees of freedom of the overlapping estimator at `m` from `phase_points`
/// (N = n + 1) for the noise `noise`: the empirical formulae of Howe, Allan and Barnes (1981), as
/// NIST SP 1065 Table 5 gives them.
double AllanEdf(PowerLawNoise noise, double phase_points, double m);

/// The degrees of freedom of a point: a stride s > 1 is the fully overlapping estimator of the
/// phase taken every s-th point (⌊(N − 1)/s⌋ + 1 of them, averages of m/s), which is what the
/// formulae above are given. For white rate noise that is the same as the full overlap's; for
/// quantisation noise, whose terms are nearly independent, it is about 1/s of it.
double AllanEdf(PowerLawNoise noise, const AllanPoint& point);

/// A two-sided confidence interval of the deviation σ(τ).
struct AllanInterval {
  double low = 0, high = 0;
};

/// The interval that holds σ(τ) with probability `confidence` (0 < c < 1), from an estimate
/// `avar` with `edf` degrees of freedom: edf · σ̂²/σ² ~ χ²_edf, so σ lies between
/// √(edf σ̂² / χ²_{upper (1−c)/2}) and √(edf σ̂² / χ²_{upper (1+c)/2}).
AllanInterval AllanDeviationInterval(double avar, double edf, double confidence);

}  // namespace accelcal
