#pragma once
/// @file rotations.hpp
/// Rotations in 3-D for the model layer: the SO(3) hat and vee maps, Exp and Log, the right
/// Jacobian and its inverse, the elementary rotations about the coordinate axes with their
/// derivatives, and the integration of a sampled angular rate (with its Jacobian with respect to
/// a constant gyro bias, for the gyroscope calibration to come).
///
/// Why our own and not a library: Sophus (the header-only Lie-group library) is not packaged for
/// Debian 12 (no libsophus-dev in bookworm: `apt-cache policy libsophus-dev` finds nothing), and
/// manif is not packaged at all; the project installs its dependencies from Debian only and
/// vendors no trees (docs: engineering notes, "vendored trees"). What we need is one group, a
/// few hundred lines of formulas; the conventions follow Sophus/manif (right perturbation,
/// `R ⊕ τ = R Exp(τ)`), so a later move to Sophus would change no formula.
///
/// Conventions (docs/model.md#rotations):
/// - Hat(w) = [w]×, the skew matrix with Hat(w) v = w × v; Vee is its inverse.
/// - Exp(φ) = I + (sin θ/θ) Φ + ((1 − cos θ)/θ²) Φ², Φ = Hat(φ), θ = |φ| (Rodrigues).
/// - Log(R) ∈ {|φ| ≤ π}: the inverse of Exp (at θ = π either of ±φ).
/// - Right Jacobian: Exp(φ + δ) = Exp(φ) Exp(J_r(φ) δ) + O(δ²),
///     J_r(φ) = I − ((1 − cos θ)/θ²) Φ + ((θ − sin θ)/θ³) Φ²,
///     J_r(φ)⁻¹ = I + ½ Φ + (1/θ² − (1 + cos θ)/(2 θ sin θ)) Φ²,
///   and Log(R Exp(δ)) = Log(R) + J_r(Log R)⁻¹ δ + O(δ²).
/// - Small angles use Taylor series below θ² = √ε (ε the Scalar's epsilon); angles near π take
///   the axis from the symmetric part of R (accurate where the skew part vanishes).
///
/// Every function is a template on the Scalar (double, float, or an automatic-differentiation
/// type with std-style cos/sin/sqrt/atan2 found by ADL); the double versions are compiled once in
/// src/model/rotations.cpp.

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "accelcal/types.hpp"

namespace accelcal {

namespace so3 {

/// [w]×: Hat(w) v = w × v.
template <typename Scalar>
Mat33T<Scalar> Hat(const Vec3T<Scalar>& w) {
  Mat33T<Scalar> W;
  W << Scalar(0), -w(2), w(1), w(2), Scalar(0), -w(0), -w(1), w(0), Scalar(0);
  return W;
}

/// The inverse of Hat on skew matrices; for any W, the vector of its skew part ½(W − Wᵀ).
template <typename Scalar>
Vec3T<Scalar> Vee(const Mat33T<Scalar>& W) {
  return Vec3T<Scalar>(W(2, 1) - W(1, 2), W(0, 2) - W(2, 0), W(1, 0) - W(0, 1)) / Scalar(2);
}

namespace detail {
/// θ² below which the closed forms lose digits to cancellation and a series is used.
template <typename Scalar>
Scalar SmallAngleSquared() {
  using std::sqrt;
  return sqrt(Eigen::NumTraits<Scalar>::epsilon());
}
}  // namespace detail

/// The right Jacobian J_r(φ) (see the file comment).
template <typename Scalar>
Mat33T<Scalar> RightJacobian(const Vec3T<Scalar>& phi) {
  using std::cos;
  using std::sin;
  using std::sqrt;
  const Scalar theta2 = phi.squaredNorm();
  const Mat33T<Scalar> Phi = Hat(phi);
  Scalar a, b;  // (1 − cos θ)/θ², (θ − sin θ)/θ³
  if (theta2 < detail::SmallAngleSquared<Scalar>()) {
    a = Scalar(0.5) - theta2 / Scalar(24);
    b = Scalar(1) / Scalar(6) - theta2 / Scalar(120);
  } else {
    const Scalar theta = sqrt(theta2);
    const Scalar half_sin = sin(theta / Scalar(2));
    a = Scalar(2) * half_sin * half_sin / theta2;
    b = (theta - sin(theta)) / (theta2 * theta);
  }
  return Mat33T<Scalar>::Identity() - a * Phi + b * Phi * Phi;
}

/// J_r(φ)⁻¹ (see the file comment); defined for |φ| < 2π.
template <typename Scalar>
Mat33T<Scalar> RightJacobianInverse(const Vec3T<Scalar>& phi) {
  using std::cos;
  using std::sin;
  using std::sqrt;
  const Scalar theta2 = phi.squaredNorm();
  const Mat33T<Scalar> Phi = Hat(phi);
  Scalar c;  // 1/θ² − (1 + cos θ)/(2 θ sin θ) = 1/12 + θ²/720 + …
  if (theta2 < detail::SmallAngleSquared<Scalar>()) {
    c = Scalar(1) / Scalar(12) + theta2 / Scalar(720);
  } else {
    const Scalar theta = sqrt(theta2);
    c = Scalar(1) / theta2 - (Scalar(1) + cos(theta)) / (Scalar(2) * theta * sin(theta));
  }
  return Mat33T<Scalar>::Identity() + Scalar(0.5) * Phi + c * Phi * Phi;
}

/// Exp(φ), Rodrigues' formula; optionally J_r(φ), the Jacobian of the right increment
/// (J_R_phi: Exp(φ + δ) = Exp(φ) Exp(J_R_phi δ) to first order).
template <typename Scalar>
Mat33T<Scalar> Exp(const Vec3T<Scalar>& phi, Mat33T<Scalar>* J_R_phi = nullptr) {
  using std::cos;
  using std::sin;
  using std::sqrt;
  const Scalar theta2 = phi.squaredNorm();
  const Mat33T<Scalar> Phi = Hat(phi);
  Scalar a, b;  // sin θ/θ, (1 − cos θ)/θ²
  if (theta2 < detail::SmallAngleSquared<Scalar>()) {
    a = Scalar(1) - theta2 / Scalar(6);
    b = Scalar(0.5) - theta2 / Scalar(24);
  } else {
    const Scalar theta = sqrt(theta2);
    const Scalar half_sin = sin(theta / Scalar(2));
    a = sin(theta) / theta;
    b = Scalar(2) * half_sin * half_sin / theta2;  // no cancellation in 1 − cos θ
  }
  if (J_R_phi != nullptr) *J_R_phi = RightJacobian(phi);
  return Mat33T<Scalar>::Identity() + a * Phi + b * Phi * Phi;
}

/// Log(R) for a rotation matrix R, |φ| ≤ π; optionally J_r(φ)⁻¹, the Jacobian of φ with respect
/// to a right increment of R (J_phi_R: Log(R Exp(δ)) = φ + J_phi_R δ to first order).
/// θ = atan2(|v|, (tr R − 1)/2) with v = Vee(R) = sin θ n, accurate at every angle. Below π/2 the
/// axis is v/|v| (θ/sin θ by its series for small θ); from π/2 on it is the largest column of
/// the symmetric part, (R + Rᵀ)/2 − cos θ I = (1 − cos θ) n nᵀ, signed by v.
template <typename Scalar>
Vec3T<Scalar> Log(const Mat33T<Scalar>& R, Mat33T<Scalar>* J_phi_R = nullptr) {
  using std::atan2;
  using std::sqrt;
  const Vec3T<Scalar> v = Vee(R);
  const Scalar sin_theta = v.norm();
  const Scalar cos_theta = (R.trace() - Scalar(1)) / Scalar(2);
  const Scalar theta = atan2(sin_theta, cos_theta);
  Vec3T<Scalar> phi;
  if (cos_theta > Scalar(0)) {
    const Scalar theta2 = theta * theta;
    const Scalar ratio = theta2 < detail::SmallAngleSquared<Scalar>()
                             ? Scalar(1) + theta2 / Scalar(6)  // θ / sin θ
                             : theta / sin_theta;
    phi = ratio * v;
  } else {
    const Mat33T<Scalar> S =
        (R + R.transpose()) / Scalar(2) - cos_theta * Mat33T<Scalar>::Identity();
    int j = 0;
    S.diagonal().maxCoeff(&j);
    Vec3T<Scalar> n = S.col(j) / sqrt(S(j, j) * (Scalar(1) - cos_theta));
    if (n.dot(v) < Scalar(0)) n = -n;
    phi = theta * n;
  }
  if (J_phi_R != nullptr) *J_phi_R = RightJacobianInverse(phi);
  return phi;
}

}  // namespace so3

enum class Axis { kX = 0, kY = 1, kZ = 2 };

/// The right-handed rotation by `angle` about a coordinate axis, R_a(θ) = Exp(θ e_a), built from
/// cos θ and sin θ directly (exact for the multiples of π/2 a gimbal table holds); optionally its
/// derivative dR_a/dθ = Hat(e_a) R_a(θ).
template <typename Scalar>
Mat33T<Scalar> AxisRotation(Axis axis, const Scalar& angle, Mat33T<Scalar>* dR_dangle = nullptr) {
  using std::cos;
  using std::sin;
  const Scalar c = cos(angle), s = sin(angle);
  const int a = static_cast<int>(axis), i = (a + 1) % 3, j = (a + 2) % 3;
  Mat33T<Scalar> R = Mat33T<Scalar>::Identity();
  R(i, i) = c;
  R(i, j) = -s;
  R(j, i) = s;
  R(j, j) = c;
  if (dR_dangle != nullptr) {
    dR_dangle->setZero();
    (*dR_dangle)(i, i) = -s;
    (*dR_dangle)(i, j) = -c;
    (*dR_dangle)(j, i) = c;
    (*dR_dangle)(j, j) = -s;
  }
  return R;
}

/// How the rate between two samples is taken.
enum class RateInterpolation {
  /// ω(t) = ω_k on [t_k, t_{k+1}) (zero-order hold; the last sample's rate is not used): exact for
  /// a rate that is constant between samples; error O(Δt) for a smoothly varying one.
  kPiecewiseConstant,
  /// φ_k = ½(ω_k + ω_{k+1}) Δt_k, the trapezoidal rule on each interval: exact for a constant
  /// rate and for a rate of fixed axis varying linearly; error O(Δt²) for a smoothly varying one
  /// (the non-commutativity of the increments is neglected at that order).
  kTrapezoidal,
};

/// The rotation R_0n of the body frame at t_n relative to the body frame at t_0, for body rates
/// ω_k (rad/s, body frame: Ṙ = R Hat(ω)) sampled at increasing times t_k (s), measured by a gyro
/// with a constant bias b (ω_true = ω_k − b):
///     R_0n = Π_k Exp(φ_k),  φ_k = (ω̄_k − b) Δt_k,  Δt_k = t_{k+1} − t_k,
/// ω̄_k by `rule`. Optionally the right Jacobian with respect to b (J_R_bias: R(b + δb) =
/// R(b) Exp(J_R_bias δb) to first order), by the recursion J_{k+1} = Exp(φ_k)ᵀ J_k − J_r(φ_k) Δt_k.
/// Throws std::invalid_argument for sizes that differ or times that do not increase; one sample
/// gives the identity.
template <typename Scalar>
Mat33T<Scalar> IntegrateAngularRate(const std::vector<Scalar>& t_s,
                                    const std::vector<Vec3T<Scalar>>& omega_rad_s,
                                    RateInterpolation rule,
                                    const Vec3T<Scalar>& bias_rad_s = Vec3T<Scalar>::Zero(),
                                    Mat33T<Scalar>* J_R_bias = nullptr) {
  if (t_s.size() != omega_rad_s.size() || t_s.empty()) {
    throw std::invalid_argument("IntegrateAngularRate: " + std::to_string(t_s.size()) +
                                " times for " + std::to_string(omega_rad_s.size()) + " rates");
  }
  Mat33T<Scalar> R = Mat33T<Scalar>::Identity();
  Mat33T<Scalar> J = Mat33T<Scalar>::Zero();
  for (std::size_t k = 0; k + 1 < t_s.size(); ++k) {
    const Scalar dt = t_s[k + 1] - t_s[k];
    if (!(dt > Scalar(0))) {
      throw std::invalid_argument("IntegrateAngularRate: times do not increase at sample " +
                                  std::to_string(k + 1));
    }
    const Vec3T<Scalar> rate =
        rule == RateInterpolation::kTrapezoidal
            ? Vec3T<Scalar>((omega_rad_s[k] + omega_rad_s[k + 1]) / Scalar(2))
            : omega_rad_s[k];
    const Vec3T<Scalar> phi = (rate - bias_rad_s) * dt;
    Mat33T<Scalar> J_r;
    const Mat33T<Scalar> increment = so3::Exp(phi, J_R_bias != nullptr ? &J_r : nullptr);
    if (J_R_bias != nullptr) J = increment.transpose() * J - J_r * dt;
    R = R * increment;
  }
  if (J_R_bias != nullptr) *J_R_bias = J;
  return R;
}

// Compiled once in rotations.cpp.
namespace so3 {
extern template Mat33T<double> Hat(const Vec3T<double>&);
extern template Vec3T<double> Vee(const Mat33T<double>&);
extern template Mat33T<double> RightJacobian(const Vec3T<double>&);
extern template Mat33T<double> RightJacobianInverse(const Vec3T<double>&);
extern template Mat33T<double> Exp(const Vec3T<double>&, Mat33T<double>*);
extern template Vec3T<double> Log(const Mat33T<double>&, Mat33T<double>*);
}  // namespace so3
extern template Mat33T<double> AxisRotation(Axis, const double&, Mat33T<double>*);
extern template Mat33T<double> IntegrateAngularRate(const std::vector<double>&,
                                                    const std::vector<Vec3T<double>>&,
                                                    RateInterpolation, const Vec3T<double>&,
                                                    Mat33T<double>*);

}  // namespace accelcal
