#pragma once
// One reusable finite-difference checker for every derivative in the project.

#include <cmath>
#include <functional>
#include <sstream>

#include <gtest/gtest.h>
#include <Eigen/Core>

namespace accelcal::testing {

/// Central-difference Jacobian of f at x, step h_j = relative_step · max(1, |x_j|).
inline Eigen::MatrixXd NumericalJacobian(
    const std::function<Eigen::VectorXd(const Eigen::VectorXd&)>& f, const Eigen::VectorXd& x,
    double relative_step = 1e-6) {
  const Eigen::VectorXd f0 = f(x);
  Eigen::MatrixXd J(f0.size(), x.size());
  for (Eigen::Index j = 0; j < x.size(); ++j) {
    const double h = relative_step * std::max(1.0, std::abs(x(j)));
    Eigen::VectorXd xp = x, xm = x;
    xp(j) += h;
    xm(j) -= h;
    J.col(j) = (f(xp) - f(xm)) / (2 * h);
  }
  return J;
}

/// Compares an analytic Jacobian with central differences. Entry (i, j) passes when
/// |J − J_fd| ≤ tolerance · (|J_ij| + max |J|): central differences have a truncation error of
/// order h² and a round-off error of order ε·|f|/h, both small relative to the largest entry for h
/// ≈ 1e-6 (optimal for double with smooth f), so 1e-6 leaves a wide but meaningful margin.
inline ::testing::AssertionResult JacobianMatches(
    const std::function<Eigen::VectorXd(const Eigen::VectorXd&)>& f, const Eigen::VectorXd& x,
    const Eigen::MatrixXd& analytic, double tolerance = 1e-6, double relative_step = 1e-6) {
  if (!analytic.allFinite()) return ::testing::AssertionFailure() << "analytic Jacobian not finite";
  const Eigen::MatrixXd numeric = NumericalJacobian(f, x, relative_step);
  if (numeric.rows() != analytic.rows() || numeric.cols() != analytic.cols()) {
    return ::testing::AssertionFailure()
           << "size mismatch: analytic " << analytic.rows() << "x" << analytic.cols()
           << ", numeric " << numeric.rows() << "x" << numeric.cols();
  }
  const double scale = analytic.cwiseAbs().maxCoeff();
  for (Eigen::Index i = 0; i < analytic.rows(); ++i) {
    for (Eigen::Index j = 0; j < analytic.cols(); ++j) {
      const double err = std::abs(analytic(i, j) - numeric(i, j));
      if (!(err <= tolerance * (std::abs(analytic(i, j)) + scale))) {
        std::ostringstream os;
        os << "entry (" << i << "," << j << "): analytic " << analytic(i, j) << ", numeric "
           << numeric(i, j) << "\nanalytic:\n"
           << analytic << "\nnumeric:\n"
           << numeric;
        return ::testing::AssertionFailure() << os.str();
      }
    }
  }
  return ::testing::AssertionSuccess();
}

}  // namespace accelcal::testing
