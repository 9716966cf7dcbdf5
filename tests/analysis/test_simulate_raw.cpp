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
