#include "solvers/smallest_eigenvector.hpp"

#include <cmath>

#include <Eigen/Cholesky>

namespace accelcal::internal {

std::optional<Eigen::Matrix<double, 10, 1>> SmallestEigenvector(
    const Eigen::Matrix<double, 10, 10>& S) {
  using Vec10 = Eigen::Matrix<double, 10, 1>;
  using Mat10 = Eigen::Matrix<double, 10, 10>;
  const Eigen::LDLT<Mat10> ldlt(S);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return std::nullopt;
  Vec10 v = Vec10::Ones() / std::sqrt(10.0);
  for (int iteration = 0; iteration < 30; ++iteration) {
    Vec10 next = ldlt.solve(v);
    next.normalize();
    if (next.dot(v) < 0) next = -next;
    const double change = (next - v).lpNorm<Eigen::Infinity>();
    v = next;
    if (!std::isfinite(change)) return std::nullopt;
    if (change > 1e-14) continue;
    const double rayleigh = v.dot(S * v);
    const double shift = rayleigh + 1e-8 * S.diagonal().maxCoeff();
    const Eigen::LDLT<Mat10> shifted(S - shift * Mat10::Identity());
    const int negative = static_cast<int>((shifted.vectorD().array() < 0).count());
    if (shifted.info() != Eigen::Success || negative != 1) return std::nullopt;
    return v;
  }
  return std::nullopt;
}

}  // namespace accelcal::internal
