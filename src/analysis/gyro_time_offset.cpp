// The gyroscope's lag behind the accelerometer (gyro_time_offset.hpp).
#include "analysis/gyro_time_offset.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>

#include <Eigen/Geometry>
#include <Eigen/LU>

namespace accelcal::internal {

namespace {

// The peak of c over shifts −S..S (index s + S), to a fraction of a step by the vertex of the
// quadratic fitted to the five values around the largest (smoother in the data than the parabola
// through three, so that the jackknife's σ holds: on 12 simulated noisy recordings the errors'
// RMS was 0.94 σ, against 1.7 σ with three), and whether it is on the edge.
std::pair<double, bool> Peak(const std::vector<double>& c) {
  const auto best = static_cast<std::size_t>(std::max_element(c.begin(), c.end()) - c.begin());
  const double S = static_cast<double>(c.size() / 2);
  if (best < 2 || best + 2 >= c.size()) return {static_cast<double>(best) - S, true};
  double sxy = 0, sx2y = 0, sy = 0;
  for (int x = -2; x <= 2; ++x) {
    const double y = c[static_cast<std::size_t>(static_cast<std::ptrdiff_t>(best) + x)];
    sxy += x * y, sx2y += x * x * y, sy += y;
  }
  const double b = sxy / 10, curvature = (sx2y - 2 * sy) / 14;
  const double fraction = curvature < 0 ? std::clamp(-b / (2 * curvature), -1.0, 1.0) : 0.0;
  return {static_cast<double>(best) - S + fraction, false};
}

// c[i] = Σ_k tilt[k] rate[k + i] over k = 0 … count − 1 (k ascending: the same sums, term by
// term, as adding each k's products to every shift in turn), for shifts i = 0 … shifts − 1, all
// of them within `rate`. Eight shifts at a time, each its own lane of four pairs of doubles, so
// that the sums stay in registers across k.
void Correlate(const double* tilt, const double* rate, std::size_t count, std::size_t shifts,
               double* c) {
  typedef double Pair __attribute__((vector_size(16)));
  const auto load = [](const double* p) {
    Pair v;
    std::memcpy(&v, p, sizeof v);
    return v;
  };
  std::size_t i = 0;
  for (; i + 8 <= shifts; i += 8) {
    Pair s0 = {0, 0}, s1 = {0, 0}, s2 = {0, 0}, s3 = {0, 0};
    const double* r = rate + i;
    for (std::size_t k = 0; k < count; ++k, ++r) {
      const Pair t = {tilt[k], tilt[k]};
      s0 += t * load(r);
      s1 += t * load(r + 2);
      s2 += t * load(r + 4);
      s3 += t * load(r + 6);
    }
    std::memcpy(c + i, &s0, sizeof s0);
    std::memcpy(c + i + 2, &s1, sizeof s1);
    std::memcpy(c + i + 4, &s2, sizeof s2);
    std::memcpy(c + i + 6, &s3, sizeof s3);
  }
  for (; i < shifts; ++i) {
    double sum = 0;
    for (std::size_t k = 0; k < count; ++k) sum += tilt[k] * rate[k + i];
    c[i] = sum;
  }
}

}  // namespace

std::optional<GyroTimeOffset> EstimateGyroLag(
    const RawLog& accel, const RawLog& gyro, const std::vector<double>& t, double step_s,
    const std::vector<std::pair<std::size_t, std::size_t>>& turns,
    const ModelParameters& accel_params, const GyroParameters& gyro_params) {
  const std::size_t n = gyro.samples.size();
  if (turns.size() < 3 || !(step_s > 0) || n < 3 || accel.samples.size() != n) return std::nullopt;
  std::size_t shortest = n;
  for (const auto& [first, last] : turns) shortest = std::min(shortest, last - first + 1);
  const auto S = std::max<std::size_t>(
      1, std::min(shortest, static_cast<std::size_t>(std::lround(kGyroLagSearch_s / step_s))));
  // The accelerometer's tilt rate |ḟ| / |f| by central differences, and the gyro's calibrated
  // rate perpendicular to f, where the correlations reach: every turn's samples widened by S for
  // the tilt, by 2 S for the rate (a shift of up to S from them).
  std::vector<char> need(n, 0);
  for (const auto& [first, last_sample] : turns) {
    const std::size_t from = first > 2 * S + 1 ? first - 2 * S - 1 : 0;
    std::fill(need.begin() + static_cast<std::ptrdiff_t>(from),
              need.begin() + static_cast<std::ptrdiff_t>(std::min(n, last_sample + 2 * S + 2)), 1);
  }
  // Only the samples needed are written (or read): most of a recording is still, and its pages
  // are then never touched.
  const std::unique_ptr<Vec3[]> f(new Vec3[n]);
  Vec3 last = Vec3::UnitZ();
  for (std::size_t k = 0; k < n; ++k) {
    if (!need[k]) continue;
    if (std::optional<Vec3> force = SpecificForce(accel_params, accel.samples[k])) last = *force;
    f[k] = last;
  }
  const Mat33 K_inv = gyro_params.K.inverse();
  const std::unique_ptr<double[]> tilt(new double[n]), rate(new double[n]);
  for (std::size_t k = 0; k < n; ++k) {
    if (!need[k]) continue;
    tilt[k] = 0, rate[k] = 0;
    if (k == 0 || k + 1 == n || !need[k - 1] || !need[k + 1]) continue;
    const double dt = t[k + 1] - t[k - 1];
    const double norm = f[k].norm();
    if (dt > 0 && norm > 0) tilt[k] = (f[k + 1] - f[k - 1]).norm() / (norm * dt);
    const Vec3 w = K_inv * (gyro.samples[k] - gyro_params.bias - gyro_params.G * f[k]);
    if (norm > 0) rate[k] = w.cross(f[k] / norm).norm();
  }
  // Per turn j, c_j(s) = Σ_k tilt_k rate_{k+s}: the gyro late by s samples aligns its rate with
  // the accelerometer's tilt at k + s.
  const std::size_t shifts = 2 * S + 1;
  std::vector<std::vector<double>> per_turn;
  std::vector<double> total(shifts, 0.0);
  for (const auto& [first, last_sample] : turns) {
    std::vector<double> c(shifts, 0.0);
    const std::size_t begin = first > S ? first - S : 0;
    const std::size_t end = std::min(n, last_sample + 1 + S);
    if (begin >= S && end + S <= n) {
      Correlate(tilt.get() + begin, rate.get() + (begin - S), end - begin, shifts, c.data());
      for (std::size_t i = 0; i < shifts; ++i) total[i] += c[i];
      per_turn.push_back(std::move(c));
      continue;
    }
    for (std::size_t k = begin; k < end; ++k) {
      // Shift i − S reads rate[k + i − S]: i within [S − k, n + S − k).
      const std::size_t i_begin = k < S ? S - k : 0;
      const std::size_t i_end = std::min(shifts, n + S - k);
      const double* r = rate.get() + (k + i_begin - S);  // rate[k + i − S] at i = i_begin
      for (std::size_t i = i_begin; i < i_end; ++i) c[i] += tilt[k] * r[i - i_begin];
    }
    for (std::size_t i = 0; i < shifts; ++i) total[i] += c[i];
    per_turn.push_back(std::move(c));
  }
  GyroTimeOffset out;
  const auto [lag, at_limit] = Peak(total);
  out.lag_s = lag * step_s;
  out.at_limit = at_limit;
  out.turns = turns.size();
  out.step_s = step_s;
  // Jackknife over the turns.
  const double J = static_cast<double>(turns.size());
  std::vector<double> without;
  for (const std::vector<double>& c : per_turn) {
    std::vector<double> rest = total;
    for (std::size_t i = 0; i < shifts; ++i) rest[i] -= c[i];
    without.push_back(Peak(rest).first);
  }
  double mean = 0;
  for (double v : without) mean += v / J;
  double sum = 0;
  for (double v : without) sum += (v - mean) * (v - mean);
  out.std_s = std::sqrt((J - 1) / J * sum) * step_s;
  return out;
}

}  // namespace accelcal::internal
