// Calibration with known orientations (known_orientation.hpp, paper 003's general turntable case):
// exact recovery, the covariance against Monte Carlo, refusals, and imucal's Ferraris result.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "accelcal/error.hpp"
#include "accelcal/known_orientation.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/orientation_file.hpp"
#include "accelcal/positions.hpp"
#include "accelcal/simulate.hpp"
#include "support/paths.hpp"

namespace accelcal {
namespace {

constexpr double kG = 9.80665;

// A platform-frame device: scale factors 0.98-1.03 raw per m/s², paper 003 eq. (5) angles of
// 0.5-3 mrad, biases of 0.1-0.3 m/s² worth, squared terms of 1e-4 g/g².
ModelParameters PlatformDevice() {
  ModelParameters p;
  p.K << 1.02, 0.002, -0.0015, -0.001, 0.98, 0.003, 0.0025, -0.0005, 1.03;
  p.bias << 0.12, -0.3, 0.21;
  p.k2 << 1e-5, -2e-5, 1.5e-5;
  return p;
}

std::vector<Vec3> SixPositions() {
  return {Vec3::UnitX(),  -Vec3::UnitX(), Vec3::UnitY(),
          -Vec3::UnitY(), Vec3::UnitZ(),  -Vec3::UnitZ()};
}

TEST(KnownOrientation, SixAxisPositionsDetermineEveryParameterExactly) {
  // Noise-free readings of the six ±axis positions (plus two tilted ones, so that there are
  // residual degrees of freedom for the quadratic model): both models recovered to round-off.
  std::vector<Vec3> directions = SixPositions();
  directions.push_back(Vec3(1, 1, 1).normalized());
  directions.push_back(Vec3(-1, 2, -0.5).normalized());
  for (ModelKind model : {ModelKind::kLinear, ModelKind::kQuadratic}) {
    ModelParameters truth = PlatformDevice();
    if (model == ModelKind::kLinear) truth.k2.setZero();
    std::vector<Vec3> readings;
    for (const Vec3& c : directions) readings.push_back(PredictRaw(truth, Vec3(kG * c)));
    KnownOrientationOptions o;
    o.model = model;
    o.gravity = kG;
    const CalibrationResult r = CalibrateKnownOrientations(readings, directions, o);
    EXPECT_EQ(r.frame, Frame::kPlatform);
    EXPECT_EQ(r.summary.method, SolverMethod::kKnownOrientation);
    EXPECT_TRUE(r.summary.converged());
    EXPECT_LT((r.params.K - truth.K).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LT((r.params.bias - truth.bias).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LT((r.params.k2 - truth.k2).cwiseAbs().maxCoeff(), 1e-13);
    EXPECT_EQ(r.degrees_of_freedom, 3 * 8 - (model == ModelKind::kLinear ? 12 : 15));
    // Paper 003 eq. (5): the six angles read from T (unit rows).
    const Misalignment beta = MisalignmentOf(r.params.K, Frame::kPlatform);
    ASSERT_EQ(beta.rad.size(), 6);
    EXPECT_EQ(beta.names[0], "beta_xz");
    EXPECT_NEAR(beta.rad(0), truth.K(0, 1) / truth.K.row(0).norm(), 1e-12);
    EXPECT_NEAR(beta.rad(5), -truth.K(2, 1) / truth.K.row(2).norm(), 1e-12);
    // The inverse of the full-K quadratic model (Newton) returns the known specific force.
    for (const Vec3& c : directions) {
      const std::optional<Vec3> f = SpecificForce(r.params, PredictRaw(r.params, Vec3(kG * c)));
      ASSERT_TRUE(f.has_value());
      EXPECT_LT((*f - kG * c).norm(), 1e-12);
    }
  }
}

TEST(KnownOrientation, CovarianceMatchesTheScatterOfRepeatedCalibrations) {
  // 2000 calibrations of the six positions with 0.01 m/s²-equivalent noise per axis, known to
  // the fit: the standard deviation of every parameter matches the reported one (sampling error
  // of a standard deviation over 2000 runs: 1.6 %, so ±6 %), and the 1σ intervals cover the truth
  // 68.3 % ± 1.5 % of the time (2000 x 12 correlated entries).
  const ModelParameters truth = [] {
    ModelParameters p = PlatformDevice();
    p.k2.setZero();
    return p;
  }();
  const std::vector<Vec3> directions = SixPositions();
  const Vec3 sigma = Vec3::Constant(0.01);
  std::mt19937_64 random(7);
  std::normal_distribution<double> normal;
  KnownOrientationOptions o;
  o.gravity = kG;
  o.reading_sigmas.assign(directions.size(), sigma);
  o.outliers.policy = OutlierPolicy::kOff;  // the plain estimator's covariance
  const auto& slots = ParameterSlots(ModelKind::kLinear, Frame::kPlatform);
  const Eigen::VectorXd theta = Pack(truth, slots);
  Eigen::VectorXd sum2 = Eigen::VectorXd::Zero(theta.size());
  Eigen::VectorXd reported;
  int covered = 0, entries = 0;
  constexpr int kRuns = 2000;
  for (int run = 0; run < kRuns; ++run) {
    std::vector<Vec3> readings;
    for (const Vec3& c : directions) {
      readings.push_back(PredictRaw(truth, Vec3(kG * c)) +
                         Vec3(normal(random), normal(random), normal(random)).cwiseProduct(sigma));
    }
    const CalibrationResult r = CalibrateKnownOrientations(readings, directions, o);
    const Eigen::VectorXd e = Pack(r.params, slots) - theta;
    sum2 += e.cwiseAbs2();
    // The reported covariance before the scatter inflation: 6 positions leave 6 degrees of
    // freedom, and max(1, R²) inflates about half the runs, so compare with the uninflated one.
    const double inflation = std::max(1.0, r.scatter_ratio * r.scatter_ratio);
    reported = r.covariance.diagonal() / inflation;
    for (Eigen::Index i = 0; i < e.size(); ++i) {
      covered += std::abs(e(i)) <= std::sqrt(reported(i)) ? 1 : 0;
      ++entries;
    }
  }
  const Eigen::VectorXd observed = (sum2 / kRuns).cwiseSqrt();
  for (Eigen::Index i = 0; i < theta.size(); ++i) {
    EXPECT_NEAR(observed(i) / std::sqrt(reported(i)), 1.0, 0.06) << slots[i].name;
  }
  EXPECT_NEAR(static_cast<double>(covered) / entries, 0.683, 0.015);
}

// 24 known orientations spread over the sphere (fixed seed), and their noisy readings.
struct Turntable {
  std::vector<Vec3> directions, readings;
};
Turntable NoisyTurntable(const ModelParameters& device, double sigma, std::mt19937_64* random) {
  // Two distributions: one shared by both engines would hand a value it cached from the fixed
  // engine to the noise, the same in every run.
  std::normal_distribution<double> direction, noise;
  Turntable t;
  std::mt19937_64 fixed(3);
  for (int k = 0; k < 24; ++k) {
    t.directions.push_back(Vec3(direction(fixed), direction(fixed), direction(fixed)).normalized());
    t.readings.push_back(PredictRaw(device, Vec3(kG * t.directions.back())) +
                         sigma * Vec3(noise(*random), noise(*random), noise(*random)));
  }
  return t;
}

TEST(KnownOrientation, ExcludesAPositionThatDisagreesAndEqualsTheFitWithoutIt) {
  // Position 6 of 24 reads 0.2 m/s² off on y (20 sigma): a bumped fixture. The F test finds it,
  // leaves it out, and the result is the fit of the other 23.
  ModelParameters device = PlatformDevice();
  device.k2.setZero();
  std::mt19937_64 random(11);
  Turntable t = NoisyTurntable(device, 0.01, &random);
  t.readings[5] += Vec3(0.0, 0.2, 0.0);
  KnownOrientationOptions o;
  o.gravity = kG;
  const CalibrationResult r = CalibrateKnownOrientations(t.readings, t.directions, o);
  ASSERT_EQ(r.outliers.size(), 1u) << r.outlier_note;
  const OutlierFinding& found = r.outliers[0];
  EXPECT_EQ(found.position, 5);
  EXPECT_TRUE(found.excluded);
  EXPECT_EQ(found.statistic, OutlierStatistic::kFisherF);
  EXPECT_GT(found.t, found.threshold);
  EXPECT_EQ(found.degrees_of_freedom, 3 * 24 - 12 - 3);
  EXPECT_NEAR(found.normal_residual, 0.2, 0.05);
  EXPECT_NEAR(found.scatter, 0.01, 0.004);  // the fit without it: the noise, ±3 sampling sigma
  EXPECT_TRUE(r.excluded(5));
  EXPECT_EQ(r.degrees_of_freedom, 3 * 23 - 12);
  Turntable without = t;
  without.readings.erase(without.readings.begin() + 5);
  without.directions.erase(without.directions.begin() + 5);
  KnownOrientationOptions off = o;
  off.outliers.policy = OutlierPolicy::kOff;
  const CalibrationResult alone =
      CalibrateKnownOrientations(without.readings, without.directions, off);
  EXPECT_LT((r.params.K - alone.params.K).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_LT((r.params.bias - alone.params.bias).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_LT((r.covariance - alone.covariance).cwiseAbs().maxCoeff(),
            1e-12 * alone.covariance.cwiseAbs().maxCoeff());
  // Flagged only: every position stays in the fit.
  KnownOrientationOptions flag = o;
  flag.outliers.policy = OutlierPolicy::kFlag;
  const CalibrationResult flagged = CalibrateKnownOrientations(t.readings, t.directions, flag);
  ASSERT_EQ(flagged.outliers.size(), 1u);
  EXPECT_FALSE(flagged.outliers[0].excluded);
  EXPECT_EQ(flagged.degrees_of_freedom, 3 * 24 - 12);
  EXPECT_TRUE(CalibrateKnownOrientations(t.readings, t.directions, off).outliers.empty());
  // Held out: the excluded position is in no refit, and not in the RMS.
  KnownOrientationOptions crossval = o;
  crossval.cross_validate = true;
  const CalibrationResult v = CalibrateKnownOrientations(t.readings, t.directions, crossval);
  ASSERT_TRUE(v.crossval_rms.has_value()) << v.crossval_note;
  EXPECT_EQ(v.crossval_errors.size(), 24u);
  EXPECT_LT(*v.crossval_rms, 0.05);  // position 6's 0.2 m/s² would dominate it
}

TEST(KnownOrientation, FalseAlarmRateOnCleanDataIsTheChosenProbability) {
  // 2000 clean turntable calibrations at false_alarm_probability = 0.05: the share with any
  // position found discordant is at most 0.05 (Bonferroni over 24 exact F tests: about 0.049),
  // within 3 binomial sigma (0.015); a test that never fires fails the lower bound.
  ModelParameters device = PlatformDevice();
  device.k2.setZero();
  std::mt19937_64 random(12);
  KnownOrientationOptions o;
  o.gravity = kG;
  o.outliers.false_alarm_probability = 0.05;
  o.outliers.policy = OutlierPolicy::kFlag;
  constexpr int kRuns = 2000;
  int alarms = 0;
  for (int run = 0; run < kRuns; ++run) {
    const Turntable t = NoisyTurntable(device, 0.01, &random);
    alarms += CalibrateKnownOrientations(t.readings, t.directions, o).outliers.empty() ? 0 : 1;
  }
  const double rate = static_cast<double>(alarms) / kRuns;
  EXPECT_LE(rate, 0.05 + 3 * std::sqrt(0.05 * 0.95 / kRuns));
  EXPECT_GE(rate, 0.025);
  std::printf("known-orientation false alarms at 0.05: %.4f\n", rate);
}

TEST(KnownOrientation, TooFewPositionsToScreenSaySo) {
  // The six axis positions, linear model: ν = 6, so F has 3 and 3 degrees of freedom and the test
  // runs; five positions leave ν − 3 < 1.
  ModelParameters device = PlatformDevice();
  device.k2.setZero();
  std::vector<Vec3> readings;
  std::mt19937_64 random(5);
  std::normal_distribution<double> normal;
  for (const Vec3& c : SixPositions()) {
    readings.push_back(PredictRaw(device, Vec3(kG * c)) +
                       0.01 * Vec3(normal(random), normal(random), normal(random)));
  }
  KnownOrientationOptions o;
  o.gravity = kG;
  o.model = ModelKind::kQuadratic;  // 15 parameters: ν = 3 with six positions
  const CalibrationResult r = CalibrateKnownOrientations(readings, SixPositions(), o);
  EXPECT_TRUE(r.outliers.empty());
  EXPECT_EQ(r.outlier_note,
            "outlier screening needs at least 7 positions for the quadratic model, got 6");
  o.outliers.false_alarm_probability = 1.5;
  EXPECT_THROW(CalibrateKnownOrientations(readings, SixPositions(), o), std::invalid_argument);
}

TEST(KnownOrientation, RefusesWhatTheOrientationsCannotDetermine) {
  // Gravity never along z: K_iz is not determined.
  const std::vector<Vec3> flat = {Vec3::UnitX(), -Vec3::UnitX(), Vec3::UnitY(), -Vec3::UnitY(),
                                  Vec3(1, 1, 0).normalized()};
  std::vector<Vec3> readings;
  for (const Vec3& c : flat) readings.push_back(PredictRaw(PlatformDevice(), Vec3(kG * c)));
  KnownOrientationOptions o;
  o.gravity = kG;
  try {
    CalibrateKnownOrientations(readings, flat, o);
    ADD_FAILURE() << "no error";
  } catch (const DataError& e) {
    EXPECT_NE(std::string(e.what()).find("do not determine parameter K_xz"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(CalibrateKnownOrientations(readings, SixPositions(), o), std::invalid_argument);
  std::vector<Vec3> not_unit = flat;
  not_unit[0] *= 2.0;
  EXPECT_THROW(CalibrateKnownOrientations(readings, not_unit, o), std::invalid_argument);
  o.model = ModelKind::kQuadratic;
  const std::vector<Vec3> four(flat.begin(), flat.begin() + 4);
  readings.resize(4);
  try {
    CalibrateKnownOrientations(readings, four, o);
    ADD_FAILURE() << "no error";
  } catch (const DataError& e) {
    EXPECT_EQ(std::string(e.what()),
              "the quadratic model with known orientations needs at least 5 positions, got 4");
  }
}

std::string Slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(KnownOrientation, ReproducesImucalsFerrarisCalibration) {
  // imucal's Ferraris method on the same six holds (example_cal.json, g = 9.81): K_a R_a = U_d/(2g)
  // from the differences of the ± holds, b_a the mean of each axis' own pair. Unweighted least
  // squares with the known directions gives the same K exactly (the ± pairs make the regressors
  // of K orthogonal to the bias column) and b the mean of all three pair means per axis.
  const std::string dir = std::string(ACCELCAL_DATA_DIR) + "/imucal-ferraris/";
  ReadOptions read;
  read.kind = InputKind::kPositions;
  const InputData data = ReadInput(dir + "ferraris_raw_means.csv", read);
  ASSERT_EQ(data.positions.size(), 6u);
  std::vector<Vec3> means;
  for (const Position& p : data.positions) means.push_back(p.mean);
  const std::vector<Vec3> directions =
      ReadOrientations(dir + "ferraris_orientations.csv").directions;
  KnownOrientationOptions o;
  o.gravity = 9.81;
  const CalibrationResult r = CalibrateKnownOrientations(means, directions, o);  // unweighted
  const nlohmann::json imucal = nlohmann::json::parse(Slurp(dir + "example_cal.json"));
  Mat33 K_a, R_a;
  Vec3 b_a;
  for (int i = 0; i < 3; ++i) {
    b_a(i) = imucal["b_a"][i].get<double>();
    for (int j = 0; j < 3; ++j) {
      K_a(i, j) = imucal["K_a"][i][j].get<double>();
      R_a(i, j) = imucal["R_a"][i][j].get<double>();
    }
  }
  EXPECT_LT((r.params.K - K_a * R_a).cwiseAbs().maxCoeff(), 1e-9 * K_a.maxCoeff());
  for (int i = 0; i < 3; ++i) {
    // imucal's b_i is axis i's own pair mean; ours the mean of the three pairs.
    EXPECT_NEAR(0.5 * (means[2 * i](i) + means[2 * i + 1](i)), b_a(i), 1e-9) << i;
    double pair_means = 0;
    for (int j = 0; j < 3; ++j) pair_means += 0.5 * (means[2 * j](i) + means[2 * j + 1](i));
    EXPECT_NEAR(r.params.bias(i), pair_means / 3, 1e-9) << i;
  }
  // Corrected readings: the two differ only through b, by K⁻¹(b_a − b). The hand-placed holds
  // disagree on the bias by up to 26 counts (y axis pair means −46.5, −48.3, −73.0: the device
  // tilted the same way in both z holds), so the corrected readings differ by up to 0.04 m/s²
  // (measured 0.0396 on y).
  const Vec3 shift = r.params.K.inverse() * (b_a - r.params.bias);
  for (const Vec3& p : means) {
    const Vec3 ours = *SpecificForce(r.params, p);
    const Vec3 theirs = R_a.inverse() * K_a.inverse() * (p - b_a);
    EXPECT_LT((ours - theirs - shift).norm(), 1e-9);
    EXPECT_LT((ours - theirs).cwiseAbs().maxCoeff(), 0.045);
  }
  // The sample-noise weighting flags the disagreement: 62 times the scatter the samples explain.
  o.reading_sigmas = SigmasOfMeans(data.positions);
  const CalibrationResult weighted = CalibrateKnownOrientations(means, directions, o);
  EXPECT_GT(weighted.scatter_ratio, 30.0);
}

}  // namespace
}  // namespace accelcal
