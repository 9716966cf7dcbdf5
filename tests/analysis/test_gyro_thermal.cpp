// The gyroscope's offsets over temperature (gyro_thermal.hpp): exact recovery, the coverage of
// their uncertainty and the degree chosen, over Monte Carlo draws of the still means; each
// sample's temperature from the logs.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "accelcal/error.hpp"
#include "accelcal/simulate.hpp"
#include "analysis/gyro_thermal.hpp"

namespace accelcal::internal {
namespace {

// 36 still positions (Yang's 18 orientations twice) through a ramp of 10 to 45 degC, each
// mean over 500 samples of 0.004 rad/s noise; offsets 0.01, -0.02, 0.005 rad/s at 25 degC moving
// b1 per K (and b2 per K^2), a g-sensitivity G.
struct Ramp {
  std::vector<GyroStill> stills;
  std::vector<double> t_c;
};
Ramp MakeRamp(const Vec3& b1, const Vec3& b2, const Mat33& G, std::mt19937_64* rng) {
  std::vector<Vec3> dirs = Yang18Directions();
  const std::vector<Vec3> again = dirs;
  dirs.insert(dirs.end(), again.begin(), again.end());
  std::normal_distribution<double> normal;
  const Vec3 sigma = Vec3::Constant(0.004 / std::sqrt(500.0));
  Ramp r;
  for (std::size_t k = 0; k < dirs.size(); ++k) {
    const double t = 10 + 35 * static_cast<double>(k) / static_cast<double>(dirs.size() - 1);
    const double dT = t - 25;
    const Vec3 f = 9.81 * dirs[k];
    Vec3 mean = Vec3(0.01, -0.02, 0.005) + b1 * dT + b2 * dT * dT + G * f;
    if (rng != nullptr) {
      for (int a = 0; a < 3; ++a) mean(a) += sigma(a) * normal(*rng);
    }
    r.stills.push_back({mean, sigma, f});
    r.t_c.push_back(t);
  }
  return r;
}

const Vec3 kB1(3e-4, -2e-4, 1.5e-4);

TEST(GyroThermal, NoiseFreeMeansGiveTheCoefficients) {
  const Vec3 b2(2e-6, -1e-6, 3e-6);
  Mat33 G;
  G << 1e-4, -2e-4, 0, 3e-4, 1e-4, -1e-4, 0, 2e-4, -3e-4;
  const Ramp r = MakeRamp(kB1, b2, G, nullptr);
  GyroThermalOptions options;
  options.degree = 2;
  options.t_ref_c = 25;
  const GyroThermal fit = FitGyroThermal(r.stills, r.t_c, options, true);
  ASSERT_EQ(fit.bias.degree(), 2);
  EXPECT_LT((fit.bias.coefficients[0] - kB1).norm(), 1e-12);
  EXPECT_LT((fit.bias.coefficients[1] - b2).norm(), 1e-14);
  EXPECT_EQ(fit.range_c, std::pair(10.0, 45.0));
  // Another T_ref: the same polynomial about another point.
  options.t_ref_c = 40;
  const GyroThermal moved = FitGyroThermal(r.stills, r.t_c, options, true);
  EXPECT_LT((moved.bias.coefficients[0] - (kB1 + 2 * 15 * b2)).norm(), 1e-12);
  EXPECT_NEAR(moved.bias.OffsetChange(25)(0), -(kB1(0) * 15 + b2(0) * 225), 1e-12);
  // The g-sensitivity left out of a fit that should have it biases the slope; the residuals say
  // so (scatter ratio 10, and the covariance inflated by it).
  const GyroThermal without = FitGyroThermal(r.stills, r.t_c, options, false);
  EXPECT_GT(without.scatter_ratio, 5);
}

// 400 noisy ramps: the 1 sigma intervals of b_1 cover the truth 68 % of the time (the
// covariance is inflated by the scatter ratio when it exceeds 1, which adds about a point), and
// the chosen degree is 1 for a linear change, 0 for none, in nearly every draw.
TEST(GyroThermal, MonteCarloCoverageAndDegree) {
  std::mt19937_64 rng(2021);
  const int runs = 400;
  int covered = 0, total = 0, chose_one = 0, chose_zero_when_none = 0;
  GyroThermalOptions given;
  given.degree = 1;
  given.t_ref_c = 27.5;
  GyroThermalOptions chosen;
  chosen.t_ref_c = 27.5;
  for (int run = 0; run < runs; ++run) {
    const Ramp r = MakeRamp(kB1, Vec3::Zero(), Mat33::Zero(), &rng);
    const GyroThermal fit = FitGyroThermal(r.stills, r.t_c, given, true);
    for (int a = 0; a < 3; ++a) {
      const double z =
          (fit.bias.coefficients[0](a) - kB1(a)) / std::sqrt(fit.bias.covariance(a, a));
      covered += std::abs(z) <= 1;
      ++total;
    }
    chose_one += FitGyroThermal(r.stills, r.t_c, chosen, true).bias.degree() == 1;
    const Ramp flat = MakeRamp(Vec3::Zero(), Vec3::Zero(), Mat33::Zero(), &rng);
    chose_zero_when_none += FitGyroThermal(flat.stills, flat.t_c, chosen, true).bias.degree() == 0;
  }
  const double coverage = static_cast<double>(covered) / total;
  // 1200 intervals: the binomial standard error of 68 % is 1.3 %; 3 of them either side.
  EXPECT_NEAR(coverage, 0.69, 0.04) << coverage;
  EXPECT_GE(chose_one, runs - 4);
  // Degree 1 for no change needs both the held-out improvement (5 %) and the Wald test (5 %).
  EXPECT_GE(chose_zero_when_none, runs * 95 / 100) << chose_zero_when_none;
}

// Found by a hostile test: a gyroscope whose die runs warmer than the accelerometer's, whose T_ref
// was outside the gyro's range, wrote a file its readers refused. T_ref moves to the stills' mean.
TEST(GyroThermal, TRefOutsideTheStillsTemperaturesMovesToTheirMean) {
  const Ramp r = MakeRamp(kB1, Vec3::Zero(), Mat33::Zero(), nullptr);
  GyroThermalOptions options;
  options.t_ref_c = 60;
  const GyroThermal fit = FitGyroThermal(r.stills, r.t_c, options, true);
  EXPECT_DOUBLE_EQ(fit.bias.t_ref_c, 27.5);
  EXPECT_NE(fit.reason.find("as 60 degC lies outside them"), std::string::npos) << fit.reason;
  EXPECT_LT((fit.bias.coefficients.at(0) - kB1).norm(), 1e-12);
  // Degree 0 given: the still means' scatter about constant offsets, not a placeholder.
  options.degree = 0;
  EXPECT_GT(FitGyroThermal(r.stills, r.t_c, options, true).scatter_ratio, 10);  // 13.8
}

TEST(GyroThermal, WhatDoesNotDetermineIt) {
  Ramp r = MakeRamp(kB1, Vec3::Zero(), Mat33::Zero(), nullptr);
  GyroThermalOptions options;
  options.t_ref_c = 25;
  // A span under 1 K: no change can be seen; asked for, an error; chosen, degree 0 and why.
  for (double& t : r.t_c) t = 25 + 0.5 * (t - 10) / 35;
  EXPECT_EQ(FitGyroThermal(r.stills, r.t_c, options, true).bias.degree(), 0);
  EXPECT_NE(FitGyroThermal(r.stills, r.t_c, options, true).reason.find("too narrow a span"),
            std::string::npos);
  options.degree = 1;
  EXPECT_THROW(FitGyroThermal(r.stills, r.t_c, options, true), DataError);
  // Two temperatures cannot carry a quadratic.
  for (std::size_t k = 0; k < r.t_c.size(); ++k) r.t_c[k] = k < 18 ? 10.0 : 40.0;
  options.degree = 2;
  EXPECT_THROW(FitGyroThermal(r.stills, r.t_c, options, true), DataError);
  options.degree = 1;
  EXPECT_NO_THROW(FitGyroThermal(r.stills, r.t_c, options, true));
  options.degree = 4;
  EXPECT_THROW(FitGyroThermal(r.stills, r.t_c, options, true), std::invalid_argument);
}

TEST(GyroThermal, EachSampleTakesTheNearestTemperatures) {
  RawLog gyro, accel;
  gyro.samples.assign(6, Vec3::Zero());
  accel.samples.assign(6, Vec3::Zero());
  gyro.source = "g.csv";
  accel.source = "a.csv";
  EXPECT_THROW(GyroSampleTemperatures(gyro, accel), DataError);
  const double nan = std::nan("");
  accel.temperature_c = {nan, 20, nan, nan, 26, nan};
  EXPECT_EQ(GyroSampleTemperatures(gyro, accel), (std::vector<double>{20, 20, 22, 24, 26, 26}));
  // The gyro's own when it has any, its gaps filled from its own (a hostile test found them
  // filled from the accelerometer's, 10 K cooler on its board).
  gyro.temperature_c = {30, nan, nan, 36, nan, nan};
  EXPECT_EQ(GyroSampleTemperatures(gyro, accel), (std::vector<double>{30, 32, 34, 36, 36, 36}));
}

}  // namespace
}  // namespace accelcal::internal
