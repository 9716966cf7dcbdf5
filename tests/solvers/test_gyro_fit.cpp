// The gyroscope's two-stage fit (solvers/gyro_fit.hpp): the motion residual's Jacobians against
// the finite-difference checker, and exact recovery from a noise-free simulated recording.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "accelcal/simulate.hpp"
#include "solvers/gyro_fit.hpp"
#include "solvers/solver_common.hpp"
#include "support/jacobian_check.hpp"

namespace accelcal::internal {
namespace {

constexpr double kG = kYang2012Gravity_ms2;

GyroParameters XsensLikeGyro(bool g_sensitive) {
  GyroParameters g;
  g.K << 4778, 12, -8, -15, 4758, 20, 9, -11, 4766;  // counts per rad/s
  g.bias = Vec3(32740, 32810, 32650);
  if (g_sensitive) g.G << 1.5, -0.4, 0.2, 0.3, -1.1, 0.6, -0.2, 0.5, 0.9;  // counts per m/s²
  return g;
}

// The fit's data from a simulated recording of Yang's 18 positions, the positions' directions
// and specific forces the truth's (the accelerometer's part is not under test here).
GyroFitData FromSimulation(const GyroParameters& truth, GyroModelKind model, double sigma_raw) {
  RawLogSimulation options;
  options.static_s = 2.0;
  options.transition_s = 3.0;
  options.sigma_raw_per_sample.setZero();
  GyroSimulation gyro;
  gyro.truth = truth;
  gyro.sigma_raw_per_sample = Vec3::Constant(sigma_raw);
  const std::vector<Vec3> directions = Yang18Directions();
  const SimulatedImuLog log = SimulateImuLog(Yang2012Truth(), kG, directions, options, gyro);
  const std::size_t still = 200, turn = 300;
  GyroFitData data;
  data.model = model;
  data.noise_sigma_raw = Vec3::Constant(sigma_raw > 0 ? sigma_raw : 1.0);
  for (std::size_t i = 0; i < directions.size(); ++i) {
    const std::size_t begin = i * (still + turn - 1);
    Vec3 sum = Vec3::Zero();
    for (std::size_t k = begin; k < begin + still; ++k) sum += log.gyro[k];
    data.directions.push_back(directions[i].normalized());
    data.stills.push_back({sum / static_cast<double>(still),
                           data.noise_sigma_raw / std::sqrt(static_cast<double>(still)),
                           kG * data.directions.back(), i});
    if (i + 1 == directions.size()) break;
    GyroMotion m;
    m.from = i;
    m.to = i + 1;
    for (std::size_t k = begin + still - 1; k <= begin + still - 1 + turn; ++k) {
      m.t_s.push_back(log.time_s[k]);
      m.raw.push_back(log.gyro[k]);
      m.f.push_back(kG * log.direction[k]);
    }
    data.motions.push_back(m);
  }
  return data;
}

// The motions are shared between copies of the data, yet each copy keeps its own list: a motion
// added to one after the copy is not in the other.
TEST(GyroFit, CopiedDataKeepTheirOwnMotions) {
  GyroFitData a;
  GyroMotion m;
  m.from = 0, m.to = 1;
  m.t_s = {0.0, 0.01};
  a.motions.push_back(m);
  const GyroFitData b = a;
  EXPECT_EQ(&a.motions[0], &b.motions[0]);  // one copy of the samples
  m.from = 1, m.to = 2;
  a.motions.push_back(m);
  ASSERT_EQ(a.motions.size(), 2u);
  ASSERT_EQ(b.motions.size(), 1u);
  EXPECT_EQ(b.motions[0].to, 1u);
  EXPECT_EQ(a.motions[1].to, 2u);
  GyroFitData c = b;
  c.motions.push_back(m);
  EXPECT_EQ(b.motions.size(), 1u);
  EXPECT_EQ(c.motions.size(), 2u);
}

TEST(GyroFit, MotionResidualJacobiansMatchFiniteDifferences) {
  for (GyroModelKind model : {GyroModelKind::kLinear, GyroModelKind::kGSensitive}) {
    const GyroParameters truth = XsensLikeGyro(model == GyroModelKind::kGSensitive);
    const GyroFitData data = FromSimulation(truth, model, 0.0);
    // Away from the solution, so that the residual and every term of its Jacobians are not zero.
    GyroParameters params = truth;
    params.K *= 1.02;
    params.K(0, 1) += 30;
    params.bias += Vec3(3, -2, 4);
    for (std::size_t k : {std::size_t{0}, std::size_t{7}, std::size_t{16}}) {
      const GyroMotion& m = data.motions[k];
      const std::optional<MotionWeight> w = WeighMotion(data, m, params);
      ASSERT_TRUE(w);
      const Vec3 c_i = data.directions[m.from], c_j = data.directions[m.to];
      Eigen::MatrixXd J_theta;
      Eigen::Matrix2d J_from, J_to;
      const Eigen::Vector2d r =
          MotionResidual(data, m, *w, params, c_i, c_j, &J_theta, &J_from, &J_to);
      EXPECT_GT(r.norm(), 1.0) << k;
      const auto by_theta = [&](const Eigen::VectorXd& t) -> Eigen::VectorXd {
        return MotionResidual(data, m, *w, UnpackGyro(t, model), c_i, c_j);
      };
      EXPECT_TRUE(testing::JacobianMatches(by_theta, Pack(params, model), J_theta)) << k;
      const auto by_from = [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
        return MotionResidual(data, m, *w, params, Retract(c_i, TangentBasis(c_i), d), c_j);
      };
      EXPECT_TRUE(testing::JacobianMatches(by_from, Eigen::Vector2d::Zero(), J_from)) << k;
      const auto by_to = [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
        return MotionResidual(data, m, *w, params, c_i, Retract(c_j, TangentBasis(c_j), d));
      };
      EXPECT_TRUE(testing::JacobianMatches(by_to, Eigen::Vector2d::Zero(), J_to)) << k;
    }
  }
}

TEST(GyroFit, NoiseFreeRecordingIsRecoveredExactly) {
  // From the closed-form start (the scale from the turned angles, no unit given), both models:
  // every parameter to 1e-9 of its size, every motion's direction to 1e-9 rad.
  for (GyroModelKind model : {GyroModelKind::kLinear, GyroModelKind::kGSensitive}) {
    const GyroParameters truth = XsensLikeGyro(model == GyroModelKind::kGSensitive);
    GyroFitData data = FromSimulation(truth, model, 0.0);
    const GyroParameters start = GyroStart(data, std::nullopt);
    data.weights = WeighMotions(data, start);
    EXPECT_NEAR(start.K(0, 0), 4767, 0.05 * 4767);  // within 5 % of the mean scale
    LeastSquaresOptions options;
    options.max_iterations = 30;
    options.step_tolerance = 1e-12;
    options.zero_residual_cost = 1e-18;
    const GyroFit fit = FitGyro(data, start, options);
    EXPECT_TRUE(fit.summary.converged()) << fit.summary.termination_message;
    const Eigen::VectorXd error = Pack(fit.params, model) - Pack(truth, model);
    EXPECT_LT((fit.params.K - truth.K).cwiseAbs().maxCoeff(), 1e-9 * 4778) << fit.params.K;
    EXPECT_LT((fit.params.bias - truth.bias).cwiseAbs().maxCoeff(), 1e-9 * 32810);
    EXPECT_LT((fit.params.G - truth.G).cwiseAbs().maxCoeff(), 1e-9 * 4778);
    for (const GyroMotion& m : data.motions) EXPECT_LT(MotionAngleError(data, m, fit.params), 1e-9);
  }
}

}  // namespace
}  // namespace accelcal::internal
