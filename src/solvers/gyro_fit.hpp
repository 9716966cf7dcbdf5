#pragma once
// The gyroscope's fit from still positions and the motions between them (issue 18; Tedaldi,
// Pretto, Menegatti, ICRA 2014, and imu_tk for the idea, written from the equations below):
//
//   - each still position i observes the rate bias: its mean raw rate ω̄_i = b_g + G f_i + noise
//     (the Earth's rate neglected here), f_i = g c_i its specific force;
//   - each motion from position i to position j observes the rotation the body made: the
//     calibrated rates integrated from the last sample of i's interval to the first of j's
//     (IntegrateCalibratedRate, gyro_model.hpp) give R, and R must turn the force direction of i
//     into j's: v = Rᵀ c_i = c_j. Its residual is e = v × c_j, ≈ P ε for a rotation error ε (P the
//     projection ⟂ c_j), taken in a basis B of the plane ⟂ c_j and whitened by the covariance the
//     rate noise propagates to, Bᵀ Σ_ε B = L⁻¹ L⁻ᵀ: r = L Bᵀ (v × c_j) ~ N(0, I₂).
//
// B and L are taken once, at the start (a weight that moves with the parameters by the residual's
// size would change nothing of note and lose the exact Jacobian). Here the directions c_i are the
// accelerometer fit's, held fixed: the two-stage fit (the joint one frees them).

#include <cstddef>
#include <memory>
#include <optional>
#include <vector>

#include "accelcal/gyro_model.hpp"
#include "accelcal/rotations.hpp"
#include "solvers/least_squares.hpp"
#include "solvers/solver_common.hpp"

namespace accelcal::internal {

/// The gyro samples of one still position.
struct GyroStill {
  Vec3 mean_raw;             ///< mean raw rate over the interval
  Vec3 sigma_mean_raw;       ///< 1σ of that mean per axis (the samples' σ / √n) [gyro raw]
  Vec3 f;                    ///< specific force (the accelerometer's, g c_i)
  std::size_t position = 0;  ///< its position: the index of c_i in GyroFitData::directions
};

/// The gyro samples of one motion, from position `from` to position `to`.
struct GyroMotion {
  std::size_t from = 0, to = 0;
  std::vector<double> t_s;
  std::vector<Vec3> raw;
  std::vector<Vec3> f;  ///< specific force at each sample (the calibrated accelerometer)
  /// One per step, t_k to t_{k+1} (IntegrateCalibratedRate); empty: all 1. A motion that starts
  /// over the still span of `from` and ends over that of `to` weights their steps from 0 up to
  /// 1 and down again, so that it turns the span's mean orientation, which the accelerometer's
  /// mean reading sees, into the next's (a unit that wobbles as it stands), not one sample's.
  std::vector<double> step_weight;
  const std::vector<double>* weights() const {
    return step_weight.empty() ? nullptr : &step_weight;
  }
};

/// The motions of a fit's data, held once however often the data are copied: each model's fit,
/// the joint problem and the held-out fits copy the data to change their own fields, never the
/// samples (on the Xsens recording six copies of 2 MB were the gyro's largest memory cost). Value
/// semantics: push_back on a shared list copies it first.
class GyroMotions {
 public:
  void push_back(GyroMotion motion) {
    if (motions_.use_count() > 1) motions_ = std::make_shared<std::vector<GyroMotion>>(*motions_);
    motions_->push_back(std::move(motion));
  }
  std::size_t size() const { return motions_->size(); }
  bool empty() const { return motions_->empty(); }
  const GyroMotion& operator[](std::size_t k) const { return (*motions_)[k]; }
  std::vector<GyroMotion>::const_iterator begin() const { return motions_->cbegin(); }
  std::vector<GyroMotion>::const_iterator end() const { return motions_->cend(); }

 private:
  std::shared_ptr<std::vector<GyroMotion>> motions_ = std::make_shared<std::vector<GyroMotion>>();
};

/// One motion's residual, whitened (2 rows), with the fixed basis and weight of the fit.
struct MotionWeight {
  Mat32 B;            ///< basis of the plane ⟂ c_j
  Eigen::Matrix2d L;  ///< (Bᵀ Σ_ε B)^(−1/2), lower-triangular
};

/// What the gyro fit is given.
struct GyroFitData {
  /// One per position where the gyro stood still (a position it turned throughout has none).
  std::vector<GyroStill> stills;
  std::vector<Vec3> directions;  ///< c_i, unit, one per position
  GyroMotions motions;
  Vec3 noise_sigma_raw = Vec3::Ones();  ///< white noise of one raw sample, per axis
  GyroModelKind model = GyroModelKind::kLinear;
  RateInterpolation rule = RateInterpolation::kTrapezoidal;
  /// Each group's noise multiplied by these (its scatter ratio, when the sample noise does not
  /// explain the group's scatter): residuals divided by them.
  double still_scale = 1, motion_scale = 1;
  /// The Earth rate's vertical part Ω_E sin φ [rad/s] (0: not modelled): at rest the body turns
  /// at it about the up direction c_i, so each still mean observes b_g + G f_i + K_g (Ω_E sin φ)
  /// c_i. Its horizontal part, in an unknown heading, is not modelled; neither is the Earth rate
  /// during the turns (15 °/h: 0.02° over a turn of 4 s).
  double earth_rate_vertical = 0;
  /// One per motion (WeighMotions): the fits use them as given.
  std::vector<MotionWeight> weights;
  /// false: motion k left out of the fit (its residual block is empty); empty: all used.
  std::vector<bool> motion_used;
  bool used(std::size_t motion) const { return motion_used.empty() || motion_used[motion]; }
};

/// The mean raw rate a still position with up direction `c` (unit) and specific force `g c`
/// predicts: b_g + G g c + K_g (Ω_E sin φ) c (GyroFitData::earth_rate_vertical).
inline Vec3 StillRate(const GyroFitData& data, const GyroParameters& params, const Vec3& c,
                      double g) {
  return PredictRate(params, Vec3(data.earth_rate_vertical * c), Vec3(g * c));
}

/// The weight of motion `m` at `params`; nullopt when its propagated covariance is not positive.
std::optional<MotionWeight> WeighMotion(const GyroFitData& data, const GyroMotion& m,
                                        const GyroParameters& params);
/// Every motion's weight at `params`. Throws std::invalid_argument when one has no rate noise.
std::vector<MotionWeight> WeighMotions(const GyroFitData& data, const GyroParameters& params);
/// r = L Bᵀ (v × c_j), v = Rᵀ c_i, and optionally ∂r/∂θ (2 x P), ∂r/∂δ_i and ∂r/∂δ_j (2 x 2, δ
/// the tangent coordinates of c_i, c_j in TangentBasis: c ⊞ δ = normalize(c + E δ)).
Eigen::Vector2d MotionResidual(const GyroFitData& data, const GyroMotion& m,
                               const MotionWeight& weight, const GyroParameters& params,
                               const Vec3& c_i, const Vec3& c_j, Eigen::MatrixXd* J_theta = nullptr,
                               Eigen::Matrix2d* J_from = nullptr, Eigen::Matrix2d* J_to = nullptr);

/// MotionResidual's r for a rotation R already integrated.
Eigen::Vector2d RotationResidual(const MotionWeight& weight, const Mat33& R, const Vec3& c_i,
                                 const Vec3& c_j);

/// The angle [rad] between the direction the motion predicts for position `to` and c_to.
double MotionAngleError(const GyroFitData& data, const GyroMotion& m, const GyroParameters& params);

/// The start: b_g the mean of the still positions' mean rates, G = 0, and K_g = k I with k from
/// `scale_raw_per_rad_s` when the unit is known, else in closed form from the turns: each taken
/// about the fixed axis n of its bias-free raw rate summed over it, s = k θ n, with θ the angle
/// about n that takes c_i to c_j (from their projections on the plane ⟂ n): k the median of
/// |s|/θ over the turns whose directions lie well off n. When that start turns the directions
/// worse than kGyroMountSearchRad RMS, the gyro is mounted otherwise than the accelerometer (its
/// axes turned or mirrored): K_g = k P for the signed permutation P of the 48 whose start turns
/// them best (a fit started from k I landed on a flipped solution, 109° RMS, for a gyro turned
/// 90° about z).
GyroParameters GyroStart(const GyroFitData& data, std::optional<double> scale_raw_per_rad_s);

/// The start's RMS turn error beyond which other mounts are tried: an aligned gyro's start is
/// within a few degrees (its scale to 2 %, its misalignment ignored); a mount turned by 90°
/// misses by 60° or more.
inline constexpr double kGyroMountSearchRad = 20.0 * 3.14159265358979323846 / 180.0;

struct GyroFit {
  GyroParameters params;
  LeastSquaresSummary summary;  ///< covariance: the flat parameters' (GyroParameterSlots order)
};
/// Gauss-Newton / Levenberg-Marquardt from `start` (LeastSquaresProblem, least_squares.hpp),
/// with data.weights.
GyroFit FitGyro(const GyroFitData& data, const GyroParameters& start,
                const LeastSquaresOptions& options);
/// For each motion k, the parameters of the fit without it, to first order from the converged
/// fit `params`: one Gauss-Newton step of the problem without block k, δ_k = S_k⁻¹ J_kᵀ r_k with
/// S_k = S − J_kᵀ J_k (LeaveOneBlockOut, least_squares.hpp).
/// `solution`: the fit's summary, when at hand (its information and kept blocks are used).
std::vector<GyroParameters> HeldOutMotionFits(const GyroFitData& data, const GyroParameters& params,
                                              const LeastSquaresSummary* solution = nullptr);

}  // namespace accelcal::internal
