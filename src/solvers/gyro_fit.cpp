// The gyroscope's two-stage fit (gyro_fit.hpp).
#include "solvers/gyro_fit.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include "solvers/solver_common.hpp"

namespace accelcal::internal {

std::optional<MotionWeight> WeighMotion(const GyroFitData& data, const GyroMotion& m,
                                        const GyroParameters& params) {
  Mat33 covariance;
  IntegrateCalibratedRate(params, data.model, m.t_s, m.raw, m.f, data.rule, nullptr,
                          &data.noise_sigma_raw, &covariance, m.weights());
  MotionWeight w;
  w.B = TangentBasis(data.directions[m.to]);
  const Eigen::Matrix2d M = w.B.transpose() * covariance * w.B;
  const Eigen::LLT<Eigen::Matrix2d> llt(M);
  if (llt.info() != Eigen::Success || !(M.determinant() > 0)) return std::nullopt;
  const Eigen::Matrix2d U = llt.matrixL();
  w.L = U.inverse();
  return w;
}

std::vector<MotionWeight> WeighMotions(const GyroFitData& data, const GyroParameters& params) {
  std::vector<MotionWeight> weights;
  weights.reserve(data.motions.size());
  for (const GyroMotion& m : data.motions) {
    std::optional<MotionWeight> w = WeighMotion(data, m, params);
    if (!w) throw std::invalid_argument("a motion without rate noise: its weight is undefined");
    weights.push_back(*w);
  }
  return weights;
}

Eigen::Vector2d MotionResidual(const GyroFitData& data, const GyroMotion& m,
                               const MotionWeight& weight, const GyroParameters& params,
                               const Vec3& c_i, const Vec3& c_j, Eigen::MatrixXd* J_theta,
                               Eigen::Matrix2d* J_from, Eigen::Matrix2d* J_to) {
  Eigen::MatrixXd J_R;
  const Mat33 R =
      IntegrateCalibratedRate(params, data.model, m.t_s, m.raw, m.f, data.rule,
                              J_theta != nullptr ? &J_R : nullptr, nullptr, nullptr, m.weights());
  const Vec3 v = R.transpose() * c_i;
  const Eigen::Matrix<double, 2, 3> W = weight.L * weight.B.transpose();
  // e = v × c_j = −[c_j]× v = [v]× c_j; v(θ ⊞ δ) = v + [v]× J_R δ, v(c_i ⊞ δ) = v + Rᵀ E_i δ.
  if (J_theta != nullptr) *J_theta = -W * so3::Hat(c_j) * so3::Hat(v) * J_R;
  if (J_from != nullptr) *J_from = -W * so3::Hat(c_j) * R.transpose() * TangentBasis(c_i);
  if (J_to != nullptr) *J_to = W * so3::Hat(v) * TangentBasis(c_j);
  return W * v.cross(c_j);
}

Eigen::Vector2d RotationResidual(const MotionWeight& weight, const Mat33& R, const Vec3& c_i,
                                 const Vec3& c_j) {
  return weight.L * weight.B.transpose() * Vec3(R.transpose() * c_i).cross(c_j);
}

double MotionAngleError(const GyroFitData& data, const GyroMotion& m,
                        const GyroParameters& params) {
  const Mat33 R = IntegrateCalibratedRate(params, data.model, m.t_s, m.raw, m.f, data.rule, nullptr,
                                          nullptr, nullptr, m.weights());
  const Vec3 v = R.transpose() * data.directions[m.from];
  const Vec3& c = data.directions[m.to];
  return std::atan2(v.cross(c).norm(), v.dot(c));
}

namespace {

// The start with K_g = k P for the mount P (a signed permutation: the gyro's axes as the
// accelerometer's, turned or mirrored), b_g the mean of the still rates, G = 0.
GyroParameters StartForMount(const GyroFitData& data, std::optional<double> scale_raw_per_rad_s,
                             const Mat33& P) {
  GyroParameters start;
  start.bias.setZero();
  for (const GyroStill& s : data.stills) start.bias += s.mean_raw;
  if (!data.stills.empty()) start.bias /= static_cast<double>(data.stills.size());
  double k = 1.0;
  if (scale_raw_per_rad_s) {
    k = *scale_raw_per_rad_s;
  } else {
    // Each turn taken about the fixed axis n = Pᵀ s/|s| of its bias-free raw rate summed over it
    // (s = k θ P n for K_g = k P): the angle θ about n that takes c_i to c_j, read from their
    // projections on the plane ⟂ n, gives k = |s|/θ; the median over the turns whose directions
    // are well off n. Without such a turn, the turned angle is taken as at least the angle
    // between c_i and c_j: k = Σ |s_m| α_m / Σ α_m² (an overestimate when turns are longer).
    std::vector<double> scales;
    double sa = 0, aa = 0;
    for (const GyroMotion& m : data.motions) {
      Vec3 sum = Vec3::Zero();  // the bias-free raw rate summed over the motion (trapezoidal)
      for (std::size_t k2 = 0; k2 + 1 < m.t_s.size(); ++k2) {
        const double w = m.step_weight.empty() ? 1.0 : m.step_weight[k2];
        sum += 0.5 * (m.raw[k2] + m.raw[k2 + 1] - 2.0 * start.bias) *
               (w * (m.t_s[k2 + 1] - m.t_s[k2]));
      }
      const Vec3& a = data.directions[m.from];
      const Vec3& b = data.directions[m.to];
      const double angle = std::atan2(a.cross(b).norm(), a.dot(b));
      sa += sum.norm() * angle;
      aa += angle * angle;
      if (!(sum.norm() > 0)) continue;
      const Vec3 n = P.transpose() * sum.normalized();
      const Vec3 pa = a - a.dot(n) * n, pb = b - b.dot(n) * n;
      if (pa.norm() < 0.3 || pb.norm() < 0.3) continue;
      // The body turns by θ about n, so the force direction turns by −θ: c_j = Exp(θ n)ᵀ c_i.
      double theta = -std::atan2(n.dot(pa.cross(pb)), pa.dot(pb));
      if (theta <= 0) theta += 2 * 3.14159265358979323846;
      if (theta < 0.35) continue;  // under 20°: the angle is too uncertain
      scales.push_back(sum.norm() / theta);
    }
    if (!scales.empty()) {
      std::nth_element(scales.begin(),
                       scales.begin() + static_cast<std::ptrdiff_t>(scales.size() / 2),
                       scales.end());
      k = scales[scales.size() / 2];
    } else if (aa > 0 && sa > 0) {
      k = sa / aa;
    }
  }
  start.K = k * P;
  return start;
}

// The turns' RMS angle error [rad] under `params` (their predicted direction against c_to).
double StartError(const GyroFitData& data, const GyroParameters& params) {
  double sum = 0;
  for (const GyroMotion& m : data.motions) {
    const double e = MotionAngleError(data, m, params);
    sum += e * e;
  }
  return data.motions.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(data.motions.size()));
}

}  // namespace

GyroParameters GyroStart(const GyroFitData& data, std::optional<double> scale_raw_per_rad_s) {
  const GyroParameters aligned = StartForMount(data, scale_raw_per_rad_s, Mat33::Identity());
  const double aligned_error = StartError(data, aligned);
  if (aligned_error <= kGyroMountSearchRad) return aligned;
  // The gyro's axes are not the accelerometer's: each of the 48 signed permutations (24 turned,
  // 24 mirrored) as the mount, the one whose start turns the directions best (the first of
  // equals, in a fixed order: the same start on any machine).
  GyroParameters best = aligned;
  double best_error = aligned_error;
  for (int order = 0; order < 6; ++order) {
    static constexpr int kPermutations[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2},
                                                {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    for (int signs = 0; signs < 8; ++signs) {
      Mat33 P = Mat33::Zero();
      for (int row = 0; row < 3; ++row) {
        P(row, kPermutations[order][row]) = (signs >> row) & 1 ? -1.0 : 1.0;
      }
      if (P.isIdentity()) continue;
      const GyroParameters start = StartForMount(data, scale_raw_per_rad_s, P);
      const double error = StartError(data, start);
      if (error < best_error) best = start, best_error = error;
    }
  }
  return best;
}

namespace {

// Global parameters θ only (the directions held); blocks: the stills (3 rows), then the motions
// (2 rows).
class TwoStageProblem : public LeastSquaresProblem {
 public:
  explicit TwoStageProblem(const GyroFitData& data) : data_(data) {}
  int GlobalSize() const override { return NumGyroParameters(data_.model); }
  int NumBlocks() const override {
    return static_cast<int>(data_.stills.size() + data_.motions.size());
  }
  bool Evaluate(int block, const Eigen::VectorXd& x, const Eigen::VectorXd& /*y*/,
                Eigen::VectorXd* residual, Eigen::MatrixXd* J_x,
                Eigen::MatrixXd* /*J_y*/) const override {
    const GyroParameters params = UnpackGyro(x, data_.model);
    const auto b = static_cast<std::size_t>(block);
    if (b < data_.stills.size()) {
      const GyroStill& s = data_.stills[b];
      const Vec3 inverse_sigma = (data_.still_scale * s.sigma_mean_raw).cwiseInverse();
      const Vec3 earth = data_.earth_rate_vertical * s.f.normalized();  // Ω_E sin φ c_i
      *residual = inverse_sigma.cwiseProduct(
          s.mean_raw - StillRate(data_, params, s.f.normalized(), s.f.norm()));
      if (J_x != nullptr) {
        *J_x = -(inverse_sigma.asDiagonal() * GyroJacobianWrtParameters(earth, s.f, data_.model));
      }
      return residual->allFinite();
    }
    const std::size_t k = b - data_.stills.size();
    const GyroMotion& m = data_.motions[k];
    if (!data_.used(k)) {
      residual->resize(0);
      if (J_x != nullptr) J_x->resize(0, GlobalSize());
      return true;
    }
    try {
      *residual = MotionResidual(data_, m, data_.weights[k], params, data_.directions[m.from],
                                 data_.directions[m.to], J_x) /
                  data_.motion_scale;
      if (J_x != nullptr) *J_x /= data_.motion_scale;
    } catch (const std::invalid_argument&) {
      return false;  // a singular K_g
    }
    return residual->allFinite() && (J_x == nullptr || J_x->allFinite());
  }

 private:
  const GyroFitData& data_;
};

}  // namespace

GyroFit FitGyro(const GyroFitData& data, const GyroParameters& start,
                const LeastSquaresOptions& options) {
  if (data.weights.size() != data.motions.size()) {
    throw std::invalid_argument("FitGyro: a weight for each motion is needed");
  }
  const TwoStageProblem problem(data);
  LeastSquaresState state;
  state.x = Pack(start, data.model);
  state.y.assign(static_cast<std::size_t>(problem.NumBlocks()), Eigen::VectorXd());
  GyroFit fit;
  fit.summary = SolveLeastSquares(problem, options, &state);
  fit.params = UnpackGyro(state.x, data.model);
  return fit;
}

std::vector<GyroParameters> HeldOutMotionFits(const GyroFitData& data, const GyroParameters& params,
                                              const LeastSquaresSummary* solution) {
  const TwoStageProblem problem(data);
  LeastSquaresState state;
  state.x = Pack(params, data.model);
  state.y.assign(static_cast<std::size_t>(problem.NumBlocks()), Eigen::VectorXd());
  std::vector<int> blocks;
  for (std::size_t k = 0; k < data.motions.size(); ++k) {
    blocks.push_back(static_cast<int>(data.stills.size() + k));
  }
  std::vector<GyroParameters> out;
  for (const Eigen::VectorXd& x : LeaveOneBlockOut(problem, state, blocks, solution)) {
    out.push_back(UnpackGyro(x, data.model));
  }
  return out;
}

}  // namespace accelcal::internal
