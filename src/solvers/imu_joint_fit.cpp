// The accelerometer and the gyroscope in one problem (imu_joint_fit.hpp).
#include "solvers/imu_joint_fit.hpp"

#include <stdexcept>

#include "solvers/solver_common.hpp"

namespace accelcal::internal {
namespace {

// x = (θ_a, θ_g, c_1 … c_m) stored, (θ_a, θ_g, δ_1 … δ_m) in the tangent.
class JointProblem : public LeastSquaresProblem {
 public:
  explicit JointProblem(const ImuJointData& data)
      : data_(data),
        slots_(ParameterSlots(data.accel_model, data.frame)),
        pa_(static_cast<int>(slots_.size())),
        pg_(NumGyroParameters(data.gyro.model)),
        m_(static_cast<int>(data.accel_means.size())),
        s_(static_cast<int>(data.gyro.stills.size())) {}

  int GlobalSize() const override { return pa_ + pg_ + 2 * m_; }
  int NumBlocks() const override { return m_ + s_ + static_cast<int>(data_.gyro.motions.size()); }
  Eigen::VectorXd PlusGlobal(const Eigen::VectorXd& x,
                             const Eigen::VectorXd& delta) const override {
    Eigen::VectorXd out = x;
    out.head(pa_ + pg_) += delta.head(pa_ + pg_);
    for (int k = 0; k < m_; ++k) {
      const Vec3 c = Direction(x, k);
      out.segment<3>(pa_ + pg_ + 3 * k) =
          Retract(c, TangentBasis(c), delta.segment<2>(pa_ + pg_ + 2 * k));
    }
    return out;
  }
  bool Evaluate(int block, const Eigen::VectorXd& x, const Eigen::VectorXd& /*y*/,
                Eigen::VectorXd* residual, Eigen::MatrixXd* J_x,
                Eigen::MatrixXd* /*J_y*/) const override {
    const int n = GlobalSize();
    if (block < m_) return AccelBlock(block, x, residual, J_x, n);
    if (block < m_ + s_) return StillBlock(block - m_, x, residual, J_x, n);
    const auto k = static_cast<std::size_t>(block - m_ - s_);
    const GyroMotion& mo = data_.gyro.motions[k];
    if (!data_.gyro.used(k)) {
      residual->resize(0);
      if (J_x != nullptr) J_x->resize(0, n);
      return true;
    }
    const GyroParameters params = UnpackGyro(x.segment(pa_, pg_), data_.gyro.model);
    Eigen::MatrixXd J_theta;
    Eigen::Matrix2d J_from, J_to;
    const bool jac = J_x != nullptr;
    try {
      *residual = MotionResidual(data_.gyro, mo, data_.gyro.weights[k], params,
                                 Direction(x, static_cast<int>(mo.from)),
                                 Direction(x, static_cast<int>(mo.to)), jac ? &J_theta : nullptr,
                                 jac ? &J_from : nullptr, jac ? &J_to : nullptr) /
                  data_.gyro.motion_scale;
    } catch (const std::invalid_argument&) {
      return false;  // a singular K_g
    }
    if (jac) {
      J_x->setZero(2, n);
      J_x->middleCols(pa_, pg_) = J_theta / data_.gyro.motion_scale;
      J_x->middleCols<2>(Tangent(static_cast<int>(mo.from))) += J_from / data_.gyro.motion_scale;
      J_x->middleCols<2>(Tangent(static_cast<int>(mo.to))) += J_to / data_.gyro.motion_scale;
    }
    return residual->allFinite() && (!jac || J_x->allFinite());
  }

  Vec3 Direction(const Eigen::VectorXd& x, int k) const { return x.segment<3>(pa_ + pg_ + 3 * k); }
  int Tangent(int k) const { return pa_ + pg_ + 2 * k; }

 private:
  bool AccelBlock(int k, const Eigen::VectorXd& x, Eigen::VectorXd* residual, Eigen::MatrixXd* J_x,
                  int n) const {
    const auto kk = static_cast<std::size_t>(k);
    if (!data_.accel_used[kk]) {
      residual->resize(0);
      if (J_x != nullptr) J_x->resize(0, n);
      return true;
    }
    const ModelParameters params = Unpack(Eigen::VectorXd(x.head(pa_)), slots_);
    const Vec3 c = Direction(x, k);
    const Vec3 f = data_.gravity * c;
    Mat33 J_f;
    const Vec3 w = data_.accel_sigmas[kk].cwiseInverse();
    *residual = w.cwiseProduct(data_.accel_means[kk] - PredictRaw(params, f, &J_f));
    if (J_x != nullptr) {
      J_x->setZero(3, n);
      for (int s = 0; s < pa_; ++s) {
        const ParameterSlot& slot = slots_[static_cast<std::size_t>(s)];
        (*J_x)(slot.row, s) = -w(slot.row) * SlotRegressor(slot, f);
      }
      J_x->middleCols<2>(Tangent(k)) = -(w.asDiagonal() * J_f) * data_.gravity * TangentBasis(c);
    }
    return residual->allFinite();
  }

  // Still k, at its position's direction.
  bool StillBlock(int still, const Eigen::VectorXd& x, Eigen::VectorXd* residual,
                  Eigen::MatrixXd* J_x, int n) const {
    const GyroStill& s = data_.gyro.stills[static_cast<std::size_t>(still)];
    const int k = static_cast<int>(s.position);
    const GyroParameters params = UnpackGyro(x.segment(pa_, pg_), data_.gyro.model);
    const Vec3 c = Direction(x, k);
    const Vec3 f = data_.gravity * c;
    const Vec3 w = (data_.gyro.still_scale * s.sigma_mean_raw).cwiseInverse();
    const double e = data_.gyro.earth_rate_vertical;  // the Earth rate about c: Ω_E sin φ
    *residual = w.cwiseProduct(s.mean_raw - StillRate(data_.gyro, params, c, data_.gravity));
    if (J_x != nullptr) {
      J_x->setZero(3, n);
      J_x->middleCols(pa_, pg_) =
          -(w.asDiagonal() * GyroJacobianWrtParameters(e * c, f, data_.gyro.model));
      J_x->middleCols<2>(Tangent(k)) =
          -(w.asDiagonal() * (data_.gravity * params.G + e * params.K)) * TangentBasis(c);
    }
    return residual->allFinite();
  }

  const ImuJointData& data_;
  const std::vector<ParameterSlot>& slots_;
  int pa_, pg_, m_;
  int s_;  // the stills' blocks follow the accelerometer's, then the motions' (one each)
};

Eigen::VectorXd Start(const ImuJointData& data, const ModelParameters& accel,
                      const GyroParameters& gyro) {
  const Eigen::VectorXd a = Pack(accel, ParameterSlots(data.accel_model, data.frame));
  const Eigen::VectorXd g = Pack(gyro, data.gyro.model);
  const auto m = static_cast<Eigen::Index>(data.gyro.directions.size());
  Eigen::VectorXd x(a.size() + g.size() + 3 * m);
  x << a, g, Eigen::VectorXd::Zero(3 * m);
  for (Eigen::Index k = 0; k < m; ++k) {
    x.segment<3>(a.size() + g.size() + 3 * k) =
        data.gyro.directions[static_cast<std::size_t>(k)].normalized();
  }
  return x;
}

ImuJointFit FromState(const ImuJointData& data, const JointProblem& problem,
                      const Eigen::VectorXd& x) {
  ImuJointFit fit;
  fit.accel_parameters = static_cast<int>(ParameterSlots(data.accel_model, data.frame).size());
  fit.gyro_parameters = NumGyroParameters(data.gyro.model);
  fit.accel = Unpack(Eigen::VectorXd(x.head(fit.accel_parameters)),
                     ParameterSlots(data.accel_model, data.frame));
  fit.gyro = UnpackGyro(x.segment(fit.accel_parameters, fit.gyro_parameters), data.gyro.model);
  for (std::size_t k = 0; k < data.accel_means.size(); ++k) {
    fit.directions.push_back(problem.Direction(x, static_cast<int>(k)));
  }
  return fit;
}

}  // namespace

ImuJointFit FitImuJoint(const ImuJointData& data, const ModelParameters& accel_start,
                        const GyroParameters& gyro_start, const LeastSquaresOptions& options) {
  if (data.frame == Frame::kPlatform) {
    throw std::invalid_argument("FitImuJoint: the platform frame has known directions");
  }
  if (data.gyro.weights.size() != data.gyro.motions.size()) {
    throw std::invalid_argument("FitImuJoint: a weight for each motion is needed");
  }
  const JointProblem problem(data);
  LeastSquaresState state;
  state.x = Start(data, accel_start, gyro_start);
  state.y.assign(static_cast<std::size_t>(problem.NumBlocks()), Eigen::VectorXd());
  LeastSquaresSummary summary = SolveLeastSquares(problem, options, &state);
  ImuJointFit fit = FromState(data, problem, state.x);
  fit.summary = std::move(summary);
  return fit;
}

namespace {

// The driver's state at a fit: its parameters and directions.
LeastSquaresState StateAt(const ImuJointData& data, const JointProblem& problem,
                          const ImuJointFit& fit) {
  LeastSquaresState state;
  state.x = Start(data, fit.accel, fit.gyro);
  for (std::size_t k = 0; k < fit.directions.size(); ++k) {
    state.x.segment<3>(fit.accel_parameters + fit.gyro_parameters +
                       3 * static_cast<Eigen::Index>(k)) = fit.directions[k];
  }
  state.y.assign(static_cast<std::size_t>(problem.NumBlocks()), Eigen::VectorXd());
  return state;
}

std::vector<ImuJointFit> HeldOutFits(const ImuJointData& data, const ImuJointFit& fit,
                                     bool motions) {
  const JointProblem problem(data);
  const LeastSquaresState state = StateAt(data, problem, fit);
  std::vector<int> blocks;
  const int m = static_cast<int>(data.accel_means.size());
  const int stills = static_cast<int>(data.gyro.stills.size());
  if (motions) {
    for (std::size_t k = 0; k < data.gyro.motions.size(); ++k) {
      blocks.push_back(m + stills + static_cast<int>(k));
    }
  } else {
    for (int k = 0; k < m; ++k) blocks.push_back(k);
  }
  std::vector<ImuJointFit> out;
  const LeastSquaresSummary* solution = fit.summary.information.rows() > 0 ? &fit.summary : nullptr;
  for (const Eigen::VectorXd& x : LeaveOneBlockOut(problem, state, blocks, solution)) {
    out.push_back(FromState(data, problem, x));
  }
  return out;
}

}  // namespace

std::vector<ImuJointFit> HeldOutMotionFits(const ImuJointData& data, const ImuJointFit& fit) {
  return HeldOutFits(data, fit, true);
}

std::vector<ImuJointFit> HeldOutPositionFits(const ImuJointData& data, const ImuJointFit& fit) {
  return HeldOutFits(data, fit, false);
}

GroupCosts JointGroupRedundancy(const ImuJointData& data, const ImuJointFit& fit) {
  const JointProblem problem(data);
  const LeastSquaresState state = StateAt(data, problem, fit);
  const std::vector<double> h = BlockLeverages(problem, state, fit.summary);
  const std::size_t m = data.accel_means.size();
  GroupCosts r;
  const std::size_t stills = data.gyro.stills.size();
  for (std::size_t k = 0; k < m; ++k) {
    if (data.accel_used[k]) r.accel += 3 - h[k];
  }
  for (std::size_t k = 0; k < stills; ++k) r.stills += 3 - h[m + k];
  for (std::size_t k = 0; k < data.gyro.motions.size(); ++k) {
    if (data.gyro.used(k)) r.turns += 2 - h[m + stills + k];
  }
  return r;
}

GroupCosts JointGroupCosts(const ImuJointData& data, const ImuJointFit& fit) {
  GroupCosts costs;
  for (std::size_t k = 0; k < data.accel_means.size(); ++k) {
    if (data.accel_used[k]) {
      costs.accel +=
          data.accel_sigmas[k]
              .cwiseInverse()
              .cwiseProduct(data.accel_means[k] -
                            PredictRaw(fit.accel, Vec3(data.gravity * fit.directions[k])))
              .squaredNorm();
    }
  }
  for (const GyroStill& s : data.gyro.stills) {
    costs.stills +=
        (data.gyro.still_scale * s.sigma_mean_raw)
            .cwiseInverse()
            .cwiseProduct(s.mean_raw -
                          StillRate(data.gyro, fit.gyro, fit.directions[s.position], data.gravity))
            .squaredNorm();
  }
  costs.turns = fit.summary.final_cost - costs.accel - costs.stills;
  return costs;
}

}  // namespace accelcal::internal
