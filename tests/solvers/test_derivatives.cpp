// Finite-difference checks of the solvers' derivatives: the per-position KKT step (paper 000
// eq. (24), corrected eq. (25)) and the joint normal equations with their Schur complement.
#include <cmath>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "accelcal/simulate.hpp"
#include "solvers/solver_common.hpp"
#include "support/jacobian_check.hpp"

namespace accelcal {
namespace {

using internal::Problem;

ModelParameters StrongQuadratic() {
  // Squared terms far larger than real ones so that the k2 terms of the Hessian matter.
  ModelParameters p = Yang2012Truth();
  p.k2 << 3.0, -2.0, 4.0;
  return p;
}

TEST(Derivatives, DirectionCostGradientAndHessian) {
  const ModelParameters params = StrongQuadratic();
  const double g = 9.8;
  const Vec3 p =
      PredictRaw(params, Vec3(g * Vec3(0.3, -0.5, 0.8).normalized())) + Vec3(40, -25, 60);
  auto cost = [&](const Eigen::VectorXd& c) -> Eigen::VectorXd {
    Eigen::VectorXd out(1);
    out(0) = (PredictRaw(params, Vec3(g * Vec3(c))) - p).squaredNorm();
    return out;
  };
  const Vec3 c(0.31, -0.52, 0.79);
  Vec3 grad;
  Mat33 hess;
  internal::DirectionCostDerivatives(params, g, p, c, &grad, &hess);
  EXPECT_TRUE(testing::JacobianMatches(cost, c, grad.transpose()));
  auto gradient = [&](const Eigen::VectorXd& x) -> Eigen::VectorXd {
    Vec3 gr;
    Mat33 h;
    internal::DirectionCostDerivatives(params, g, p, Vec3(x), &gr, &h);
    return gr;
  };
  EXPECT_TRUE(testing::JacobianMatches(gradient, c, hess));
}

TEST(Derivatives, KktDirectionIsTheConstrainedMinimum) {
  const ModelParameters params = StrongQuadratic();
  const double g = 9.8;
  const Vec3 truth = Vec3(0.3, -0.5, 0.8).normalized();
  const Vec3 p = PredictRaw(params, Vec3(g * truth)) + Vec3(4, -2.5, 6);
  const Vec3 c = internal::KktDirection(params, g, p, Vec3(0.35, -0.45, 0.82), 50);
  EXPECT_NEAR(c.norm(), 1.0, 1e-15);
  Vec3 grad;
  Mat33 hess;
  internal::DirectionCostDerivatives(params, g, p, c, &grad, &hess);
  // KKT: the gradient is normal to the sphere (its tangential part vanishes).
  const Vec3 tangential = grad - grad.dot(c) * c;
  EXPECT_LE(tangential.norm(), 1e-9 * grad.norm());
  // And it is a minimum: no nearby point on the sphere has a lower cost.
  const double f0 = (PredictRaw(params, Vec3(g * c)) - p).squaredNorm();
  const internal::Mat32 B = internal::TangentBasis(c);
  for (double a = 0; a < 6.28; a += 0.5) {
    const Vec3 q = internal::Retract(c, B, 1e-4 * Eigen::Vector2d(std::cos(a), std::sin(a)));
    EXPECT_GE((PredictRaw(params, Vec3(g * q)) - p).squaredNorm(), f0);
  }
}

TEST(Derivatives, TangentBasisIsOrthonormalAndTangent) {
  for (const Vec3& c : Yang18Directions()) {
    const internal::Mat32 B = internal::TangentBasis(c);
    EXPECT_LT((B.transpose() * B - Eigen::Matrix2d::Identity()).norm(), 1e-15);
    EXPECT_LT((B.transpose() * c).norm(), 1e-15);
  }
}

// Stacks the residuals r_k = μ(θ, g·retract(c_k, δ_k)) − p_k over all positions as a function of
// x = (θ (12), δ_1, ..., δ_m), the variables of the joint solver.
struct JointResidual {
  const Problem& problem;
  const std::vector<Vec3>& dirs;
  std::vector<internal::Mat32> bases;
  Eigen::VectorXd operator()(const Eigen::VectorXd& x) const {
    const ModelParameters params = internal::FromVec12(x.head<12>());
    Eigen::VectorXd r(3 * problem.positions());
    for (int k = 0; k < problem.positions(); ++k) {
      const Vec3 c = internal::Retract(dirs[k], bases[k], x.segment<2>(12 + 2 * k));
      r.segment<3>(3 * k) = PredictRaw(params, Vec3(problem.gravity * c)) - problem.readings[k];
    }
    return r;
  }
};

TEST(Derivatives, JointNormalEquationsAndSchurComplement) {
  const ModelParameters truth = StrongQuadratic();
  const std::vector<Vec3> dirs = RandomDirections(14, 3);
  const std::vector<Vec3> readings = SimulatePositions(truth, 9.8, dirs, Vec3(30, 30, 30), 4);
  const Problem problem{readings, 9.8, ModelKind::kQuadratic};
  // Evaluate away from the optimum so residuals are large.
  std::vector<Vec3> start = dirs;
  for (Vec3& c : start) c = (c + Vec3(0.01, -0.02, 0.015)).normalized();
  internal::NormalEquations ne;
  internal::BuildNormalEquations(problem, truth, start, &ne);

  JointResidual residual{problem, start, ne.tangent};
  const int m = problem.positions();
  Eigen::VectorXd x = Eigen::VectorXd::Zero(12 + 2 * m);
  x.head<12>() = internal::ToVec12(truth);
  Eigen::MatrixXd J(3 * m, 12 + 2 * m);
  J.setZero();
  for (int k = 0; k < m; ++k) {
    Mat33 J_p_f;
    PredictRaw(truth, Vec3(9.8 * start[k]), &J_p_f);
    J.block<3, 12>(3 * k, 0) = JacobianWrtParameters(Vec3(9.8 * start[k]));
    J.block<3, 2>(3 * k, 12 + 2 * k) = 9.8 * J_p_f * ne.tangent[k];
  }
  EXPECT_TRUE(testing::JacobianMatches(residual, x, J));

  const Eigen::MatrixXd H = J.transpose() * J;
  const Eigen::VectorXd grad = J.transpose() * residual(x);
  EXPECT_LT((H.topLeftCorner<12, 12>() - ne.A).norm(), 1e-12 * H.norm());
  EXPECT_LT((grad.head<12>() - ne.g_theta).norm(), 1e-12 * grad.norm());
  for (int k = 0; k < m; ++k) {
    EXPECT_LT((H.block<12, 2>(0, 12 + 2 * k) - internal::B(ne, k)).norm(), 1e-12 * H.norm());
    EXPECT_LT((H.block<2, 2>(12 + 2 * k, 12 + 2 * k) - ne.D[k]).norm(), 1e-12 * H.norm());
    EXPECT_LT((grad.segment<2>(12 + 2 * k) - ne.g_c[k]).norm(), 1e-12 * grad.norm());
  }
  EXPECT_NEAR(ne.cost, residual(x).squaredNorm(), 1e-12 * ne.cost);

  // Schur complement against dense elimination of the direction block.
  const Eigen::MatrixXd Hcc = H.bottomRightCorner(2 * m, 2 * m);
  const Eigen::MatrixXd Htc = H.topRightCorner(12, 2 * m);
  const Eigen::MatrixXd dense = H.topLeftCorner<12, 12>() - Htc * Hcc.inverse() * Htc.transpose();
  const internal::Mat12 reduced =
      internal::ReducedMatrix(ne, 0.0, internal::FreeMask(ModelKind::kQuadratic));
  EXPECT_LT((reduced - dense).norm(), 1e-9 * dense.norm());
  // The square-root form used for the information matrix gives the same matrix.
  internal::Vec12 A_diagonal;
  const internal::Mat12 direct = internal::ReducedInformation(problem, truth, start, &A_diagonal);
  EXPECT_LT((direct - dense).norm(), 1e-9 * dense.norm());
  EXPECT_LT((A_diagonal - ne.A.diagonal()).norm(), 1e-12 * ne.A.diagonal().norm());
}

}  // namespace
}  // namespace accelcal
