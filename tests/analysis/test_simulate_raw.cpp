// The raw-log simulator: what detection and calibration see on a recording with known truth.
#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "accelcal/calibrate.hpp"
#include "accelcal/design.hpp"
#include "accelcal/positions.hpp"
#include "accelcal/simulate.hpp"
#include "accelcal/static_detection.hpp"

namespace accelcal {
namespace {

constexpr double kG = kYang2012Gravity_ms2;

TEST(SimulateRawLog, DetectionAndCalibrationRecoverTheTruth) {
  // Paper 000 §5 as a recording: Table-3 device, Table 2's 18 positions, 60 s each at 100 Hz with
  // 100 µg per sample (10 µg/√Hz), 4-s turns between them.
  const ModelParameters truth = Yang2012Truth();
  RawLogSimulation sim;
  for (int i = 0; i < 3; ++i) sim.sigma_raw_per_sample(i) = truth.K.row(i).norm() * 100e-6 * kG;
  sim.seed = 3;
  const std::vector<Vec3> dirs = Yang18Directions();
  const SimulatedLog simulated = SimulateRawLog(truth, kG, dirs, sim);
  ASSERT_EQ(simulated.samples.size(), 18u * 6000u + 17u * 399u);
  // The turns are smooth: the direction moves at most 1.5·angle/T per second (smooth-step
  // profile), ≤ 1.5·π/400 = 0.012 rad per sample here, so consecutive samples differ by at most
  // 0.012·|K|·g plus noise; 0.02·|K|·g would catch a jump from one position to the next.
  double largest_step = 0;
  for (std::size_t i = 1; i < simulated.samples.size(); ++i) {
    largest_step = std::max(
        largest_step, (simulated.samples[i] - simulated.samples[i - 1]).lpNorm<Eigen::Infinity>());
  }
  EXPECT_LT(largest_step, 0.02 * truth.K.rowwise().norm().maxCoeff() * kG);
  RawLog log;
  log.samples = simulated.samples;
  log.time_s = simulated.time_s;
  log.rate_hz = sim.rate_hz;
  const StaticDetectionResult detected = DetectStaticIntervals(log, StaticDetectionOptions{});
  ASSERT_EQ(detected.intervals.size(), 18u);
  const std::vector<Position> positions = PositionsFromIntervals(detected.intervals);
  CalibrationOptions o;
  o.model = ModelKind::kQuadratic;
  o.gravity = kG;
  o.reading_sigmas = SigmasOfMeans(positions);
  ASSERT_EQ(o.reading_sigmas.size(), 18u);
  const CalibrationResult r = Calibrate(Means(positions), o);
  ASSERT_TRUE(r.summary.converged());
  // Every parameter within 4.5 of its reported standard deviations of the truth (12 parameters:
  // a 4.5σ excursion has probability 1e-4), and the interval noise explains the scatter (R ≈ 1:
  // the detected intervals hold only white noise; a 1-σ band of √(2/6) around 1, 3 of those).
  const Eigen::VectorXd error = Pack(r.params, o.model) - Pack(truth, o.model);
  for (Eigen::Index i = 0; i < error.size(); ++i) {
    EXPECT_LT(std::abs(error(i)), 4.5 * std::sqrt(r.covariance(i, i)))
        << ParameterSlots(o.model)[static_cast<std::size_t>(i)].name;
  }
  EXPECT_NEAR(r.scatter_ratio, 1.0, 3.0 * std::sqrt(2.0 / 6.0));
}

}  // namespace
}  // namespace accelcal

namespace accelcal {
namespace {

GyroParameters XsensLikeGyro() {
  GyroParameters g;
  g.K << 4778, 12, -8, -15, 4758, 20, 9, -11, 4766;  // counts per rad/s, about 0.3 % cross-axis
  g.bias = Vec3(32740, 32810, 32650);
  g.G << 1.5, -0.4, 0.2, 0.3, -1.1, 0.6, -0.2, 0.5, 0.9;  // counts per m/s²
  return g;
}

TEST(SimulateImuLog, TheTurnsIntegrateExactlyToTheNextDirection) {
  // Noise-free: every sample is the model's, and the trapezoidal integration of the sampled rates
  // (true, or calibrated from the raw gyro with the truth) turns each still direction into the
  // next one to round-off, so a calibration can be checked for exact recovery.
  ModelParameters accel = Yang2012Truth();
  const std::vector<Vec3> directions = Yang18Directions();
  RawLogSimulation options;
  options.static_s = 1.0;
  options.transition_s = 2.5;  // 250 samples: the triangle's peak falls between two of them
  options.sigma_raw_per_sample.setZero();
  GyroSimulation gyro;
  gyro.truth = XsensLikeGyro();
  const SimulatedImuLog log =
      SimulateImuLog(accel, kYang2012Gravity_ms2, directions, options, gyro);
  ASSERT_EQ(static_cast<double>(log.time_s.size()),
            SimulatedSampleCount(directions.size(), options));
  for (std::size_t k = 0; k < log.time_s.size(); ++k) {
    const Vec3 f = kYang2012Gravity_ms2 * log.direction[k];
    ASSERT_EQ(log.accel[k], PredictRaw(accel, f));
    ASSERT_EQ(log.gyro[k], PredictRate(gyro.truth, log.omega_rad_s[k], f));
  }
  const std::size_t still = 100, turn = 250;
  double largest = 0;
  for (std::size_t j = 0; j + 1 < directions.size(); ++j) {
    const std::size_t from = j * (still + turn - 1) + still - 1, to = from + turn;
    const std::vector<double> t(log.time_s.begin() + from, log.time_s.begin() + to + 1);
    const std::vector<Vec3> omega(log.omega_rad_s.begin() + from, log.omega_rad_s.begin() + to + 1);
    const std::vector<Vec3> raw(log.gyro.begin() + from, log.gyro.begin() + to + 1);
    std::vector<Vec3> f;
    for (std::size_t k = from; k <= to; ++k) f.push_back(kYang2012Gravity_ms2 * log.direction[k]);
    const Mat33 R = IntegrateAngularRate(t, omega, RateInterpolation::kTrapezoidal);
    const Mat33 R_raw = IntegrateCalibratedRate(gyro.truth, GyroModelKind::kGSensitive, t, raw, f,
                                                RateInterpolation::kTrapezoidal);
    EXPECT_EQ(log.direction[from], directions[j].normalized());
    EXPECT_EQ(log.direction[to], directions[j + 1].normalized());
    largest = std::max({largest, (R.transpose() * log.direction[from] - log.direction[to]).norm(),
                        (R_raw.transpose() * log.direction[from] - log.direction[to]).norm()});
  }
  EXPECT_LT(largest, 1e-13);
}

TEST(SimulateImuLog, NoiseIsDrawnPerSampleAndDeterministic) {
  RawLogSimulation options;
  options.static_s = 2.0;
  options.transition_s = 1.0;
  options.sigma_raw_per_sample = Vec3(2, 3, 4);
  GyroSimulation gyro;
  gyro.truth = XsensLikeGyro();
  gyro.sigma_raw_per_sample = Vec3(5, 6, 7);
  const std::vector<Vec3> directions = Yang18Directions();
  const SimulatedImuLog a = SimulateImuLog(Yang2012Truth(), 9.8, directions, options, gyro);
  const SimulatedImuLog b = SimulateImuLog(Yang2012Truth(), 9.8, directions, options, gyro);
  EXPECT_EQ(a.gyro, b.gyro);
  EXPECT_EQ(a.accel, b.accel);
  // The gyro noise of the still samples: their scatter about the model, per axis.
  Vec3 sum2 = Vec3::Zero();
  int n = 0;
  for (std::size_t k = 0; k < a.time_s.size(); ++k) {
    if (!a.omega_rad_s[k].isZero(0)) continue;
    const Vec3 e =
        a.gyro[k] - PredictRate(gyro.truth, Vec3(Vec3::Zero()), Vec3(9.8 * a.direction[k]));
    sum2 += e.cwiseProduct(e);
    ++n;
  }
  ASSERT_GT(n, 3000);
  const Vec3 sigma = (sum2 / n).cwiseSqrt();
  // n draws: the sample σ is within 4 σ/√(2n) of the truth (about 5 %).
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(sigma(i), gyro.sigma_raw_per_sample(i),
                4 * gyro.sigma_raw_per_sample(i) / std::sqrt(2.0 * n));
  }
}

}  // namespace
}  // namespace accelcal
