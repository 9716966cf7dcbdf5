#pragma once
/// @file engineering.hpp
/// Engineering quantities of a calibration, as in paper 000 Table 3 (see docs/errata.md#000-table3
/// for the conventions): K = k_a T with k_a = diag(scale factors) and T lower-triangular with unit
/// rows.

#include "accelcal/frame.hpp"
#include "accelcal/model.hpp"

namespace accelcal {

inline constexpr double kArcsecPerRad = 206264.80624709636;

/// Paper 000 Table 3 quantities.
struct EngineeringParameters {
  /// k_a,i = |row i of K| [raw per specific-force unit]: the axis' scale factor.
  Vec3 scale_factor;
  /// τ_yx, τ_zx, τ_zy: off-diagonal entries of T (rows of T are unit vectors) [rad, small-angle].
  /// τ_yx = sin of the angle between sensor y and body y; (τ_zx, τ_zy) = sin(tilt of z)·(cos, sin).
  double tau_yx = 0, tau_zx = 0, tau_zy = 0;
  /// τ_yy, τ_zz: diagonal of T, close to 1.
  double tau_yy = 1, tau_zz = 1;
  /// Acceleration-equivalent bias b_i / k_a,i [specific-force unit]
  /// (docs/errata.md#000-table3: p0 = k_a·b).
  Vec3 bias_force;
  /// Acceleration-equivalent squared coefficients k2_i · g / k_a,i [g/g²]
  /// (docs/errata.md#000-table3: k2 = k_a·K2/g), with g the gravity magnitude of the calibration in
  /// the specific-force unit.
  Vec3 k2_g_per_g2;
};

/// Converts model parameters to engineering quantities. g = gravity magnitude in the force unit.
EngineeringParameters ToEngineering(const ModelParameters& params, double gravity);
/// Inverse of ToEngineering (for building truths such as paper 000 Table 3).
ModelParameters FromEngineering(const EngineeringParameters& eng, double gravity);

/// 1σ of the engineering quantities, propagated to first order from the covariance of the flat
/// parameters (in the order of ParameterSlots(model, frame), frame.hpp): J C Jᵀ with J by central
/// differences of the smooth map (steps of 1e-6 of each parameter's own standard deviation, far
/// inside the region where the map is linear).
struct EngineeringStd {
  Vec3 scale_factor;                 ///< [raw per specific-force unit]
  Eigen::VectorXd misalignment_rad;  ///< the frame's misalignment angles (MisalignmentOf)
  Vec3 bias_force;                   ///< [specific-force unit]
  Vec3 k2_g_per_g2;                  ///< [g/g²]
};
EngineeringStd EngineeringUncertainty(const ModelParameters& params, ModelKind model, Frame frame,
                                      double gravity, const Eigen::MatrixXd& covariance);

}  // namespace accelcal
