#pragma once
// Internals of gimbal_platform.cpp exposed for the finite-difference tests.

#include <vector>

#include <Eigen/Core>

#include "accelcal/gimbal_platform.hpp"

namespace accelcal::internal {

using CoarseParameters = Eigen::Matrix<double, 14, 1>;  ///< s(3), δb(3), β(6), θ20, θ30
using CoarseJacobian = Eigen::Matrix<double, Eigen::Dynamic, 14>;

/// Eq. (7) at every commanded position: the predicted outputs stacked (3m) and, optionally, their
/// Jacobian with respect to the parameters.
Eigen::VectorXd CoarsePrediction(const std::vector<Vec3>& commanded, double gravity,
                                 const CoarseParameters& p, CoarseJacobian* jacobian);

/// The fine stage's observation ½(g² − |f̂^p|²) per position for a device estimate, and the rows
/// of eq. (16).
Eigen::VectorXd FineObservation(const std::vector<Vec3>& outputs,
                                const PlatformAccelerometer& estimate, double gravity,
                                Eigen::Matrix<double, Eigen::Dynamic, 12>* rows);

/// The full-value update of the fine stage (FineCalibrationResult) applied to `device`.
void ApplyFineUpdate(const Eigen::Matrix<double, 12, 1>& dx, PlatformAccelerometer* device);

}  // namespace accelcal::internal
