#pragma once
/// @file types.hpp
/// Short aliases for the fixed-size Eigen types used throughout accelcal.

#include <Eigen/Core>

namespace accelcal {

template <typename Scalar>
using Vec3T = Eigen::Matrix<Scalar, 3, 1>;
template <typename Scalar>
using Mat33T = Eigen::Matrix<Scalar, 3, 3>;

using Vec3 = Vec3T<double>;
using Mat33 = Mat33T<double>;
using VecX = Eigen::VectorXd;
using MatX = Eigen::MatrixXd;

}  // namespace accelcal
