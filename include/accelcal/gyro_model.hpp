#pragma once
/// @file gyro_model.hpp
/// The gyroscope error model, written once, beside the accelerometer's (model.hpp):
///
///     ω_raw = K_g ω + b_g + G f + v
///
///   ω_raw  raw output of the three rate axes               [gyro raw unit: counts, rad/s, °/s]
///   ω      angular rate of the body frame, in the body frame  [rad/s]
///          The body frame is the accelerometer calibration's (x-first or z-first, frame.hpp):
///          the gyroscope is calibrated into the frame the accelerometer defines.
///   K_g    full 3x3: the scale factors, the misalignment of the rate axes and their alignment
///          to the body frame, all in one                     [gyro raw per rad/s]
///   b_g    bias                                              [gyro raw]
///   G      g-sensitivity: a rate bias in proportion to the specific force, 3x3
///                                                            [gyro raw per specific-force unit]
///          zero in the linear model
///   f      specific force in the body frame                  [the accelerometer's force unit]
///   v      noise
///
/// K_g = I, b_g = 0, G = 0 make the model the identity (a gyro that reads rad/s).
///
/// Flat parameter order, grouped by output axis as the accelerometer's (row i of K_g, b_i, then
/// row i of G):
///
///     g-sensitive (21): K_xx K_xy K_xz b_x G_xx G_xy G_xz | K_yx … b_y G_yx … | K_zx … b_z G_zx …
///     linear      (12): K_xx K_xy K_xz b_x                | K_yx K_yy K_yz b_y | K_zx K_zy K_zz
///     b_z
///
/// so that each output axis is linear in its own seven (four) parameters.

#include <optional>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>

#include "accelcal/names.hpp"
#include "accelcal/rotations.hpp"
#include "accelcal/types.hpp"

namespace accelcal {

/// Which gyroscope error model is fitted.
enum class GyroModelKind {
  kLinear,      ///< G = 0: 12 parameters.
  kGSensitive,  ///< 21 parameters.
};

std::string_view ToString(GyroModelKind kind);
/// Parses "linear" or "g-sensitive"; std::nullopt for anything else.
std::optional<GyroModelKind> GyroModelKindFromString(std::string_view text);
template <>
struct EnumNames<GyroModelKind> {
  static constexpr std::pair<GyroModelKind, std::string_view> kTable[] = {
      {GyroModelKind::kLinear, "linear"}, {GyroModelKind::kGSensitive, "g-sensitive"}};
};

/// Number of parameters of the model (12 or 21).
constexpr int NumGyroParameters(GyroModelKind kind) {
  return kind == GyroModelKind::kLinear ? 12 : 21;
}
/// Parameters per output axis (4 or 7).
constexpr int GyroParametersPerAxis(GyroModelKind kind) {
  return kind == GyroModelKind::kLinear ? 4 : 7;
}
inline constexpr int kMaxGyroParameters = 21;

/// Which member of GyroParameters a flat parameter is.
enum class GyroParameterGroup { kK, kBias, kG };

/// One entry of the flat parameter vector: group, row (output axis), column (for K_g and G).
struct GyroParameterSlot {
  GyroParameterGroup group;
  int row;
  int col;                ///< −1 for the bias
  std::string_view name;  ///< e.g. "Kg_xy", "bg_z", "G_zx"
};

/// The slots of the flat parameter vector in order; size NumGyroParameters(kind).
const std::vector<GyroParameterSlot>& GyroParameterSlots(GyroModelKind kind);

/// Parameters of ω_raw = K_g ω + b_g + G f. Units as in the file comment.
template <typename Scalar>
struct GyroParametersT {
  Mat33T<Scalar> K = Mat33T<Scalar>::Identity();  ///< gyro raw per rad/s
  Vec3T<Scalar> bias = Vec3T<Scalar>::Zero();     ///< gyro raw
  Mat33T<Scalar> G = Mat33T<Scalar>::Zero();      ///< gyro raw per specific-force unit

  template <typename Other>
  GyroParametersT<Other> cast() const {
    return {K.template cast<Other>(), bias.template cast<Other>(), G.template cast<Other>()};
  }
};
using GyroParameters = GyroParametersT<double>;

/// Flat vector from parameters (G dropped for the linear model).
Eigen::VectorXd Pack(const GyroParameters& params, GyroModelKind kind);
/// Parameters from a flat vector of size NumGyroParameters(kind); G = 0 for the linear model.
GyroParameters UnpackGyro(const Eigen::VectorXd& theta, GyroModelKind kind);

/// The forward model without noise: ω_raw = K_g ω + b_g + G f.
template <typename Scalar>
Vec3T<Scalar> PredictRate(const GyroParametersT<Scalar>& params, const Vec3T<Scalar>& omega_rad_s,
                          const Vec3T<Scalar>& f) {
  return params.K * omega_rad_s + params.bias + params.G * f;
}

/// The inverse: the body rate ω = K_g⁻¹ (ω_raw − b_g − G f) [rad/s]; std::nullopt when K_g is
/// singular.
template <typename Scalar>
std::optional<Vec3T<Scalar>> BodyRate(const GyroParametersT<Scalar>& params,
                                      const Vec3T<Scalar>& raw, const Vec3T<Scalar>& f) {
  const Eigen::PartialPivLU<Mat33T<Scalar>> lu(params.K);
  if (!(lu.determinant() != Scalar(0))) return std::nullopt;
  return Vec3T<Scalar>(lu.solve(Vec3T<Scalar>(raw - params.bias - params.G * f)));
}

/// ∂ω_raw/∂θ of the forward model (3 x NumGyroParameters(kind)) at ω and f: row i holds
/// (ω_x, ω_y, ω_z, 1[, f_x, f_y, f_z]) in axis i's group and zeros elsewhere.
Eigen::MatrixXd GyroJacobianWrtParameters(const Vec3& omega_rad_s, const Vec3& f,
                                          GyroModelKind kind);

/// The rotation R of the body frame at t_n relative to the body frame at t_0 that the calibrated
/// rates of raw gyro samples ω_raw,k (at increasing times t_k [s], with the specific force f_k at
/// each) integrate to, as IntegrateAngularRate (rotations.hpp) with ω_k = BodyRate(params, ω_raw,k,
/// f_k) and `rule`:
///     R = Π_k Exp(φ_k),  φ_k = ω̄_k Δt_k.
/// Optionally its right Jacobian with respect to the flat parameters of `kind` (3 x
/// NumGyroParameters: R(θ + δ) = R(θ) Exp(J δ) to first order), by the recursion
///     J_{k+1} = Exp(φ_k)ᵀ J_k + J_r(φ_k) ∂φ_k/∂θ,   ∂ω_k/∂θ = −K_g⁻¹ ∂ω_raw/∂θ (ω_k, f_k)
/// (the forward model is linear in θ: d(K_g ω + b_g + G f) = 0 at fixed ω_raw). Optionally the
/// covariance [rad²] of the right perturbation ε of R (R(ω_raw + n) = R Exp(ε)) from white noise
/// n_k of 1σ `noise_sigma_raw` per axis on each raw sample, to first order:
///     ε = Rᵀ Σ_m C_m K_g⁻¹ n_m,  C_m = Σ_k R_{k+1} J_r(φ_k) ∂φ_k/∂ω_m
/// (R_k the product of the first k increments; a sample enters the step before it and the step
/// after it with weights Δt/2 under the trapezoidal rule, the step after it with Δt under the
/// piecewise-constant one). With `step_weights` (one per step, t_k to t_{k+1}), each increment is
/// φ_k = w_k ω̄_k Δt_k, its Jacobian and its samples' noise scaled alike: rates weighted from 0
/// to 1 over a still span integrate from the span's mean orientation rather than from one of its
/// samples (gyro_fit.hpp). Throws std::invalid_argument for sizes that differ, times that do not
/// increase, or a singular K_g.
Mat33 IntegrateCalibratedRate(const GyroParameters& params, GyroModelKind kind,
                              const std::vector<double>& t_s, const std::vector<Vec3>& raw,
                              const std::vector<Vec3>& f, RateInterpolation rule,
                              Eigen::MatrixXd* J_R_theta = nullptr,
                              const Vec3* noise_sigma_raw = nullptr, Mat33* covariance = nullptr,
                              const std::vector<double>* step_weights = nullptr);

/// The angle the body turned through between the first and the last sample: θ = |s|, s = ∫ ω dt
/// of the calibrated rates ω_k = BodyRate(params, ω_raw,k, f_k), summed with the weights c_k of
/// `rule` (trapezoidal: half of the step before sample k and half of the step after it;
/// piecewise-constant: the step after it). About a fixed axis it is the rotation's angle unwrapped
/// (a full turn gives 2π, where the angle of the rotation, |Log R|, gives 0); for a turn whose axis
/// wanders it is longer than |Log R|. It is linear in the rates, so its parameter gradient and its
/// noise are exact: with n = s/θ and a = K_g⁻ᵀ n, ∂θ/∂θ_p in output axis i's group is
/// −a_i (s_j for K_ij, Σ c_k for b_i, (Σ c_k f_k)_j for G_ij), and white noise of 1σ
/// `noise_sigma_raw` per axis on each raw sample adds the variance Σ c_k² aᵀ diag(σ²) a.
struct TurnedAngle {
  double angle_rad = 0;
  Eigen::RowVectorXd gradient;  ///< ∂θ/∂θ_p over the flat parameters of the model [rad]
  double noise_variance_rad2 = 0;
};
/// With `step_weights`, each step's share of its samples' weights c_k scaled by its weight (as
/// IntegrateCalibratedRate). Throws std::invalid_argument as IntegrateCalibratedRate.
TurnedAngle IntegrateTurnedAngle(const GyroParameters& params, GyroModelKind kind,
                                 const std::vector<double>& t_s, const std::vector<Vec3>& raw,
                                 const std::vector<Vec3>& f, RateInterpolation rule,
                                 const Vec3& noise_sigma_raw,
                                 const std::vector<double>* step_weights = nullptr);

}  // namespace accelcal
