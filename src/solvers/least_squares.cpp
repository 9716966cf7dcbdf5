// The reusable Gauss-Newton / Levenberg-Marquardt driver (least_squares.hpp).
#include "solvers/least_squares.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include "core/parallel.hpp"
#include "core/text_format.hpp"

namespace accelcal::internal {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// The damping at or below which a step is close enough to Gauss-Newton to judge convergence.
constexpr double kMaxConvergedDamping = 1e-6;
// The damping a rejected undamped (λ = 0) step continues with.
constexpr double kFirstDamping = 1e-8;
constexpr double kMaxDamping = 1e16;

// The residuals and Jacobians at a point, and the normal equations' blocks.
struct Linearization {
  std::vector<VectorXd> r;
  std::vector<MatrixXd> J_x, J_y;
  MatrixXd A;   // Σ J_xᵀ J_x
  VectorXd gx;  // Σ J_xᵀ r
  std::vector<MatrixXd> B, D;
  std::vector<VectorXd> gy;
  double cost = 0;
};

// Every block's residual (and Jacobians) at `state`, on `threads` threads, each block into its
// own slot: what is summed from them afterwards, in block order, is the same for any count.
bool EvaluateBlocks(const LeastSquaresProblem& problem, const LeastSquaresState& state,
                    bool jacobians, int threads, std::vector<VectorXd>* r,
                    std::vector<MatrixXd>* J_x, std::vector<MatrixXd>* J_y) {
  const int m = problem.NumBlocks();
  r->resize(static_cast<std::size_t>(m));
  if (jacobians) {
    J_x->resize(static_cast<std::size_t>(m));
    J_y->resize(static_cast<std::size_t>(m));
  }
  std::vector<char> ok(static_cast<std::size_t>(m), 0);
  ParallelFor(m, ThreadCount(threads, m), [&](int k) {
    const auto b = static_cast<std::size_t>(k);
    const bool local = jacobians && problem.LocalSize(k) > 0;
    ok[b] = problem.Evaluate(k, state.x, state.y[b], &(*r)[b], jacobians ? &(*J_x)[b] : nullptr,
                             local ? &(*J_y)[b] : nullptr);
  });
  return std::all_of(ok.begin(), ok.end(), [](char v) { return v != 0; });
}

// A block's Jacobian on its nonzero columns only (a turn touches the gyroscope's parameters and
// two directions of many): J = J_c E_cᵀ.
struct SparseColumns {
  std::vector<Eigen::Index> cols;
  MatrixXd J_c;
  explicit SparseColumns(const MatrixXd& J) {
    for (Eigen::Index c = 0; c < J.cols(); ++c) {
      if (!J.col(c).isZero(0)) cols.push_back(c);
    }
    J_c.resize(J.rows(), static_cast<Eigen::Index>(cols.size()));
    for (std::size_t c = 0; c < cols.size(); ++c) {
      J_c.col(static_cast<Eigen::Index>(c)) = J.col(cols[c]);
    }
  }
};

bool Linearize(const LeastSquaresProblem& problem, const LeastSquaresState& state,
               Linearization* lin, int threads) {
  const int n = problem.GlobalSize(), m = problem.NumBlocks();
  lin->B.resize(m);
  lin->D.resize(m);
  lin->gy.resize(m);
  lin->A = MatrixXd::Zero(n, n);
  lin->gx = VectorXd::Zero(n);
  lin->cost = 0;
  if (!EvaluateBlocks(problem, state, true, threads, &lin->r, &lin->J_x, &lin->J_y)) return false;
  for (int k = 0; k < m; ++k) {
    const int q = problem.LocalSize(k);
    if (!lin->r[k].allFinite() || !lin->J_x[k].allFinite()) return false;
    lin->cost += lin->r[k].squaredNorm();
    const MatrixXd& J = lin->J_x[k];
    // A block that touches few of the global parameters adds to A through its nonzero columns
    // only.
    const SparseColumns sparse(J);
    const std::vector<Eigen::Index>& cols = sparse.cols;
    if (J.rows() > 0 && 4 * cols.size() < static_cast<std::size_t>(n)) {
      const auto nc = static_cast<Eigen::Index>(cols.size());
      const MatrixXd Ac = sparse.J_c.transpose() * sparse.J_c;
      const VectorXd gc = sparse.J_c.transpose() * lin->r[k];
      for (Eigen::Index a = 0; a < nc; ++a) {
        const Eigen::Index i = cols[static_cast<std::size_t>(a)];
        lin->gx(i) += gc(a);
        for (Eigen::Index b = 0; b < nc; ++b)
          lin->A(i, cols[static_cast<std::size_t>(b)]) += Ac(a, b);
      }
    } else if (m == 1) {
      lin->A.noalias() = J.transpose() * J;
      lin->gx.noalias() += J.transpose() * lin->r[k];
    } else {
      lin->A.noalias() += J.transpose() * J;
      lin->gx.noalias() += J.transpose() * lin->r[k];
    }
    if (q > 0) {
      if (!lin->J_y[k].allFinite()) return false;
      lin->B[k].noalias() = lin->J_x[k].transpose() * lin->J_y[k];
      lin->D[k].noalias() = lin->J_y[k].transpose() * lin->J_y[k];
      lin->gy[k].noalias() = lin->J_y[k].transpose() * lin->r[k];
    } else {
      lin->J_y[k].resize(lin->r[k].size(), 0);
    }
  }
  return std::isfinite(lin->cost);
}

double Cost(const LeastSquaresProblem& problem, const LeastSquaresState& state, int threads) {
  std::vector<VectorXd> r;
  if (!EvaluateBlocks(problem, state, false, threads, &r, nullptr, nullptr)) {
    return std::numeric_limits<double>::infinity();
  }
  double cost = 0;
  for (const VectorXd& rk : r) cost += rk.squaredNorm();
  return std::isfinite(cost) ? cost : std::numeric_limits<double>::infinity();
}

// The reduced system at a damping, factorised.
struct ReducedSolve {
  bool ok = false;
  std::string failure;          // why not
  int weakest = -1;             // global parameter most in the null direction
  double rcond = 0;             // min/max eigenvalue of N, or (a step's check) a lower bound on it
  VectorXd scale;               // Jacobi scaling 1/√S_jj
  Eigen::LLT<MatrixXd> llt;     // of N = diag(scale) S diag(scale)
  std::vector<MatrixXd> D_inv;  // (D_kλ)⁻¹
  MatrixXd S;
  // S⁻¹ v
  VectorXd Solve(const VectorXd& v) const {
    return scale.cwiseProduct(llt.solve(scale.cwiseProduct(v)));
  }
  MatrixXd Inverse() const {
    const auto n = scale.size();
    return scale.asDiagonal() * llt.solve(MatrixXd::Identity(n, n)) * scale.asDiagonal();
  }
};

// How Reduce judges the reduced matrix's condition: a step needs only to know that it is above
// the threshold; the solution's summary states it.
enum class Condition { kBoundIsEnough, kExact };

void Reduce(const Linearization& lin, double lambda, double min_rcond, Condition condition,
            ReducedSolve* out) {
  const auto m = static_cast<int>(lin.r.size());
  out->ok = false;
  out->S = lin.A;
  out->S.diagonal() += lambda * lin.A.diagonal();
  out->D_inv.assign(m, MatrixXd());
  for (int k = 0; k < m; ++k) {
    if (lin.J_y[k].cols() == 0) continue;
    MatrixXd D = lin.D[k];
    D.diagonal() += lambda * lin.D[k].diagonal();
    const Eigen::LDLT<MatrixXd> ldlt(D);
    if (ldlt.info() != Eigen::Success || !ldlt.isPositive() ||
        !(ldlt.vectorD().minCoeff() > min_rcond * ldlt.vectorD().maxCoeff())) {
      out->failure = internal::Format("block %d's own parameters are not determined", k);
      return;
    }
    out->D_inv[k] = ldlt.solve(MatrixXd::Identity(D.rows(), D.cols()));
    out->S.noalias() -= lin.B[k] * out->D_inv[k] * lin.B[k].transpose();
  }
  const Eigen::Index n = out->S.rows();
  if (n == 0) {
    out->ok = true;
    out->rcond = 1;
    return;
  }
  const VectorXd diagonal = out->S.diagonal();
  for (Eigen::Index j = 0; j < n; ++j) {
    if (!(diagonal(j) > 0)) {
      out->weakest = static_cast<int>(j);
      out->failure = internal::Format("global parameter %d has no information", out->weakest);
      return;
    }
  }
  out->scale = diagonal.cwiseSqrt().cwiseInverse();
  const MatrixXd N = out->scale.asDiagonal() * out->S * out->scale.asDiagonal();
  // N's reciprocal condition λ_min/λ_max is at least 1 / (‖N‖_∞ tr N⁻¹): λ_max is bounded by
  // any induced norm, and 1/λ_min by the sum of N⁻¹'s eigenvalues, tr N⁻¹ = ‖L⁻¹‖²_F for N = LLᵀ.
  // When that bound clears the threshold, the Cholesky factor is all a step needs (with L⁻¹,
  // about a tenth of the work of the eigen-decomposition it replaces). Otherwise, and for the
  // solution's summary, the eigenvalues; their vectors only to name the weakest parameter.
  out->llt.compute(N);
  const bool factored = out->llt.info() == Eigen::Success;
  if (factored && condition == Condition::kBoundIsEnough) {
    const MatrixXd L_inverse = out->llt.matrixL().solve(MatrixXd::Identity(n, n));
    const double bound = 1.0 / (N.cwiseAbs().rowwise().sum().maxCoeff() * L_inverse.squaredNorm());
    if (bound > min_rcond) {
      out->rcond = bound;
      out->ok = true;
      return;
    }
  }
  const Eigen::SelfAdjointEigenSolver<MatrixXd> values(N, Eigen::EigenvaluesOnly);
  const VectorXd& ev = values.eigenvalues();  // ascending
  out->rcond = ev(0) / ev(n - 1);
  if (!(out->rcond > min_rcond) || !factored) {
    const Eigen::SelfAdjointEigenSolver<MatrixXd> eig(N);
    eig.eigenvectors().col(0).cwiseAbs().maxCoeff(&out->weakest);
    out->failure = internal::Format(
        "the reduced normal matrix is singular: reciprocal condition %.3g <= %.0e (min/max "
        "eigenvalue, Jacobi-scaled), weakest global parameter %d",
        out->rcond, min_rcond, out->weakest);
    return;
  }
  out->ok = true;
}

struct Step {
  VectorXd dx;
  std::vector<VectorXd> dy;
  double predicted_reduction = 0;  // F − Σ ‖r_k + J_k δ‖²
  double max_change = 0;           // max |J δ|
};

Step ComputeStep(const Linearization& lin, const ReducedSolve& reduced) {
  const auto m = static_cast<int>(lin.r.size());
  VectorXd rhs = -lin.gx;
  for (int k = 0; k < m; ++k) {
    if (lin.J_y[k].cols() > 0) rhs.noalias() += lin.B[k] * (reduced.D_inv[k] * lin.gy[k]);
  }
  Step step;
  step.dx = rhs.size() > 0 ? reduced.Solve(rhs) : VectorXd();
  step.dy.resize(m);
  double remaining = 0;
  for (int k = 0; k < m; ++k) {
    VectorXd change = lin.J_x[k] * step.dx;
    if (lin.J_y[k].cols() > 0) {
      step.dy[k] = -reduced.D_inv[k] * (lin.gy[k] + lin.B[k].transpose() * step.dx);
      change.noalias() += lin.J_y[k] * step.dy[k];
    }
    if (change.size() > 0)
      step.max_change = std::max(step.max_change, change.cwiseAbs().maxCoeff());
    remaining += (lin.r[k] + change).squaredNorm();
  }
  step.predicted_reduction = lin.cost - remaining;
  return step;
}

LeastSquaresState Plus(const LeastSquaresProblem& problem, const LeastSquaresState& state,
                       const Step& step) {
  LeastSquaresState out;
  out.x = step.dx.size() > 0 ? problem.PlusGlobal(state.x, step.dx) : state.x;
  out.y.resize(state.y.size());
  for (std::size_t k = 0; k < state.y.size(); ++k) {
    out.y[k] = step.dy[k].size() > 0
                   ? problem.PlusLocal(static_cast<int>(k), state.y[k], step.dy[k])
                   : state.y[k];
  }
  return out;
}

}  // namespace

LeastSquaresSummary SolveLeastSquares(const LeastSquaresProblem& problem,
                                      const LeastSquaresOptions& options,
                                      LeastSquaresState* state) {
  LeastSquaresSummary summary;
  const int m = problem.NumBlocks();
  state->y.resize(m);
  Linearization lin;
  if (!Linearize(problem, *state, &lin, options.threads)) {
    summary.termination = TerminationType::kNoProgress;
    summary.termination_message = "the residuals are not finite at the start";
    return summary;
  }
  summary.parameters = problem.GlobalSize();
  for (int k = 0; k < m; ++k) {
    summary.residuals += static_cast<int>(lin.r[k].size());
    summary.parameters += problem.LocalSize(k);
  }
  summary.degrees_of_freedom = summary.residuals - summary.parameters;
  summary.initial_cost = lin.cost;
  summary.cost_history.push_back(lin.cost);
  summary.termination = TerminationType::kMaxIterations;
  summary.termination_message =
      internal::Format("reached max_iterations = %d", options.max_iterations);

  double lambda = options.initial_damping, nu = 2;
  int reset_at = -1;  // the iteration at which the damping was last reset for a small step
  ReducedSolve reduced;
  std::int64_t passes = 0;  // trial steps, accepted or not: a backstop against cycling
  while (summary.iterations < options.max_iterations) {
    if (++passes > 100 * static_cast<std::int64_t>(options.max_iterations)) {
      summary.termination = TerminationType::kNoProgress;
      summary.termination_message =
          internal::Format("no progress after %lld trial steps (damping cycled)",
                           static_cast<long long>(passes - 1));
      break;
    }
    if (options.zero_residual_cost >= 0 && lin.cost <= options.zero_residual_cost) {
      summary.termination = TerminationType::kZeroResidual;
      summary.termination_message = internal::Format("F = %.3e <= zero-residual level %.3e",
                                                     lin.cost, options.zero_residual_cost);
      break;
    }
    Reduce(lin, lambda, options.min_reciprocal_condition, Condition::kBoundIsEnough, &reduced);
    if (!reduced.ok) {
      summary.termination = TerminationType::kNoProgress;
      summary.rank_deficient = true;
      summary.reciprocal_condition = reduced.rcond;
      summary.termination_message = reduced.failure;
      break;
    }
    const Step step = ComputeStep(lin, reduced);
    summary.step_change = step.max_change;
    const bool small = options.step_tolerance > 0 && step.max_change <= options.step_tolerance;
    if (small && lambda > kMaxConvergedDamping && reset_at != summary.iterations) {
      // A small step under heavy damping says only that λ is large: retry near Gauss-Newton.
      reset_at = summary.iterations;
      lambda = std::min(options.initial_damping, kMaxConvergedDamping);
      nu = 2;
      continue;
    }
    if (small) {
      // The step would change no residual by more than the tolerance, at the level where F's
      // round-off decides acceptance: the point is the solution, and the step is not taken (its
      // evaluation, the most costly part of an iteration, would change nothing of note).
      summary.termination = TerminationType::kParameterTolerance;
      summary.termination_message = internal::Format("max |J dx| = %.3e <= step_tolerance %.3e",
                                                     step.max_change, options.step_tolerance);
      break;
    }
    LeastSquaresState trial = Plus(problem, *state, step);
    // The trial's cost, and its linearisation when the step is taken: one evaluation with the
    // Jacobians when most steps are taken (linearize_trials), else the cost first.
    Linearization next;
    double trial_cost = std::numeric_limits<double>::infinity();
    bool linearized = false;
    if (options.linearize_trials) {
      linearized = Linearize(problem, trial, &next, options.threads);
      if (linearized) trial_cost = next.cost;
    } else {
      trial_cost = Cost(problem, trial, options.threads);
      linearized = trial_cost < lin.cost && Linearize(problem, trial, &next, options.threads);
    }
    ++summary.evaluations;
    if (trial_cost < lin.cost && linearized) {
      const double actual = lin.cost - trial_cost;
      const double rho = step.predicted_reduction > 0 ? actual / step.predicted_reduction : 1.0;
      lambda *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3));
      nu = 2;
      const double before = lin.cost;
      *state = std::move(trial);
      lin = std::move(next);
      ++summary.iterations;
      summary.cost_history.push_back(lin.cost);
      if (options.function_tolerance > 0 && actual <= options.function_tolerance * before) {
        summary.termination = TerminationType::kFunctionTolerance;
        summary.termination_message = internal::Format("|dF| / F = %.3e <= function_tolerance %.1e",
                                                       actual / before, options.function_tolerance);
        break;
      }
    } else {
      lambda = lambda > 0 ? lambda * nu : kFirstDamping;
      nu *= 2;
      if (lambda > kMaxDamping) {
        summary.termination = TerminationType::kNoProgress;
        summary.termination_message =
            internal::Format("no step reduced F = %.6e with damping up to %.0e (%d evaluations)",
                             lin.cost, kMaxDamping, summary.evaluations);
        break;
      }
    }
  }
  summary.final_cost = lin.cost;
  summary.sigma2 = summary.degrees_of_freedom > 0
                       ? lin.cost / static_cast<double>(summary.degrees_of_freedom)
                       : 0.0;
  Reduce(lin, 0.0, options.min_reciprocal_condition, Condition::kExact, &reduced);
  summary.information = reduced.S;
  summary.reciprocal_condition = reduced.rcond;
  if (!reduced.ok) {
    summary.rank_deficient = true;
    if (summary.converged()) {
      summary.termination = TerminationType::kNoProgress;
      summary.termination_message = reduced.failure;
    }
  } else if ((options.compute_covariance || options.keep_blocks) && problem.GlobalSize() > 0) {
    summary.information_inverse = reduced.Inverse();
    if (options.compute_covariance)
      summary.covariance = summary.sigma2 * summary.information_inverse;
  }
  if (options.keep_blocks) {
    summary.block_residuals = std::move(lin.r);
    summary.block_jacobians = std::move(lin.J_x);
  }
  return summary;
}

namespace {

// S⁻¹, formed once through S's Jacobi scaling, S = D Ŝ D with D = diag(S)^(1/2), so that
// parameters of any unit factor alike: S⁻¹ = D⁻¹ Ŝ⁻¹ D⁻¹. Throws std::invalid_argument (naming
// `who`) when S is not positive definite.
MatrixXd ScaledInverse(const MatrixXd& S, const char* who) {
  const VectorXd d = S.diagonal().cwiseMax(0.0).cwiseSqrt();
  if (!(d.minCoeff() > 0)) throw std::invalid_argument(std::string(who) + ": S is singular");
  const VectorXd d_inverse = d.cwiseInverse();
  const Eigen::LDLT<MatrixXd> ldlt(d_inverse.asDiagonal() * S * d_inverse.asDiagonal());
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0)) {
    throw std::invalid_argument(std::string(who) + ": S is singular");
  }
  return d_inverse.asDiagonal() * ldlt.solve(MatrixXd::Identity(S.rows(), S.cols())) *
         d_inverse.asDiagonal();
}

// Each block's residual and Jacobian at `state` (`who` names the caller in what it throws): the
// solution's when it kept them, else evaluated.
void BlocksAt(const LeastSquaresProblem& problem, const LeastSquaresState& state,
              const LeastSquaresSummary* solution, const char* who, std::vector<VectorXd>* r,
              std::vector<MatrixXd>* J) {
  const auto m = static_cast<std::size_t>(problem.NumBlocks());
  for (int b = 0; b < problem.NumBlocks(); ++b) {
    if (problem.LocalSize(b) != 0) {
      throw std::invalid_argument(std::string(who) + ": a block with its own parameters");
    }
  }
  if (solution != nullptr && solution->block_jacobians.size() == m &&
      solution->block_residuals.size() == m) {
    *r = solution->block_residuals;
    *J = solution->block_jacobians;
    return;
  }
  r->resize(m);
  J->resize(m);
  for (int b = 0; b < problem.NumBlocks(); ++b) {
    const auto k = static_cast<std::size_t>(b);
    if (!problem.Evaluate(b, state.x, state.y[k], &(*r)[k], &(*J)[k], nullptr)) {
      throw std::invalid_argument(Format("%s: block %d cannot be evaluated", who, b));
    }
  }
}

}  // namespace

std::vector<VectorXd> LeaveOneBlockOut(const LeastSquaresProblem& problem,
                                       const LeastSquaresState& state,
                                       const std::vector<int>& blocks,
                                       const LeastSquaresSummary* solution) {
  const int n = problem.GlobalSize();
  std::vector<MatrixXd> J;
  std::vector<VectorXd> r;
  BlocksAt(problem, state, solution, "LeaveOneBlockOut", &r, &J);
  MatrixXd S;
  if (solution != nullptr) {
    if (solution->information.rows() != n || solution->information.cols() != n) {
      throw std::invalid_argument("LeaveOneBlockOut: the information matrix is not n x n");
    }
    S = solution->information;
  } else {
    S = MatrixXd::Zero(n, n);
    for (const MatrixXd& Jk : J) {
      if (Jk.rows() > 0) S.selfadjointView<Eigen::Lower>().rankUpdate(Jk.transpose());
    }
    S.triangularView<Eigen::StrictlyUpper>() = S.transpose();
  }
  const MatrixXd S_inverse = solution != nullptr && solution->information_inverse.rows() == n
                                 ? solution->information_inverse
                                 : ScaledInverse(S, "LeaveOneBlockOut");
  std::vector<VectorXd> out;
  for (int b : blocks) {
    const auto k = static_cast<std::size_t>(b);
    if (J[k].rows() == 0) {
      out.push_back(state.x);
      continue;
    }
    // δ = S_k⁻¹ J_kᵀ r_k = U M⁻¹ r_k with U = S⁻¹ J_kᵀ, M = I − J_k U (Woodbury).
    const SparseColumns Jk(J[k]);
    MatrixXd U = MatrixXd::Zero(n, J[k].rows());
    for (std::size_t c = 0; c < Jk.cols.size(); ++c) {
      U.noalias() +=
          S_inverse.col(Jk.cols[c]) * Jk.J_c.col(static_cast<Eigen::Index>(c)).transpose();
    }
    const MatrixXd M = MatrixXd::Identity(J[k].rows(), J[k].rows()) - J[k] * U;
    const Eigen::PartialPivLU<MatrixXd> lu(M);
    if (!(std::abs(lu.determinant()) > 1e-12)) {
      // The fit cannot do without this block (its leverage is 1): not determined.
      out.push_back(VectorXd::Constant(state.x.size(), std::numeric_limits<double>::quiet_NaN()));
      continue;
    }
    out.push_back(problem.PlusGlobal(state.x, U * lu.solve(r[k])));
  }
  return out;
}

std::vector<double> BlockLeverages(const LeastSquaresProblem& problem,
                                   const LeastSquaresState& state,
                                   const LeastSquaresSummary& solution) {
  const int n = problem.GlobalSize();
  const MatrixXd& information = solution.information;
  if (information.rows() != n || information.cols() != n) {
    throw std::invalid_argument("BlockLeverages: the information matrix is not n x n");
  }
  std::vector<MatrixXd> Js;
  std::vector<VectorXd> r;
  BlocksAt(problem, state, &solution, "BlockLeverages", &r, &Js);
  const MatrixXd S_inverse = solution.information_inverse.rows() == n
                                 ? solution.information_inverse
                                 : ScaledInverse(information, "BlockLeverages");
  std::vector<double> leverage(Js.size(), 0.0);
  for (std::size_t k = 0; k < Js.size(); ++k) {
    const MatrixXd& J = Js[k];
    if (J.rows() == 0) continue;
    // tr(J S⁻¹ Jᵀ) over J's nonzero columns c: tr(J_c (S⁻¹)_cc J_cᵀ).
    const SparseColumns Jk(J);
    const auto nc = static_cast<Eigen::Index>(Jk.cols.size());
    MatrixXd S_cc(nc, nc);
    for (Eigen::Index a = 0; a < nc; ++a) {
      for (Eigen::Index c = 0; c < nc; ++c) {
        S_cc(a, c) =
            S_inverse(Jk.cols[static_cast<std::size_t>(a)], Jk.cols[static_cast<std::size_t>(c)]);
      }
    }
    leverage[k] = (Jk.J_c * S_cc * Jk.J_c.transpose()).trace();
  }
  return leverage;
}

}  // namespace accelcal::internal
