// The noise of still positions' means (position_noise.hpp): a filtered sensor's correlated
// samples, white noise, and the positions too short to batch.
#include "accelcal/position_noise.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <random>
#include <vector>

#include <gtest/gtest.h>

namespace accelcal {
namespace {

// `positions` still positions of `samples` each, one after another; axis a is an AR(1)
// x_t = ρ_a x_(t−1) + e_t, e_t ~ N(0, 1), started in its stationary distribution: the output of
// a sensor that low-passes its white noise. The variance of a mean of n samples is then
// LRV/n less O(1/n²), LRV = 1/(1 − ρ)², while the samples' own variance is 1/(1 − ρ²):
// σ/√n is low by √((1 + ρ)/(1 − ρ)) (4.4 at ρ = 0.9).
struct Log {
  RawLog raw;
  std::vector<Position> positions;
};

Log Correlated(const Vec3& rho, int positions, std::size_t samples, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  Log log;
  for (int k = 0; k < positions; ++k) {
    StaticInterval in;
    in.begin = log.raw.samples.size();
    Vec3 x;
    for (int a = 0; a < 3; ++a) x(a) = normal(rng) / std::sqrt(1 - rho(a) * rho(a));
    Vec3 sum = Vec3::Zero(), sum2 = Vec3::Zero();
    for (std::size_t i = 0; i < samples; ++i) {
      if (i > 0) {
        for (int a = 0; a < 3; ++a) x(a) = rho(a) * x(a) + normal(rng);
      }
      log.raw.samples.push_back(x);
      sum += x;
      sum2 += x.cwiseAbs2();
    }
    in.end = log.raw.samples.size();
    const double n = static_cast<double>(samples);
    in.mean = sum / n;
    in.std = ((sum2 - n * in.mean.cwiseAbs2()) / (n - 1)).cwiseSqrt();
    log.positions.push_back(PositionsFromIntervals({in}).front());
  }
  return log;
}

PositionNoise Measure(const Log& log) {
  std::vector<Vec3> variances;
  for (const Position& p : log.positions) variances.push_back(PositionMeanVariance(log.raw, p));
  return PoolPositionNoise(log.positions, variances);
}

TEST(PositionNoise, ACorrelatedSensorsMeansAreAsNoisyAsTheyScatter) {
  const Vec3 rho(0.0, 0.5, 0.9);
  const Log log = Correlated(rho, 64, 4096, 7);
  const PositionNoise noise = Measure(log);
  EXPECT_EQ(noise.batched, 64U);
  ASSERT_EQ(noise.sigmas.size(), 64U);
  for (int a = 0; a < 3; ++a) {
    const double lrv = 1 / ((1 - rho(a)) * (1 - rho(a)));
    // The batch means of 256 samples hold all but 2ρ/(256 (1 − ρ²)) of it (3.7 % at ρ = 0.9).
    const double expected = lrv * (1 - 2 * rho(a) / (256 * (1 - rho(a) * rho(a))));
    // One position's (1.4826 MAD)² of 16 batch means scatters by about 60 % (the MAD keeps 37 %
    // of their 15 degrees of freedom); the median of 64 by 1.25 × 60 % / 8 = 9.4 %: 3σ.
    EXPECT_NEAR(noise.per_sample_variance(a) / expected, 1, 0.28) << "axis " << a;
    // The samples' standard deviation over √n would have put it at 1/(1 − ρ²): 1.33 at
    // ρ = 0.5 against 4, 5.3 at ρ = 0.9 against 100.
    EXPECT_NEAR(noise.sigmas[5](a), std::sqrt(noise.per_sample_variance(a) / 4096), 1e-15);
  }
  // The mean's actual scatter over the positions (64 means: ± 18 % at 2σ of the variance).
  for (int a = 0; a < 3; ++a) {
    double s2 = 0, mean = 0;
    for (const Position& p : log.positions) mean += p.mean(a) / 64;
    for (const Position& p : log.positions) s2 += std::pow(p.mean(a) - mean, 2) / 63;
    const double predicted = noise.sigmas[0](a) * noise.sigmas[0](a);
    EXPECT_NEAR(s2 / predicted, 1, 0.45) << "axis " << a;  // both uncertain: 0.18 and 0.28, 3σ
  }
}

TEST(PositionNoise, APositionTooShortToBatchHasItsSamplesNoise) {
  Log log = Correlated(Vec3::Zero(), 3, 100, 11);  // 100 < 16 batches of 8
  const PositionNoise noise = Measure(log);
  EXPECT_EQ(noise.batched, 0U);
  for (int a = 0; a < 3; ++a) {
    std::vector<double> per_sample;
    for (const Position& p : log.positions) per_sample.push_back(std::pow((*p.std)(a), 2));
    std::sort(per_sample.begin(), per_sample.end());
    EXPECT_DOUBLE_EQ(noise.per_sample_variance(a), per_sample[1]);  // the median of three
  }
  // A position without its interval, or beyond the log, is refused.
  Position loose;
  EXPECT_THROW(PositionMeanVariance(log.raw, loose), std::invalid_argument);
  StaticInterval past = log.positions.back().interval.value();
  past.end += 1;
  Position beyond = PositionsFromIntervals({past}).front();
  EXPECT_THROW(PositionMeanVariance(log.raw, beyond), std::invalid_argument);
  EXPECT_THROW(PoolPositionNoise(log.positions, {}), std::invalid_argument);
}

TEST(PositionNoise, EachSessionIsPooledOnItsOwn) {
  // Two files of one sensor, the second 10 times noisier (or at another rate: a per-sample
  // variance is the density² times the rate): one pool over both gave the quiet session's
  // positions the median's noise, and a scatter ratio of 5.1 where each alone had 1.1.
  LoadedInput input;
  for (const double scale : {1.0, 10.0}) {
    Log log = Correlated(Vec3::Zero(), 8, 2048, scale == 1.0 ? 21 : 22);
    for (Vec3& x : log.raw.samples) x *= scale;
    LoadedFile file;
    file.path = scale == 1.0 ? "quiet.csv" : "noisy.csv";
    file.data.kind = InputKind::kRaw;
    file.data.raw = log.raw;
    file.detection.emplace();
    for (Position& p : log.positions) {
      StaticInterval in = *p.interval;
      in.std *= scale;
      in.mean *= scale;
      file.detection->intervals.push_back(in);
      input.positions.push_back(PositionsFromIntervals({in}).front());
    }
    input.files.push_back(file);
  }
  const std::optional<PositionNoise> noise = MeasurePositionNoise(input);
  ASSERT_TRUE(noise.has_value());
  ASSERT_EQ(noise->sigmas.size(), 16U);
  EXPECT_EQ(noise->batched, 16U);
  for (int a = 0; a < 3; ++a) {
    // White noise of 1 and of 10 a sample: the median of 8 positions' (1.4826 MAD)² of 16 batch
    // means scatters by 1.25 × 60 % / √8 = 27 %, so within ± 0.8 of it (3σ) on the variance.
    EXPECT_NEAR(noise->sigmas[0](a) * noise->sigmas[0](a) * 2048, 1, 0.8) << a;
    EXPECT_NEAR(noise->sigmas[8](a) * noise->sigmas[8](a) * 2048, 100, 80) << a;
    EXPECT_DOUBLE_EQ(noise->sigmas[0](a), noise->sigmas[7](a));
    EXPECT_DOUBLE_EQ(noise->sigmas[8](a), noise->sigmas[15](a));
  }
  // A positions file among them: its own columns give its noise (SigmasOfMeans).
  input.files[1].data.kind = InputKind::kPositions;
  EXPECT_FALSE(MeasurePositionNoise(input).has_value());
}

TEST(PositionNoise, AMeanOfReadingsThatDoNotDitherKeepsItsRoundingError) {
  // Issue 47: readings rounded to a step ten times their noise (a 12-bit part, a log written with
  // 2 decimals) round the same way nearly every time, so each mean is off its true value by up
  // to half a step whatever the number of samples: 40 positions of 2048 samples, true values
  // spread over the steps, noise 0.1 step. Each mean's σ must cover that error (q/√12 = 0.29
  // step, not the flicker's 0.1/√2048). The readings' variance is below q²/12, so the floor
  // takes their noise before rounding as 0 and is q²/12, where a noise of 0.1 step does dither
  // the error down a little: its mean square over the true value's place is Σ_k q²/(2π²k²)
  // exp(−4π²k²σ²/q²) = 0.0369 q², an RMS of 0.192 step, so the errors' RMS over the σ is 0.665
  // (the RMS of 120 errors has a relative standard error of about 6 %): within 0.55-0.8.
  std::mt19937_64 rng(47);
  std::normal_distribution<double> normal(0.0, 0.1);
  std::uniform_real_distribution<double> place(0.0, 1.0);
  LoadedInput input;
  LoadedFile file;
  file.path = "quantised.csv";
  file.data.kind = InputKind::kRaw;
  file.detection.emplace();
  std::vector<Vec3> truth;
  for (int k = 0; k < 40; ++k) {
    const Vec3 value(100 + place(rng), -50 + place(rng), 7 + place(rng));
    truth.push_back(value);
    StaticInterval in;
    in.begin = file.data.raw.samples.size();
    Vec3 sum = Vec3::Zero(), sum2 = Vec3::Zero();
    for (int i = 0; i < 2048; ++i) {
      Vec3 x;
      for (int a = 0; a < 3; ++a) x(a) = std::round(value(a) + normal(rng));
      file.data.raw.samples.push_back(x);
      sum += x;
      sum2 += x.cwiseAbs2();
    }
    in.end = file.data.raw.samples.size();
    in.mean = sum / 2048.0;
    in.std = ((sum2 - 2048.0 * in.mean.cwiseAbs2()) / 2047.0).cwiseSqrt();
    file.detection->intervals.push_back(in);
    input.positions.push_back(PositionsFromIntervals({in}).front());
  }
  file.detection->quantisation_step = Vec3::Ones();
  input.files.push_back(file);
  const std::optional<PositionNoise> noise = MeasurePositionNoise(input);
  ASSERT_TRUE(noise.has_value());
  double sum_ratio2 = 0;
  for (std::size_t k = 0; k < truth.size(); ++k) {
    for (int a = 0; a < 3; ++a) {
      EXPECT_GE(noise->sigmas[k](a), 0.8 / std::sqrt(12.0)) << k << " " << a;
      const double e = input.positions[k].mean(a) - truth[k](a);
      sum_ratio2 += e * e / (noise->sigmas[k](a) * noise->sigmas[k](a));
    }
  }
  const double rms_ratio = std::sqrt(sum_ratio2 / (3.0 * static_cast<double>(truth.size())));
  EXPECT_GT(rms_ratio, 0.55);
  EXPECT_LT(rms_ratio, 0.8);
}

}  // namespace
}  // namespace accelcal
