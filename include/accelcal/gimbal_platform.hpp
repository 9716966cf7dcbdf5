#pragma once
/// @file gimbal_platform.hpp
/// Paper 003 (Wu et al. 2018) §2-3: a tri-axis accelerometer on the platform of a three-gimbal
/// (space-stable) INS, and the device-level coarse calibration with the gimbals' zero offsets.
///
/// The gimbal chain and the measurement model are platform_model.hpp's.
///
/// Observability (beyond the paper): θ10 turns the platform about its own z axis in every
/// position, exactly as a rotation of the accelerometer would, so only β_xz + θ10 and β_yz + θ10
/// are determined. The coarse fit holds θ10 at 0 (its effect lands in β_xz, β_yz) and says so; the
/// paper, too, corrects the platform by θ20 and θ30 only.

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "accelcal/platform_model.hpp"
#include "accelcal/types.hpp"

namespace accelcal {

/// Result of the coarse stage: the 14 determined parameters in the order s(3), δb(3), β(6), θ20,
/// θ30, their covariance σ̂² (JᵀJ)⁻¹ (σ̂² from the residuals, 3m − 14 degrees of freedom).
struct CoarseCalibrationResult {
  PlatformAccelerometer device;
  Vec3 offsets = Vec3::Zero();  ///< (θ10 = 0: not separable, see above; θ20; θ30) [rad]
  Eigen::MatrixXd covariance;   ///< 14 x 14
  Eigen::Matrix<double, 14, 1> std = Eigen::Matrix<double, 14, 1>::Zero();
  double residual_rms = 0;  ///< [output]
  int iterations = 0;
  bool converged = false;
  std::string note;  ///< what the fit could not separate
};

/// Gauss-Newton on eq. (7) for the outputs measured at `commanded` gimbal angles (18 or more;
/// Table 1's), started from the known-orientation least squares with zero offsets. Throws
/// DataError when the positions do not determine the parameters.
CoarseCalibrationResult CoarseCalibration(const std::vector<Vec3>& outputs,
                                          const std::vector<Vec3>& commanded, double gravity);

/// The paper's loop: measure at Table 1's angles with the angle sensors re-zeroed by the offsets
/// estimated so far, calibrate, and repeat until |θ̂20|, |θ̂30| of the latest run are below
/// `tolerance_rad` (or `max_rounds` runs). `measure` drives the platform (or a simulation) to
/// the given angles in the sensors' original readings and returns the mean output of each
/// position. The result's offsets are the accumulated corrections.
CoarseCalibrationResult IteratedCoarseCalibration(
    const std::function<std::vector<Vec3>(const std::vector<Vec3>& commanded)>& measure,
    double gravity, double tolerance_rad = 1e-7, int max_rounds = 5);

/// Paper 003 §4, device-level fine calibration. With the coarse estimate, each position's output
/// gives v = ŜF (f^a − δ̂b) and f̂^p = Ĉ_a^p v (eq. (9)); the observation ½(g² − |f̂^p|²) is linear
/// in the error vector dx of eq. (17) with the row of eq. (16):
///     [v_x², v_y², v_z², −v_x, −v_y, −v_z, −v_x³, −v_y³, −v_z³, v_x v_y, v_x v_z, v_y v_z],
///     dx = [ΔSF_i/SF_i (3), SF_i δb̃_i (3), K_nl,i/SF_i (3), Δβ_yz − Δβ_xz, Δβ_xy − Δβ_zy,
///           Δβ_zx − Δβ_yx].
/// It uses gravity magnitudes only, so the pairs (β_xz, β_yz), (β_zy, β_xy), (β_yx, β_zx) are not
/// separable: the update moves each pair symmetrically by half its difference, keeping the coarse
/// value of its sum. The paper takes one least-squares step; this iterates it (Gauss-Newton) until
/// the step changes no prediction by more than 1e-13 of g, which removes the linearisation's
/// second-order error.
struct FineCalibrationResult {
  PlatformAccelerometer device;  ///< the coarse device with every update applied
  /// dx of the last step's linearisation, summed over the iterations, and its 1σ (σ̂ from the
  /// residuals, m − 12 degrees of freedom)
  Eigen::Matrix<double, 12, 1> dx = Eigen::Matrix<double, 12, 1>::Zero();
  Eigen::Matrix<double, 12, 1> dx_std = Eigen::Matrix<double, 12, 1>::Zero();
  double residual_rms = 0;  ///< of ½(g² − |f̂^p|²)/g [output]
  int iterations = 0;
  bool converged = false;
  std::string note;
};
/// Throws DataError for fewer than 13 positions or positions that do not determine dx.
FineCalibrationResult FineCalibration(const std::vector<Vec3>& outputs,
                                      const PlatformAccelerometer& coarse, double gravity);

}  // namespace accelcal
