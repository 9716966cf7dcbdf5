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
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "accelcal/calibration_types.hpp"
#include "accelcal/gravity.hpp"
#include "accelcal/platform_model.hpp"
#include "accelcal/types.hpp"

namespace accelcal {

/// How one of paper 003's estimators went (the gimbal stages here, the system-level estimator of
/// system_level.hpp), in the style of Calibrate's Summary.
struct PlatformSummary {
  int iterations = 0;  ///< accepted Gauss-Newton steps (0 for a closed form)
  /// kParameterTolerance, kFunctionTolerance, kZeroResidual: converged by that criterion (see the
  /// options of each estimator for its formula); kClosedForm: a direct solution; kMaxIterations,
  /// kNoProgress: not converged.
  TerminationType termination = TerminationType::kMaxIterations;
  std::string termination_message;  ///< the criterion met, as a formula with its numbers
  double initial_cost = 0;          ///< the estimator's sum of squares at the start
  double final_cost = 0;            ///< and at the solution
  bool converged() const {
    return termination != TerminationType::kMaxIterations &&
           termination != TerminationType::kNoProgress;
  }
  /// One line: the termination, its message and the iterations.
  std::string BriefReport() const;
};

/// Options of the coarse stage. The stopping rule (kParameterTolerance): the next Gauss-Newton
/// step δ would change no predicted output by more than `step_tolerance` of the signal,
///     max_k |(J δ)_k| ≤ step_tolerance · g · max_i s_i,
/// s_i from the known-orientation start; `max_iterations` steps without it: kMaxIterations.
struct CoarseCalibrationOptions {
  double gravity = kStandardGravity_ms2;  ///< g in the unit of the specific force
  int max_iterations = 50;
  double step_tolerance = 1e-13;
  /// Levenberg-Marquardt damping at the start, relative to the normal matrix' diagonal; 0: plain
  /// Gauss-Newton steps for as long as they reduce the sum of squares.
  double initial_damping = 0;
  /// The Jacobi-scaled normal matrix' eigenvalue ratio below which the positions do not
  /// determine the parameters (DataError).
  double min_reciprocal_condition = 1e-12;
  /// An error message when an option is out of range, else std::nullopt.
  std::optional<std::string> Validate() const;
};

/// Result of the coarse stage: the 14 determined parameters in the order s(3), δb(3), β(6), θ20,
/// θ30, their covariance σ̂² (JᵀJ)⁻¹ (σ̂² from the residuals, 3m − 14 degrees of freedom).
struct CoarseCalibrationResult {
  PlatformAccelerometer device;
  Vec3 offsets = Vec3::Zero();  ///< (θ10 = 0: not separable, see above; θ20; θ30) [rad]
  Eigen::MatrixXd covariance;   ///< 14 x 14
  Eigen::Matrix<double, 14, 1> std = Eigen::Matrix<double, 14, 1>::Zero();
  double residual_rms = 0;  ///< [output]
  PlatformSummary summary;
  /// IteratedCoarseCalibration: the measurement rounds run (1 for CoarseCalibration).
  int rounds = 1;
  std::string note;  ///< what the fit could not separate
};

/// Gauss-Newton on eq. (7) for the outputs measured at `commanded` gimbal angles (18 or more;
/// Table 1's), started from the known-orientation least squares with zero offsets. Throws
/// DataError when the positions do not determine the parameters, std::invalid_argument for
/// options that fail Validate().
CoarseCalibrationResult CoarseCalibration(const std::vector<Vec3>& outputs,
                                          const std::vector<Vec3>& commanded,
                                          const CoarseCalibrationOptions& options = {});

/// Options of the paper's loop. It stops (kParameterTolerance) when the offsets estimated by
/// the latest run are below the tolerance, max(|θ̂20|, |θ̂30|) < offset_tolerance_rad, or after
/// `max_rounds` runs (kMaxIterations; the summary's iterations count the runs).
struct IteratedCoarseCalibrationOptions {
  CoarseCalibrationOptions coarse;
  double offset_tolerance_rad = 1e-7;
  int max_rounds = 5;
  std::optional<std::string> Validate() const;
};

/// The paper's loop: measure at Table 1's angles with the angle sensors re-zeroed by the offsets
/// estimated so far, calibrate, and repeat until the latest offsets are negligible (options).
/// `measure` drives the platform (or a simulation) to the given angles in the sensors' original
/// readings and returns the mean output of each position. The result's offsets are the
/// accumulated corrections, its summary the loop's (termination by the offset criterion).
CoarseCalibrationResult IteratedCoarseCalibration(
    const std::function<std::vector<Vec3>(const std::vector<Vec3>& commanded)>& measure,
    const IteratedCoarseCalibrationOptions& options = {});

/// Options of the fine stage. The stopping rule (kParameterTolerance): the next step dx would
/// change no observation by more than `step_tolerance` of g²,
///     max_j |(A dx)_j| ≤ step_tolerance · g²;
/// `max_iterations` steps without it: kMaxIterations.
struct FineCalibrationOptions {
  double gravity = kStandardGravity_ms2;  ///< g in the unit of the specific force
  int max_iterations = 20;
  double step_tolerance = 1e-13;
  double initial_damping = 0;  ///< as for the coarse stage
  double min_reciprocal_condition = 1e-12;
  std::optional<std::string> Validate() const;
};

/// Paper 003 §4, device-level fine calibration. With the coarse estimate, each position's output
/// gives v = ŜF (f^a − δ̂b) and f̂^p = Ĉ_a^p v (eq. (9)); the observation ½(g² − |f̂^p|²) is linear
/// in the error vector dx of eq. (17) with the row of eq. (16):
///     [v_x², v_y², v_z², −v_x, −v_y, −v_z, −v_x³, −v_y³, −v_z³, v_x v_y, v_x v_z, v_y v_z],
///     dx = [ΔSF_i/SF_i (3), SF_i δb̃_i (3), K_nl,i/SF_i (3), Δβ_yz − Δβ_xz, Δβ_xy − Δβ_zy,
///           Δβ_zx − Δβ_yx].
/// It uses gravity magnitudes only, so the pairs (β_xz, β_yz), (β_zy, β_xy), (β_yx, β_zx) are not
/// separable: the update moves each pair symmetrically by half its difference, keeping the coarse
/// value of its sum. The paper takes one least-squares step; this iterates it (Gauss-Newton) until
/// the stopping rule of FineCalibrationOptions, which removes the linearisation's second-order
/// error.
struct FineCalibrationResult {
  PlatformAccelerometer device;  ///< the coarse device with every update applied
  /// dx of the last step's linearisation, summed over the iterations, and its 1σ (σ̂ from the
  /// residuals, m − 12 degrees of freedom, at the solution)
  Eigen::Matrix<double, 12, 1> dx = Eigen::Matrix<double, 12, 1>::Zero();
  Eigen::Matrix<double, 12, 1> dx_std = Eigen::Matrix<double, 12, 1>::Zero();
  double residual_rms = 0;  ///< of ½(g² − |f̂^p|²)/g [output]
  PlatformSummary summary;
  std::string note;
};
/// Throws DataError for fewer than 13 positions or positions that do not determine dx,
/// std::invalid_argument for options that fail Validate().
FineCalibrationResult FineCalibration(const std::vector<Vec3>& outputs,
                                      const PlatformAccelerometer& coarse,
                                      const FineCalibrationOptions& options = {});

}  // namespace accelcal
