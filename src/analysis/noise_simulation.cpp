// A still sensor's noise, simulated term by term (noise_simulation.hpp).
#include "accelcal/noise_simulation.hpp"

#include <cmath>
#include <complex>
#include <random>
#include <stdexcept>

#include <unsupported/Eigen/FFT>

namespace accelcal {

namespace {

// White noise of unit variance through (1 − z⁻¹)^−½: the filter h_0 = 1, h_k = h_{k−1} (k − ½)/k
// (Kasdin and Walter 1992, eq. for α = 1), convolved by FFT over twice the length (no wrap).
std::vector<double> Flicker(std::size_t n, std::mt19937_64& rng,
                            std::normal_distribution<double>& normal) {
  std::size_t size = 1;
  while (size < 2 * n) size <<= 1;
  std::vector<double> w(size, 0.0), h(size, 0.0);
  for (std::size_t k = 0; k < n; ++k) w[k] = normal(rng);
  h[0] = 1;
  for (std::size_t k = 1; k < n; ++k)
    h[k] = h[k - 1] * (static_cast<double>(k) - 0.5) / static_cast<double>(k);
  Eigen::FFT<double> fft;
  std::vector<std::complex<double>> W, H;
  fft.fwd(W, w);
  fft.fwd(H, h);
  for (std::size_t k = 0; k < W.size(); ++k) W[k] *= H[k];
  std::vector<double> out;
  fft.inv(out, W);
  out.resize(n);
  return out;
}

}  // namespace

std::vector<double> SimulateNoise(const std::array<double, kNoiseTerms>& terms, std::size_t samples,
                                  double sample_period_s, std::uint64_t seed) {
  for (double t : terms) {
    if (!(t >= 0) || !std::isfinite(t)) {
      throw std::invalid_argument("SimulateNoise: a noise term is negative or not finite");
    }
  }
  if (!(sample_period_s > 0) || !std::isfinite(sample_period_s)) {
    throw std::invalid_argument("SimulateNoise: the sample period must be finite and positive");
  }
  const double Q = terms[0], N = terms[1], B = terms[2], K = terms[3], R = terms[4];
  if (B > 0 && samples > (std::size_t{1} << 28)) {
    throw std::invalid_argument("SimulateNoise: at most 2^28 samples with bias instability");
  }
  const double tau0 = sample_period_s;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<double> y(samples, 0.0);
  // Each term from its own draws, in a fixed order: white, quantisation, random walk, flicker.
  if (N > 0) {
    for (double& v : y) v += N / std::sqrt(tau0) * normal(rng);
  }
  if (Q > 0) {
    double x = Q * normal(rng);
    for (double& v : y) {
      const double next = Q * normal(rng);
      v += (next - x) / tau0;
      x = next;
    }
  }
  if (K > 0) {
    double walk = 0;
    for (double& v : y) v += walk += K * std::sqrt(tau0) * normal(rng);
  }
  if (B > 0) {
    const std::vector<double> f = Flicker(samples, rng, normal);
    for (std::size_t k = 0; k < samples; ++k) y[k] += B * f[k];
  }
  if (R > 0) {
    for (std::size_t k = 0; k < samples; ++k) y[k] += R * tau0 * static_cast<double>(k);
  }
  return y;
}

}  // namespace accelcal
