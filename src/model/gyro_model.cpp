#include "accelcal/gyro_model.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace accelcal {

std::string_view ToString(GyroModelKind kind) { return NameOf(kind); }

std::optional<GyroModelKind> GyroModelKindFromString(std::string_view text) {
  return FromName<GyroModelKind>(text);
}

const std::vector<GyroParameterSlot>& GyroParameterSlots(GyroModelKind kind) {
  using Group = GyroParameterGroup;
  static const std::vector<GyroParameterSlot> g_sensitive = {
      {Group::kK, 0, 0, "Kg_xx"},    {Group::kK, 0, 1, "Kg_xy"},    {Group::kK, 0, 2, "Kg_xz"},
      {Group::kBias, 0, -1, "bg_x"}, {Group::kG, 0, 0, "G_xx"},     {Group::kG, 0, 1, "G_xy"},
      {Group::kG, 0, 2, "G_xz"},     {Group::kK, 1, 0, "Kg_yx"},    {Group::kK, 1, 1, "Kg_yy"},
      {Group::kK, 1, 2, "Kg_yz"},    {Group::kBias, 1, -1, "bg_y"}, {Group::kG, 1, 0, "G_yx"},
      {Group::kG, 1, 1, "G_yy"},     {Group::kG, 1, 2, "G_yz"},     {Group::kK, 2, 0, "Kg_zx"},
      {Group::kK, 2, 1, "Kg_zy"},    {Group::kK, 2, 2, "Kg_zz"},    {Group::kBias, 2, -1, "bg_z"},
      {Group::kG, 2, 0, "G_zx"},     {Group::kG, 2, 1, "G_zy"},     {Group::kG, 2, 2, "G_zz"}};
  static const std::vector<GyroParameterSlot> linear = [] {
    std::vector<GyroParameterSlot> slots;
    for (const GyroParameterSlot& s : g_sensitive) {
      if (s.group != Group::kG) slots.push_back(s);
    }
    return slots;
  }();
  return kind == GyroModelKind::kLinear ? linear : g_sensitive;
}

namespace {
double& SlotRef(GyroParameters& p, const GyroParameterSlot& s) {
  switch (s.group) {
    case GyroParameterGroup::kK:
      return p.K(s.row, s.col);
    case GyroParameterGroup::kBias:
      return p.bias(s.row);
    case GyroParameterGroup::kG:
      break;
  }
  return p.G(s.row, s.col);
}
}  // namespace

Eigen::VectorXd Pack(const GyroParameters& params, GyroModelKind kind) {
  const std::vector<GyroParameterSlot>& slots = GyroParameterSlots(kind);
  Eigen::VectorXd theta(static_cast<Eigen::Index>(slots.size()));
  GyroParameters copy = params;
  for (std::size_t i = 0; i < slots.size(); ++i) {
    theta(static_cast<Eigen::Index>(i)) = SlotRef(copy, slots[i]);
  }
  return theta;
}

GyroParameters UnpackGyro(const Eigen::VectorXd& theta, GyroModelKind kind) {
  const std::vector<GyroParameterSlot>& slots = GyroParameterSlots(kind);
  GyroParameters params;
  params.K.setZero();
  for (std::size_t i = 0; i < slots.size(); ++i) {
    SlotRef(params, slots[i]) = theta(static_cast<Eigen::Index>(i));
  }
  return params;
}

Eigen::MatrixXd GyroJacobianWrtParameters(const Vec3& omega_rad_s, const Vec3& f,
                                          GyroModelKind kind) {
  const int per_axis = GyroParametersPerAxis(kind);
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(3, NumGyroParameters(kind));
  for (int i = 0; i < 3; ++i) {
    const int start = i * per_axis;
    J.block<1, 3>(i, start) = omega_rad_s.transpose();
    J(i, start + 3) = 1.0;
    if (kind == GyroModelKind::kGSensitive) J.block<1, 3>(i, start + 4) = f.transpose();
  }
  return J;
}

namespace {

// Exp(φ) and J_r(φ) (rotations.hpp) for the small angle of one sample step, sharing Hat(φ) and
// its square: I + a Φ + b Φ² and I − b Φ + c Φ² with a = sin θ/θ, b = (1 − cos θ)/θ²,
// c = (θ − sin θ)/θ³. Below θ = 1/4 their Taylor series in θ² to the θ¹⁰ term (the first term
// left out is below 1e-17 there: θ¹²/13! < 1e-17), so no sine is taken; above, so3's closed
// forms.
inline Mat33 StepExp(const Vec3& phi, Mat33* J_r) {
  const double t = phi.squaredNorm();
  if (!(t < 0.0625)) {
    if (J_r != nullptr) *J_r = so3::RightJacobian(phi);
    return so3::Exp(phi);
  }
  // Horner in t = θ², the coefficients (−1)ⁿ/(2n+1)!, (−1)ⁿ/(2n+2)!, (−1)ⁿ/(2n+3)! (constants:
  // a division per term would take most of the step's time).
  constexpr double a1 = -1.0 / 6, a2 = 1.0 / 120, a3 = -1.0 / 5040, a4 = 1.0 / 362880,
                   a5 = -1.0 / 39916800;
  constexpr double b0 = 1.0 / 2, b1 = -1.0 / 24, b2 = 1.0 / 720, b3 = -1.0 / 40320,
                   b4 = 1.0 / 3628800, b5 = -1.0 / 479001600;
  const double a = 1 + t * (a1 + t * (a2 + t * (a3 + t * (a4 + t * a5))));
  const double b = b0 + t * (b1 + t * (b2 + t * (b3 + t * (b4 + t * b5))));
  // Φ² = φφᵀ − θ² I, so I + a Φ + b Φ² = (1 − b θ²) I + a Φ + b φφᵀ, and J_r likewise: no
  // matrix product.
  const double x = phi.x(), y = phi.y(), z = phi.z();
  const auto compose = [&](double diagonal, double skew, double outer) {
    Mat33 M;
    M(0, 0) = diagonal + outer * x * x;
    M(1, 1) = diagonal + outer * y * y;
    M(2, 2) = diagonal + outer * z * z;
    M(0, 1) = outer * x * y - skew * z;
    M(1, 0) = outer * x * y + skew * z;
    M(0, 2) = outer * x * z + skew * y;
    M(2, 0) = outer * x * z - skew * y;
    M(1, 2) = outer * y * z - skew * x;
    M(2, 1) = outer * y * z + skew * x;
    return M;
  };
  if (J_r != nullptr) {
    constexpr double c0 = 1.0 / 6, c1 = -1.0 / 120, c2 = 1.0 / 5040, c3 = -1.0 / 362880,
                     c4 = 1.0 / 39916800, c5 = -1.0 / 6227020800;
    const double c = c0 + t * (c1 + t * (c2 + t * (c3 + t * (c4 + t * c5))));
    *J_r = compose(1 - c * t, -b, c);  // I − b Φ + c Φ²
  }
  return compose(1 - b * t, a, b);  // I + a Φ + b Φ²
}

}  // namespace

namespace {

// The integration of IntegrateCalibratedRate for a model of `PerAxis` parameters per output axis
// (4 or 7), in fixed-size storage: checked inputs, K_g⁻¹ given.
template <int PerAxis>
Mat33 Integrate(const GyroParameters& params, const Mat33& K_inverse,
                const std::vector<double>& t_s, const std::vector<Vec3>& raw,
                const std::vector<Vec3>& f, RateInterpolation rule, Eigen::MatrixXd* J_R_theta,
                const Vec3* noise_sigma_raw, Mat33* covariance,
                const std::vector<double>* step_weights) {
  const bool jacobian = J_R_theta != nullptr;
  // ∂ω_k/∂θ = −K_g⁻¹ ∂ω_raw/∂θ, whose columns of axis i's group are −K_g⁻¹ e_i u_kᵀ with u_k =
  // (ω_k, 1[, f_k]) (GyroJacobianWrtParameters): each step adds to J rank-one blocks −J_r K_g⁻¹ e_i
  // ūᵀ Δt. K_g⁻¹ is the same at every step, so it is applied once at the end: the steps sum
  // T_b = Σ A_k e_b ūᵀ Δt (A_k = R_{k+1} J_r(φ_k)), and axis i's block is −Σ_b T_b (K_g⁻¹)_bi.
  using Regressor = Eigen::Matrix<double, 1, PerAxis>;
  const auto rate = [&](std::size_t k, Regressor* u) {
    const Vec3 omega = K_inverse * (raw[k] - params.bias - params.G * f[k]);
    if (u != nullptr) {
      u->template head<3>() = omega.transpose();
      (*u)(3) = 1.0;
      if constexpr (PerAxis == 7) u->template tail<3>() = f[k].transpose();
    }
    return omega;
  };
  const bool noise = noise_sigma_raw != nullptr && covariance != nullptr;
  const bool trapezoid = rule == RateInterpolation::kTrapezoidal;
  // The rate noise K_g⁻¹ n_m, Q = K_g⁻¹ diag(σ²) K_g⁻ᵀ; C_m summed over the steps sample m enters,
  // accumulated in the frame of the first sample (S = Σ C_m Q C_mᵀ) and turned to R's at the end.
  const Mat33 Q =
      noise ? Mat33(K_inverse * noise_sigma_raw->cwiseAbs2().asDiagonal() * K_inverse.transpose())
            : Mat33::Zero();
  Mat33 S = Mat33::Zero(), C = Mat33::Zero();  // C: sample k's C_m, so far
  Mat33 R = Mat33::Identity();
  Eigen::Matrix<double, 3, 3 * PerAxis> T = Eigen::Matrix<double, 3, 3 * PerAxis>::Zero();
  Regressor u_this, u_next;
  Vec3 omega_this = rate(0, jacobian ? &u_this : nullptr);
  for (std::size_t k = 0; k + 1 < t_s.size(); ++k) {
    const double dt = t_s[k + 1] - t_s[k];
    if (!(dt > 0)) {
      throw std::invalid_argument("IntegrateCalibratedRate: times do not increase at sample " +
                                  std::to_string(k + 1));
    }
    const Vec3 omega_next = rate(k + 1, jacobian ? &u_next : nullptr);
    // The step's weight scales its increment, its parameter regressor and its samples' noise
    // alike (all linear in the rates).
    const double w = step_weights != nullptr ? (*step_weights)[k] : 1.0;
    const Vec3 phi = (trapezoid ? Vec3(0.5 * (omega_this + omega_next)) : omega_this) * (w * dt);
    Mat33 J_r;
    const Mat33 increment = StepExp(phi, jacobian || noise ? &J_r : nullptr);
    if (noise) {
      const Mat33 A = R * increment * J_r;  // R_{k+1} J_r(φ_k)
      C += A *
           (trapezoid ? 0.5 * w * dt : w * dt);  // sample k's share of this step: C_k is complete
      S += C * Q * C.transpose();
      C = trapezoid ? Mat33(A * (0.5 * w * dt)) : Mat33::Zero();  // sample k + 1's share
    }
    R = R * increment;
    if (jacobian) {
      // In the frame of the first sample, W = R_k J_k: W_{k+1} = W_k + R_{k+1} ΔJ_k, where the
      // recursion's Exp(φ_k)ᵀ cancels (J_n = R_nᵀ W_n).
      const Regressor u =
          trapezoid ? Regressor(0.5 * w * dt * (u_this + u_next)) : Regressor(w * dt * u_this);
      const Mat33 A = R * J_r;
      for (int b = 0; b < 3; ++b) {
        T.template middleCols<PerAxis>(b * PerAxis).noalias() += A.col(b) * u;
      }
      u_this = u_next;
    }
    omega_this = omega_next;
  }
  if (jacobian) {
    Eigen::Matrix<double, 3, 3 * PerAxis> J;
    for (int i = 0; i < 3; ++i) {
      J.template middleCols<PerAxis>(i * PerAxis) =
          -(K_inverse(0, i) * T.template middleCols<PerAxis>(0) +
            K_inverse(1, i) * T.template middleCols<PerAxis>(PerAxis) +
            K_inverse(2, i) * T.template middleCols<PerAxis>(2 * PerAxis));
    }
    *J_R_theta = R.transpose() * J;
  }
  if (noise) {
    S += C * Q * C.transpose();  // the last sample (its step before it)
    *covariance = R.transpose() * S * R;
  }
  return R;
}

}  // namespace

namespace {

// K_g⁻¹ after the checks both integrations make (`who` names the caller in their messages).
Mat33 CheckedInverse(const char* who, const GyroParameters& params, const std::vector<double>& t_s,
                     const std::vector<Vec3>& raw, const std::vector<Vec3>& f,
                     const std::vector<double>* step_weights) {
  if (t_s.size() != raw.size() || t_s.size() != f.size() || t_s.empty()) {
    throw std::invalid_argument(std::string(who) + ": " + std::to_string(t_s.size()) +
                                " times for " + std::to_string(raw.size()) + " rates and " +
                                std::to_string(f.size()) + " specific forces");
  }
  if (step_weights != nullptr && step_weights->size() + 1 != t_s.size()) {
    throw std::invalid_argument(std::string(who) + ": " + std::to_string(step_weights->size()) +
                                " step weights for " + std::to_string(t_s.size()) + " samples");
  }
  const Eigen::PartialPivLU<Mat33> lu(params.K);
  if (!(lu.determinant() != 0.0) || !std::isfinite(lu.determinant())) {
    throw std::invalid_argument(std::string(who) + ": K_g is singular");
  }
  return lu.inverse();
}

}  // namespace

Mat33 IntegrateCalibratedRate(const GyroParameters& params, GyroModelKind kind,
                              const std::vector<double>& t_s, const std::vector<Vec3>& raw,
                              const std::vector<Vec3>& f, RateInterpolation rule,
                              Eigen::MatrixXd* J_R_theta, const Vec3* noise_sigma_raw,
                              Mat33* covariance, const std::vector<double>* step_weights) {
  const Mat33 K_inverse =
      CheckedInverse("IntegrateCalibratedRate", params, t_s, raw, f, step_weights);
  return kind == GyroModelKind::kLinear
             ? Integrate<4>(params, K_inverse, t_s, raw, f, rule, J_R_theta, noise_sigma_raw,
                            covariance, step_weights)
             : Integrate<7>(params, K_inverse, t_s, raw, f, rule, J_R_theta, noise_sigma_raw,
                            covariance, step_weights);
}

TurnedAngle IntegrateTurnedAngle(const GyroParameters& params, GyroModelKind kind,
                                 const std::vector<double>& t_s, const std::vector<Vec3>& raw,
                                 const std::vector<Vec3>& f, RateInterpolation rule,
                                 const Vec3& noise_sigma_raw,
                                 const std::vector<double>* step_weights) {
  const Mat33 K_inverse = CheckedInverse("IntegrateTurnedAngle", params, t_s, raw, f, step_weights);
  // The weights c_k of the rule, and the sums s = K_g⁻¹ Σ c_k u_k (u_k = ω_raw,k − b_g − G f_k),
  // Σ c_k, Σ c_k f_k and Σ c_k².
  const bool trapezoid = rule == RateInterpolation::kTrapezoidal;
  const std::size_t n = t_s.size();
  Vec3 u_sum = Vec3::Zero(), f_sum = Vec3::Zero();
  double c_sum = 0, c_sq = 0;
  const auto weight = [&](std::size_t step) {
    return step_weights != nullptr ? (*step_weights)[step] : 1.0;
  };
  for (std::size_t k = 0; k < n; ++k) {
    const double before = k > 0 ? (t_s[k] - t_s[k - 1]) * weight(k - 1) : 0.0;
    const double after = k + 1 < n ? (t_s[k + 1] - t_s[k]) * weight(k) : 0.0;
    if (k + 1 < n && !(t_s[k + 1] > t_s[k])) {
      throw std::invalid_argument("IntegrateTurnedAngle: times do not increase at sample " +
                                  std::to_string(k + 1));
    }
    const double c = trapezoid ? 0.5 * (before + after) : after;
    u_sum += c * (raw[k] - params.bias - params.G * f[k]);
    f_sum += c * f[k];
    c_sum += c;
    c_sq += c * c;
  }
  const Vec3 s = K_inverse * u_sum;
  TurnedAngle out;
  out.angle_rad = s.norm();
  out.gradient = Eigen::RowVectorXd::Zero(NumGyroParameters(kind));
  if (!(out.angle_rad > 0)) return out;  // no turn: no direction to differentiate along
  const Vec3 a = K_inverse.transpose() * (s / out.angle_rad);
  const auto& slots = GyroParameterSlots(kind);
  for (std::size_t p = 0; p < slots.size(); ++p) {
    const GyroParameterSlot& slot = slots[p];
    const double value = slot.group == GyroParameterGroup::kK      ? s(slot.col)
                         : slot.group == GyroParameterGroup::kBias ? c_sum
                                                                   : f_sum(slot.col);
    out.gradient(static_cast<Eigen::Index>(p)) = -a(slot.row) * value;
  }
  out.noise_variance_rad2 = c_sq * a.cwiseAbs2().dot(noise_sigma_raw.cwiseAbs2());
  return out;
}

}  // namespace accelcal
