#pragma once
// One reusable nonlinear least-squares driver: Gauss-Newton / Levenberg-Marquardt on
//     F(x, y_1..y_m) = Σ_k ‖r_k(x, y_k)‖²
// with global parameters x and optional per-item blocks y_k (a position's direction, a pose),
// each residual block r_k depending on x and on its own y_k only. The y_k are eliminated by the
// Schur complement, so a step costs O(m) plus one dense solve in x. Parameters may live on a
// manifold: the problem's Plus maps a tangent step to the new value (x ⊞ δ).
//
// The step solves the damped normal equations, J the Jacobian in the tangent coordinates,
//     (JᵀJ + λ diag(JᵀJ)) δ = −Jᵀ r,
// with x's block reduced to S_λ = A_λ − Σ_k B_k D_kλ⁻¹ B_kᵀ (A = Σ J_xᵀJ_x, B_k = J_xᵀJ_y,
// D_k = J_yᵀJ_y), Jacobi-scaled by S_λ's diagonal and solved by its eigen-decomposition (whose
// extreme eigenvalues give the reciprocal condition), then δy_k = −D_kλ⁻¹(J_yᵀr_k + B_kᵀδx).
// Damping (Marquardt's, relative to the diagonal) follows Nielsen's rule; λ = 0 gives plain
// Gauss-Newton steps as long as they reduce F.
#include <string>
#include <vector>

#include <Eigen/Core>

#include "accelcal/calibration_types.hpp"

namespace accelcal::internal {

/// The problem: sizes, residual blocks with their Jacobians, and the update of the parameters.
/// Tangent sizes may differ from the stored sizes (a unit vector stored in 3, moved in 2).
class LeastSquaresProblem {
 public:
  virtual ~LeastSquaresProblem() = default;
  /// Tangent dimension of the global parameters x.
  virtual int GlobalSize() const = 0;
  /// Number of residual blocks (items).
  virtual int NumBlocks() const = 0;
  /// Tangent dimension of block k's own parameters y_k (0: the block depends on x only).
  virtual int LocalSize(int /*block*/) const { return 0; }
  /// r_k(x, y_k), and when the pointers are given its Jacobians with respect to the tangent
  /// coordinates of x (rows × GlobalSize) and y_k (rows × LocalSize). False when the residual
  /// cannot be evaluated there (the step is then rejected).
  virtual bool Evaluate(int block, const Eigen::VectorXd& x, const Eigen::VectorXd& y,
                        Eigen::VectorXd* residual, Eigen::MatrixXd* J_x,
                        Eigen::MatrixXd* J_y) const = 0;
  /// x ⊞ δ (default x + δ).
  virtual Eigen::VectorXd PlusGlobal(const Eigen::VectorXd& x, const Eigen::VectorXd& delta) const {
    return x + delta;
  }
  /// y_k ⊞ δ (default y_k + δ).
  virtual Eigen::VectorXd PlusLocal(int /*block*/, const Eigen::VectorXd& y,
                                    const Eigen::VectorXd& delta) const {
    return y + delta;
  }
};

/// The parameters, updated in place by the solve.
struct LeastSquaresState {
  Eigen::VectorXd x;
  std::vector<Eigen::VectorXd> y;  ///< one per block (empty vectors for blocks without)
};

struct LeastSquaresOptions {
  /// Cap on accepted steps (kMaxIterations).
  int max_iterations = 50;
  /// kParameterTolerance: the next step would change no residual by more than this,
  /// max_i |(J δ)_i| ≤ step_tolerance [residual units], with λ ≤ 1e-6 (a nearly Gauss-Newton
  /// step; a small damped step only retries with less damping): the point is the solution, and
  /// that step is not taken. 0 disables.
  double step_tolerance = 0;
  /// kFunctionTolerance: an accepted step with |F_before − F_after| ≤ function_tolerance ·
  /// F_before. 0 disables.
  double function_tolerance = 0;
  /// kZeroResidual: F ≤ zero_residual_cost (the residuals are round-off). Negative disables.
  double zero_residual_cost = -1;
  /// λ at the start, relative to the diagonal of the normal matrix; 0 starts with Gauss-Newton.
  double initial_damping = 0;
  /// The Jacobi-scaled reduced normal matrix is singular when its eigenvalues' ratio
  /// min/max is not above this (the parameters are not determined): the solve stops.
  double min_reciprocal_condition = 1e-12;
  /// σ̂² S⁻¹ at the solution (the global parameters' marginal covariance).
  bool compute_covariance = true;
  /// Threads the residual blocks are evaluated on (0: one per hardware thread). Each block is
  /// evaluated whole by one thread and the sums are taken in block order, so the result is the
  /// same bits for any count; the problem's Evaluate must be safe to call concurrently.
  int threads = 1;
  /// A trial point is evaluated with its Jacobians at once (one evaluation instead of two when
  /// the step is taken, one wasted Jacobian when it is not): for expensive blocks whose steps
  /// are mostly taken. The iterates are the same either way.
  bool linearize_trials = false;
  /// The blocks' residuals and Jacobians at the solution are kept in the summary (for a problem
  /// without per-item parameters), so that LeaveOneBlockOut and BlockLeverages evaluate nothing
  /// again.
  bool keep_blocks = false;
};

struct LeastSquaresSummary {
  TerminationType termination = TerminationType::kMaxIterations;
  std::string termination_message;  ///< the criterion met, as a formula with its numbers
  /// The reduced normal matrix was singular (termination kNoProgress); its reciprocal condition
  /// is in reciprocal_condition.
  bool rank_deficient = false;
  int iterations = 0;      ///< accepted steps
  double step_change = 0;  ///< max |J δ| of the last step computed [residual units]
  int evaluations = 0;     ///< evaluations of F at trial points
  double initial_cost = 0, final_cost = 0;  ///< F = Σ‖r_k‖²
  std::vector<double> cost_history;         ///< F at the start and after each accepted step
  int residuals = 0;                        ///< rows of r
  int parameters = 0;                       ///< tangent dimension of x and all y_k
  int degrees_of_freedom = 0;               ///< residuals − parameters
  /// Of the Jacobi-scaled S at the last linearisation (λ = 0 when converged).
  double reciprocal_condition = 0;
  double sigma2 = 0;            ///< σ̂² = F / degrees_of_freedom (0 without any)
  Eigen::MatrixXd covariance;   ///< σ̂² S⁻¹ for x (GlobalSize²), when computed
  Eigen::MatrixXd information;  ///< S = JᵀJ reduced to x, at the solution (λ = 0)
  /// S⁻¹ (with the covariance or the kept blocks; empty when S is singular).
  Eigen::MatrixXd information_inverse;
  /// With LeastSquaresOptions::keep_blocks: each block's r_k and ∂r_k/∂x at the solution.
  std::vector<Eigen::VectorXd> block_residuals;
  std::vector<Eigen::MatrixXd> block_jacobians;
  bool converged() const {
    return termination != TerminationType::kMaxIterations &&
           termination != TerminationType::kNoProgress;
  }
};

/// Minimises F from `state` (updated in place to the last accepted point) and returns how.
LeastSquaresSummary SolveLeastSquares(const LeastSquaresProblem& problem,
                                      const LeastSquaresOptions& options, LeastSquaresState* state);

/// Leave-one-block-out to first order, for a problem without per-item parameters at a converged
/// `state` (its gradient Σ J_bᵀ r_b zero): for each of `blocks`, x ⊞ δ_k with δ_k = S_k⁻¹ J_kᵀ r_k,
/// S_k = S − J_kᵀ J_k, one Gauss-Newton step of the problem without block k (S⁻¹ by Woodbury's
/// identity from one factorisation of S = Σ J_bᵀ J_b). Its error is of second order in the step:
/// small when one block moves the fit little. A block the fit cannot do without (S_k singular:
/// its leverage is 1) gets x filled with NaN, its held-out fit not determined. Throws
/// std::invalid_argument when the problem has per-item parameters, a block cannot be evaluated,
/// or S is singular.
/// `solution`, when given, is the summary of the solve that converged at `state`: its
/// information S, and its blocks when kept (LeastSquaresOptions::keep_blocks), are taken instead
/// of being evaluated again.
std::vector<Eigen::VectorXd> LeaveOneBlockOut(const LeastSquaresProblem& problem,
                                              const LeastSquaresState& state,
                                              const std::vector<int>& blocks,
                                              const LeastSquaresSummary* solution = nullptr);

/// Each block's leverage h_k = tr(J_k S⁻¹ J_kᵀ) at `state`, for a problem without per-item
/// parameters (S the information matrix, as LeaveOneBlockOut's): the share of the parameters
/// that block k's residuals pay for. Σ h_k = the number of parameters, and a group G of blocks
/// has n_G − Σ_G h_k degrees of freedom (its redundancy): E[χ²_G] = n_G − Σ_G h_k under the
/// model. Throws std::invalid_argument as LeaveOneBlockOut. `solution`: the summary of the solve
/// that converged at `state`, as LeaveOneBlockOut's (its information is required).
std::vector<double> BlockLeverages(const LeastSquaresProblem& problem,
                                   const LeastSquaresState& state,
                                   const LeastSquaresSummary& solution);

}  // namespace accelcal::internal
