#include "accelcal/simulate.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include <Eigen/Geometry>

#include "accelcal/engineering.hpp"
#include "accelcal/rotations.hpp"

namespace accelcal {

namespace {
// Three draws in a fixed order. Vec3(normal(rng), normal(rng), normal(rng)) leaves the order to the
// compiler (GCC draws z first, clang x first), which made simulations compiler-dependent; this
// keeps GCC's order, so every figure computed before stays the same.
Vec3 NormalVector(std::normal_distribution<double>& normal, std::mt19937_64& rng) {
  const double z = normal(rng);
  const double y = normal(rng);
  const double x = normal(rng);
  return Vec3(x, y, z);
}
}  // namespace

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;
}  // namespace

Vec3 DirectionFromAngles(double theta_rad, double phi_rad) {
  return {std::sin(theta_rad), std::cos(theta_rad) * std::cos(phi_rad),
          -std::cos(theta_rad) * std::sin(phi_rad)};
}

std::vector<Vec3> Yang18Directions() {
  const double h = kPi / 2, q = kPi / 4;
  const double table[18][2] = {{h, 0}, {-h, 0},                             // k_axx, k2_x, p0_x
                               {0, 0}, {0, kPi},                            // k_ayy, k2_y, p0_y
                               {0, h}, {0, -h},                             // k_azz, k2_z, p0_z
                               {q, 0}, {-q, 0},  {q, kPi},   {-q, kPi},     // k_ayx
                               {q, h}, {q, -h},  {-q, h},    {-q, -h},      // k_azx
                               {0, q}, {0, -q},  {0, 3 * q}, {0, -3 * q}};  // k_azy
  std::vector<Vec3> dirs;
  for (const auto& row : table) dirs.push_back(DirectionFromAngles(row[0], row[1]));
  return dirs;
}

Vec3 RawNoiseFromDensity(const ModelParameters& device, double gravity, double density_ug,
                         double rate_hz, double samples) {
  const double sigma_force = density_ug * 1e-6 * gravity * std::sqrt(rate_hz / samples);
  Vec3 sigma;
  for (int i = 0; i < 3; ++i) sigma(i) = device.K.row(i).norm() * sigma_force;
  return sigma;
}

Vec3 Yang2012SigmaRaw(const ModelParameters& device) {
  Vec3 sigma;
  for (int i = 0; i < 3; ++i) sigma(i) = device.K.row(i).norm() * kYang2012PositionSigma_ms2;
  return sigma;
}

ModelParameters Yang2012Truth() {
  EngineeringParameters eng;
  eng.scale_factor = Vec3(4800, 4900, 5000);
  eng.tau_yx = std::sin(0.01 * kDeg);
  eng.tau_yy = std::sqrt(1 - eng.tau_yx * eng.tau_yx);
  eng.tau_zx = std::sin(0.02 * kDeg) * std::cos(30 * kDeg);
  eng.tau_zy = std::sin(0.02 * kDeg) * std::sin(30 * kDeg);
  eng.tau_zz = std::sqrt(1 - eng.tau_zx * eng.tau_zx - eng.tau_zy * eng.tau_zy);
  eng.bias_force = Vec3(0.01, 0.02, 0.03);
  eng.k2_g_per_g2 = Vec3(1e-5, 2e-5, 3e-5);
  return FromEngineering(eng, kYang2012Gravity_ms2);
}

std::vector<Vec3> SimulatePositions(const ModelParameters& truth, double gravity,
                                    const std::vector<Vec3>& directions, const Vec3& sigma_raw,
                                    std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<Vec3> readings;
  readings.reserve(directions.size());
  for (const Vec3& c : directions) {
    Vec3 p = PredictRaw(truth, Vec3(gravity * c.normalized()));
    for (int i = 0; i < 3; ++i) p(i) += sigma_raw(i) * normal(rng);
    readings.push_back(p);
  }
  return readings;
}

Mat33 SunXu2020Ta() {
  Mat33 T;
  T << 1.1500, 0.0602, -0.0401, 0, 1.0985, 0.0575, 0, 0, 1.0978;
  return T;
}

Vec3 SunXu2020Ba() { return {0.1, 0.15, 0.2}; }

std::vector<Vec3> SunXu2020Directions(int count, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<Vec3> dirs;
  for (int k = 0; k < count; ++k) {
    const double pitch = 120.0 * kDeg * normal(rng);
    const double roll = 120.0 * kDeg * normal(rng);
    normal(rng);  // heading: drawn to keep the paper's three angles, does not move gravity
    dirs.emplace_back(std::sin(pitch), -std::sin(roll) * std::cos(pitch),
                      -std::cos(roll) * std::cos(pitch));
  }
  return dirs;
}

std::vector<Vec3> SimulateLinearPositions(const Mat33& M, const Vec3& b,
                                          const std::vector<Vec3>& directions, double sigma,
                                          std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<Vec3> readings;
  readings.reserve(directions.size());
  for (const Vec3& c : directions) {
    readings.push_back(M * c + b + sigma * NormalVector(normal, rng));
  }
  return readings;
}

std::vector<Vec3> RandomDirections(int count, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<Vec3> dirs;
  for (int k = 0; k < count; ++k) {
    Vec3 v = NormalVector(normal, rng);
    dirs.push_back(v.normalized());
  }
  return dirs;
}

std::vector<Vec3> RandomDirectionsInCap(int count, double half_angle_rad, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  // Archimedes: z uniform on [cos α, 1] and the azimuth uniform give a uniform density on the cap.
  const double z_min = std::cos(half_angle_rad);
  std::vector<Vec3> dirs;
  for (int k = 0; k < count; ++k) {
    const double z = z_min + (1.0 - z_min) * uniform(rng);
    const double azimuth = 2.0 * kPi * uniform(rng);
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    dirs.emplace_back(r * std::cos(azimuth), r * std::sin(azimuth), z);
  }
  return dirs;
}

void SimulateRawLog(const ModelParameters& truth, double gravity,
                    const std::vector<Vec3>& directions, const RawLogSimulation& options,
                    const std::function<void(double time_s, const Vec3& raw)>& sink) {
  std::mt19937_64 rng(options.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const auto still = static_cast<std::size_t>(std::llround(options.static_s * options.rate_hz));
  const auto turn = static_cast<std::size_t>(std::llround(options.transition_s * options.rate_hz));
  std::size_t index = 0;
  const auto emit = [&](const Vec3& c) {
    const double t = static_cast<double>(index++) / options.rate_hz;
    const Vec3 noise = NormalVector(normal, rng);
    sink(t,
         PredictRaw(truth, Vec3(gravity * c)) + options.sigma_raw_per_sample.cwiseProduct(noise));
  };
  for (std::size_t k = 0; k < directions.size(); ++k) {
    const Vec3 c = directions[k].normalized();
    for (std::size_t i = 0; i < still; ++i) emit(c);
    if (k + 1 == directions.size()) break;
    // Turn to the next direction: slerp with a smooth-step profile (zero rate at both ends).
    const Vec3 next = directions[k + 1].normalized();
    const double angle = std::atan2(c.cross(next).norm(), c.dot(next));
    Vec3 axis = c.cross(next);
    if (axis.norm() < 1e-12)
      axis = c.cross(Vec3::UnitX()).norm() > 0.1 ? c.cross(Vec3::UnitX()) : c.cross(Vec3::UnitY());
    axis.normalize();
    for (std::size_t i = 1; i < turn; ++i) {
      const double s = static_cast<double>(i) / static_cast<double>(turn);
      const double progress = s * s * (3.0 - 2.0 * s);
      emit(Eigen::AngleAxisd(progress * angle, axis) * c);
    }
  }
}

SimulatedLog SimulateRawLog(const ModelParameters& truth, double gravity,
                            const std::vector<Vec3>& directions, const RawLogSimulation& options) {
  SimulatedLog log;
  SimulateRawLog(truth, gravity, directions, options, [&log](double t, const Vec3& raw) {
    log.time_s.push_back(t);
    log.samples.push_back(raw);
  });
  return log;
}

SimulatedImuLog SimulateImuLog(const ModelParameters& accel_truth, double gravity,
                               const std::vector<Vec3>& directions, const RawLogSimulation& options,
                               const GyroSimulation& gyro) {
  std::mt19937_64 rng(options.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const auto still = static_cast<std::size_t>(std::llround(options.static_s * options.rate_hz));
  const auto turn = static_cast<std::size_t>(std::llround(options.transition_s * options.rate_hz));
  const double h = 1.0 / options.rate_hz;
  SimulatedImuLog log;
  const auto emit = [&](const Vec3& c, const Vec3& omega) {
    const double t = static_cast<double>(log.time_s.size()) / options.rate_hz;
    const Vec3 f = gravity * c;
    const Vec3 accel_noise = NormalVector(normal, rng);
    const Vec3 gyro_noise = NormalVector(normal, rng);
    log.time_s.push_back(t);
    log.accel.push_back(PredictRaw(accel_truth, f) +
                        options.sigma_raw_per_sample.cwiseProduct(accel_noise));
    log.gyro.push_back(PredictRate(gyro.truth, omega, f) +
                       gyro.sigma_raw_per_sample.cwiseProduct(gyro_noise));
    log.omega_rad_s.push_back(omega);
    log.direction.push_back(c);
  };
  // The wobble: per axis three sinusoids of the rate (angular frequency, amplitude, phase), from a
  // generator of their own, drawn anew for each position; three of amplitude A have σ A √(3/2).
  struct Wave {
    double omega_rad_s, amplitude, phase;
  };
  std::vector<Wave> waves[3];
  std::mt19937_64 wobble_rng(options.seed ^ 0x9e3779b97f4a7c15ULL);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const auto draw_waves = [&] {
    const double amplitude = gyro.wobble_rad_s * std::sqrt(2.0 / 3.0);
    for (std::vector<Wave>& axis : waves) {
      axis.clear();
      for (const double ratio : {0.6, 1.0, 1.6}) {
        const double f = gyro.wobble_hz * ratio * (0.8 + 0.4 * unit(wobble_rng));
        axis.push_back({2 * kPi * f, amplitude, 2 * kPi * unit(wobble_rng)});
      }
    }
  };
  // The rate profile of a turn about the vertical in a still position: a triangle over its
  // middle half, scaled to the angle under the trapezoidal rule.
  const auto vertical_rates = [&](std::size_t position) {
    std::vector<double> rate;
    for (const auto& [p, angle] : gyro.vertical_turns) {
      if (p != position || angle == 0) continue;
      rate.assign(still, 0.0);
      const std::size_t first = still / 4, last = (3 * still) / 4;
      if (last < first + 2) break;
      double area = 0;
      for (std::size_t i = first; i <= last; ++i) {
        const double s = static_cast<double>(i - first) / static_cast<double>(last - first);
        rate[i] = 1.0 - std::abs(2.0 * s - 1.0);
        area += rate[i];
      }
      for (double& r : rate) r *= angle / (h * area);
    }
    return rate;
  };
  const double ramp_s = 0.25;  // the wobble fades in and out: no jump at a turn's still ends
  Vec3 c = directions.empty() ? Vec3::UnitZ() : directions[0].normalized();
  for (std::size_t k = 0; k < directions.size(); ++k) {
    c = directions[k].normalized();
    const std::vector<double> vertical = vertical_rates(k);
    if (gyro.wobble_rad_s > 0) draw_waves();
    if (gyro.wobble_rad_s > 0 || !vertical.empty()) {
      // The body's rates while it stands, and the force direction they move.
      Vec3 omega_before = Vec3::Zero();
      for (std::size_t i = 0; i < still; ++i) {
        const double t = static_cast<double>(i) * h;
        const double envelope =
            std::min({1.0, t / ramp_s, (static_cast<double>(still - 1) * h - t) / ramp_s});
        Vec3 omega = Vec3::Zero();
        for (int a = 0; a < 3; ++a) {
          for (const Wave& w : waves[a]) {
            omega(a) += envelope * w.amplitude * std::cos(w.omega_rad_s * t + w.phase);
          }
        }
        if (!vertical.empty()) omega += vertical[i] * c;
        if (i > 0) c = so3::Exp(Vec3(-0.5 * h * (omega_before + omega))) * c;
        emit(c, omega);
        omega_before = omega;
      }
    } else {
      for (std::size_t i = 0; i < still; ++i) emit(c, Vec3::Zero());
    }
    if (k + 1 == directions.size() || turn < 2) continue;
    const Vec3 next = directions[k + 1].normalized();
    const double angle = std::atan2(c.cross(next).norm(), c.dot(next));
    Vec3 axis = c.cross(next);
    if (axis.norm() < 1e-12) {
      axis = c.cross(Vec3::UnitX()).norm() > 0.1 ? c.cross(Vec3::UnitX()) : c.cross(Vec3::UnitY());
    }
    axis.normalize();
    // α̇ at sample i of the turn (i = 0: the last still sample, i = turn: the next one's first) is
    // peak · shape_i, shape a triangle; the trapezoidal sum over the turn is h Σ shape_i · peak.
    std::vector<double> shape(turn + 1);
    double area = 0;
    for (std::size_t i = 0; i <= turn; ++i) {
      const double s = static_cast<double>(i) / static_cast<double>(turn);
      shape[i] = 1.0 - std::abs(2.0 * s - 1.0);
      area += shape[i];
    }
    const double peak = angle / (h * area);
    double alpha = 0;
    for (std::size_t i = 1; i < turn; ++i) {
      alpha += 0.5 * h * peak * (shape[i - 1] + shape[i]);
      emit(Eigen::AngleAxisd(alpha, axis) * c, Vec3(-peak * shape[i] * axis));
    }
  }
  return log;
}

double SimulatedSampleCount(std::size_t directions, const RawLogSimulation& options) {
  if (directions == 0) return 0;
  const double still = std::round(options.static_s * options.rate_hz);
  const double turn = std::round(options.transition_s * options.rate_hz);
  return static_cast<double>(directions) * still +
         static_cast<double>(directions - 1) * std::max(turn - 1, 0.0);
}

}  // namespace accelcal
