#pragma once
/// @file bias_drift.hpp
/// A bias that changes with time within one session, written once.
///
/// The model of model.hpp with the bias a function of time:
///
///     p_k = K f_k + b(t_k) + k2 ∘ f_k² + v_k,    b(t) = b + D φ(t),   φ(t_ref) = 0
///
///   t_k  the time of position k: the middle of its still interval          [s]
///   b    the bias at the reference time t_ref                                [raw]
///   φ    J basis functions of time, each zero at t_ref                       [dimensionless]
///   D    3 × J drift coefficients, row i the output axis i                   [raw]
///
/// The bases (BiasModelKind):
///   constant   J = 0: b(t) = b, the model of model.hpp.
///   linear     J = 1: φ(t) = (t − t_ref) / 60 s, so D is the drift in raw per minute; extrapolated
///              linearly outside the positions' times.
///   spline:K   K knots τ_0 … τ_{K−1} equally spaced from the first to the last position's time,
///              b(t) linear between knots (the hat functions B_j, Σ_j B_j = 1), held at the end
///              knots' values outside them: J = K − 1, φ_j(t) = B_j(t) − B_j(t_ref) for
///              j = 1 … K − 1, so D's column j is the bias at knot j less the bias at knot 0 (and
///              b(t) = Σ_j β_j B_j(t) for any knot biases β_j). spline:2 is the linear model held
///              constant outside the session.
///   t_ref      the mean of the positions' times: b is the session's mean bias, and for the linear
///              basis uncorrelated with D when the positions are evenly spread.
///
/// Flat order of D (the drift coefficients after the model's flat parameters in
/// BiasDrift::covariance): by output axis in the order of the frame's own axes x, y, z, each axis'
/// J coefficients in basis order: D_x1 … D_xJ, D_y1 … D_yJ, D_z1 … D_zJ.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "accelcal/model.hpp"
#include "accelcal/names.hpp"
#include "accelcal/types.hpp"

namespace accelcal {

/// How the bias depends on time within a session.
enum class BiasModelKind {
  kConstant,  ///< "constant"
  kLinear,    ///< "linear"
  kSpline,    ///< "spline:K"
};
template <>
struct EnumNames<BiasModelKind> {
  static constexpr std::pair<BiasModelKind, std::string_view> kTable[] = {
      {BiasModelKind::kConstant, "constant"},
      {BiasModelKind::kLinear, "linear"},
      {BiasModelKind::kSpline, "spline"}};
};

/// Most knots of a spline bias (each adds three parameters).
inline constexpr int kMaxBiasKnots = 32;

struct BiasModel {
  BiasModelKind kind = BiasModelKind::kConstant;
  int knots = 0;  ///< kSpline only: K, 2 … kMaxBiasKnots
  /// Basis functions J: 0, 1, K − 1.
  int functions() const {
    return kind == BiasModelKind::kConstant ? 0 : kind == BiasModelKind::kLinear ? 1 : knots - 1;
  }
  bool constant() const { return kind == BiasModelKind::kConstant; }
  friend bool operator==(const BiasModel& a, const BiasModel& b) {
    return a.kind == b.kind && (a.kind != BiasModelKind::kSpline || a.knots == b.knots);
  }
  friend bool operator!=(const BiasModel& a, const BiasModel& b) { return !(a == b); }
};
/// "constant", "linear", "spline:5".
std::string ToString(const BiasModel& model);
/// Parses the names above; std::nullopt for anything else (a spline with fewer than 2 or more than
/// kMaxBiasKnots knots included).
std::optional<BiasModel> BiasModelFromString(std::string_view text);

/// The basis φ(t) of a bias model over one session (see the file comment).
struct BiasTimeBasis {
  BiasModel model;
  double t_ref_s = 0;
  std::vector<double> knots_s;  ///< kSpline: τ_0 … τ_{K−1}, increasing

  /// The basis of `model` for positions at `times_s` (their middle times): t_ref their mean, the
  /// knots spread over their span. Throws std::invalid_argument for a non-finite time, or, unless
  /// the model is constant, fewer than two positions or times that do not span any time.
  static BiasTimeBasis For(const BiasModel& model, const std::vector<double>& times_s);
  int size() const { return model.functions(); }
  /// φ(t), size() entries.
  Eigen::VectorXd Evaluate(double t_s) const;
};

/// A fitted drift: b(t) − b = D φ(t).
struct BiasDrift {
  BiasTimeBasis basis;
  Eigen::Matrix<double, 3, Eigen::Dynamic> D;  ///< [raw], 3 × basis.size()
  /// Joint covariance of the model's flat parameters (model.hpp / frame.hpp order) followed by
  /// D's entries in the flat order of the file comment; empty when the fit has none.
  Eigen::MatrixXd covariance;
  /// The position times the fit used, one per reading [s].
  std::vector<double> times_s;
  /// The random walk q per axis [raw/√s] whose prior the fit had (a spline bias with
  /// CalibrationOptions::bias_random_walk), else none.
  std::optional<Vec3> random_walk;

  /// D φ(t) [raw]: the bias at t less the bias at t_ref.
  Vec3 Offset(double t_s) const;
  /// 1σ of the bias b(t) = b + D φ(t) per axis [raw], from `covariance` (the rows of b and D);
  /// NaN without a covariance. `bias_slots`: the flat indices of b_x, b_y, b_z.
  Vec3 BiasSigma(double t_s, const int bias_slots[3]) const;
};

/// MirrorAxes for a drift (frame.hpp): the rows of D mapped by P (D = P D_mirrored, column by
/// column), and the joint covariance of `model`'s flat parameters and D by the matching signed
/// permutation (MirrorSigns for the parameters). An involution, as MirrorAxes.
BiasDrift MirrorAxes(const BiasDrift& drift, ModelKind model);

}  // namespace accelcal
