#pragma once
/// @file noise_simulation.hpp
/// A still sensor's rate, simulated with the IEEE noise terms of noise_model.hpp (part of the
/// library so that tests, benchmarks and users share it; deterministic for a given seed).

#include <cstddef>
#include <cstdint>
#include <vector>

#include "accelcal/noise_model.hpp"

namespace accelcal {

/// `samples` readings taken every `sample_period_s` of a rate whose Allan variance is
/// NoiseModelAvar of the squared `terms` (Q, N, B, K, R by NoiseTerm; each ≥ 0), around 0:
///   - quantisation: (x_{k+1} − x_k)/τ₀, x white of σ Q (white phase: σ² = 3Q²/τ² exactly);
///   - white: σ N/√τ₀ per sample (σ² = N²/τ exactly);
///   - bias instability: white noise of σ B through the fractional integrator (1 − z⁻¹)^−½
///     (Kasdin and Walter 1992), whose two-sided spectrum τ₀ σ_w² / (2 sin π f τ₀) is B²/(2π f)
///     at low frequency (IEEE Std 952's S_Ω is two-sided): σ² is (2 ln 2/π) B² within 2 % from
///     m = 8 on, and above it at the shortest τ (1.44 times at m = 1);
///   - random walk: steps of σ K √τ₀ per sample (σ² = K² τ/3 + K² τ₀²/(6 τ): a white part
///     of K² τ₀²/6, below the others in practice);
///   - rate ramp: R τ₀ k.
/// Throws std::invalid_argument for a negative or non-finite term, a period not finite and
/// positive, or more than 2^28 samples with bias instability (its filter is applied by FFT).
std::vector<double> SimulateNoise(const std::array<double, kNoiseTerms>& terms, std::size_t samples,
                                  double sample_period_s, std::uint64_t seed);

}  // namespace accelcal
