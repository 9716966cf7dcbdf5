#pragma once
// One position's row of the reduced information of an orientation-free problem whose blocks are
// directions c_k moved in their tangent planes (calibrate.hpp): u_k = J_xᵀ n_k, n_k the unit
// normal of the fitted surface at g c_k (⟂ the columns of J_y), the direction of p_k's residual
// that no change of direction can take up. S = Σ u_k u_kᵀ / σ_k² is the information of x with the
// directions profiled out.

#include <Eigen/Core>
#include <Eigen/Geometry>  // cross

#include "accelcal/types.hpp"
#include "solvers/least_squares.hpp"

namespace accelcal::internal {

/// Block k's u_k at (x, c), its normal to `normal`, and its residual to `residual` unless null.
inline Eigen::VectorXd InformationRow(const LeastSquaresProblem& problem, const Eigen::VectorXd& x,
                                      int k, const Vec3& c, Vec3* normal,
                                      Vec3* residual = nullptr) {
  Eigen::VectorXd r;
  Eigen::MatrixXd J_x, J_y;
  problem.Evaluate(k, x, c, &r, &J_x, &J_y);
  *normal = Vec3(J_y.col(0)).cross(Vec3(J_y.col(1))).normalized();
  if (residual != nullptr) *residual = r;
  return J_x.transpose() * *normal;
}

}  // namespace accelcal::internal
