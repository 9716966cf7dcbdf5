#pragma once
/// @file platform_model.hpp
/// Paper 003 (Wu et al. 2018) §2: the three-gimbal platform's kinematics and the model of the
/// accelerometer on it, shared by the orientation files (io) and the gimbal estimators (platform).
///
/// Gimbal chain, reconstructed from Table 1 (docs/wu2018-table1.md): outer gimbal angle θ3 about
/// y, middle θ2 about x, inner (platform) θ1 about z. With R_a the right-handed rotation about
/// axis a (AxisRotation, rotations.hpp), the direction of the specific force of gravity (up) in
/// the platform frame is
///     u(θ) = R_z(θ1)ᵀ R_x(θ2)ᵀ R_y(θ3)ᵀ e_z,  f^p = g u,
/// which reproduces every legible nominal entry of Table 1 and all but two of its first-order
/// offset terms (the two are explained in the doc).
///
/// Measurement model, eq. (5), (7): f^a = SF⁻¹ C_p^a f^p + δb, written here with s = SF⁻¹ (output
/// per input, one per axis) and C_p^a = [[1, β_xz, −β_xy], [−β_yz, 1, β_yx], [β_zy, −β_zx, 1]].
/// The angles the gimbals really take are the commanded ones plus the zero offsets θ_i0.

#include <vector>

#include <Eigen/Core>

#include "accelcal/types.hpp"

namespace accelcal {

/// u(θ) above; optionally its Jacobian ∂u/∂(θ1, θ2, θ3).
Vec3 PlatformUp(const Vec3& angles_rad, Mat33* jacobian = nullptr);

/// Table 1's 18 commanded (θ1, θ2, θ3) [rad] without the offsets, in order.
std::vector<Vec3> Wu2018Table1Angles();

/// The accelerometer of eq. (7) (and eq. (6)'s nonlinear term for the fine stage).
struct PlatformAccelerometer {
  Vec3 s = Vec3::Ones();     ///< SF⁻¹ per axis [output per input]
  Vec3 bias = Vec3::Zero();  ///< δb [output]
  /// β_xz, β_xy, β_yz, β_yx, β_zy, β_zx of eq. (5) [rad]
  Eigen::Matrix<double, 6, 1> beta = Eigen::Matrix<double, 6, 1>::Zero();
  Vec3 k_nl = Vec3::Zero();  ///< K_nl of eq. (6) [per output unit]: + k_nl ∘ (f^a − δb)²
};
/// C_p^a of eq. (5).
Mat33 InstallationMatrix(const Eigen::Matrix<double, 6, 1>& beta);
/// The output for a platform-frame specific force f^p, eq. (6)-(7): solved by fixed-point
/// iteration when K_nl ≠ 0 (it is tiny against 1).
Vec3 PlatformOutput(const PlatformAccelerometer& device, const Vec3& f_p);

}  // namespace accelcal
