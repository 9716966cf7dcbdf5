#pragma once
/// @file simulate.hpp
/// Simulation of static multi-position recordings (part of the library so that tests, benchmarks
/// and users share it; deterministic for a given seed).

#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

#include "accelcal/gyro_model.hpp"
#include "accelcal/model.hpp"

namespace accelcal {

/// Unit direction of specific force for pitch θ and roll φ (paper 000 eq. (6), (30)):
/// c = (sin θ, cos θ cos φ, −cos θ sin φ).
Vec3 DirectionFromAngles(double theta_rad, double phi_rad);

/// Paper 000 Table 2: the 18 optimal positions (θ, φ); '*' entries taken as φ = 0.
std::vector<Vec3> Yang18Directions();

/// Paper 000 Table 3 truth in raw pulses with f in m/s² and g = 9.8 (docs/errata.md#000-table3
/// conventions): k_a = (4800, 4900, 5000) pulse/(m/s²); τ_yx = sin 0.01°, (τ_zx, τ_zy) = sin
/// 0.02°·(cos 30°, sin 30°), unit rows; biases (0.01, 0.02, 0.03) m/s²; squared coefficients
/// (1, 2, 3)e-5 g/g².
ModelParameters Yang2012Truth();
inline constexpr double kYang2012Gravity_ms2 = 9.8;
/// Per-axis noise of one averaged position in Table 4 (docs/errata.md#000-table4):
/// 10 µg/√Hz·√100 Hz / √6000 [m/s²].
inline constexpr double kYang2012PositionSigma_ms2 = 10e-6 * 10.0 / 77.45966692414834 * 9.8;
/// That noise in raw units for a device: per axis, the length of its row of K times it.
Vec3 Yang2012SigmaRaw(const ModelParameters& device);

/// Per-axis 1σ [raw] of the mean of `samples` samples of white noise of density `density_ug`
/// [µg/√Hz, µg relative to `gravity`] sampled at `rate_hz` (`samples` = 1: one sample): density ·
/// √(rate / samples) in the specific-force unit, mapped to each raw axis by the length of its row
/// of K. The one conversion design and simulate use.
Vec3 RawNoiseFromDensity(const ModelParameters& device, double gravity, double density_ug,
                         double rate_hz, double samples = 1);

/// Averaged readings p_k = μ(g c_k) + v_k, v_k ~ N(0, diag(sigma_raw²)), deterministic in seed.
std::vector<Vec3> SimulatePositions(const ModelParameters& truth, double gravity,
                                    const std::vector<Vec3>& directions, const Vec3& sigma_raw,
                                    std::uint64_t seed);

/// Paper 001 eq. (19): T_a (upper-triangular, the z-first frame of frame.hpp) in raw units per g.
Mat33 SunXu2020Ta();
/// Paper 001 eq. (19): b_a [g].
Vec3 SunXu2020Ba();
inline constexpr double kSunXu2020Sigma_g = 0.1;  ///< §4.1 noise, per axis [g]

/// Paper 001 §4.1 attitudes: pitch, roll and heading of (120°, 120°, 80°) each multiplied by a
/// standard-normal factor (docs/errata.md#001-attitudes: uniform factors leave the problem nearly
/// unobservable). Returns the unit specific-force direction in the body frame, c = (sin θ, −sin φ
/// cos θ, −cos φ cos θ) (heading does not move gravity).
std::vector<Vec3> SunXu2020Directions(int count, std::uint64_t seed);

/// Readings p_k = M c_k + b + n_k, n_k ~ N(0, sigma² I), for any 3x3 M (paper 001 eq. (4) with
/// |c_k| = 1); deterministic in seed.
std::vector<Vec3> SimulateLinearPositions(const Mat33& M, const Vec3& b,
                                          const std::vector<Vec3>& directions, double sigma,
                                          std::uint64_t seed);

/// A raw log as an accelerometer would record it: `static_s` seconds still in each direction,
/// joined by `transition_s` seconds of turning (the direction moves along the great circle with a
/// smooth start and stop), white noise of `sigma_raw_per_sample` on every sample, deterministic in
/// seed.
struct RawLogSimulation {
  double rate_hz = 100.0;
  double static_s = 60.0;
  double transition_s = 4.0;
  Vec3 sigma_raw_per_sample = Vec3::Ones();
  std::uint64_t seed = 1;
};
/// Samples and their times (t = index / rate).
struct SimulatedLog {
  std::vector<double> time_s;
  std::vector<Vec3> samples;
};
SimulatedLog SimulateRawLog(const ModelParameters& truth, double gravity,
                            const std::vector<Vec3>& directions, const RawLogSimulation& options);
/// The same samples, handed one at a time to `sink` (time [s], raw reading) without being held:
/// a long log costs no memory.
void SimulateRawLog(const ModelParameters& truth, double gravity,
                    const std::vector<Vec3>& directions, const RawLogSimulation& options,
                    const std::function<void(double time_s, const Vec3& raw)>& sink);
/// How many samples SimulateRawLog gives (as a double: options may ask for more than any
/// integer holds; check it before simulating).
double SimulatedSampleCount(std::size_t directions, const RawLogSimulation& options);

/// A gyroscope recorded beside the accelerometer of SimulateImuLog, on the same clock.
struct GyroSimulation {
  GyroParameters truth;  ///< K_g [gyro raw per rad/s], b_g, G [gyro raw per force unit]
  Vec3 sigma_raw_per_sample = Vec3::Zero();  ///< white noise of each rate sample [gyro raw]
  /// The body's own slow motion while it stands in a position (a unit held by hand or on a soft
  /// mount): about each body axis a rate of three sinusoids near `wobble_hz` (0.6, 1 and 1.6
  /// times it, each frequency within ±20 %, with random phases; drawn anew for each position),
  /// of σ `wobble_rad_s` in all, whose
  /// angle starts at 0 in each position and stays bounded (σ_ω / 2πf). Both sensors see it: the
  /// force direction moves with the body. 0: still.
  double wobble_rad_s = 0;
  double wobble_hz = 0.5;
  /// Turns about the vertical (the force direction, which they leave unchanged) inside still
  /// positions: (position, angle [rad]) with the position 0-based, turned over the middle half
  /// of the position at a rate that rises and falls linearly.
  std::vector<std::pair<std::size_t, double>> vertical_turns;
};
/// An accelerometer's and a gyroscope's samples at the same times.
struct SimulatedImuLog {
  std::vector<double> time_s;
  std::vector<Vec3> accel;  ///< raw accelerometer readings
  std::vector<Vec3> gyro;   ///< raw gyro readings
  /// The body rate [rad/s] and the force direction c (|c| = 1, body frame) at each sample.
  std::vector<Vec3> omega_rad_s, direction;
};
/// A raw log as SimulateRawLog, with a gyroscope: between two still directions the body turns
/// about the fixed axis a = c × c_next at a rate that rises and falls linearly (zero at both
/// ends), ω = −α̇ a (the direction moves as c(t) = Exp(α(t) a) c in the body frame, so the body
/// turns by Exp(−α a)); α at each sample is the trapezoidal sum of the sampled rates, so
/// IntegrateAngularRate with RateInterpolation::kTrapezoidal gives the motion exactly, and the
/// turn ends on c_next. Each gyro sample is ω_raw = K_g ω + b_g + G f + noise with f = gravity · c
/// (no linear or centripetal acceleration: the sensor turns about itself). With a wobble or a turn
/// about the vertical (GyroSimulation) the force direction in a still position follows the body
/// rates by the same trapezoidal rule, c_{k+1} = Exp(−½(ω_k + ω_{k+1}) h) c_k, and the turn out
/// of it starts where the body is. Noise draws: the accelerometer's three, then the gyro's three,
/// per sample (the wobble's phases and frequencies from a generator of their own, so the noise is
/// the same with and without it); deterministic in options.seed.
SimulatedImuLog SimulateImuLog(const ModelParameters& accel_truth, double gravity,
                               const std::vector<Vec3>& directions, const RawLogSimulation& options,
                               const GyroSimulation& gyro);

/// Random unit directions, uniform on the sphere, deterministic in seed.
std::vector<Vec3> RandomDirections(int count, std::uint64_t seed);

/// Random unit directions, uniform on the cap of half-angle `half_angle_rad` about +z (a poorly
/// spread recording, e.g. a device only tilted on a desk), deterministic in seed.
std::vector<Vec3> RandomDirectionsInCap(int count, double half_angle_rad, std::uint64_t seed);

}  // namespace accelcal
