// The model kernels: packing, forward model, exact inverse, engineering conversions, gravity.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "accelcal/engineering.hpp"
#include "accelcal/gravity.hpp"
#include "accelcal/model.hpp"
#include "accelcal/simulate.hpp"
#include "support/jacobian_check.hpp"

namespace accelcal {
namespace {

// A MEMS-like device in raw counts with f in m/s²: large bias, strong squared terms.
ModelParameters Device() {
  ModelParameters p;
  p.K << 414.4, 0, 0, 1.47, 412.1, 0, 3.83, 8.84, 414.5;
  p.bias << 33123.8, 33275.2, 32364.5;
  p.k2 << 0.02, -0.03, 0.05;
  return p;
}

TEST(Model, PackUnpackRoundTripAndOrder) {
  const ModelParameters p = Device();
  const Eigen::VectorXd q = Pack(p, ModelKind::kQuadratic);
  ASSERT_EQ(q.size(), 12);
  // Paper 000 eq. (8) order.
  EXPECT_EQ(q(0), p.K(0, 0));
  EXPECT_EQ(q(1), p.bias(0));
  EXPECT_EQ(q(2), p.k2(0));
  EXPECT_EQ(q(3), p.K(1, 0));
  EXPECT_EQ(q(9), p.K(2, 2));
  EXPECT_EQ(q(11), p.k2(2));
  const ModelParameters back = Unpack(q, ModelKind::kQuadratic);
  EXPECT_EQ(back.K, p.K);
  EXPECT_EQ(back.bias, p.bias);
  EXPECT_EQ(back.k2, p.k2);

  const Eigen::VectorXd l = Pack(p, ModelKind::kLinear);
  ASSERT_EQ(l.size(), 9);
  const ModelParameters lin = Unpack(l, ModelKind::kLinear);
  EXPECT_EQ(lin.K, p.K);
  EXPECT_TRUE(lin.k2.isZero(0));
  EXPECT_EQ(ParameterSlots(ModelKind::kLinear)[2].name, "K_yx");
  EXPECT_EQ(ActiveColumns(ModelKind::kLinear).size(), 9u);
}

TEST(Model, IdentityParametersAreIdentity) {
  const ModelParameters identity;
  const Vec3 f(0.3, -9.1, 2.2);
  EXPECT_EQ(PredictRaw(identity, f), f);
  EXPECT_EQ(*SpecificForce(identity, f), f);
}

TEST(Model, JacobianWrtSpecificForceMatchesFiniteDifferences) {
  const ModelParameters p = Device();
  const Vec3 f(3.1, -7.2, 5.5);
  Mat33 J;
  PredictRaw(p, f, &J);
  auto fun = [&](const Eigen::VectorXd& x) -> Eigen::VectorXd { return PredictRaw(p, Vec3(x)); };
  EXPECT_TRUE(testing::JacobianMatches(fun, f, J));
}

TEST(Model, JacobianWrtParametersMatchesFiniteDifferences) {
  const ModelParameters p = Device();
  const Vec3 f(3.1, -7.2, 5.5);
  const Eigen::MatrixXd J = JacobianWrtParameters(f);
  auto fun = [&](const Eigen::VectorXd& theta) -> Eigen::VectorXd {
    return PredictRaw(Unpack(theta, ModelKind::kQuadratic), f);
  };
  EXPECT_TRUE(testing::JacobianMatches(fun, Pack(p, ModelKind::kQuadratic), J));
}

TEST(Model, InverseRoundTripIsExact) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-20.0, 20.0);
  // Also a device with reversed axes (negative diagonal), which takes the other root branch.
  ModelParameters reversed = Device();
  reversed.K.diagonal() << -414.4, -412.1, 414.5;
  double worst = 0;
  for (const ModelParameters& p : {Device(), reversed}) {
    for (int i = 0; i < 10000; ++i) {
      const double z = u(rng), y = u(rng), x = u(rng);  // in a fixed order (GCC's)
      const Vec3 f(x, y, z);
      const std::optional<Vec3> back = SpecificForce(p, PredictRaw(p, f));
      ASSERT_TRUE(back.has_value());
      worst = std::max(worst, (*back - f).norm() / f.norm());
    }
  }
  // The closed-form per-row solution is exact up to round-off (issue: ≤ 1e-12 relative).
  EXPECT_LE(worst, 1e-12);
}

TEST(Model, InverseReportsOutOfRange) {
  ModelParameters p;
  p.k2 << 0.1, 0, 0;  // 1·f + 0.1 f² never goes below −2.5
  EXPECT_FALSE(SpecificForce(p, Vec3(-3.0, 0, 0)).has_value());
  EXPECT_TRUE(SpecificForce(p, Vec3(-2.0, 0, 0)).has_value());
}

TEST(Model, KernelsInstantiateWithFloat) {
  const ModelParametersT<float> p = Device().cast<float>();
  const Vec3T<float> f(3.1f, -7.2f, 5.5f);
  const std::optional<Vec3T<float>> back = SpecificForce(p, PredictRaw(p, f));
  ASSERT_TRUE(back.has_value());
  // float round-off on outputs of ~4e4 counts: ~4e4·6e-8 = 2.4e-3 counts ≈ 6e-6 m/s².
  EXPECT_LT((*back - f).norm(), 1e-3f);
}

TEST(Engineering, Yang2012TruthMatchesTable3) {
  const ModelParameters truth = Yang2012Truth();
  const EngineeringParameters e = ToEngineering(truth, kYang2012Gravity_ms2);
  EXPECT_NEAR(e.scale_factor(0), 4800, 1e-9);
  EXPECT_NEAR(e.scale_factor(2), 5000, 1e-9);
  EXPECT_NEAR(e.tau_yx, 1.7453e-4, 1e-8);  // Table 3 prints 5 digits
  EXPECT_NEAR(e.tau_zx, 3.0229e-4, 1e-8);
  EXPECT_NEAR(e.tau_zy, 1.7453e-4, 1e-8);
  EXPECT_NEAR(e.tau_yy, 0.99999998, 1e-8);
  EXPECT_NEAR(e.tau_zz, 0.99999993, 1e-8);
  EXPECT_NEAR(e.bias_force(1), 0.02, 1e-15);
  EXPECT_NEAR(e.k2_g_per_g2(2), 3e-5, 1e-18);
  const ModelParameters back = FromEngineering(e, kYang2012Gravity_ms2);
  EXPECT_LT((back.K - truth.K).norm(), 1e-10);
  EXPECT_LT((back.k2 - truth.k2).norm(), 1e-16);
}

TEST(Gravity, Wgs84NormalGravityKnownValues) {
  // NIMA TR8350.2 Table 3.4: γ_e and γ_p.
  EXPECT_NEAR(NormalGravityWgs84_ms2(0.0), 9.7803253359, 1e-10);
  EXPECT_NEAR(NormalGravityWgs84_ms2(90.0), 9.8321849378, 1e-9);
  EXPECT_NEAR(NormalGravityWgs84_ms2(-90.0), 9.8321849378, 1e-9);
  // Free-air gradient near the surface is about −3.086e-6 (m/s²)/m.
  const double dg = NormalGravityWgs84_ms2(45.0, 1000.0) - NormalGravityWgs84_ms2(45.0);
  EXPECT_NEAR(dg, -3.086e-3, 0.005e-3);
}

TEST(Enums, StringRoundTrips) {
  EXPECT_EQ(ModelKindFromString("quadratic"), ModelKind::kQuadratic);
  EXPECT_EQ(ModelKindFromString("cubic"), std::nullopt);
  EXPECT_EQ(ForceUnitFromString("g"), ForceUnit::kStandardGravity);
  EXPECT_EQ(ToString(ForceUnit::kMetersPerSecond2), "m/s2");
}

}  // namespace
}  // namespace accelcal
