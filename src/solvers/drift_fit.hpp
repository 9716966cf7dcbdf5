#pragma once
// The orientation-free problem with a bias that drifts with time (bias_drift.hpp): maximum
// likelihood over θ, D and the directions at once,
//     min J = Σ_k ‖p_k − K g c_k − b − D φ(t_k) − k2 ∘ (g c_k)²‖²,  |c_k| = 1,
// by the least-squares driver (least_squares.hpp), x = (θ, D) and each direction a per-position
// block moved in its tangent plane. The directions profile out of the information as in
// calibrate.hpp: position k adds u_k u_kᵀ, u_k = −J_xᵀ n_k with n_k the unit normal of the fitted
// surface at g c_k (the direction of p_k's residual that no direction change can take up).

#include <optional>
#include <vector>

#include <Eigen/Core>

#include "accelcal/bias_drift.hpp"
#include "accelcal/calibration_types.hpp"
#include "solvers/information_row.hpp"
#include "solvers/least_squares.hpp"
#include "solvers/solver_common.hpp"

namespace accelcal::internal {

/// A random-walk prior on a spline bias (bias_drift.hpp): the knot biases' increments
/// β_{j+1} − β_j of axis i are N(0, q_i² Δτ_j), Δτ_j = τ_{j+1} − τ_j. With it every residual is
/// whitened: position k's axis i is divided by √(s_ki² + q_i² v_k), s_ki the 1σ of its reading
/// (CalibrationOptions::reading_sigmas) and v_k = (t_k − τ_j)(τ_{j+1} − t_k)/Δτ_j the variance of a
/// random walk about the straight line between the knots around t_k (a Brownian bridge), and the
/// prior enters as (β_{j+1} − β_j) / (q_i √Δτ_j). The sum of squares is then the negative
/// log-posterior, and the inverse of its Gauss-Newton Hessian the posterior covariance.
struct RandomWalkPrior {
  Vec3 q_raw_per_sqrt_s = Vec3::Zero();
  std::vector<Vec3> reading_sigmas;  ///< one per position [raw]
};

/// The problem for the least-squares driver: x = (θ, D), each of the first m blocks one position
/// with its direction c_k (stored 3, moved in 2), and with a prior one more block of x alone.
class DriftProblem : public LeastSquaresProblem {
 public:
  DriftProblem(const Problem& problem, const BiasTimeBasis& basis,
               const std::vector<double>& times_s,
               const std::optional<RandomWalkPrior>& prior = std::nullopt);
  int GlobalSize() const override { return P_ + 3 * J_; }
  int NumBlocks() const override { return problem_.positions() + (prior_rows_.rows() > 0); }
  int LocalSize(int block) const override { return block < problem_.positions() ? 2 : 0; }
  Eigen::VectorXd PlusLocal(int block, const Eigen::VectorXd& y,
                            const Eigen::VectorXd& delta) const override;
  bool Evaluate(int block, const Eigen::VectorXd& x, const Eigen::VectorXd& y,
                Eigen::VectorXd* residual, Eigen::MatrixXd* J_x,
                Eigen::MatrixXd* J_y) const override;

  /// Position k's whitening, 1/√(s² + q² v) per axis with a prior, else ones.
  Vec3 Weight(int k) const {
    return weights_.empty() ? Vec3::Ones() : weights_[static_cast<std::size_t>(k)];
  }
  ModelParameters Params(const Eigen::VectorXd& x) const;
  Eigen::Matrix<double, 3, Eigen::Dynamic> Drift(const Eigen::VectorXd& x) const;

 private:
  const Problem& problem_;
  const std::vector<ParameterSlot>& slots_;
  int P_, J_;
  std::vector<Eigen::VectorXd> phi_;
  std::vector<Vec3> weights_;   ///< with the prior: each position's whitening, 1/√(s² + q² v)
  Eigen::MatrixXd prior_rows_;  ///< the prior's residual = prior_rows_ · D's entries
};

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
  /// Each position's p_k − μ(θ, g c_k) − D φ(t_k) [raw].
  std::vector<Vec3> residuals;
};

/// Solves from the constant-bias fit (`start`, `dirs`) with D = 0, by the joint method's limits
/// (CalibrationOptions::Joint: iterations, damping; steps stop at parameter_tolerance times the
/// signal amplitude in raw units; with the prior, whitened: at parameter_tolerance). With a
/// random-walk prior (a spline basis only: std::invalid_argument otherwise) the problem is
/// RandomWalkPrior's: DriftFit::U holds the readings' whitened rows and normals, S includes the
/// prior, and the summary's cost is the whitened sum with the prior's part.
DriftFit SolveDrift(const Problem& problem, const BiasTimeBasis& basis,
                    const std::vector<double>& times_s, const ModelParameters& start,
                    const std::vector<Vec3>& dirs, const CalibrationOptions::Joint& joint,
                    const std::optional<RandomWalkPrior>& prior = std::nullopt);

}  // namespace accelcal::internal
