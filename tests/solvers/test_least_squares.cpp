// The reusable least-squares driver (solvers/least_squares.hpp): a certified known answer (NIST
// StRD Misra1a, values and standard deviations), the test problems' Jacobians against finite
// differences, a Schur-eliminated problem against the same problem solved densely, and the
// termination reasons.
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "solvers/least_squares.hpp"
#include "support/jacobian_check.hpp"

namespace accelcal::internal {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// Misra1a (NIST StRD, lower difficulty): y = b1 (1 − exp(−b2 x)), 14 observations.
class Misra1a : public LeastSquaresProblem {
 public:
  int GlobalSize() const override { return 2; }
  int NumBlocks() const override { return 1; }
  bool Evaluate(int, const VectorXd& b, const VectorXd&, VectorXd* r, MatrixXd* J_x,
                MatrixXd*) const override {
    static const double kX[14] = {77.6,  114.9, 141.1, 190.8, 239.9, 289.0, 332.8,
                                  378.4, 434.8, 477.3, 536.8, 593.1, 689.1, 760.0};
    static const double kY[14] = {10.07, 14.73, 17.94, 23.93, 29.61, 35.18, 40.02,
                                  44.82, 50.76, 55.05, 61.01, 66.40, 75.47, 81.78};
    r->resize(14);
    if (J_x != nullptr) J_x->resize(14, 2);
    for (int i = 0; i < 14; ++i) {
      const double e = std::exp(-b(1) * kX[i]);
      (*r)(i) = b(0) * (1 - e) - kY[i];
      if (J_x != nullptr) {
        (*J_x)(i, 0) = 1 - e;
        (*J_x)(i, 1) = b(0) * kX[i] * e;
      }
    }
    return true;
  }
};

TEST(LeastSquares, CertifiedMisra1a) {
  // Certified values: b1 = 2.3894212918E+02 (sd 2.7070075241E+00), b2 = 5.5015643181E-04
  // (sd 7.2668688436E-06), residual sum of squares 1.2455138894E-01; both NIST starts.
  for (const VectorXd& start : {VectorXd((VectorXd(2) << 500, 1e-4).finished()),
                                VectorXd((VectorXd(2) << 250, 5e-4).finished())}) {
    LeastSquaresState state{start, {}};
    LeastSquaresOptions options;
    options.initial_damping = 1e-3;
    options.step_tolerance = 1e-12;
    const LeastSquaresSummary s = SolveLeastSquares(Misra1a(), options, &state);
    ASSERT_TRUE(s.converged()) << s.termination_message;
    EXPECT_EQ(s.termination, TerminationType::kParameterTolerance);
    EXPECT_NE(s.termination_message.find("<= step_tolerance"), std::string::npos);
    // Log relative error (correct digits) of at least 9, as the certified values carry 11.
    EXPECT_NEAR(state.x(0), 2.3894212918E+02, 1e-9 * 2.39e2);
    EXPECT_NEAR(state.x(1), 5.5015643181E-04, 1e-9 * 5.5e-4);
    EXPECT_NEAR(s.final_cost, 1.2455138894E-01, 1e-9);
    EXPECT_EQ(s.degrees_of_freedom, 12);
    EXPECT_NEAR(std::sqrt(s.covariance(0, 0)), 2.7070075241E+00, 1e-7);
    EXPECT_NEAR(std::sqrt(s.covariance(1, 1)), 7.2668688436E-06, 1e-13);
    EXPECT_EQ(s.cost_history.front(), s.initial_cost);
    EXPECT_EQ(s.cost_history.back(), s.final_cost);
    EXPECT_EQ(static_cast<int>(s.cost_history.size()), s.iterations + 1);
  }
}

TEST(LeastSquares, Misra1aJacobianMatchesFiniteDifferences) {
  const Misra1a problem;
  for (const VectorXd& b : {VectorXd((VectorXd(2) << 500, 1e-4).finished()),
                            VectorXd((VectorXd(2) << 238.9, 5.5e-4).finished())}) {
    VectorXd r;
    MatrixXd J;
    problem.Evaluate(0, b, VectorXd(), &r, &J, nullptr);
    const auto f = [&](const VectorXd& v) -> VectorXd {
      VectorXd out;
      problem.Evaluate(0, v, VectorXd(), &out, nullptr, nullptr);
      return out;
    };
    // b2 ~ 1e-4: a step relative to its size, not the default max(1, |x|) · 1e-6.
    EXPECT_TRUE(accelcal::testing::JacobianMatches(f, b, J, 1e-6, 1e-9));
  }
}

TEST(LeastSquares, LinearProblemInOneStep) {
  // A straight line: Gauss-Newton solves it in one step; the second would change nothing, so it
  // is not taken.
  class Line : public LeastSquaresProblem {
   public:
    int GlobalSize() const override { return 2; }
    int NumBlocks() const override { return 5; }
    bool Evaluate(int k, const VectorXd& x, const VectorXd&, VectorXd* r, MatrixXd* J_x,
                  MatrixXd*) const override {
      const double t = k, y = 1.5 + 0.5 * k + (k % 2 ? 0.1 : -0.1);
      *r = VectorXd::Constant(1, x(0) + x(1) * t - y);
      if (J_x != nullptr) *J_x = (MatrixXd(1, 2) << 1.0, t).finished();
      return true;
    }
  };
  LeastSquaresState state{VectorXd::Zero(2), {}};
  LeastSquaresOptions options;
  options.step_tolerance = 1e-12;
  const LeastSquaresSummary s = SolveLeastSquares(Line(), options, &state);
  EXPECT_EQ(s.termination, TerminationType::kParameterTolerance);
  EXPECT_EQ(s.iterations, 1);
  EXPECT_EQ(s.cost_history.size(), 2u);
  // Least squares of (0..4, y), deviations (−0.1, 0.1, −0.1, 0.1, −0.1) from the line 1.5 + 0.5 t:
  // symmetric about t = 2, so the slope stays 0.5 and the intercept moves by their mean, −0.02.
  EXPECT_NEAR(state.x(0), 1.48, 1e-13);
  EXPECT_NEAR(state.x(1), 0.5, 1e-13);
}

// Points near a circle: global (c_x, c_y, R), each point's own angle φ_k,
// r_k = c + R (cos φ_k, sin φ_k) − p_k. `dense` makes the angles global parameters too; the
// Schur form stores each angle as a unit vector (cos, sin), moved by a rotation (a manifold).
class Circle : public LeastSquaresProblem {
 public:
  Circle(bool dense, std::uint64_t seed) : dense_(dense) {
    std::mt19937_64 random(seed);
    std::normal_distribution<double> normal;
    for (int k = 0; k < 12; ++k) {
      const double phi = 0.5 * k;
      points_.emplace_back(1.0 + 2.0 * std::cos(phi) + 0.05 * normal(random),
                           -0.5 + 2.0 * std::sin(phi) + 0.05 * normal(random));
    }
  }
  int GlobalSize() const override { return dense_ ? 3 + Points() : 3; }
  int NumBlocks() const override { return Points(); }
  int LocalSize(int) const override { return dense_ ? 0 : 1; }
  bool Evaluate(int k, const VectorXd& x, const VectorXd& y, VectorXd* r, MatrixXd* J_x,
                MatrixXd* J_y) const override {
    const Eigen::Vector2d u = dense_ ? Eigen::Vector2d(std::cos(x(3 + k)), std::sin(x(3 + k)))
                                     : Eigen::Vector2d(y(0), y(1));
    *r = x.head<2>() + x(2) * u - points_[k];
    const Eigen::Vector2d du(-u(1), u(0));  // ∂u/∂φ
    if (J_x != nullptr) {
      J_x->setZero(2, GlobalSize());
      J_x->block<2, 2>(0, 0).setIdentity();
      J_x->col(2) = u;
      if (dense_) J_x->col(3 + k) = x(2) * du;
    }
    if (J_y != nullptr) *J_y = x(2) * du;
    return true;
  }
  VectorXd PlusLocal(int, const VectorXd& y, const VectorXd& d) const override {
    const double c = std::cos(d(0)), s = std::sin(d(0));
    return Eigen::Vector2d(c * y(0) - s * y(1), s * y(0) + c * y(1));
  }
  int Points() const { return static_cast<int>(points_.size()); }
  const std::vector<Eigen::Vector2d>& points() const { return points_; }

 private:
  bool dense_;
  std::vector<Eigen::Vector2d> points_;
};

TEST(LeastSquares, CircleJacobiansMatchFiniteDifferences) {
  const Circle dense(true, 1), schur(false, 1);
  VectorXd x(3 + dense.Points());
  x << 0.9, -0.4, 2.1, VectorXd::LinSpaced(dense.Points(), 0.1, 5.6);
  for (int k = 0; k < dense.Points(); ++k) {
    VectorXd r;
    MatrixXd J_x, J_y;
    dense.Evaluate(k, x, VectorXd(), &r, &J_x, nullptr);
    const auto f = [&](const VectorXd& v) -> VectorXd {
      VectorXd out;
      dense.Evaluate(k, v, VectorXd(), &out, nullptr, nullptr);
      return out;
    };
    EXPECT_TRUE(accelcal::testing::JacobianMatches(f, x, J_x)) << k;
    // The Schur form's local Jacobian is with respect to the rotation angle of its unit vector.
    const VectorXd y = Eigen::Vector2d(std::cos(x(3 + k)), std::sin(x(3 + k)));
    schur.Evaluate(k, x.head<3>(), y, &r, &J_x, &J_y);
    const auto g = [&](const VectorXd& d) -> VectorXd {
      VectorXd out;
      schur.Evaluate(k, x.head<3>(), schur.PlusLocal(k, y, d), &out, nullptr, nullptr);
      return out;
    };
    EXPECT_TRUE(accelcal::testing::JacobianMatches(g, VectorXd::Zero(1), J_y)) << k;
  }
}

TEST(LeastSquares, SchurEliminationMatchesTheDenseSolution) {
  const Circle dense(true, 2), schur(false, 2);
  const int m = dense.Points();
  // Start: centre at the mean, radius the mean distance, angles from the centre.
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  for (const auto& p : dense.points()) centre += p / m;
  double radius = 0;
  for (const auto& p : dense.points()) radius += (p - centre).norm() / m;
  LeastSquaresState d{VectorXd(3 + m), {}}, s{VectorXd(3), {}};
  d.x.head<2>() = centre;
  d.x(2) = radius;
  s.x = d.x.head<3>();
  for (int k = 0; k < m; ++k) {
    const Eigen::Vector2d u = (dense.points()[k] - centre).normalized();
    d.x(3 + k) = std::atan2(u(1), u(0));
    s.y.push_back(u);
  }
  LeastSquaresOptions options;
  options.step_tolerance = 1e-13;
  const LeastSquaresSummary ds = SolveLeastSquares(dense, options, &d);
  const LeastSquaresSummary ss = SolveLeastSquares(schur, options, &s);
  ASSERT_TRUE(ds.converged()) << ds.termination_message;
  ASSERT_TRUE(ss.converged()) << ss.termination_message;
  EXPECT_LT((d.x.head<3>() - s.x).cwiseAbs().maxCoeff(), 1e-10);
  // Gauss-Newton converges linearly on a problem with residuals: both stop within a few
  // steps' size of the optimum (the angles' own 1σ here is 0.025 rad).
  for (int k = 0; k < m; ++k) {
    EXPECT_NEAR(std::cos(d.x(3 + k)), s.y[k](0), 1e-10);
    EXPECT_NEAR(std::sin(d.x(3 + k)), s.y[k](1), 1e-10);
  }
  EXPECT_NEAR(ds.final_cost, ss.final_cost, 1e-15);
  EXPECT_EQ(ds.degrees_of_freedom, 2 * m - 3 - m);
  EXPECT_EQ(ss.degrees_of_freedom, ds.degrees_of_freedom);
  // The Schur complement's inverse is the global block of the full inverse.
  EXPECT_LT((ds.covariance.topLeftCorner<3, 3>() - ss.covariance).cwiseAbs().maxCoeff(),
            1e-10 * ss.covariance.cwiseAbs().maxCoeff());
  EXPECT_EQ(ss.covariance.rows(), 3);
}

TEST(LeastSquares, TerminationReasons) {
  LeastSquaresOptions options;
  options.initial_damping = 1e-3;
  // The iteration cap, stated with its number.
  {
    LeastSquaresState state{(VectorXd(2) << 500, 1e-4).finished(), {}};
    options.max_iterations = 2;
    const LeastSquaresSummary s = SolveLeastSquares(Misra1a(), options, &state);
    EXPECT_EQ(s.termination, TerminationType::kMaxIterations);
    EXPECT_EQ(s.termination_message, "reached max_iterations = 2");
    EXPECT_FALSE(s.converged());
    EXPECT_EQ(s.iterations, 2);
  }
  // The cost criterion.
  {
    LeastSquaresState state{(VectorXd(2) << 500, 1e-4).finished(), {}};
    options.max_iterations = 100;
    options.function_tolerance = 1e-10;
    const LeastSquaresSummary s = SolveLeastSquares(Misra1a(), options, &state);
    EXPECT_EQ(s.termination, TerminationType::kFunctionTolerance) << s.termination_message;
    EXPECT_NE(s.termination_message.find("|dF| / F = "), std::string::npos);
    EXPECT_NEAR(state.x(0), 2.3894212918E+02, 1e-4);
  }
  // Zero residual.
  {
    class Exact : public LeastSquaresProblem {
     public:
      int GlobalSize() const override { return 1; }
      int NumBlocks() const override { return 1; }
      bool Evaluate(int, const VectorXd& x, const VectorXd&, VectorXd* r, MatrixXd* J,
                    MatrixXd*) const override {
        *r = VectorXd::Constant(2, x(0) * x(0) - 4);
        if (J != nullptr) *J = MatrixXd::Constant(2, 1, 2 * x(0));
        return true;
      }
    };
    LeastSquaresState state{VectorXd::Constant(1, 3.0), {}};
    LeastSquaresOptions exact;
    exact.zero_residual_cost = 1e-28;
    const LeastSquaresSummary s = SolveLeastSquares(Exact(), exact, &state);
    EXPECT_EQ(s.termination, TerminationType::kZeroResidual) << s.termination_message;
    EXPECT_NEAR(state.x(0), 2.0, 1e-14);
    EXPECT_LT(s.sigma2, 1e-27);  // one degree of freedom, zero residual
  }
  // Two parameters the data cannot tell apart: singular, named.
  {
    class Twins : public LeastSquaresProblem {
     public:
      int GlobalSize() const override { return 2; }
      int NumBlocks() const override { return 1; }
      bool Evaluate(int, const VectorXd& x, const VectorXd&, VectorXd* r, MatrixXd* J,
                    MatrixXd*) const override {
        *r = (VectorXd(3) << x(0) + x(1) - 1, x(0) + x(1) - 2, x(0) + x(1)).finished();
        if (J != nullptr) *J = MatrixXd::Ones(3, 2);
        return true;
      }
    };
    LeastSquaresState state{VectorXd::Zero(2), {}};
    const LeastSquaresSummary s = SolveLeastSquares(Twins(), LeastSquaresOptions(), &state);
    EXPECT_EQ(s.termination, TerminationType::kNoProgress);
    EXPECT_TRUE(s.rank_deficient);
    EXPECT_NE(s.termination_message.find("singular"), std::string::npos) << s.termination_message;
    EXPECT_TRUE(s.covariance.size() == 0);
  }
  // Two parameters the data can barely tell apart: S is positive definite (its Cholesky factor
  // exists) but its reciprocal condition, about ε²/4 = 2.5e-15, is below the threshold 1e-12.
  // A step's cheap check (a lower bound on it) must not pass it: no step is taken.
  {
    class NearTwins : public LeastSquaresProblem {
     public:
      int GlobalSize() const override { return 2; }
      int NumBlocks() const override { return 1; }
      bool Evaluate(int, const VectorXd& x, const VectorXd&, VectorXd* r, MatrixXd* J,
                    MatrixXd*) const override {
        const double e = 1e-7;
        *r = (VectorXd(2) << x(0) + x(1) - 1, x(0) + (1 + e) * x(1) - 2).finished();
        if (J != nullptr) *J = (MatrixXd(2, 2) << 1, 1, 1, 1 + e).finished();
        return true;
      }
    };
    LeastSquaresState state{VectorXd::Zero(2), {}};
    const LeastSquaresSummary s = SolveLeastSquares(NearTwins(), LeastSquaresOptions(), &state);
    EXPECT_TRUE(s.rank_deficient);
    EXPECT_EQ(s.iterations, 0);
    EXPECT_EQ(state.x, VectorXd::Zero(2));
    EXPECT_GT(s.reciprocal_condition, 0);
    EXPECT_LT(s.reciprocal_condition, 1e-12);
    // With the threshold below it, the same problem is solved exactly (square and regular).
    LeastSquaresOptions loose;
    loose.min_reciprocal_condition = 1e-16;
    loose.zero_residual_cost = 1e-20;
    LeastSquaresState solved{VectorXd::Zero(2), {}};
    const LeastSquaresSummary t = SolveLeastSquares(NearTwins(), loose, &solved);
    EXPECT_FALSE(t.rank_deficient) << t.termination_message;
    EXPECT_GT(t.iterations, 0);
  }
}

}  // namespace
}  // namespace accelcal::internal

namespace accelcal::internal {
namespace {

// A straight line through 7 points, one 2-row block each (y and a second, weighted reading of
// it): linear, so a Gauss-Newton step from the solution without a block is that fit exactly.
class TwoRowLine : public LeastSquaresProblem {
 public:
  explicit TwoRowLine(std::vector<bool> used = {}) : used_(std::move(used)) {}
  int GlobalSize() const override { return 2; }
  int NumBlocks() const override { return 7; }
  bool Evaluate(int k, const VectorXd& x, const VectorXd&, VectorXd* r, MatrixXd* J_x,
                MatrixXd*) const override {
    if (!used_.empty() && !used_[static_cast<std::size_t>(k)]) {
      r->resize(0);
      if (J_x != nullptr) J_x->resize(0, 2);
      return true;
    }
    const double t = k, y = 0.3 + 1.7 * t + 0.2 * std::sin(3.0 * t), w = 1.0 + 0.5 * (k % 3);
    *r = (VectorXd(2) << x(0) + x(1) * t - y, w * (x(0) + x(1) * t - y - 0.05)).finished();
    if (J_x != nullptr) *J_x = (MatrixXd(2, 2) << 1.0, t, w, w * t).finished();
    return true;
  }

 private:
  std::vector<bool> used_;
};

LeastSquaresState Solved(const LeastSquaresProblem& problem, LeastSquaresSummary* summary) {
  LeastSquaresState state{VectorXd::Zero(2), std::vector<VectorXd>(7)};
  LeastSquaresOptions options;
  options.step_tolerance = 1e-13;
  *summary = SolveLeastSquares(problem, options, &state);
  return state;
}

TEST(LeastSquares, LeaveOneBlockOutIsTheRefitOfALinearProblem) {
  LeastSquaresSummary summary;
  const LeastSquaresState full = Solved(TwoRowLine(), &summary);
  const std::vector<int> blocks = {0, 3, 6};
  LeastSquaresSummary kept;
  LeastSquaresState state{VectorXd::Zero(2), std::vector<VectorXd>(7)};
  LeastSquaresOptions options;
  options.step_tolerance = 1e-13;
  options.keep_blocks = true;
  kept = SolveLeastSquares(TwoRowLine(), options, &state);
  ASSERT_EQ(kept.block_jacobians.size(), 7u);
  EXPECT_EQ(state.x, full.x);
  // Evaluated, the solution's information, and its blocks kept: the same held-out fits.
  const std::vector<const LeastSquaresSummary*> solutions = {nullptr, &summary, &kept};
  for (const LeastSquaresSummary* solution : solutions) {
    const std::vector<VectorXd> held = LeaveOneBlockOut(TwoRowLine(), full, blocks, solution);
    for (std::size_t i = 0; i < blocks.size(); ++i) {
      std::vector<bool> used(7, true);
      used[static_cast<std::size_t>(blocks[i])] = false;
      LeastSquaresSummary s;
      const LeastSquaresState refit = Solved(TwoRowLine(used), &s);
      EXPECT_LT((held[i] - refit.x).norm(), 1e-11) << blocks[i];
    }
  }
}

TEST(LeastSquares, BlockLeveragesSumToTheParameters) {
  LeastSquaresSummary summary;
  const LeastSquaresState full = Solved(TwoRowLine(), &summary);
  const std::vector<double> h = BlockLeverages(TwoRowLine(), full, summary);
  double sum = 0;
  for (double v : h) {
    EXPECT_GT(v, 0);
    EXPECT_LT(v, 2);
    sum += v;
  }
  EXPECT_NEAR(sum, 2.0, 1e-12);  // tr(J S⁻¹ Jᵀ) = tr(I_P) = P
}

}  // namespace
}  // namespace accelcal::internal
