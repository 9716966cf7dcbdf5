// The IEEE noise terms fitted to the Allan variance (noise_model.hpp): the estimates' correlation
// against its integral, known answers, and the coverage of the terms' intervals on simulated
// noise (noise_simulation.hpp).
#include "accelcal/noise_model.hpp"

#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "accelcal/noise_simulation.hpp"

namespace accelcal {
namespace {

// The coverage tests run their full count in the sanitized build too (about 75 s there): fewer
// logs could not hold the 93 % to its meaning (one miss in 40 is 2.5 %).

std::vector<AllanPoint> Octaves(int count, double tau0, std::uint64_t samples) {
  std::vector<AllanPoint> points;
  for (int j = 0; j < count; ++j) {
    AllanPoint p;
    p.m = std::uint64_t{1} << j;
    p.tau_s = tau0 * static_cast<double>(p.m);
    p.stride = 1;
    p.phase_points = samples + 1;
    p.terms = samples + 1 - 2 * p.m;
    points.push_back(p);
  }
  return points;
}

// References: the integral ∫ A_m A_m' S² dν normalised, on 2·10⁶ points in ln ν from 10⁻⁴/1024
// to ½ (numpy's trapezoid rule), for one term at a time. The white noise's first two agree with
// the correlation of 2000 simulated logs of 16384 samples (0.465 and 0.161, ± 0.02).
TEST(NoiseModel, CorrelationOfTheEstimatesIsTheIntegral) {
  struct Case {
    NoiseTerm term;
    std::array<double, 6> rho;  // (1,2) (1,4) (16,32) (256,512) (256,1024) (512,1024)
  };
  const Case cases[] = {
      {NoiseTerm::kWhite, {0.4629, 0.1806, 0.5298, 0.5303, 0.1875, 0.5303}},
      {NoiseTerm::kRandomWalk, {0.8271, 0.6003, 0.8875, 0.8877, 0.6760, 0.8877}},
      {NoiseTerm::kBiasInstability, {0.5976, 0.2442, 0.6890, 0.6894, 0.3094, 0.6894}},
      {NoiseTerm::kQuantization, {0.3238, 0.5354, 0.4002, 0.4000, 0.5143, 0.4000}},
  };
  const std::vector<AllanPoint> points = Octaves(11, 0.01, 1 << 20);
  const std::pair<int, int> pairs[] = {{0, 1}, {0, 2}, {4, 5}, {8, 9}, {8, 10}, {9, 10}};
  for (const Case& c : cases) {
    std::array<double, kNoiseTerms> squared{};
    squared[static_cast<std::size_t>(c.term)] = 1.0;
    const Eigen::MatrixXd rho = AllanCorrelation(points, squared);
    for (std::size_t k = 0; k < 6; ++k) {
      // The tolerance: the fast oscillation's mean taken over a period (noise_model.cpp), within
      // 0.0035 of the integral for these.
      EXPECT_NEAR(rho(pairs[k].first, pairs[k].second), c.rho[k], 0.005)
          << ToString(c.term) << " m " << points[std::size_t(pairs[k].first)].m << ", "
          << points[std::size_t(pairs[k].second)].m;
    }
    EXPECT_NEAR(rho(3, 3), 1.0, 0.0);
  }
}

TEST(NoiseModel, ExactVariancesGiveTheTermsBack) {
  // Each term dominant somewhere on 25 octaves from 10 ms (a long log at 100 Hz).
  const std::array<double, kNoiseTerms> truth = {1e-4, 1e-3, 2e-4, 3e-6, 5e-8};
  std::vector<AllanPoint> points = Octaves(25, 0.01, std::uint64_t{1} << 27);
  std::array<double, kNoiseTerms> squared;
  for (int t = 0; t < kNoiseTerms; ++t)
    squared[std::size_t(t)] = truth[std::size_t(t)] * truth[std::size_t(t)];
  for (AllanPoint& p : points) p.avar = NoiseModelAvar(squared, p.tau_s);
  const NoiseModelFit fit = FitNoiseModel(points);
  EXPECT_TRUE(fit.converged);
  for (int t = 0; t < kNoiseTerms; ++t) {
    const NoiseTermEstimate& e = fit.terms[std::size_t(t)];
    EXPECT_NEAR(e.value, truth[std::size_t(t)], 1e-9 * truth[std::size_t(t)])
        << ToString(NoiseTerm(t));
    EXPECT_TRUE(e.fitted && e.resolved) << ToString(NoiseTerm(t));
    EXPECT_LT(e.low, e.value);
    EXPECT_GT(e.high, e.value);
  }
  EXPECT_NEAR(fit.chi2, 0.0, 1e-12);
  EXPECT_EQ(fit.dof, 25 - 5);
  // A term not asked for is left out, and the others take its part.
  NoiseFitOptions without;
  without.terms[std::size_t(NoiseTerm::kRateRamp)] = false;
  const NoiseModelFit four = FitNoiseModel(points, without);
  EXPECT_FALSE(four.terms[std::size_t(NoiseTerm::kRateRamp)].fitted);
  EXPECT_GT(four.chi2, 1000.0);
}

TEST(NoiseModel, RefusesWhatItCannotFit) {
  std::vector<AllanPoint> points = Octaves(1, 0.01, 1000);
  points[0].avar = 1;
  EXPECT_THROW(FitNoiseModel(points), std::invalid_argument);
  points = Octaves(6, 0.01, 1000);
  for (AllanPoint& p : points) p.avar = 1.0 / static_cast<double>(p.m);
  for (double bad : {-1.0, std::nan(""), HUGE_VAL}) {
    std::vector<AllanPoint> copy = points;
    copy[2].avar = bad;
    EXPECT_THROW(FitNoiseModel(copy), std::invalid_argument) << bad;
  }
  NoiseFitOptions options;
  options.terms = {false, false, false, false, false};
  EXPECT_THROW(FitNoiseModel(points, options), std::invalid_argument);
  for (double c : {0.0, 1.0, -0.5, std::nan("")}) {
    options = NoiseFitOptions();
    options.confidence = c;
    EXPECT_THROW(FitNoiseModel(points, options), std::invalid_argument) << c;
  }
}

TEST(NoiseModel, ATermBelowZeroIsBoundedByTheAllanDeviationAlone) {
  // White noise whose long averages fall faster than 1/τ (a sensor that filters its output, or
  // anti-correlated samples): the fit puts the random walk below 0 beyond its interval, where
  // c + z σ_c is below 0 too and bounds nothing (the T265 rest's accelerometer y wrote an upper
  // bound of 0, which pins an estimator's bias for ever).
  std::vector<AllanPoint> points = Octaves(12, 0.01, std::uint64_t{1} << 20);
  for (AllanPoint& p : points) {
    p.avar = 1e-6 / p.tau_s * (p.m >= 64 ? 64.0 / static_cast<double>(p.m) : 1.0);
  }
  NoiseFitOptions two;  // white noise and random walk: the random walk takes the fall
  two.terms = {false, true, false, true, false};
  const NoiseModelFit fit = FitNoiseModel(points, two);
  const NoiseTermEstimate& k = fit.terms[std::size_t(NoiseTerm::kRandomWalk)];
  ASSERT_LT(k.z, -1.96);
  EXPECT_FALSE(k.resolved);
  // Every term adds a variance >= 0: K² τ/3 <= σ²(τ)'s upper limit at every τ, each limit at
  // 1 - 0.05/12 so that all twelve hold together.
  double bound2 = HUGE_VAL;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double high = AllanDeviationInterval(points[i].avar, fit.edf[i], 1 - 0.05 / 12).high;
    bound2 = std::min(bound2, high * high / (points[i].tau_s / 3));
  }
  EXPECT_GT(k.high, 0.0);
  EXPECT_DOUBLE_EQ(k.high, std::sqrt(bound2));
  // The same at another scale (the fit's power-of-4 scaling carries the bound exactly).
  for (AllanPoint& p : points) p.avar *= 1e40;
  EXPECT_DOUBLE_EQ(FitNoiseModel(points, two).terms[std::size_t(NoiseTerm::kRandomWalk)].high,
                   k.high * 1e20);
}

// Over `runs` simulated logs of `truth`, per term the fraction whose 95 % interval holds its
// true value (0 for a term absent: an interval from 0 holds it), and the fractions it lies below
// and above.
struct Covered {
  std::array<double, kNoiseTerms> inside{}, below{}, above{};
};

Covered Coverage(const std::array<double, kNoiseTerms>& truth, std::size_t samples, double tau0,
                 int runs, std::uint64_t first_seed) {
  Covered out;
  AllanOptions options;
  options.sample_period_s = tau0;
  for (int run = 0; run < runs; ++run) {
    const std::vector<double> y =
        SimulateNoise(truth, samples, tau0, first_seed + static_cast<std::uint64_t>(run));
    const NoiseModelFit fit = FitNoiseModel(AllanVariance(y, options));
    for (int t = 0; t < kNoiseTerms; ++t) {
      const NoiseTermEstimate& e = fit.terms[std::size_t(t)];
      const double v = truth[std::size_t(t)];
      out.inside[std::size_t(t)] += (e.low <= v && v <= e.high) ? 1.0 / runs : 0.0;
      out.below[std::size_t(t)] += v < e.low ? 1.0 / runs : 0.0;
      out.above[std::size_t(t)] += v > e.high ? 1.0 / runs : 0.0;
    }
  }
  return out;
}

void ExpectCoverage(const std::array<double, kNoiseTerms>& truth, std::size_t samples, double tau0,
                    int runs, std::uint64_t seed, const std::string& what) {
  const Covered covered = Coverage(truth, samples, tau0, runs, seed);
  for (int t = 0; t < kNoiseTerms; ++t) {
    // Issue 19: inside the 95 % interval in at least 93 % of the logs.
    EXPECT_GE(covered.inside[std::size_t(t)], 0.93) << what << ": " << ToString(NoiseTerm(t));
    // And not by erring to one side: each end is missed in 2.5 % of logs, 5 % is 2.8 standard
    // deviations of the count over 200 logs, 3.4 over 300.
    EXPECT_LE(covered.below[std::size_t(t)], 0.05) << what << ": " << ToString(NoiseTerm(t));
    EXPECT_LE(covered.above[std::size_t(t)], 0.05) << what << ": " << ToString(NoiseTerm(t));
  }
}

TEST(NoiseModel, IntervalsCoverWhiteNoiseAndRandomWalk) {
  // An accelerometer-like axis at 100 Hz for 22 minutes: 100 µg/√Hz, random walk 3 µg/√s.
  const double g = 9.80665;
  ExpectCoverage({0, 100e-6 * g, 0, 3e-6 * g, 0}, std::size_t{1} << 17, 0.01, 300, 1000,
                 "white + random walk");
}

TEST(NoiseModel, IntervalsCoverBiasInstability) {
  // A gyro-like axis at 200 Hz for 11 minutes: 0.01 °/s/√Hz, 10 °/h bias instability (the floor
  // from about 20 s), random walk 7 °/h/√h (rad/s throughout).
  const double deg = 3.14159265358979323846 / 180;
  ExpectCoverage({0, 0.01 * deg, 10.0 / 3600 * deg, 7.0 / 3600 / 60 * deg, 0}, std::size_t{1} << 17,
                 0.005, 200, 5000, "white + bias instability + random walk");
}

TEST(NoiseModel, IntervalsCoverARandomWalkUnderABiasInstability) {
  // At 100 Hz for 11 minutes, 100 µg/√Hz, 20 µg bias instability, random walk 8 µg/√s: only the
  // last octaves show the random walk, of a few degrees of freedom. From the standard error at
  // the estimate alone, the truth lay above its interval in 17 of these 300 logs (those whose
  // random walk came out near 0 weighted the long τ as quiet); now in 1.
  const double g = 9.80665;
  ExpectCoverage({0, 100e-6 * g, 20e-6 * g, 8e-6 * g, 0}, std::size_t{1} << 16, 0.01, 300, 7000,
                 "white + bias instability + random walk, 11 minutes");
}

TEST(NoiseModel, AnIntervalEndFollowsTheScatterAtThatEnd) {
  // One term alone, exactly a random walk: its σ_c scales with it (D with the term, ρ not at
  // all), σ_c(c') = c' σ_c / c. The upper end c' − c = z σ_c(c') is c / (1 − z/Z), Z = c / σ_c:
  // above c + z σ_c, which holds the truth less often than 97.5 % where Z is small. Where that
  // end lies beyond the Allan deviation's own bound (each point's upper limit at 1 − 0.05/n over
  // its avar at value 1), or there is none (Z ≤ z), that bound is the end.
  NoiseFitOptions alone;
  alone.terms = {false, false, false, true, false};
  const double z = 1.959963984540054;
  for (const int octaves : {5, 4, 3, 2}) {  // the bound from 3 down
    std::vector<AllanPoint> points = Octaves(octaves, 0.01, std::uint64_t{1} << (octaves + 1));
    for (AllanPoint& p : points) p.avar = 4e-10 * p.tau_s / 3;
    const NoiseModelFit fit = FitNoiseModel(points, alone);
    const NoiseTermEstimate k = fit.terms[std::size_t(NoiseTerm::kRandomWalk)];
    EXPECT_NEAR(k.value, 2e-5, 1e-12) << octaves;
    double bound2 = HUGE_VAL;
    for (std::size_t i = 0; i < points.size(); ++i) {
      const double high = AllanDeviationInterval(points[i].avar, fit.edf[i],
                                                 1 - 0.05 / static_cast<double>(points.size()))
                              .high;
      bound2 = std::min(bound2, high * high / (points[i].tau_s / 3));
    }
    const double c = k.value * k.value;
    const double score = k.z > z ? c / (1 - z / k.z) : HUGE_VAL;
    if (score < bound2) {
      // 10⁻³: where the search stops. With 4 and 5 octaves 1.88 c and 1.50 c, against the
      // Wald interval's 1.47 c and 1.33 c.
      EXPECT_NEAR(k.high * k.high / score, 1, 1e-3) << octaves << " octaves, Z " << k.z;
      EXPECT_GT(k.high * k.high, 1.02 * c * (1 + z / k.z)) << octaves << " octaves";
    } else {
      EXPECT_DOUBLE_EQ(k.high, std::sqrt(bound2)) << octaves << " octaves, Z " << k.z;
    }
  }
}

TEST(NoiseModel, AnUnresolvedTermIsBoundedNoHigherThanTheAllanDeviationAllows) {
  // Five-second logs (500 samples at 100 Hz, white noise and a random walk): the terms the log
  // does not resolve have c + z σ_c up to 2.4 times the bound the Allan deviation sets alone
  // (each point's upper limit at 1 − 0.05/n over the term's avar at value 1: every term adds a
  // variance ≥ 0). Their upper end is that bound, or their estimate where it lies beyond.
  const double g = 9.80665;
  int capped = 0;
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    AllanOptions options;
    options.sample_period_s = 0.01;
    const std::vector<AllanPoint> points =
        AllanVariance(SimulateNoise({0, 100e-6 * g, 0, 30e-6 * g, 0}, 500, 0.01, seed), options);
    const NoiseModelFit fit = FitNoiseModel(points);
    for (int t = 0; t < kNoiseTerms; ++t) {
      const NoiseTermEstimate& e = fit.terms[std::size_t(t)];
      if (e.resolved) continue;
      std::array<double, kNoiseTerms> unit{};
      unit[std::size_t(t)] = 1;
      double bound2 = HUGE_VAL;
      for (std::size_t i = 0; i < points.size(); ++i) {
        const double high = AllanDeviationInterval(points[i].avar, fit.edf[i],
                                                   1 - 0.05 / static_cast<double>(points.size()))
                                .high;
        bound2 = std::min(bound2, high * high / NoiseModelAvar(unit, points[i].tau_s));
      }
      const double bound = std::max(std::sqrt(bound2), e.value);
      EXPECT_LE(e.high, bound * (1 + 1e-12)) << "seed " << seed << " " << ToString(NoiseTerm(t));
      capped += e.high >= bound * (1 - 1e-12);
    }
  }
  EXPECT_GT(capped, 0);  // the bound is reached, not merely respected
}

TEST(NoiseModel, WithoutIntervalsTheEstimatesAreTheSame) {
  // calibrate's check of its rest asks for the terms' z alone: the same fit, no interval search.
  AllanOptions options;
  options.sample_period_s = 0.01;
  const double g = 9.80665;
  const std::vector<AllanPoint> points = AllanVariance(
      SimulateNoise({0, 100e-6 * g, 20e-6 * g, 30e-6 * g, 0}, 1 << 14, 0.01, 5), options);
  NoiseFitOptions bare;
  bare.intervals = false;
  const NoiseModelFit full = FitNoiseModel(points), fit = FitNoiseModel(points, bare);
  EXPECT_TRUE(fit.intervals.empty());
  EXPECT_EQ(full.intervals.size(), points.size());
  for (int t = 0; t < kNoiseTerms; ++t) {
    const NoiseTermEstimate &a = full.terms[std::size_t(t)], &b = fit.terms[std::size_t(t)];
    EXPECT_EQ(a.value, b.value) << t;
    EXPECT_EQ(a.z, b.z) << t;
    EXPECT_EQ(a.resolved, b.resolved) << t;
    EXPECT_EQ(a.low, b.low) << t;
    if (b.resolved) {  // the Wald end c + z σ_c, σ_c = c / Z
      const double c = b.value * b.value;
      EXPECT_NEAR(b.high * b.high / (c * (1 + 1.959963984540054 / b.z)), 1, 1e-12) << t;
    }
  }
}

}  // namespace
}  // namespace accelcal
