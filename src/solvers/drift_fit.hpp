#pragma once
// The orientation-free problem with a bias that drifts with time (bias_drift.hpp): maximum
// likelihood over θ, D and the directions at once,
//     min J = Σ_k ‖p_k − K g c_k − b − D φ(t_k) − k2 ∘ (g c_k)²‖²,  |c_k| = 1,
// by the least-squares driver (least_squares.hpp), x = (θ, D) and each direction a per-position
// block moved in its tangent plane. The directions profile out of the information as in
// calibrate.hpp: position k adds u_k u_kᵀ, u_k = −J_xᵀ n_k with n_k the unit normal of the fitted
// surface at g c_k (the direction of p_k's residual that no direction change can take up).

#include <vector>

#include <Eigen/Core>

#include "accelcal/bias_drift.hpp"
#include "accelcal/calibration_types.hpp"
#include "solvers/least_squares.hpp"
#include "solvers/solver_common.hpp"

namespace accelcal::internal {

/// The problem for the least-squares driver: x = (θ, D), each block one position with its
/// direction c_k (stored 3, moved in 2).
class DriftProblem : public LeastSquaresProblem {
 public:
  DriftProblem(const Problem& problem, const BiasTimeBasis& basis,
               const std::vector<double>& times_s)
      : problem_(problem),
        slots_(ParameterSlots(problem.model)),
        P_(static_cast<int>(slots_.size())),
        J_(basis.size()) {
    phi_.reserve(times_s.size());
    for (double t : times_s) phi_.push_back(basis.Evaluate(t));
  }
  int GlobalSize() const override { return P_ + 3 * J_; }
  int NumBlocks() const override { return problem_.positions(); }
  int LocalSize(int /*block*/) const override { return 2; }
  Eigen::VectorXd PlusLocal(int /*block*/, const Eigen::VectorXd& y,
                            const Eigen::VectorXd& delta) const override {
    const Vec3 c = y;
    return Retract(c, TangentBasis(c), Eigen::Vector2d(delta));
  }
  bool Evaluate(int block, const Eigen::VectorXd& x, const Eigen::VectorXd& y,
                Eigen::VectorXd* residual, Eigen::MatrixXd* J_x,
                Eigen::MatrixXd* J_y) const override {
    const auto k = static_cast<std::size_t>(block);
    const ModelParameters params = Params(x);
    const Vec3 c = y;
    const Vec3 f = problem_.gravity * c;
    const Eigen::VectorXd& phi = phi_[k];
    Mat33 J_f;
    Vec3 offset = Vec3::Zero();
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < J_; ++j) offset(i) += x(P_ + i * J_ + j) * phi(j);
    }
    *residual = problem_.readings[k] - PredictRaw(params, f, &J_f) - offset;
    if (J_x != nullptr) {
      J_x->setZero(3, GlobalSize());
      for (int s = 0; s < P_; ++s) {
        const ParameterSlot& slot = slots_[static_cast<std::size_t>(s)];
        const double d = slot.group == ParameterGroup::kK      ? f(slot.col)
                         : slot.group == ParameterGroup::kBias ? 1.0
                                                               : f(slot.row) * f(slot.row);
        (*J_x)(slot.row, s) = -d;
      }
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < J_; ++j) (*J_x)(i, P_ + i * J_ + j) = -phi(j);
      }
    }
    if (J_y != nullptr) *J_y = -(J_f * problem_.gravity) * TangentBasis(c);
    return residual->allFinite();
  }

  ModelParameters Params(const Eigen::VectorXd& x) const {
    return Unpack(Eigen::VectorXd(x.head(P_)), slots_);
  }
  Eigen::Matrix<double, 3, Eigen::Dynamic> Drift(const Eigen::VectorXd& x) const {
    Eigen::Matrix<double, 3, Eigen::Dynamic> D(3, J_);
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < J_; ++j) D(i, j) = x(P_ + i * J_ + j);
    }
    return D;
  }

 private:
  const Problem& problem_;
  const std::vector<ParameterSlot>& slots_;
  int P_, J_;
  std::vector<Eigen::VectorXd> phi_;
};

/// Position k's row of the reduced information at (x, c): u = J_xᵀ n, n the unit normal of the
/// fitted surface at g c (⟂ the columns of J_y), written to `normal`.
Eigen::VectorXd DriftInformationRow(const DriftProblem& problem, const Eigen::VectorXd& x, int k,
                                    const Vec3& c, Vec3* normal);

struct DriftFit {
  ModelParameters params;
  Eigen::Matrix<double, 3, Eigen::Dynamic> D;
  std::vector<Vec3> dirs;
  LeastSquaresSummary summary;
  /// At the solution: the rows u_k (m × (P + 3J), x's order: the model's flat parameters, then D
  /// in bias_drift.hpp's flat order), the unit normals n_k, and S⁻¹ (empty when S is singular).
  Eigen::MatrixXd U;
  std::vector<Vec3> normals;
  Eigen::MatrixXd S_inverse;
};

/// p_k − μ(θ, g c_k) − D φ(t_k) for each position.
std::vector<Vec3> DriftResiduals(const Problem& problem, const BiasTimeBasis& basis,
                                 const std::vector<double>& times_s, const ModelParameters& params,
                                 const Eigen::Matrix<double, 3, Eigen::Dynamic>& D,
                                 const std::vector<Vec3>& dirs);

/// Solves from the constant-bias fit (`start`, `dirs`) with D = 0, by the joint method's limits
/// (CalibrationOptions::Joint: iterations, damping; steps stop at parameter_tolerance times the
/// signal amplitude in raw units).
DriftFit SolveDrift(const Problem& problem, const BiasTimeBasis& basis,
                    const std::vector<double>& times_s, const ModelParameters& start,
                    const std::vector<Vec3>& dirs, const CalibrationOptions::Joint& joint);

}  // namespace accelcal::internal
