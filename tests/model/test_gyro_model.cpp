// gyro_model.hpp: the flat order round trips, the inverse model inverts the forward one, and the
// parameter Jacobian against the one finite-difference checker.
#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "accelcal/gyro_model.hpp"
#include "support/jacobian_check.hpp"

namespace accelcal {
namespace {

// A gyro reading counts (Xsens-like: about 4770 counts per rad/s around 32768), 1 % of
// misalignment, and a g-sensitivity of a few counts per m/s².
GyroParameters Typical(std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::normal_distribution<double> normal;
  GyroParameters p;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      p.K(i, j) = (i == j ? 4770.0 : 0.0) + 50.0 * normal(random);
      p.G(i, j) = 2.0 * normal(random);
    }
    p.bias(i) = 32768.0 + 100.0 * normal(random);
  }
  return p;
}

TEST(GyroModel, FlatOrderRoundTripsAndNamesEverySlotOnce) {
  for (GyroModelKind kind : {GyroModelKind::kLinear, GyroModelKind::kGSensitive}) {
    GyroParameters p = Typical(1);
    if (kind == GyroModelKind::kLinear) p.G.setZero();
    const Eigen::VectorXd theta = Pack(p, kind);
    ASSERT_EQ(theta.size(), NumGyroParameters(kind));
    const GyroParameters back = UnpackGyro(theta, kind);
    EXPECT_EQ(back.K, p.K);
    EXPECT_EQ(back.bias, p.bias);
    EXPECT_EQ(back.G, p.G);
    std::set<std::string> names;
    for (const GyroParameterSlot& s : GyroParameterSlots(kind)) names.insert(std::string(s.name));
    EXPECT_EQ(static_cast<int>(names.size()), NumGyroParameters(kind));
  }
  // Grouped by output axis: axis y's bias is the 11th entry (g-sensitive), the 8th (linear).
  EXPECT_EQ(GyroParameterSlots(GyroModelKind::kGSensitive)[10].name, "bg_y");
  EXPECT_EQ(GyroParameterSlots(GyroModelKind::kLinear)[7].name, "bg_y");
  EXPECT_EQ(GyroModelKindFromString("g-sensitive"), GyroModelKind::kGSensitive);
  EXPECT_EQ(GyroModelKindFromString("quadratic"), std::nullopt);
}

TEST(GyroModel, BodyRateInvertsTheForwardModel) {
  std::mt19937_64 random(2);
  std::normal_distribution<double> normal;
  for (int trial = 0; trial < 50; ++trial) {
    const GyroParameters p = Typical(static_cast<std::uint64_t>(trial));
    const Vec3 omega(normal(random), normal(random), normal(random));
    const Vec3 f = 9.81 * Vec3(normal(random), normal(random), normal(random)).normalized();
    const std::optional<Vec3> back = BodyRate(p, PredictRate(p, omega, f), f);
    ASSERT_TRUE(back);
    EXPECT_LT((*back - omega).norm(), 1e-12 * (1 + omega.norm()));
  }
  GyroParameters singular;
  singular.K.row(2).setZero();
  EXPECT_FALSE(BodyRate(singular, Vec3(1, 2, 3), Vec3(0, 0, 9.81)));
}

TEST(GyroModel, ParameterJacobianMatchesFiniteDifferences) {
  const Vec3 omega(0.3, -1.2, 0.7), f(1.0, -2.0, 9.5);
  for (GyroModelKind kind : {GyroModelKind::kLinear, GyroModelKind::kGSensitive}) {
    const Eigen::VectorXd theta = Pack(Typical(3), kind);
    const auto predict = [&](const Eigen::VectorXd& t) -> Eigen::VectorXd {
      return PredictRate(UnpackGyro(t, kind), omega, f);
    };
    EXPECT_TRUE(testing::JacobianMatches(predict, theta, GyroJacobianWrtParameters(omega, f, kind)))
        << ToString(kind);
  }
}

// A 1.5 s turn sampled at 200 Hz, its axis and speed changing (up to about 2 rad/s), with the
// specific force turning with it; the raw samples of `p` for it.
struct Motion {
  std::vector<double> t;
  std::vector<Vec3> omega, f, raw;
};
Motion Turn(const GyroParameters& p) {
  Motion m;
  for (int k = 0; k <= 300; ++k) {
    const double t = 0.005 * k + 1e-4 * std::sin(7.0 * k);  // a slightly irregular clock
    const Vec3 omega(1.2 * std::sin(2.0 * t), 0.8 + 0.5 * t, -0.6 * std::cos(3.0 * t));
    m.t.push_back(t);
    m.omega.push_back(omega);
    m.f.push_back(Vec3(3.0 * std::sin(t), -2.0 + t, 9.0 * std::cos(0.5 * t)));
    m.raw.push_back(PredictRate(p, omega, m.f.back()));
  }
  return m;
}

TEST(GyroModel, CalibratedRatesIntegrateAsTheTrueRates) {
  // The raw samples of a gyro with K_g, b_g and G, corrected by the same parameters, give the
  // rotation of the true rates: the same bits as IntegrateAngularRate on them, to round-off.
  const GyroParameters p = Typical(4);
  const Motion m = Turn(p);
  for (RateInterpolation rule :
       {RateInterpolation::kPiecewiseConstant, RateInterpolation::kTrapezoidal}) {
    const Mat33 R = IntegrateCalibratedRate(p, GyroModelKind::kGSensitive, m.t, m.raw, m.f, rule);
    const Mat33 truth = IntegrateAngularRate(m.t, m.omega, rule);
    EXPECT_LT((R - truth).norm(), 1e-12);
    EXPECT_GT(so3::Log(truth).norm(), 1.0);  // a real turn
  }
  // The identity model integrates the raw samples as rates. The step's exponential is taken from
  // its series below 1/4 rad (gyro_model.cpp), IntegrateAngularRate's from sines: each step's
  // differs by a few units in the last place, so the product by at most steps · 4 ε.
  const GyroParameters identity;
  const double steps = static_cast<double>(m.t.size() - 1);
  EXPECT_LT((IntegrateCalibratedRate(identity, GyroModelKind::kLinear, m.t, m.omega, m.f,
                                     RateInterpolation::kTrapezoidal) -
             IntegrateAngularRate(m.t, m.omega, RateInterpolation::kTrapezoidal))
                .norm(),
            steps * 4 * std::numeric_limits<double>::epsilon());
}

TEST(GyroModel, IntegrationJacobianMatchesFiniteDifferences) {
  // J in right-perturbation coordinates: Log(R(θ₀)ᵀ R(θ)) = J (θ − θ₀) to first order.
  const GyroParameters p = Typical(5);
  const Motion m = Turn(p);
  for (GyroModelKind kind : {GyroModelKind::kLinear, GyroModelKind::kGSensitive}) {
    for (RateInterpolation rule :
         {RateInterpolation::kPiecewiseConstant, RateInterpolation::kTrapezoidal}) {
      GyroParameters q = p;
      if (kind == GyroModelKind::kLinear) q.G.setZero();
      const Eigen::VectorXd theta = Pack(q, kind);
      Eigen::MatrixXd J;
      const Mat33 R0 = IntegrateCalibratedRate(q, kind, m.t, m.raw, m.f, rule, &J);
      const auto log = [&](const Eigen::VectorXd& t) -> Eigen::VectorXd {
        const Mat33 R = IntegrateCalibratedRate(UnpackGyro(t, kind), kind, m.t, m.raw, m.f, rule);
        return so3::Log(Mat33(R0.transpose() * R));
      };
      EXPECT_TRUE(testing::JacobianMatches(log, theta, J, 1e-6))
          << ToString(kind) << " " << static_cast<int>(rule);
    }
  }
}

// The covariance IntegrateCalibratedRate states for white noise of `sigma` on every raw sample
// (with `weights`, or none) against the right perturbations Log(Rᵀ R_noisy) of 4000 noisy draws.
// Each entry of a sample covariance of N draws has the standard deviation √((Σ_ii Σ_jj + Σ_ij²) /
// N); 5 of them bound it for all 9 entries. Returns the stated covariance.
Mat33 ExpectStatedNoiseMatchesDraws(const GyroParameters& p, const Motion& m,
                                    RateInterpolation rule, const Vec3& sigma,
                                    const std::vector<double>* weights, std::mt19937_64& random) {
  std::normal_distribution<double> normal;
  const GyroModelKind kind = GyroModelKind::kGSensitive;
  Mat33 stated;
  const Mat33 R =
      IntegrateCalibratedRate(p, kind, m.t, m.raw, m.f, rule, nullptr, &sigma, &stated, weights);
  constexpr int kDraws = 4000;
  Mat33 sum = Mat33::Zero();
  for (int draw = 0; draw < kDraws; ++draw) {
    std::vector<Vec3> noisy = m.raw;
    for (Vec3& r : noisy) {
      for (int i = 0; i < 3; ++i) r(i) += sigma(i) * normal(random);
    }
    const Vec3 e = so3::Log(
        Mat33(R.transpose() * IntegrateCalibratedRate(p, kind, m.t, noisy, m.f, rule, nullptr,
                                                      nullptr, nullptr, weights)));
    sum += e * e.transpose();
  }
  const Mat33 sampled = sum / kDraws;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const double sd =
          std::sqrt((stated(i, i) * stated(j, j) + stated(i, j) * stated(i, j)) / kDraws);
      EXPECT_NEAR(sampled(i, j), stated(i, j), 5 * sd)
          << i << "," << j << " rule " << static_cast<int>(rule);
    }
  }
  return stated;
}

// Step weights for `m` as a motion between two still spans weights them: rising over the first
// fifth of its steps, falling over the last fifth.
std::vector<double> Ramps(const Motion& m) {
  const std::size_t steps = m.t.size() - 1, ramp = steps / 5;
  std::vector<double> w(steps, 1.0);
  for (std::size_t k = 0; k < ramp; ++k) {
    w[k] = static_cast<double>(k + 1) / static_cast<double>(ramp + 1);
    w[steps - 1 - k] = w[k];
  }
  return w;
}

TEST(GyroModel, WeightedIntegrationJacobianAndNoiseMatchTheirChecks) {
  // Issue 47: a motion integrated from a still span's mean orientation weights its steps. The
  // weights scale each increment, its Jacobian and its samples' noise alike: the Jacobian against
  // the finite-difference checker, the noise against 4000 noisy draws (as unweighted above), and
  // weights of 1 are no weights, bit for bit.
  const GyroParameters p = Typical(5);
  const Motion m = Turn(p);
  const std::vector<double> w = Ramps(m), ones(m.t.size() - 1, 1.0);
  for (RateInterpolation rule :
       {RateInterpolation::kPiecewiseConstant, RateInterpolation::kTrapezoidal}) {
    const GyroModelKind kind = GyroModelKind::kGSensitive;
    Eigen::MatrixXd J;
    const Mat33 R0 =
        IntegrateCalibratedRate(p, kind, m.t, m.raw, m.f, rule, &J, nullptr, nullptr, &w);
    EXPECT_EQ(
        IntegrateCalibratedRate(p, kind, m.t, m.raw, m.f, rule, nullptr, nullptr, nullptr, &ones),
        IntegrateCalibratedRate(p, kind, m.t, m.raw, m.f, rule));
    // Not vacuous: the weights change the rotation.
    EXPECT_GT(
        so3::Log(Mat33(R0.transpose() * IntegrateCalibratedRate(p, kind, m.t, m.raw, m.f, rule)))
            .norm(),
        0.01);
    const auto log = [&](const Eigen::VectorXd& t) -> Eigen::VectorXd {
      const Mat33 R = IntegrateCalibratedRate(UnpackGyro(t, kind), kind, m.t, m.raw, m.f, rule,
                                              nullptr, nullptr, nullptr, &w);
      return so3::Log(Mat33(R0.transpose() * R));
    };
    EXPECT_TRUE(testing::JacobianMatches(log, Pack(p, kind), J, 1e-6)) << static_cast<int>(rule);
    const Vec3 sigma(40, 55, 70);
    std::mt19937_64 random(8);
    ExpectStatedNoiseMatchesDraws(p, m, rule, sigma, &w, random);
    // The turned angle's gradient with the same weights, against the checker too.
    const TurnedAngle turned = IntegrateTurnedAngle(p, kind, m.t, m.raw, m.f, rule, sigma, &w);
    const auto angle = [&](const Eigen::VectorXd& t) -> Eigen::VectorXd {
      return Eigen::VectorXd::Constant(1, IntegrateTurnedAngle(UnpackGyro(t, kind), kind, m.t,
                                                               m.raw, m.f, rule, Vec3::Zero(), &w)
                                              .angle_rad);
    };
    EXPECT_TRUE(testing::JacobianMatches(angle, Pack(p, kind), turned.gradient, 1e-6));
  }
  const std::vector<double> one_short(m.t.size() - 2, 1.0);  // a weight per step, not per sample
  EXPECT_THROW(IntegrateCalibratedRate(p, GyroModelKind::kLinear, m.t, m.raw, m.f,
                                       RateInterpolation::kTrapezoidal, nullptr, nullptr, nullptr,
                                       &one_short),
               std::invalid_argument);
}

TEST(GyroModel, PropagatedNoiseCovarianceMatchesMonteCarlo) {
  // White noise on every raw sample: the right perturbation Log(Rᵀ R_noisy) of 4000 draws has the
  // stated covariance. Each entry of a sample covariance of N draws has the standard deviation
  // √((Σ_ii Σ_jj + Σ_ij²) / N); 5 of them bound it for all 9 entries and both rules.
  const GyroParameters p = Typical(6);
  const Motion m = Turn(p);
  const Vec3 sigma(40, 55, 70);  // counts: about 0.01 rad/s per sample
  std::mt19937_64 random(7);
  for (RateInterpolation rule :
       {RateInterpolation::kPiecewiseConstant, RateInterpolation::kTrapezoidal}) {
    const Mat33 stated = ExpectStatedNoiseMatchesDraws(p, m, rule, sigma, nullptr, random);
    EXPECT_GT(stated.trace(), 1e-6);  // not vacuous: about 0.05° per axis
  }
}

TEST(GyroModel, AFullTurnAboutAFixedAxisTurnsThroughTwoPi) {
  // The rate about a fixed axis rising and falling linearly in time (a triangle whose corner is a
  // sample): the trapezoidal sum is the exact integral, 2π, where the rotation's angle |Log R| is
  // 0.
  const GyroParameters p = Typical(8);
  const Vec3 axis = Vec3(0.3, -0.5, 0.8).normalized();
  const double two_pi = 2 * std::acos(-1.0);
  const double peak = two_pi;  // a triangle 2 s long and 2π high: area 2π
  std::vector<double> t;
  std::vector<Vec3> raw, f;
  for (int k = 0; k <= 200; ++k) {
    const double tk = 0.01 * k;
    const double rate = peak * (tk <= 1.0 ? tk : 2.0 - tk);
    t.push_back(tk);
    f.push_back(9.8 * axis);
    raw.push_back(PredictRate(p, Vec3(rate * axis), f.back()));
  }
  const TurnedAngle turned = IntegrateTurnedAngle(p, GyroModelKind::kGSensitive, t, raw, f,
                                                  RateInterpolation::kTrapezoidal, Vec3::Zero());
  EXPECT_NEAR(turned.angle_rad, two_pi, 1e-12);
  EXPECT_LT(so3::Log(IntegrateCalibratedRate(p, GyroModelKind::kGSensitive, t, raw, f,
                                             RateInterpolation::kTrapezoidal))
                .norm(),
            1e-9);
  EXPECT_EQ(turned.noise_variance_rad2, 0.0);
}

TEST(GyroModel, TurnedAngleGradientMatchesFiniteDifferences) {
  const GyroParameters p = Typical(9);
  const Motion m = Turn(p);
  for (GyroModelKind kind : {GyroModelKind::kLinear, GyroModelKind::kGSensitive}) {
    for (RateInterpolation rule :
         {RateInterpolation::kPiecewiseConstant, RateInterpolation::kTrapezoidal}) {
      GyroParameters q = p;
      if (kind == GyroModelKind::kLinear) q.G.setZero();
      const TurnedAngle turned = IntegrateTurnedAngle(q, kind, m.t, m.raw, m.f, rule, Vec3::Zero());
      const auto angle = [&](const Eigen::VectorXd& t) -> Eigen::VectorXd {
        return Eigen::VectorXd::Constant(
            1, IntegrateTurnedAngle(UnpackGyro(t, kind), kind, m.t, m.raw, m.f, rule, Vec3::Zero())
                   .angle_rad);
      };
      EXPECT_TRUE(testing::JacobianMatches(angle, Pack(q, kind), turned.gradient, 1e-6))
          << ToString(kind) << " " << static_cast<int>(rule);
    }
  }
}

TEST(GyroModel, TurnedAngleNoiseMatchesMonteCarlo) {
  // The sample variance of N draws has the standard deviation √(2/N) of the variance; 5 of them.
  const GyroParameters p = Typical(10);
  const Motion m = Turn(p);
  const Vec3 sigma(40, 55, 70);
  std::mt19937_64 random(11);
  std::normal_distribution<double> normal;
  for (RateInterpolation rule :
       {RateInterpolation::kPiecewiseConstant, RateInterpolation::kTrapezoidal}) {
    const TurnedAngle stated =
        IntegrateTurnedAngle(p, GyroModelKind::kGSensitive, m.t, m.raw, m.f, rule, sigma);
    constexpr int kDraws = 4000;
    double sum = 0;
    for (int draw = 0; draw < kDraws; ++draw) {
      std::vector<Vec3> noisy = m.raw;
      for (Vec3& r : noisy) {
        for (int i = 0; i < 3; ++i) r(i) += sigma(i) * normal(random);
      }
      const double e =
          IntegrateTurnedAngle(p, GyroModelKind::kGSensitive, m.t, noisy, m.f, rule, sigma)
              .angle_rad -
          stated.angle_rad;
      sum += e * e;
    }
    EXPECT_NEAR(sum / kDraws, stated.noise_variance_rad2,
                5 * std::sqrt(2.0 / kDraws) * stated.noise_variance_rad2)
        << static_cast<int>(rule);
    EXPECT_GT(stated.noise_variance_rad2, 1e-7);  // not vacuous: about 0.05°
  }
}

TEST(GyroModel, IntegrationRefusesBadInput) {
  const Motion m = Turn(GyroParameters{});
  std::vector<double> t = m.t;
  t[5] = t[4];
  EXPECT_THROW(IntegrateCalibratedRate({}, GyroModelKind::kLinear, t, m.raw, m.f,
                                       RateInterpolation::kTrapezoidal),
               std::invalid_argument);
  GyroParameters singular;
  singular.K(1, 1) = 0;
  EXPECT_THROW(IntegrateCalibratedRate(singular, GyroModelKind::kLinear, m.t, m.raw, m.f,
                                       RateInterpolation::kTrapezoidal),
               std::invalid_argument);
  EXPECT_THROW(IntegrateCalibratedRate({}, GyroModelKind::kLinear, m.t, m.raw, {},
                                       RateInterpolation::kTrapezoidal),
               std::invalid_argument);
}

}  // namespace
}  // namespace accelcal
