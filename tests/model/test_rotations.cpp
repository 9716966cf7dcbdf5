// rotations.hpp: Exp∘Log round trips (near 0 and near π too), every Jacobian against the one
// finite-difference checker, the integration of a rate against closed forms, float instances.
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>
#include <Eigen/LU>

#include "accelcal/rotations.hpp"
#include "support/jacobian_check.hpp"

namespace accelcal {
namespace {

using Vec3d = Vec3T<double>;
using Mat3d = Mat33T<double>;
constexpr double kPi = 3.14159265358979323846;

Eigen::VectorXd Flat(const Mat3d& M) { return Eigen::Map<const Eigen::VectorXd>(M.data(), 9); }

// Rotation vectors of many sizes: tiny, small, ordinary, and within 1e-6..1e-12 of π.
std::vector<Vec3d> TestVectors() {
  std::mt19937_64 random(5);
  std::normal_distribution<double> normal;
  std::vector<Vec3d> out;
  for (const double angle :
       {0.0, 1e-12, 1e-8, 1e-5, 1e-3, 0.1, 1.0, 2.0, 3.0, kPi - 1e-6, kPi - 1e-9, kPi - 1e-12}) {
    for (int k = 0; k < 4; ++k) {
      const Vec3d axis = Vec3d(normal(random), normal(random), normal(random)).normalized();
      out.push_back(angle * axis);
    }
  }
  out.push_back(Vec3d(kPi - 1e-10, 0, 0));
  out.push_back(Vec3d(0, 0, -(kPi - 1e-10)));
  return out;
}

TEST(Rotations, HatVeeAndCrossProduct) {
  const Vec3d w(0.3, -1.2, 2.5), v(-0.7, 0.4, 1.1);
  EXPECT_LT((so3::Hat(w) * v - w.cross(v)).norm(), 1e-15);
  EXPECT_EQ(so3::Vee(so3::Hat(w)), w);
  EXPECT_EQ(so3::Hat(w).transpose(), -so3::Hat(w));
}

TEST(Rotations, ExpIsARotationAndMatchesClosedForms) {
  for (const Vec3d& phi : TestVectors()) {
    const Mat3d R = so3::Exp(phi);
    EXPECT_LT((R.transpose() * R - Mat3d::Identity()).norm(), 4e-15) << phi.transpose();
    EXPECT_NEAR(R.determinant(), 1.0, 4e-15);
    EXPECT_LT((R * phi - phi).norm(), 1e-15 * (1 + phi.norm()));  // the axis is fixed
  }
  // About z by θ: the elementary rotation; a half turn about x.
  for (const double angle : {1e-9, 0.4, -2.0, kPi}) {
    EXPECT_LT((so3::Exp(Vec3d(0, 0, angle)) - AxisRotation(Axis::kZ, angle)).norm(), 1e-15);
  }
  EXPECT_LT((so3::Exp(Vec3d(kPi, 0, 0)) - Vec3d(1, -1, -1).asDiagonal().toDenseMatrix()).norm(),
            1e-15);
}

TEST(Rotations, LogInvertsExpNearZeroAndNearPi) {
  for (const Vec3d& phi : TestVectors()) {
    const Vec3d back = so3::Log(so3::Exp(phi));
    // ε relative to the angle, plus Exp's own round-off: a rotation matrix determines the axis
    // near π to ~ε/(π − θ) only in the skew part, which is why Log reads it from the symmetric
    // part; measured errors below 5e-16 (ordinary) and 2e-15 (π − 1e-12).
    EXPECT_LT((back - phi).norm(), 4e-15 * std::max(1.0, phi.norm())) << phi.transpose();
    // And Exp∘Log on the matrices.
    const Mat3d R = so3::Exp(phi);
    EXPECT_LT((so3::Exp(back) - R).norm(), 4e-15) << phi.transpose();
  }
  // At exactly π either sign is the logarithm; the angle must be π.
  EXPECT_NEAR(so3::Log(AxisRotation(Axis::kY, kPi)).norm(), kPi, 1e-15);
  EXPECT_LT((so3::Log(AxisRotation(Axis::kY, kPi)).cwiseAbs() - Vec3d(0, kPi, 0)).norm(), 1e-15);
  // Small angles keep their relative precision (no 1 − cos cancellation).
  const Vec3d tiny(1e-10, -2e-10, 3e-10);
  EXPECT_LT((so3::Log(so3::Exp(tiny)) - tiny).norm(), 1e-16 * tiny.norm() * 10);
}

TEST(Rotations, RightJacobianMatchesFiniteDifferences) {
  for (const Vec3d& phi : TestVectors()) {
    if (phi.norm() > kPi - 1e-3) continue;  // Log of the perturbed point wraps past π there
    Mat3d J;
    const Mat3d R = so3::Exp(phi, &J);
    EXPECT_EQ(J, so3::RightJacobian(phi));
    // Exp(φ + δ) = Exp(φ) Exp(J_r δ): J_r = ∂ Log(Exp(φ)ᵀ Exp(φ + δ)) / ∂δ at δ = 0.
    const auto f = [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
      return so3::Log(Mat3d(R.transpose() * so3::Exp(Vec3d(phi + d))));
    };
    EXPECT_TRUE(testing::JacobianMatches(f, Eigen::VectorXd::Zero(3), J)) << phi.transpose();
  }
}

TEST(Rotations, LogJacobianIsTheInverseRightJacobian) {
  for (const Vec3d& phi : TestVectors()) {
    if (phi.norm() > kPi - 1e-3) continue;
    Mat3d J;
    const Vec3d back = so3::Log(so3::Exp(phi), &J);
    // Log(R Exp(δ)) = φ + J_r⁻¹ δ.
    const Mat3d R = so3::Exp(phi);
    const auto f = [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
      return so3::Log(Mat3d(R * so3::Exp(Vec3d(d))));
    };
    EXPECT_TRUE(testing::JacobianMatches(f, Eigen::VectorXd::Zero(3), J)) << phi.transpose();
    EXPECT_LT((J * so3::RightJacobian(back) - Mat3d::Identity()).norm(), 1e-13) << phi.transpose();
  }
}

TEST(Rotations, AxisRotationAndItsDerivative) {
  for (const Axis axis : {Axis::kX, Axis::kY, Axis::kZ}) {
    const Vec3d e = Vec3d::Unit(static_cast<int>(axis));
    for (const double angle : {-2.5, -0.3, 0.0, 0.7, kPi / 2, 3.0}) {
      Mat3d dR;
      const Mat3d R = AxisRotation(axis, angle, &dR);
      EXPECT_LT((R - so3::Exp(Vec3d(angle * e))).norm(), 1e-15);
      EXPECT_LT((dR - so3::Hat(e) * R).norm(), 1e-15);
      const auto f = [&](const Eigen::VectorXd& a) -> Eigen::VectorXd {
        return Flat(AxisRotation(axis, a(0)));
      };
      EXPECT_TRUE(testing::JacobianMatches(f, Eigen::VectorXd::Constant(1, angle), Flat(dR)));
    }
  }
  // Exact at quarter turns: the gimbal table's multiples of π/4 rely on cos/sin directly.
  const Mat3d quarter = AxisRotation(Axis::kX, kPi / 2);
  EXPECT_EQ(quarter(0, 0), 1.0);
  EXPECT_EQ(quarter(2, 1), 1.0);
}

TEST(Rotations, ConstantRateIntegratesToTheExponential) {
  // Constant ω over 2 s: R = Exp((ω − b) T) for both rules, whatever the (uneven) steps.
  const Vec3d omega(0.4, -0.9, 1.3), bias(0.01, 0.02, -0.03);
  std::vector<double> t;
  std::vector<Vec3d> w;
  for (double time = 0; time < 2.0; time += 0.013 + 0.005 * std::sin(37 * time)) {
    t.push_back(time);
    w.push_back(omega);
  }
  t.push_back(2.0);
  w.push_back(omega);
  const Mat3d expected = so3::Exp(Vec3d((omega - bias) * 2.0));
  for (const RateInterpolation rule :
       {RateInterpolation::kPiecewiseConstant, RateInterpolation::kTrapezoidal}) {
    const Mat3d R = IntegrateAngularRate(t, w, rule, bias);
    EXPECT_LT((R - expected).norm(), 1e-13);
  }
  // One sample: no time has passed.
  EXPECT_EQ(IntegrateAngularRate(std::vector<double>{0.5}, std::vector<Vec3d>{omega},
                                 RateInterpolation::kTrapezoidal),
            Mat3d::Identity());
  EXPECT_THROW(IntegrateAngularRate(std::vector<double>{0.0, 0.0}, std::vector<Vec3d>(2, omega),
                                    RateInterpolation::kTrapezoidal),
               std::invalid_argument);
  EXPECT_THROW(IntegrateAngularRate(std::vector<double>{0.0, 1.0}, std::vector<Vec3d>(1, omega),
                                    RateInterpolation::kTrapezoidal),
               std::invalid_argument);
}

TEST(Rotations, VaryingRateConvergesAtTheStatedOrder) {
  // R(t) = R_z(α t) R_x(β t²) has the body rate ω(t) = R_x(β t²)ᵀ α e_z + 2 β t e_x (Rᵀ Ṙ):
  // its axis turns and its size changes. Halving the step divides the error by 2 (piecewise
  // constant) and by 4 (trapezoidal).
  const double alpha = 0.8, beta = 0.6, T = 1.5;
  const Mat3d truth = AxisRotation(Axis::kZ, alpha * T) * AxisRotation(Axis::kX, beta * T * T);
  const auto error = [&](int steps, RateInterpolation rule) {
    std::vector<double> t;
    std::vector<Vec3d> w;
    for (int k = 0; k <= steps; ++k) {
      const double time = T * k / steps;
      t.push_back(time);
      w.push_back(AxisRotation(Axis::kX, beta * time * time).transpose() * Vec3d(0, 0, alpha) +
                  Vec3d(2 * beta * time, 0, 0));
    }
    return so3::Log(Mat3d(truth.transpose() * IntegrateAngularRate(t, w, rule))).norm();
  };
  const double pc = error(200, RateInterpolation::kPiecewiseConstant) /
                    error(400, RateInterpolation::kPiecewiseConstant);
  const double tr =
      error(200, RateInterpolation::kTrapezoidal) / error(400, RateInterpolation::kTrapezoidal);
  EXPECT_NEAR(pc, 2.0, 0.05);
  EXPECT_NEAR(tr, 4.0, 0.2);
  EXPECT_LT(error(400, RateInterpolation::kTrapezoidal), 1e-5);
}

TEST(Rotations, BiasJacobianMatchesFiniteDifferences) {
  std::mt19937_64 random(3);
  std::normal_distribution<double> normal;
  std::vector<double> t;
  std::vector<Vec3d> w;
  for (int k = 0; k < 50; ++k) {
    t.push_back(0.02 * k + 0.004 * normal(random) * 0.1);
    w.push_back(Vec3d(1.0 + normal(random), -0.5 + normal(random), 0.7 * normal(random)));
  }
  const Vec3d bias(0.05, -0.02, 0.01);
  for (const RateInterpolation rule :
       {RateInterpolation::kPiecewiseConstant, RateInterpolation::kTrapezoidal}) {
    Mat3d J;
    const Mat3d R = IntegrateAngularRate(t, w, rule, bias, &J);
    const auto f = [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
      return so3::Log(Mat3d(R.transpose() * IntegrateAngularRate(t, w, rule, Vec3d(bias + d))));
    };
    EXPECT_TRUE(testing::JacobianMatches(f, Eigen::VectorXd::Zero(3), J));
    // A constant rate: the Jacobian is −T J_r((ω − b) T).
    std::vector<Vec3d> constant(t.size(), w[0]);
    Mat3d Jc;
    IntegrateAngularRate(t, constant, rule, bias, &Jc);
    const double T = t.back() - t.front();
    EXPECT_LT((Jc + T * so3::RightJacobian(Vec3d((w[0] - bias) * T))).norm(), 1e-12);
  }
}

TEST(Rotations, FloatInstances) {
  // The templates on float: the same identities at float's precision.
  using Vec3f = Vec3T<float>;
  using Mat3f = Mat33T<float>;
  for (const Vec3d& phi_d : TestVectors()) {
    const Vec3f phi = phi_d.cast<float>();
    if (phi.norm() > 3.1f) continue;  // float cannot resolve π − 1e-6
    Mat3f J, J_inverse;
    const Mat3f R = so3::Exp(phi, &J);
    EXPECT_LT((R.transpose() * R - Mat3f::Identity()).norm(), 1e-6f);
    EXPECT_LT((so3::Log(R, &J_inverse) - phi).norm(), 1e-6f * std::max(1.0f, phi.norm()));
    EXPECT_LT((J_inverse * J - Mat3f::Identity()).norm(), 1e-5f);
  }
  const Mat3f Ry = AxisRotation(Axis::kY, 0.5f);
  EXPECT_LT((Ry - so3::Exp(Vec3f(0, 0.5f, 0))).norm(), 1e-6f);
}

}  // namespace
}  // namespace accelcal
