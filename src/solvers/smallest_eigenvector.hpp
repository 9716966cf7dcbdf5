#pragma once
// The ellipsoid fit's eigenvector (internal; exposed for its test).

#include <optional>

#include <Eigen/Core>

namespace accelcal::internal {

/// The eigenvector of the smallest eigenvalue of a symmetric positive definite S by inverse
/// iteration, certified by Sylvester's law of inertia (S − μ'I with μ' just above the converged
/// Rayleigh quotient has exactly one negative pivot, so no smaller eigenvalue was missed);
/// std::nullopt when it does not converge or cannot be certified. A tenth of the cost of the full
/// decomposition when the data fit an ellipsoid: the quadric is then S's near-null vector, far
/// below the next eigenvalue, and a few iterations reach round-off.
std::optional<Eigen::Matrix<double, 10, 1>> SmallestEigenvector(
    const Eigen::Matrix<double, 10, 10>& S);

}  // namespace accelcal::internal
