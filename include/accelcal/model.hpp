#pragma once
/// @file model.hpp
/// The accelerometer error model, written once.
///
/// Paper 000 (Yang et al. 2012) eq. (3) and (7):
///
///     p = K f + b + k2 ∘ f² + v
///
///   p   raw output of the three axes                          [raw units, e.g. counts]
///   f   specific force in the body frame b                    [specific-force unit: m/s² or g]
///   K   lower-triangular 3x3 (K = k_a T_b^a of eq. (2)):       [raw per specific-force unit]
///       body x = sensor x axis, body y in the sensor x-y plane, body z completes a right-handed
///       frame (the x-first frame; the z-first frame of frame.hpp has K upper-triangular, and
///       its parameters are those of the axis-mirrored problem, see MirrorAxes)
///   b   bias                                                   [raw]
///   k2  squared (second-order) coefficients, one per axis      [raw per (specific-force unit)²]
///       zero in the linear model
///   ∘   element-wise product; f² = f ∘ f
///
/// All-zero k2 and b with K = I make the model the identity.
///
/// Flat parameter order (paper 000 eq. (8)), grouped by output axis so that the linear
/// least-squares step of the two-step method (eq. (15)) splits into three independent problems:
///
///     quadratic (12): K_xx b_x k2_x | K_yx K_yy b_y k2_y | K_zx K_zy K_zz b_z k2_z
///     linear     (9): K_xx b_x      | K_yx K_yy b_y      | K_zx K_zy K_zz b_z
///
/// (x-first frame; the z-first order is in frame.hpp.)
///
/// In a static position f = g c with |c| = 1 and g the local gravity magnitude (eq. (6)).

#include <array>
#include <optional>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>  // SpecificForce of a full K

#include "accelcal/names.hpp"
#include "accelcal/types.hpp"

namespace accelcal {

/// Which error model is fitted.
enum class ModelKind {
  kLinear,     ///< k2 = 0: 9 parameters.
  kQuadratic,  ///< 12 parameters.
};

std::string_view ToString(ModelKind kind);
/// Parses "linear" or "quadratic"; std::nullopt for anything else.
std::optional<ModelKind> ModelKindFromString(std::string_view text);
template <>
struct EnumNames<ModelKind> {
  static constexpr std::pair<ModelKind, std::string_view> kTable[] = {
      {ModelKind::kLinear, "linear"}, {ModelKind::kQuadratic, "quadratic"}};
};

/// Number of free parameters of the model (9 or 12).
constexpr int NumParameters(ModelKind kind) { return kind == ModelKind::kLinear ? 9 : 12; }

/// Maximum number of parameters of any model; flat vectors are padded to this size in kernels.
constexpr int kMaxParameters = 12;

/// Which member of ModelParameters a flat parameter is.
enum class ParameterGroup { kK, kBias, kK2 };

/// One entry of the flat parameter vector: group, row (output axis) and column (for K).
struct ParameterSlot {
  ParameterGroup group;
  int row;
  int col;
  std::string_view name;  ///< e.g. "K_yx", "b_z", "k2_x".
};

/// The slots of the flat parameter vector in order (eq. (8)); size NumParameters(kind).
const std::vector<ParameterSlot>& ParameterSlots(ModelKind kind);

/// Parameters of p = K f + b + k2 ∘ f². Units as in the file comment.
template <typename Scalar>
struct ModelParametersT {
  Mat33T<Scalar> K = Mat33T<Scalar>::Identity();  ///< raw per specific-force unit, triangular
  Vec3T<Scalar> bias = Vec3T<Scalar>::Zero();     ///< raw
  Vec3T<Scalar> k2 = Vec3T<Scalar>::Zero();       ///< raw per (specific-force unit)²

  template <typename Other>
  ModelParametersT<Other> cast() const {
    return {K.template cast<Other>(), bias.template cast<Other>(), k2.template cast<Other>()};
  }
};
using ModelParameters = ModelParametersT<double>;

/// The entry of `p` that slot `s` names.
double& SlotRef(ModelParameters& p, const ParameterSlot& s);
/// ∂μ_row/∂θ_s at specific force f (μ is linear in θ): K's entry (row, col) moves axis `row` by
/// f_col, b_row by 1, k2_row by f_row².
double SlotRegressor(const ParameterSlot& s, const Vec3& f);

/// Flat vector (eq. (8) order) from parameters; k2 is dropped for the linear model.
Eigen::VectorXd Pack(const ModelParameters& params, ModelKind kind);
/// Parameters from a flat vector of size NumParameters(kind); k2 = 0 for the linear model.
ModelParameters Unpack(const Eigen::VectorXd& theta, ModelKind kind);
/// The same in the order of any slot list (e.g. a frame's, frame.hpp); Unpack leaves every entry
/// that no slot names at zero.
Eigen::VectorXd Pack(const ModelParameters& params, const std::vector<ParameterSlot>& slots);
ModelParameters Unpack(const Eigen::VectorXd& theta, const std::vector<ParameterSlot>& slots);

/// Forward model μ(f) = K f + b + k2 ∘ f² (eq. (11) without noise), for any K (lower-triangular
/// in the x-first frame, upper in the z-first frame of frame.hpp). Optionally returns
/// J_p_f = ∂p/∂f = K + 2 diag(k2 ∘ f).
template <typename Scalar>
Vec3T<Scalar> PredictRaw(const ModelParametersT<Scalar>& params, const Vec3T<Scalar>& f,
                         Mat33T<Scalar>* J_p_f = nullptr) {
  const Mat33T<Scalar>& K = params.K;
  const Vec3T<Scalar>& k2 = params.k2;
  if (J_p_f != nullptr) {
    *J_p_f = K;
    for (int i = 0; i < 3; ++i) (*J_p_f)(i, i) += Scalar(2) * k2(i) * f(i);
  }
  Vec3T<Scalar> p;
  for (int i = 0; i < 3; ++i) {
    p(i) = K(i, 0) * f(0) + K(i, 1) * f(1) + K(i, 2) * f(2) + params.bias(i) + k2(i) * f(i) * f(i);
  }
  return p;
}

/// Jacobian of the forward model with respect to the 12 flat parameters (quadratic order, eq. (15)
/// rows): row x = [f_x 1 f_x² | 0 ...], row y = [0 0 0 | f_x f_y 1 f_y² | 0 ...], row z likewise.
/// For the linear model drop columns 2, 6 and 11.
template <typename Scalar>
Eigen::Matrix<Scalar, 3, kMaxParameters> JacobianWrtParameters(const Vec3T<Scalar>& f) {
  Eigen::Matrix<Scalar, 3, kMaxParameters> J = Eigen::Matrix<Scalar, 3, kMaxParameters>::Zero();
  J(0, 0) = f.x();
  J(0, 1) = Scalar(1);
  J(0, 2) = f.x() * f.x();
  J(1, 3) = f.x();
  J(1, 4) = f.y();
  J(1, 5) = Scalar(1);
  J(1, 6) = f.y() * f.y();
  J(2, 7) = f.x();
  J(2, 8) = f.y();
  J(2, 9) = f.z();
  J(2, 10) = Scalar(1);
  J(2, 11) = f.z() * f.z();
  return J;
}

/// Column indices of the quadratic (12-parameter) layout used by a model kind.
const std::vector<int>& ActiveColumns(ModelKind kind);

/// Exact inverse of the forward model: the specific force f with PredictRaw(params, f) = p.
///
/// For a triangular K (lower: x-first frame; upper: z-first) and diagonal k2, row i reads
/// K_ii f_i + k2_i f_i² = r_i with r_i known once the other components of the triangle are: a
/// scalar quadratic solved in closed form, taking the root that tends to the linear solution
/// r_i / K_ii as k2_i → 0 (written 2 r / (K + sqrt(K² + 4 k2 r)) to avoid cancellation). A full K
/// (platform frame) is inverted, and with k2 ≠ 0 refined by Newton's method from that linear
/// solution. Returns std::nullopt when p lies outside the range the model can produce (negative
/// discriminant, or Newton not converging in 8 steps), or when K is singular (a zero diagonal of
/// a triangular K).
template <typename Scalar>
std::optional<Vec3T<Scalar>> SpecificForce(const ModelParametersT<Scalar>& params,
                                           const Vec3T<Scalar>& p) {
  using std::sqrt;
  const Mat33T<Scalar>& K = params.K;
  const bool lower = K(0, 1) == Scalar(0) && K(0, 2) == Scalar(0) && K(1, 2) == Scalar(0);
  const bool upper = K(1, 0) == Scalar(0) && K(2, 0) == Scalar(0) && K(2, 1) == Scalar(0);
  if (!lower && !upper) {
    const Scalar det = K.determinant();
    if (det == Scalar(0)) return std::nullopt;
    const Vec3T<Scalar> target = p - params.bias;
    Vec3T<Scalar> f = K.inverse() * target;
    if (params.k2.isZero(0)) return f;
    // Full K with squared terms (platform frame): Newton from the linear solution, the root that
    // continues it (|2 k2 f| ≪ |K| for any real device). Quadratic convergence: 8 steps take a
    // start 10 % off to round-off; more means no such root.
    for (int iteration = 0; iteration < 8; ++iteration) {
      Mat33T<Scalar> J;
      const Vec3T<Scalar> step = (PredictRaw(params, f, &J) - p);
      const Vec3T<Scalar> delta = J.inverse() * step;
      f -= delta;
      if (!(delta.squaredNorm() > Scalar(1e-30) * f.squaredNorm())) return f;
    }
    return std::nullopt;
  }
  Vec3T<Scalar> f = Vec3T<Scalar>::Zero();
  for (int n = 0; n < 3; ++n) {
    const int i = lower ? n : 2 - n;  // solve along the triangle
    Scalar r = p(i) - params.bias(i);
    for (int j = 0; j < 3; ++j) {
      if (j != i) r -= K(i, j) * f(j);  // the entries outside the triangle are zero
    }
    const Scalar a = K(i, i);
    if (a == Scalar(0)) return std::nullopt;
    // k2 = 0: the root below is exactly r / a (√(a²) = |a| in floating point), without its cost.
    if (params.k2(i) == Scalar(0) && a * a >= Scalar(0)) {
      f(i) = r / a;
      continue;
    }
    const Scalar disc = a * a + Scalar(4) * params.k2(i) * r;
    if (!(disc >= Scalar(0))) return std::nullopt;
    const Scalar root = sqrt(disc);
    const Scalar denom = a >= Scalar(0) ? a + root : a - root;
    f(i) = Scalar(2) * r / denom;
  }
  return f;
}

}  // namespace accelcal
