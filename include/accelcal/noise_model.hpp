#pragma once
/// @file noise_model.hpp
/// The IEEE Std 952-1997 (Annex C) / Std 1293 noise terms of a rate sensor, fitted to its Allan
/// variance (allan.hpp):
///
///   σ²(τ) = 3 Q²/τ² + N²/τ + (2 ln 2/π) B² + K² τ/3 + R² τ²/2,
///
/// with, for a rate in [unit] (rad/s, m/s², or the sensor's raw unit):
///
///   Q  quantisation noise       [unit·s]      (of the integrated rate: angle, velocity)
///   N  white noise, the noise density [unit/√Hz] = [unit·√s] (angle / velocity random walk)
///   B  bias instability          [unit]       (the flicker floor)
///   K  random walk of the rate   [unit·√Hz] = [unit/√s] (rate / acceleration random walk)
///   R  rate ramp                 [unit/s]
///
/// A sampled white noise of σ per sample at period τ₀ has N = σ √τ₀; a rate random walk with
/// steps of σ_b per sample has K = σ_b / √τ₀.
///
/// The fit is generalised least squares on σ², the coefficients Q² … R² unconstrained (a term
/// the data do not show comes out near 0, either side). The estimates' covariance is D ρ D: D
/// each point's σ, √(2/edf) times the model's σ², with the degrees of freedom of the noise that
/// dominates the model there (AllanEdf); ρ the correlation of estimates that share their samples,
/// from the model's spectrum (AllanCorrelation). Both follow the model (its terms' positive
/// part), so the fit is iterated until it settles. A term whose interval c ± z σ_c lies above 0
/// is resolved, and its interval is the square root of that; otherwise the data bound it from
/// above only. The upper end is raised to the score end where that is higher: the least c' with
/// c' − c ≥ z σ_c(c'), σ_c(c') the standard error were the term c' and the others fitted again
/// with it held there. σ_c follows a term that dominates the points it is determined by (a
/// random walk at the longest τ, a few degrees of freedom each), and a log whose random walk
/// came out low weighs those points as quiet; c + z σ_c then held the truth in 91 % of simulated
/// one-hour logs, the score end in 98 %. The score end is sought up to the Allan deviation's own
/// bound (NoiseTermEstimate::resolved), and is that bound where none lies below it; a term not
/// resolved has no upper end beyond that bound unless its estimate lies beyond it.

#include <array>
#include <vector>

#include "accelcal/allan.hpp"
#include "accelcal/types.hpp"

namespace accelcal {

enum class NoiseTerm { kQuantization, kWhite, kBiasInstability, kRandomWalk, kRateRamp };
inline constexpr int kNoiseTerms = 5;

/// "quantization", "white", "bias_instability", "random_walk", "rate_ramp".
const char* ToString(NoiseTerm term);

struct NoiseTermEstimate {
  double value = 0;  ///< the coefficient (Q, N, B, K or R), ≥ 0
  /// Its standard error (delta method from σ(value²)) when resolved; else 0.
  double sigma = 0;
  /// The `confidence` interval of the value (of its square, taken to the square root; the
  /// upper end the score end where that is higher: see above).
  double low = 0, high = 0;
  /// The interval excludes 0: the term is seen in the data. Not resolved, `high` is an upper
  /// bound: for a term the fit puts below 0 beyond its interval (z below −1.96), the Allan
  /// deviation's own, √(min over τ of σ²(τ)'s upper limit over the term's avar at value 1), each
  /// limit at 1 − (1 − confidence)/n: every term adds a variance ≥ 0.
  bool resolved = false;
  bool fitted = false;  ///< false: left out of the fit (not asked for)
  /// The squared coefficient over its standard error, c / σ_c, unconstrained: below −1.96 it is
  /// in `below_zero`; far below (−3 and less: by chance in 0.13 % of logs) the terms do not
  /// describe the noise.
  double z = 0;
};

struct NoiseFitOptions {
  /// The terms fitted (all by default).
  std::array<bool, kNoiseTerms> terms = {true, true, true, true, true};
  double confidence = 0.95;  ///< of the intervals, two-sided
  int max_iterations = 200;  ///< of the reweighting (71 on the T265 rest's accelerometer y)
  /// false: the estimates, their σ and z alone, for a caller that needs no interval (calibrate's
  /// check of its rest): each term's `high` is then c + z σ_c (0 for a term below 0), without
  /// the score end or the Allan deviation's own bound, and NoiseModelFit::intervals is empty.
  bool intervals = true;
};

struct NoiseModelFit {
  std::array<NoiseTermEstimate, kNoiseTerms> terms;  ///< by NoiseTerm
  std::vector<AllanPoint> points;                    ///< as given
  std::vector<double> model_avar;                    ///< the fitted σ²(τ) at each point
  std::vector<PowerLawNoise> dominant;               ///< the term largest there
  std::vector<double> edf;                           ///< each point's degrees of freedom
  std::vector<AllanInterval> intervals;              ///< each point's interval of σ(τ)
  double chi2 = 0;  ///< rᵀ Σ⁻¹ r of the residuals r = σ̂² − model, with the final Σ
  int dof = 0;      ///< points − terms fitted
  /// P(χ²_dof ≥ chi2): small when the terms do not describe the Allan variance.
  double chi2_p = 1;
  /// Terms significantly below 0 (c < −z σ_c): the five terms do not describe this noise (a
  /// filter before the samples, a vibration, a drift that is not a ramp), and the others'
  /// values take up what is missing.
  std::vector<NoiseTerm> below_zero;
  int iterations = 0;
  bool converged = false;
};

/// Fits the terms to `points` (from one accumulator: at least one more than the terms fitted).
/// Throws std::invalid_argument for fewer points, points that do not tell the terms apart, a
/// negative or non-finite σ², or options out of range.
NoiseModelFit FitNoiseModel(const std::vector<AllanPoint>& points,
                            const NoiseFitOptions& options = {});

/// The correlation of the overlapping Allan variance estimates at `points` (one accumulator's)
/// under the noise of the terms' squared coefficients c = (Q², N², B², K², R²), to first order in
/// m/N: for Gaussian noise their covariance is proportional to ∫ A_m(ν) A_m'(ν) S(ν)² dν, A_m the
/// Allan variance's transfer function at m samples, S the spectrum whose Allan variance each term
/// is (IEEE Std 952 Table C.2).
Eigen::MatrixXd AllanCorrelation(const std::vector<AllanPoint>& points,
                                 const std::array<double, kNoiseTerms>& squared);

/// σ²(τ) of the terms' coefficients c = (Q², N², B², K², R²) at τ.
double NoiseModelAvar(const std::array<double, kNoiseTerms>& squared, double tau_s);

}  // namespace accelcal
