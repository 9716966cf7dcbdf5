// The ellipsoid method's held-out fits, exact, by downdating its scatter matrix (held_out.hpp).
#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <vector>

#include <Eigen/Eigenvalues>

#include "model/ellipsoid_quadric.hpp"
#include "solvers/smallest_eigenvector.hpp"
#include "statistics/held_out_detail.hpp"

namespace accelcal::internal::held_out {

namespace {

// The ellipsoid method's held-out fits: its algebraic fit is the smallest eigenvector of the
// scatter D'ᵀD' of the design rows d(q) = (x², y², z², 2xy, 2xz, 2yz, 2x, 2y, 2z, 1) of the
// readings centred on their mean and divided by their largest deviation (ellipsoid_fit.cpp).
// Without position k the mean and scale change: q' = a q + t, d(q') = A d(q), so the held-out
// scatter is A (DᵀD − d_k d_kᵀ) Aᵀ, exactly.
using Vec10 = Eigen::Matrix<double, 10, 1>;
using Mat10 = Eigen::Matrix<double, 10, 10>;

Vec10 DesignRow(const Vec3& q) {
  Vec10 d;
  d << q(0) * q(0), q(1) * q(1), q(2) * q(2), 2 * q(0) * q(1), 2 * q(0) * q(2), 2 * q(1) * q(2),
      2 * q(0), 2 * q(1), 2 * q(2), 1.0;
  return d;
}

Mat10 DesignTransform(double a, const Vec3& t) {
  Mat10 A = Mat10::Zero();
  for (int i = 0; i < 3; ++i) {
    A(i, i) = a * a;  // x'² = a² x² + a t_x (2x) + t_x²
    A(i, 6 + i) = a * t(i);
    A(i, 9) = t(i) * t(i);
    A(6 + i, 6 + i) = a;  // 2x' = a (2x) + 2 t_x
    A(6 + i, 9) = 2 * t(i);
  }
  const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};  // 2xy, 2xz, 2yz
  for (int p = 0; p < 3; ++p) {
    const int i = pairs[p][0], j = pairs[p][1];
    A(3 + p, 3 + p) = a * a;  // 2x'y' = a² (2xy) + a t_y (2x) + a t_x (2y) + 2 t_x t_y
    A(3 + p, 6 + i) = a * t(j);
    A(3 + p, 6 + j) = a * t(i);
    A(3 + p, 9) = 2 * t(i) * t(j);
  }
  A(9, 9) = 1.0;
  return A;
}

// K and b of the quadric v in coordinates q = (p − mean) / scale (the algebraic fit's
// parameters, ellipsoid_fit.hpp); false when it is no real ellipsoid (the refit then tries the
// constrained fit).
bool QuadricParameters(const Vec10& v, const Vec3& mean, double scale, double gravity,
                       ModelParameters* params) {
  return !QuadricToParameters(v, mean, scale, gravity, params);
}

}  // namespace

Candidates EllipsoidHeldOut(const Setup& setup, const ModelParameters& params,
                            HeldOutPaths* paths) {
  const std::size_t n = setup.readings.size();
  Candidates out{std::vector<double>(n, std::nan("")), std::vector<bool>(n, true)};
  Vec3 sum = Vec3::Zero();
  for (const Vec3& p : setup.readings) sum += p;
  const Vec3 mean = sum / static_cast<double>(n);
  double scale = 0;
  for (const Vec3& p : setup.readings)
    scale = std::max(scale, (p - mean).lpNorm<Eigen::Infinity>());
  Mat10 S = Mat10::Zero();
  for (const Vec3& p : setup.readings) {
    const Vec10 d = DesignRow((p - mean) / scale);
    S.selfadjointView<Eigen::Lower>().rankUpdate(d);
  }
  S.triangularView<Eigen::StrictlyUpper>() = S.transpose();
  // The two largest and smallest readings of each axis: the held-out scale's extremes.
  std::array<std::array<std::size_t, 2>, 3> high{}, low{};
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<std::size_t> order(n);
    for (std::size_t j = 0; j < n; ++j) order[j] = j;
    const auto by = [&](std::size_t a, std::size_t b) {
      return setup.readings[a](axis) > setup.readings[b](axis);
    };
    std::partial_sort(order.begin(), order.begin() + 2, order.end(), by);
    high[axis] = {order[0], order[1]};
    const auto below = [&](std::size_t a, std::size_t b) { return by(b, a); };
    std::partial_sort(order.begin(), order.begin() + 2, order.end(), below);
    low[axis] = {order[0], order[1]};
  }
  const Problem problem{setup.readings, setup.gravity, setup.model};
  const Structure structure = StructureOf(setup, params, DirectionsFromParams(problem, params));
  for (std::size_t k = 0; k < n; ++k) {
    if (MayFailWithout(setup, structure, k)) continue;
    const Vec3& p = setup.readings[k];
    const Vec3 held_mean = (sum - p) / static_cast<double>(n - 1);
    double held_scale = 0;
    for (int axis = 0; axis < 3; ++axis) {
      const double hi = setup.readings[high[axis][high[axis][0] == k ? 1 : 0]](axis);
      const double lo = setup.readings[low[axis][low[axis][0] == k ? 1 : 0]](axis);
      held_scale = std::max({held_scale, hi - held_mean(axis), held_mean(axis) - lo});
    }
    const Vec10 d = DesignRow((p - mean) / scale);
    const Mat10 A = DesignTransform(scale / held_scale, (mean - held_mean) / held_scale);
    Mat10 held = A * (S - d * d.transpose()) * A.transpose();
    held = (0.5 * (held + held.transpose())).eval();
    Vec10 v;
    if (const std::optional<Vec10> smallest = SmallestEigenvector(held)) {
      v = *smallest;
    } else {
      v = Eigen::SelfAdjointEigenSolver<Mat10>(held).eigenvectors().col(0);
    }
    ModelParameters fit;
    if (!QuadricParameters(v, held_mean, held_scale, setup.gravity, &fit)) continue;
    const double e = HeldOutError(fit, p, setup.gravity);
    if (!std::isfinite(e)) continue;
    out.error[k] = e;
    out.refit[k] = false;
    if (paths) ++paths->from_expansion;
  }
  return out;
}

}  // namespace accelcal::internal::held_out
