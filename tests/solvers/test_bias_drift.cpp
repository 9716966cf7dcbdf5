// A bias that drifts within the session (bias_drift.hpp, drift_fit.hpp): the basis, the
// derivatives, exact recovery, the statistics of the joint fit and its covariance, the screening
// and the held-out validation with a drift.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "accelcal/bias_drift.hpp"
#include "accelcal/calibrate.hpp"
#include "accelcal/error.hpp"
#include "accelcal/frame.hpp"
#include "accelcal/model_selection.hpp"
#include "accelcal/simulate.hpp"
#include "solvers/drift_fit.hpp"
#include "support/jacobian_check.hpp"

namespace accelcal {
namespace {

constexpr double kG = kYang2012Gravity_ms2;

// Positions 20 s apart (10 s still, the middle its time), directions random.
std::vector<double> Times(int m) {
  std::vector<double> t;
  for (int k = 0; k < m; ++k) t.push_back(5.0 + 20.0 * k);
  return t;
}

// Paper 000 Table 3's device without its squared terms: the linear model holds.
ModelParameters LinearDevice() {
  ModelParameters device = Yang2012Truth();
  device.k2.setZero();
  return device;
}

BiasModel Spline(int knots) { return BiasModel{BiasModelKind::kSpline, knots}; }
BiasModel Linear() { return BiasModel{BiasModelKind::kLinear, 0}; }

CalibrationOptions Options(const BiasModel& bias, const std::vector<double>& times) {
  CalibrationOptions o;
  o.gravity = kG;
  o.bias_model = bias;
  o.position_times_s = times;
  return o;
}

// Readings of `truth` with the bias offset `drift(t)` added at each position's time, and white
// noise of sigma per axis (none when sigma is zero).
template <typename Drift>
std::vector<Vec3> DriftingReadings(const ModelParameters& truth, const std::vector<Vec3>& dirs,
                                   const std::vector<double>& times, const Drift& drift,
                                   const Vec3& sigma, std::uint64_t seed) {
  std::vector<Vec3> readings =
      sigma.isZero() ? SimulatePositions(truth, kG, dirs, Vec3::Constant(1e-300), seed)
                     : SimulatePositions(truth, kG, dirs, sigma, seed);
  for (std::size_t k = 0; k < readings.size(); ++k) readings[k] += drift(times[k]);
  return readings;
}

TEST(BiasModel, NamesRoundTripAndBadNamesAreRefused) {
  for (const char* name : {"constant", "linear", "spline:2", "spline:7", "spline:32"}) {
    const std::optional<BiasModel> m = BiasModelFromString(name);
    ASSERT_TRUE(m) << name;
    EXPECT_EQ(ToString(*m), name);
  }
  for (const char* bad : {"", "spline", "spline:", "spline:1", "spline:33", "spline:-3",
                          "spline:3x", "spline: 3", "linear:3", "constant:", "Linear", "auto"}) {
    EXPECT_FALSE(BiasModelFromString(bad)) << bad;
  }
  EXPECT_EQ(BiasModelFromString("spline:5")->functions(), 4);
  EXPECT_EQ(BiasModelFromString("linear")->functions(), 1);
  EXPECT_EQ(BiasModelFromString("constant")->functions(), 0);
}

TEST(BiasTimeBasis, IsZeroAtTheReferenceAndReproducesTheKnotBiases) {
  const std::vector<double> times = {10, 13, 40, 70, 100};
  const BiasTimeBasis linear = BiasTimeBasis::For(Linear(), times);
  EXPECT_DOUBLE_EQ(linear.t_ref_s, 46.6);
  EXPECT_DOUBLE_EQ(linear.Evaluate(106.6)(0), 1.0);  // one minute later: D per minute
  EXPECT_DOUBLE_EQ(linear.Evaluate(46.6)(0), 0.0);

  const BiasTimeBasis spline = BiasTimeBasis::For(Spline(4), times);
  ASSERT_EQ(spline.knots_s.size(), 4u);
  EXPECT_DOUBLE_EQ(spline.knots_s.front(), 10.0);
  EXPECT_DOUBLE_EQ(spline.knots_s[1], 40.0);
  EXPECT_DOUBLE_EQ(spline.knots_s.back(), 100.0);
  EXPECT_TRUE(spline.Evaluate(spline.t_ref_s).isZero(0));
  // Knot biases β_j: D_j = β_j − β_0 and b = b(t_ref) give b(τ_j) = β_j, linear between knots,
  // held outside.
  const Eigen::Vector4d beta(1.0, -2.0, 4.0, 3.0);
  BiasDrift drift;
  drift.basis = spline;
  drift.D.resize(3, 3);
  drift.D.setZero();
  for (int j = 1; j < 4; ++j) drift.D(0, j - 1) = beta(j) - beta(0);
  // b(t_ref) = Σ β_j B_j(t_ref): t_ref = 46.6 lies between τ_1 = 40 and τ_2 = 70.
  const double w = (46.6 - 40.0) / 30.0;
  const double b_ref = (1 - w) * beta(1) + w * beta(2);
  for (int j = 0; j < 4; ++j) {
    EXPECT_NEAR(b_ref + drift.Offset(spline.knots_s[std::size_t(j)])(0), beta(j), 1e-12) << j;
  }
  EXPECT_NEAR(b_ref + drift.Offset(55.0)(0), 0.5 * (beta(1) + beta(2)), 1e-12);
  EXPECT_NEAR(b_ref + drift.Offset(-50.0)(0), beta(0), 1e-12);
  EXPECT_NEAR(b_ref + drift.Offset(500.0)(0), beta(3), 1e-12);

  EXPECT_THROW(BiasTimeBasis::For(Linear(), {5.0}), std::invalid_argument);
  EXPECT_THROW(BiasTimeBasis::For(Linear(), {5.0, 5.0, 5.0}), std::invalid_argument);
  EXPECT_THROW(BiasTimeBasis::For(Linear(), {5.0, std::nan("")}), std::invalid_argument);
  EXPECT_NO_THROW(BiasTimeBasis::For(BiasModel{}, {}));
}

// Every derivative of the drift problem against central differences: the residual's Jacobian in
// x = (θ, D), and in the tangent coordinates of the direction (c ⊞ δ at δ = 0).
TEST(DriftProblem, JacobiansMatchFiniteDifferences) {
  const std::vector<Vec3> dirs = RandomDirections(12, 3);
  const std::vector<double> times = Times(12);
  ModelParameters truth = Yang2012Truth();
  const std::vector<Vec3> readings = SimulatePositions(truth, kG, dirs, Vec3::Ones(), 5);
  for (ModelKind model : {ModelKind::kLinear, ModelKind::kQuadratic}) {
    for (const auto& [bias, with_prior] :
         {std::pair{Linear(), false}, std::pair{Spline(4), false}, std::pair{Spline(4), true}}) {
      const internal::Problem problem{readings, kG, model};
      const BiasTimeBasis basis = BiasTimeBasis::For(bias, times);
      std::optional<internal::RandomWalkPrior> prior;
      if (with_prior) {
        prior = internal::RandomWalkPrior{Vec3(0.2, 0.3, 0.5), {}};
        for (std::size_t k = 0; k < times.size(); ++k) {
          prior->reading_sigmas.push_back(Vec3(1.0, 2.0, 0.5) * (1.0 + 0.1 * double(k)));
        }
      }
      const internal::DriftProblem lsq(problem, basis, times, prior);
      Eigen::VectorXd x(lsq.GlobalSize());
      x.head(NumParameters(model)) = Pack(truth, model);
      for (Eigen::Index i = NumParameters(model); i < x.size(); ++i) x(i) = 0.3 * double(i % 5);
      for (int k : {0, 7, 11}) {
        const Eigen::VectorXd c = dirs[std::size_t(k)];
        Eigen::VectorXd r;
        Eigen::MatrixXd J_x, J_y;
        ASSERT_TRUE(lsq.Evaluate(k, x, c, &r, &J_x, &J_y));
        const auto of_x = [&](const Eigen::VectorXd& xx) {
          Eigen::VectorXd rr;
          lsq.Evaluate(k, xx, c, &rr, nullptr, nullptr);
          return rr;
        };
        EXPECT_TRUE(testing::JacobianMatches(of_x, x, J_x)) << ToString(bias);
        const auto of_delta = [&](const Eigen::VectorXd& delta) {
          Eigen::VectorXd rr;
          lsq.Evaluate(k, x, lsq.PlusLocal(k, c, delta), &rr, nullptr, nullptr);
          return rr;
        };
        EXPECT_TRUE(testing::JacobianMatches(of_delta, Eigen::Vector2d::Zero(), J_y))
            << ToString(bias);
      }
      if (!with_prior) continue;
      // The prior's block: residuals linear in D, no direction.
      ASSERT_EQ(lsq.NumBlocks(), 13);
      Eigen::VectorXd r;
      Eigen::MatrixXd J_x;
      ASSERT_TRUE(lsq.Evaluate(12, x, Eigen::VectorXd(), &r, &J_x, nullptr));
      const auto of_x = [&](const Eigen::VectorXd& xx) {
        Eigen::VectorXd rr;
        lsq.Evaluate(12, xx, Eigen::VectorXd(), &rr, nullptr, nullptr);
        return rr;
      };
      EXPECT_TRUE(testing::JacobianMatches(of_x, x, J_x));
    }
  }
}

// Without noise the fit is the truth, drift included, in both frames, for either model.
TEST(BiasDrift, NoiseFreeReadingsGiveTheTruth) {
  const int m = 30;
  const std::vector<Vec3> dirs = RandomDirections(m, 11);
  const std::vector<double> times = Times(m);
  const ModelParameters truth = Yang2012Truth();
  const Vec3 per_minute(3.0, -2.0, 1.5);  // raw per minute
  const double t_mean = 5.0 + 20.0 * (m - 1) / 2.0;
  const auto drift = [&](double t) { return Vec3(per_minute * (t - t_mean) / 60.0); };
  for (Frame frame : {Frame::kXFirst, Frame::kZFirst}) {
    ModelParameters device = truth;
    if (frame == Frame::kZFirst) device = MirrorAxes(truth);
    // A z-first device: its readings are those of the mirrored x-first truth, mirrored back.
    std::vector<Vec3> readings = DriftingReadings(truth, dirs, times, drift, Vec3::Zero(), 1);
    CalibrationOptions o = Options(Linear(), times);
    o.frame = frame;
    o.model = ModelKind::kQuadratic;
    if (frame == Frame::kZFirst) {
      for (Vec3& p : readings) p = MirrorAxes(p);
    }
    const CalibrationResult r = Calibrate(readings, o);
    ASSERT_TRUE(r.summary.converged()) << r.summary.termination_message;
    ASSERT_TRUE(r.drift);
    const ModelParameters expected = frame == Frame::kZFirst ? MirrorAxes(truth) : truth;
    EXPECT_LT((r.params.K - expected.K).cwiseAbs().maxCoeff(), 1e-9 * 5000);
    EXPECT_LT((r.params.bias - expected.bias).cwiseAbs().maxCoeff(), 1e-7);
    const Vec3 expected_drift = frame == Frame::kZFirst ? MirrorAxes(per_minute) : per_minute;
    EXPECT_LT((Vec3(r.drift->D.col(0)) - expected_drift).cwiseAbs().maxCoeff(), 1e-8)
        << r.drift->D.transpose();
  }
  // A spline bias: knot biases β_j, the truth's b their value at t_ref.
  const BiasTimeBasis basis = BiasTimeBasis::For(Spline(4), times);
  const Eigen::Matrix<double, 3, 3> D =
      (Eigen::Matrix<double, 3, 3>() << 2, -1, 3, 0.5, 1, -2, -3, 1, 0.2).finished();
  const auto spline = [&](double t) { return Vec3(D * basis.Evaluate(t)); };
  const std::vector<Vec3> readings = DriftingReadings(truth, dirs, times, spline, Vec3::Zero(), 1);
  CalibrationOptions o = Options(Spline(4), times);
  o.model = ModelKind::kQuadratic;
  const CalibrationResult r = Calibrate(readings, o);
  ASSERT_TRUE(r.summary.converged()) << r.summary.termination_message;
  EXPECT_LT((r.drift->D - D).cwiseAbs().maxCoeff(), 1e-8)
      << r.drift->D << "\n"
      << r.summary.termination_message << " J " << r.summary.final_cost;
  EXPECT_LT((r.params.bias - truth.bias).cwiseAbs().maxCoeff(), 1e-7);
}

// The joint fit's covariance describes its scatter: over Monte Carlo runs with a linear drift,
// the errors of K, b and D divided by their σ have RMS 1 and 68 % lie within ±1.
TEST(BiasDrift, CovarianceMatchesTheScatterOfLinearDriftFits) {
  const int m = 30, runs = 200;
  const ModelParameters truth = LinearDevice();
  const Vec3 sigma = Yang2012SigmaRaw(truth);
  const std::vector<double> times = Times(m);
  const double t_mean = 5.0 + 20.0 * (m - 1) / 2.0;
  const Vec3 per_minute = 2.0 * sigma;  // ~20 σ over the session
  const auto drift = [&](double t) { return Vec3(per_minute * (t - t_mean) / 60.0); };
  int inside = 0, count = 0;
  double sum2 = 0;
  for (int run = 1; run <= runs; ++run) {
    const auto seed = static_cast<std::uint64_t>(run);
    const std::vector<Vec3> dirs = RandomDirections(m, 1000 + seed);
    const std::vector<Vec3> readings = DriftingReadings(truth, dirs, times, drift, sigma, seed);
    CalibrationOptions o = Options(Linear(), times);
    o.outliers.policy = OutlierPolicy::kOff;
    const CalibrationResult r = Calibrate(readings, o);
    ASSERT_TRUE(r.summary.converged());
    const Eigen::VectorXd estimate =
        (Eigen::VectorXd(12) << Pack(r.params, ModelKind::kLinear), r.drift->D.col(0)).finished();
    const Eigen::VectorXd expected =
        (Eigen::VectorXd(12) << Pack(truth, ModelKind::kLinear), per_minute).finished();
    for (Eigen::Index i = 0; i < 12; ++i) {
      const double z = (estimate(i) - expected(i)) / std::sqrt(r.drift->covariance(i, i));
      sum2 += z * z;
      inside += std::abs(z) < 1.0 ? 1 : 0;
      ++count;
    }
  }
  // σ̂ from the residuals: z is Student's t with m − 12 = 18 degrees of freedom, so E z² =
  // 18/16 = 1.125 and P(|z| < 1) = 0.670. 2400 values (12 per run, correlated within a run): the
  // standard error of the fraction is at most 0.019 even if only 600 were independent.
  const double rms = std::sqrt(sum2 / count);
  const double coverage = static_cast<double>(inside) / count;
  EXPECT_NEAR(rms, std::sqrt(1.125), 0.08) << "coverage " << coverage;
  EXPECT_NEAR(coverage, 0.670, 0.04) << "rms " << rms;
}

// A bias that wanders as a random walk (steps every second, q per √s) is followed by a spline of
// many knots with the random-walk prior (drift_fit.hpp, RandomWalkPrior), and the posterior
// covariance covers the truth as a 1σ interval should: the 68 ± 3 %. Without the prior a
// few knots take the walk's wiggles between them for noise and cover less (rms z above 1).
TEST(BiasDrift, RandomWalkPriorCoversARandomWalkingBias) {
  const int m = 36, runs = 200;
  const ModelParameters truth = LinearDevice();
  const Vec3 sigma = Yang2012SigmaRaw(truth);
  const std::vector<double> times = Times(m);
  const Vec3 q = 2.0 * sigma / std::sqrt(60.0);  // 2 σ per √minute: ~11 σ over the session
  const auto coverage_of = [&](const BiasModel& model, bool prior, double* rms) {
    int inside = 0, count = 0;
    double sum2 = 0;
    for (int run = 1; run <= runs; ++run) {
      const auto seed = static_cast<std::uint64_t>(run);
      std::mt19937_64 rng(seed * 7919);
      std::normal_distribution<double> normal;
      std::vector<Vec3> walk(static_cast<std::size_t>(times.back()) + 2, Vec3::Zero());
      for (std::size_t i = 1; i < walk.size(); ++i) {
        for (int a = 0; a < 3; ++a) walk[i](a) = walk[i - 1](a) + q(a) * normal(rng);
      }
      // The truth's bias is the walk's mean over the positions' times: t_ref's bias for the fit
      // is not a parameter of the walk, so b is compared where both are defined, at each time.
      const auto drift = [&](double t) { return walk[static_cast<std::size_t>(t)]; };
      const std::vector<Vec3> dirs = RandomDirections(m, 5000 + seed);
      const std::vector<Vec3> readings = DriftingReadings(truth, dirs, times, drift, sigma, seed);
      CalibrationOptions o = Options(model, times);
      o.outliers.policy = OutlierPolicy::kOff;
      o.reading_sigmas.assign(std::size_t(m), sigma);
      if (prior) o.bias_random_walk = q;
      const CalibrationResult r = Calibrate(readings, o);
      EXPECT_TRUE(r.summary.converged()) << "run " << run;
      if (r.covariance.rows() != 9) {
        ADD_FAILURE() << "run " << run << ": no covariance";
        continue;
      }
      // K from the fit; the truth's bias is b at t_ref plus the walk there (the fitted b is the
      // bias at t_ref, which the walk moves): compare K's six entries, and b(t_ref).
      ModelParameters expected = truth;
      expected.bias += drift(r.drift->basis.t_ref_s);
      const Eigen::VectorXd e =
          Pack(r.params, ModelKind::kLinear) - Pack(expected, ModelKind::kLinear);
      for (Eigen::Index i = 0; i < 9; ++i) {
        const double z = e(i) / std::sqrt(r.covariance(i, i));
        sum2 += z * z;
        inside += std::abs(z) < 1.0 ? 1 : 0;
        ++count;
      }
    }
    *rms = std::sqrt(sum2 / count);
    return static_cast<double>(inside) / count;
  };
  // 1800 values per case (9 per run, correlated within a run): the standard error of a fraction
  // is at most 0.019 even if only 600 were independent; the issue asks 0.68 ± 0.03. Measured:
  // 0.674 (rms z 1.054) with 12 knots, 0.689 (0.998) with 32.
  for (int knots : {12, kMaxBiasKnots}) {
    double rms = 0;
    const double coverage = coverage_of(Spline(knots), true, &rms);
    EXPECT_NEAR(coverage, 0.68, 0.03) << knots << " knots, rms z " << rms;
    EXPECT_NEAR(rms, 1.0, 0.08) << knots << " knots, coverage " << coverage;
  }
  // Without the prior a line takes the walk's wanderings for noise: 0.541 (rms z 1.90), far
  // outside 0.68 ± 3 standard errors. (Free splines of 3-8 knots: 0.57-0.67, rms z 1.10-1.42.)
  double rms = 0;
  EXPECT_LT(coverage_of(Linear(), false, &rms), 0.62) << "rms z " << rms;
}

// A position knocked during its interval is found and excluded under a drifting bias, and the
// drift is then that of the other positions.
TEST(BiasDrift, ScreeningFindsABumpedPositionUnderADrift) {
  const int m = 30;
  const ModelParameters truth = LinearDevice();
  const Vec3 sigma = Yang2012SigmaRaw(truth);
  const std::vector<double> times = Times(m);
  const std::vector<Vec3> dirs = RandomDirections(m, 21);
  const auto drift = [&](double t) { return Vec3(40.0 * sigma * (t - 295.0) / 600.0); };
  std::vector<Vec3> readings = DriftingReadings(truth, dirs, times, drift, sigma, 4);
  readings[12] += 60.0 * sigma.cwiseProduct(dirs[12]);  // along gravity: off the surface
  const CalibrationResult r = Calibrate(readings, Options(Linear(), times));
  ASSERT_TRUE(r.summary.converged());
  ASSERT_EQ(r.outliers.size(), 1u);
  EXPECT_EQ(r.outliers[0].position, 12);
  EXPECT_TRUE(r.outliers[0].excluded);
  EXPECT_EQ(r.degrees_of_freedom, m - 1 - 12);
  ASSERT_EQ(r.drift->times_s.size(), std::size_t(m));  // every position's time, the excluded too
  ASSERT_EQ(r.residuals.size(), std::size_t(m));
  // The excluded position's residual is the bump, seen under the fit.
  EXPECT_GT(r.residuals[12].norm(), 30.0 * sigma.minCoeff());
}

// The held-out errors with a drift are those of refits without each position, each position
// corrected with the bias at its own time; without the drift they are those of a constant bias.
TEST(BiasDrift, HeldOutErrorsAreThoseOfRefits) {
  const int m = 24;
  const ModelParameters truth = LinearDevice();
  const Vec3 sigma = Yang2012SigmaRaw(truth);
  const std::vector<double> times = Times(m);
  const std::vector<Vec3> dirs = RandomDirections(m, 31);
  const auto drift = [&](double t) { return Vec3(30.0 * sigma * (t - 235.0) / 480.0); };
  const std::vector<Vec3> readings = DriftingReadings(truth, dirs, times, drift, sigma, 6);
  CalibrationOptions o = Options(Linear(), times);
  o.cross_validate = true;
  const CalibrationResult r = Calibrate(readings, o);
  ASSERT_TRUE(r.crossval_rms) << r.crossval_note;
  for (int k : {0, 9, 23}) {
    std::vector<Vec3> rest;
    std::vector<double> rest_times;
    for (int j = 0; j < m; ++j) {
      if (j == k) continue;
      rest.push_back(readings[std::size_t(j)]);
      rest_times.push_back(times[std::size_t(j)]);
    }
    CalibrationOptions without = Options(Linear(), rest_times);
    without.bias_basis = r.drift->basis;  // the full set's reference time
    const CalibrationResult fit = Calibrate(rest, without);
    const Vec3 p = readings[std::size_t(k)] - fit.drift->Offset(times[std::size_t(k)]);
    const double expected = GravityNormErrors(fit.params, {p}, kG)[0];
    EXPECT_NEAR(r.crossval_errors[std::size_t(k)], expected, 1e-9 * kG) << k;
  }
  // The drift is 30 σ over the session: the constant bias predicts held-out positions far worse.
  CalibrationOptions constant = o;
  constant.bias_model = BiasModel{};
  const CalibrationResult c = Calibrate(readings, constant);
  EXPECT_GT(*c.crossval_rms, 3.0 * *r.crossval_rms);
}

TEST(BiasDrift, OptionsOutOfPlaceAreRefused) {
  const std::vector<Vec3> readings = SimulatePositions(Yang2012Truth(), kG, RandomDirections(20, 2),
                                                       Yang2012SigmaRaw(Yang2012Truth()), 2);
  CalibrationOptions o = Options(Linear(), Times(19));  // one time short
  EXPECT_THROW(Calibrate(readings, o), std::invalid_argument);
  o.position_times_s = Times(20);
  for (SolverMethod method : {SolverMethod::kTwoStep, SolverMethod::kModulus}) {
    CalibrationOptions other = o;
    other.method = method;
    EXPECT_TRUE(other.Validate()) << ToString(method);
  }
  CalibrationOptions corrected = o;
  corrected.estimator = Estimator::kBiasCorrected;
  EXPECT_TRUE(corrected.Validate());
  CalibrationOptions wrong_basis = o;
  wrong_basis.bias_basis = BiasTimeBasis::For(Spline(3), o.position_times_s);
  EXPECT_TRUE(wrong_basis.Validate());
  // All positions at one time: no drift can be told.
  o.position_times_s.assign(20, 7.0);
  EXPECT_THROW(Calibrate(readings, o), std::invalid_argument);
  // A spline whose knots no position lies near: the drift is not determined there.
  std::vector<double> clustered(20, 0.0);
  for (int k = 0; k < 20; ++k) clustered[std::size_t(k)] = k < 19 ? k : 1000.0;
  o.position_times_s = clustered;
  o.bias_model = Spline(6);
  EXPECT_THROW(Calibrate(readings, o), DataError);
}

}  // namespace
}  // namespace accelcal
