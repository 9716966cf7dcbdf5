// The Cramér-Rao bound of a planned set of positions (design.hpp).
#include <cmath>
#include <limits>

#include <gtest/gtest.h>
#include <Eigen/Dense>
#include <Eigen/Geometry>

#include "accelcal/calibrate.hpp"
#include "accelcal/design.hpp"
#include "accelcal/error.hpp"
#include "accelcal/simulate.hpp"
#include "solvers/solver_common.hpp"
#include "support/jacobian_check.hpp"

namespace accelcal {
namespace {

constexpr double kG = kYang2012Gravity_ms2;

TEST(Design, CrlbIsTheInverseOfTheFiniteDifferenceFisherMatrix) {
  // The full Fisher matrix of (θ, the tangent coordinates of every direction) from central
  // differences of the whitened prediction, inverted, its θ block: the bound with the directions
  // unknown. The closed form (Σ u uᵀ/σ_k²) must agree.
  const ModelParameters device = Yang2012Truth();
  const Vec3 sigma = Yang2012SigmaRaw(device);
  const std::vector<Vec3> dirs = Yang18Directions();
  const int m = static_cast<int>(dirs.size());
  std::vector<internal::Mat32> tangent;
  for (const Vec3& c : dirs) tangent.push_back(internal::TangentBasis(c));
  const std::vector<int>& cols = ActiveColumns(ModelKind::kQuadratic);
  const int P = static_cast<int>(cols.size());
  Eigen::VectorXd x = Eigen::VectorXd::Zero(P + 2 * m);
  x.head(P) = Pack(device, ModelKind::kQuadratic);
  const auto whitened = [&](const Eigen::VectorXd& v) {
    const ModelParameters params = Unpack(v.head(P), ModelKind::kQuadratic);
    Eigen::VectorXd out(3 * m);
    for (int k = 0; k < m; ++k) {
      const Vec3 c =
          internal::Retract(dirs[static_cast<std::size_t>(k)], tangent[static_cast<std::size_t>(k)],
                            v.segment<2>(P + 2 * k));
      out.segment<3>(3 * k) = PredictRaw(params, Vec3(kG * c)).cwiseQuotient(sigma);
    }
    return out;
  };
  const Eigen::MatrixXd J = testing::NumericalJacobian(whitened, x);
  const Eigen::MatrixXd fisher = J.transpose() * J;
  const Eigen::MatrixXd bound =
      fisher.ldlt().solve(Eigen::MatrixXd::Identity(P + 2 * m, P + 2 * m)).topLeftCorner(P, P);
  const PlannedUncertainty planned =
      PredictUncertainty(device, ModelKind::kQuadratic, kG, dirs, sigma);
  ASSERT_TRUE(planned.observable);
  // Central differences of a function linear in θ and smooth in δ: errors ~1e-10 relative; the
  // inversion amplifies them by the condition number of the scaled Fisher matrix (~1e4).
  for (int i = 0; i < P; ++i) {
    EXPECT_NEAR(std::sqrt(planned.crlb(i, i)), std::sqrt(bound(i, i)),
                1e-5 * std::sqrt(bound(i, i)))
        << ParameterSlots(ModelKind::kQuadratic)[static_cast<std::size_t>(i)].name;
  }
  EXPECT_LT((planned.crlb - bound).norm(), 1e-5 * bound.norm());
}

TEST(Design, MaximumLikelihoodReachesTheBound) {
  // 300 simulated calibrations of the Table-3 device on Table 2's 18 positions: the spread of the
  // joint solver's estimates against the CRLB. The standard deviation of a sample standard
  // deviation over 300 runs is 1/√600 = 4 %: ±15 % is 3.6 of those.
  const ModelParameters device = Yang2012Truth();
  const Vec3 sigma = Yang2012SigmaRaw(device);
  const PlannedUncertainty planned =
      PredictUncertainty(device, ModelKind::kQuadratic, kG, Yang18Directions(), sigma);
  CalibrationOptions o;
  o.model = ModelKind::kQuadratic;
  o.gravity = kG;
  const Eigen::VectorXd truth = Pack(device, ModelKind::kQuadratic);
  Eigen::VectorXd sum2 = Eigen::VectorXd::Zero(truth.size());
  const int runs = 300;
  for (int run = 0; run < runs; ++run) {
    const std::vector<Vec3> readings =
        SimulatePositions(device, kG, Yang18Directions(), sigma, 5000 + static_cast<unsigned>(run));
    const Eigen::VectorXd e = Pack(Calibrate(readings, o).params, ModelKind::kQuadratic) - truth;
    sum2 += e.cwiseAbs2();
  }
  for (Eigen::Index i = 0; i < truth.size(); ++i) {
    const double ratio = std::sqrt(sum2(i) / runs / planned.crlb(i, i));
    EXPECT_NEAR(ratio, 1.0, 0.15)
        << ParameterSlots(ModelKind::kQuadratic)[static_cast<std::size_t>(i)].name;
  }
}

TEST(Design, FlagsWhatSixAxisPositionsCannotDetermine) {
  // Six axis-aligned positions with unknown orientations cannot fix 9 parameters.
  const std::vector<Vec3> six = *SchemeDirections("six");
  ModelParameters device = Yang2012Truth();
  const PlannedUncertainty planned =
      PredictUncertainty(device, ModelKind::kLinear, kG, six, Yang2012SigmaRaw(device));
  EXPECT_FALSE(planned.observable);
  EXPECT_FALSE(planned.weakest.empty());
  EXPECT_EQ(planned.crlb.size(), 0);
  EXPECT_TRUE(PredictUncertainty(device, ModelKind::kLinear, kG, *SchemeDirections("yang18"),
                                 Yang2012SigmaRaw(device))
                  .observable);
}

TEST(Design, ObservabilityDoesNotDependOnTheNoiseLevel) {
  // Whether positions determine the parameters is geometry: the reciprocal condition must be the
  // same at any noise level, for a device in g (K ≈ 1) as for one in raw counts. Before issue
  // 17 the Jacobi scaling used A's unwhitened diagonal, so paper 000's own scheme was declared
  // unobservable for a device in g at a noise of 6e-6 g (reciprocal condition 3.6e-11).
  ModelParameters in_g;
  in_g.K << 1.001, 0, 0, 0.002, 0.998, 0, -0.001, 0.003, 1.002;
  in_g.bias = Vec3(0.01, -0.02, 0.005);
  for (const ModelParameters& device : {Yang2012Truth(), in_g}) {
    const double g = &device == &in_g ? 1.0 : kG;
    const PlannedUncertainty reference =
        PredictUncertainty(device, ModelKind::kLinear, g, Yang18Directions(), Vec3(1.0, 1.2, 0.9));
    ASSERT_TRUE(reference.observable);
    for (double scale : {1e-9, 6e-6, 1e-3, 1e4}) {
      const PlannedUncertainty planned = PredictUncertainty(
          device, ModelKind::kLinear, g, Yang18Directions(), scale * Vec3(1.0, 1.2, 0.9));
      EXPECT_TRUE(planned.observable) << scale;
      // Only round-off differs: the matrices are the same up to a factor 1/scale².
      EXPECT_NEAR(planned.rcond, reference.rcond, 1e-12 * reference.rcond + 1e-15) << scale;
    }
  }
}

TEST(Design, NoiseDensityGivesPaper000sPositionNoise) {
  // 10 µg/√Hz at 100 Hz averaged over 60 s is Table 4's per-position noise (errata 000-table4),
  // mapped to raw units by the rows of K; one sample is √6000 times larger.
  const ModelParameters device = Yang2012Truth();
  const Vec3 averaged = RawNoiseFromDensity(device, kG, 10.0, 100.0, 6000.0);
  const Vec3 table4 = Yang2012SigmaRaw(device);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(averaged(i), table4(i), 1e-14 * table4(i)) << i;
    EXPECT_NEAR(RawNoiseFromDensity(device, kG, 10.0, 100.0)(i), std::sqrt(6000.0) * table4(i),
                1e-12 * table4(i))
        << i;
  }
}

TEST(Design, OptionsInSummaryOut) {
  const ModelParameters device = Yang2012Truth();
  const Vec3 sigma = Yang2012SigmaRaw(device);
  const std::vector<Vec3> candidates = *SchemeDirections("random:60:4");
  DesignOptions options;
  options.device = device;
  options.gravity = kG;
  options.sigma_raw = sigma;
  options.choose = 12;
  const DesignResult d = Design(candidates, options);
  EXPECT_EQ(d.chosen, ChooseDOptimal(device, ModelKind::kLinear, kG, candidates, sigma, 12));
  EXPECT_TRUE(d.summary.converged) << d.summary.termination_message;
  EXPECT_NE(d.summary.termination_message.find("det I"), std::string::npos);
  std::vector<Vec3> subset;
  for (int k : d.chosen) subset.push_back(candidates[static_cast<std::size_t>(k)]);
  EXPECT_EQ(d.planned.crlb, PredictUncertainty(device, ModelKind::kLinear, kG, subset, sigma).crlb);
  EXPECT_GT(d.d_efficiency, 0.0);
  // A cap of one sweep is reported, not hidden.
  options.max_exchanges = 1;
  const DesignResult capped = Design(candidates, options);
  if (capped.summary.exchanges > 0) {
    EXPECT_FALSE(capped.summary.converged);
    EXPECT_NE(capped.summary.termination_message.find("max_exchanges = 1"), std::string::npos);
  }
  // A platform-frame device (full K: the x-first K turned by a rotation) has the bound of its
  // x-first form with the directions turned the same way.
  const Mat33 R = Eigen::AngleAxisd(0.3, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  DesignOptions platform = options;
  platform.choose = 0;
  platform.frame = Frame::kPlatform;
  platform.device.K = device.K * R;
  platform.device.k2.setZero();
  std::vector<Vec3> turned;
  for (const Vec3& c : Yang18Directions()) turned.push_back(R.transpose() * c);
  const PlannedUncertainty a = Design(turned, platform).planned;
  const PlannedUncertainty b =
      PredictUncertainty(device, ModelKind::kLinear, kG, Yang18Directions(), sigma);
  ASSERT_TRUE(a.observable && b.observable);
  EXPECT_LT((a.crlb - b.crlb).norm(), 1e-9 * b.crlb.norm());
  // Invalid options name the fields, never a command-line flag.
  platform.model = ModelKind::kQuadratic;
  ASSERT_TRUE(platform.Validate());
  EXPECT_EQ(platform.Validate()->find("--"), std::string::npos);
  options.sigma_raw = Vec3(1, 0, 1);
  EXPECT_THROW(Design(candidates, options), std::invalid_argument);
}

TEST(Design, NamedSchemes) {
  EXPECT_EQ(SchemeDirections("yang18")->size(), 18u);
  EXPECT_EQ(SchemeDirections("six")->size(), 6u);
  EXPECT_EQ(SchemeDirections("random:25")->size(), 25u);
  EXPECT_EQ(*SchemeDirections("random:25"), *SchemeDirections("random:25:1"));
  EXPECT_NE(*SchemeDirections("random:25:2"), *SchemeDirections("random:25:1"));
  // A "random:" spec is a scheme, never a file name: one that is not a count is an error.
  for (const char* bad : {"random:", "random:0", "random:5x", "random:-5", "random:100001"}) {
    EXPECT_THROW(SchemeDirections(bad), InputError) << bad;
  }
  EXPECT_EQ(SchemeDirections("random:100000")->size(), 100000u);
  EXPECT_FALSE(SchemeDirections("octahedron").has_value());
}

}  // namespace
}  // namespace accelcal

namespace accelcal {
namespace {

// Every choice of 10 of 13 candidates (286), for the exhaustive checks of the optimal designs.
std::vector<std::vector<int>> TenOfThirteen() {
  std::vector<std::vector<int>> subsets;
  for (int a = 0; a < 13; ++a) {
    for (int b = a + 1; b < 13; ++b) {
      for (int c = b + 1; c < 13; ++c) {
        std::vector<int> subset;
        for (int k = 0; k < 13; ++k) {
          if (k != a && k != b && k != c) subset.push_back(k);
        }
        subsets.push_back(std::move(subset));
      }
    }
  }
  return subsets;
}

TEST(Design, DOptimalChoiceMatchesExhaustiveSearchOnASmallSet) {
  // 10 of 13 random candidates, linear model: all 286 subsets checked.
  const ModelParameters device = Yang2012Truth();
  const Vec3 sigma = Yang2012SigmaRaw(device);
  const std::vector<Vec3> candidates = *SchemeDirections("random:13:4");
  const std::vector<int> chosen =
      ChooseDOptimal(device, ModelKind::kLinear, kG, candidates, sigma, 10);
  ASSERT_EQ(chosen.size(), 10u);
  const auto logdet = [&](const std::vector<int>& subset) {
    std::vector<Vec3> dirs;
    for (int k : subset) dirs.push_back(candidates[static_cast<std::size_t>(k)]);
    return LogDetInformation(device, ModelKind::kLinear, kG, dirs, sigma);
  };
  double best = -std::numeric_limits<double>::infinity();
  for (const std::vector<int>& subset : TenOfThirteen()) best = std::max(best, logdet(subset));
  EXPECT_NEAR(logdet(chosen), best, 1e-9 * std::abs(best));
}

TEST(Design, AOptimalChoiceMatchesExhaustiveSearchOnASmallSet) {
  // As above with the trace of the CRLB; the Woodbury update of the exchange is checked by the
  // exhaustive minimum it must reach, and against the D-optimal start it must not be worse. (From
  // the D-optimal start alone the exchange stopped 0.6 % above the minimum on this set, a local
  // minimum no single swap leaves; with the restarts it reaches it on all of 30 such sets.)
  const ModelParameters device = Yang2012Truth();
  const Vec3 sigma = Yang2012SigmaRaw(device);
  const std::vector<Vec3> candidates = *SchemeDirections("random:13:4");
  const auto trace = [&](const std::vector<int>& subset) {
    std::vector<Vec3> dirs;
    for (int k : subset) dirs.push_back(candidates[static_cast<std::size_t>(k)]);
    return TraceCrlb(device, ModelKind::kLinear, kG, dirs, sigma);
  };
  const std::vector<int> chosen =
      ChooseAOptimal(device, ModelKind::kLinear, kG, candidates, sigma, 10);
  ASSERT_EQ(chosen.size(), 10u);
  double best = std::numeric_limits<double>::infinity();
  for (const std::vector<int>& subset : TenOfThirteen()) best = std::min(best, trace(subset));
  EXPECT_NEAR(trace(chosen), best, 1e-9 * best);
  EXPECT_LE(trace(chosen),
            trace(ChooseDOptimal(device, ModelKind::kLinear, kG, candidates, sigma, 10)));
  // The metric: the trace equals the CRLB's, each parameter scaled by its ParameterScales entry.
  std::vector<Vec3> dirs;
  for (int k : chosen) dirs.push_back(candidates[static_cast<std::size_t>(k)]);
  const PlannedUncertainty planned =
      PredictUncertainty(device, ModelKind::kLinear, kG, dirs, sigma);
  const std::vector<Vec3> no_readings(dirs.size());
  const internal::Problem problem{no_readings, kG, ModelKind::kLinear};
  const internal::Vec12 scales = internal::ParameterScales(problem, device);
  const std::vector<int>& cols = ActiveColumns(ModelKind::kLinear);
  double scaled_trace = 0;
  for (std::size_t j = 0; j < cols.size(); ++j) {
    const auto i = static_cast<Eigen::Index>(j);
    scaled_trace += planned.crlb(i, i) * std::pow(scales(cols[j]), 2);
  }
  EXPECT_NEAR(trace(chosen), scaled_trace, 1e-9 * scaled_trace);
  EXPECT_TRUE(std::isinf(TraceCrlb(device, ModelKind::kLinear, kG,
                                   {Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ()}, sigma)));
}

TEST(Design, DOptimalEighteenOutOfFiveHundredRivalsPaper000sScheme) {
  // Paper 000 §4 chose its 18 positions by its own sensitivity analysis, not for det I: a D-optimal
  // choice from 500 random candidates does better on that criterion (D-efficiency
  // (det/det_yang18)^(1/P) measured 1.147; a search that lost to a fixed scheme would be broken).
  const ModelParameters device = Yang2012Truth();
  const Vec3 sigma = Yang2012SigmaRaw(device);
  const std::vector<Vec3> candidates = *SchemeDirections("random:500");
  const std::vector<int> chosen =
      ChooseDOptimal(device, ModelKind::kQuadratic, kG, candidates, sigma, 18);
  std::vector<Vec3> dirs;
  for (int k : chosen) dirs.push_back(candidates[static_cast<std::size_t>(k)]);
  const double efficiency =
      std::exp((LogDetInformation(device, ModelKind::kQuadratic, kG, dirs, sigma) -
                LogDetInformation(device, ModelKind::kQuadratic, kG, Yang18Directions(), sigma)) /
               12.0);
  EXPECT_GT(efficiency, 1.05);
  // A-optimal: trace of the CRLB in the device's metric, against yang18 (measured: 1.54 for the
  // A-optimal choice, 1.47 for the D-optimal one). It must beat the D-optimal choice, which is one
  // of its starts.
  const std::vector<int> a_chosen =
      ChooseAOptimal(device, ModelKind::kQuadratic, kG, candidates, sigma, 18);
  std::vector<Vec3> a_dirs;
  for (int k : a_chosen) a_dirs.push_back(candidates[static_cast<std::size_t>(k)]);
  const double yang18 = TraceCrlb(device, ModelKind::kQuadratic, kG, Yang18Directions(), sigma);
  const double a_trace = TraceCrlb(device, ModelKind::kQuadratic, kG, a_dirs, sigma);
  EXPECT_LT(a_trace, TraceCrlb(device, ModelKind::kQuadratic, kG, dirs, sigma));
  EXPECT_GT(yang18 / a_trace, 1.05);
}

}  // namespace
}  // namespace accelcal

namespace accelcal {
namespace {

// A drift within the session costs a plan what its order lets the drift take up: the 18 face and
// edge directions with every +x position first and every −x last leave K_xx to be told from a
// drift by the other axes alone (its 1σ ×6.2 with a linear bias). Each up followed by its down is
// not enough when an axis is visited early only: its bias at the session's middle is then an
// extrapolation (b_x ×4.2). Going through the pairs and back through them in reverse visits each
// orientation early and late and loses almost nothing.
TEST(DesignDrift, AnOrderWithEachAxisUpThenDownLetsTheDriftTakeUpItsScale) {
  std::vector<Vec3> grouped, interleaved;
  for (int x = -1; x <= 1; ++x) {
    for (int y = -1; y <= 1; ++y) {
      for (int z = -1; z <= 1; ++z) {
        const int nonzero = (x != 0) + (y != 0) + (z != 0);
        if (nonzero == 1 || nonzero == 2) grouped.push_back(Vec3(x, y, z).normalized());
      }
    }
  }
  // Grouped: +x first, then x = 0, then −x (the loops above give −x first: reverse them).
  std::stable_sort(grouped.begin(), grouped.end(),
                   [](const Vec3& a, const Vec3& b) { return a(0) > b(0) + 0.5; });
  // Interleaved: each direction followed by its opposite.
  for (const Vec3& c : grouped) {
    if (c(0) > 0 || (c(0) == 0 && (c(1) > 0 || (c(1) == 0 && c(2) > 0)))) {
      interleaved.push_back(c);
      interleaved.push_back(-c);
    }
  }
  ASSERT_EQ(grouped.size(), 18u);
  ASSERT_EQ(interleaved.size(), 18u);
  std::vector<Vec3> there_and_back = interleaved;
  there_and_back.insert(there_and_back.end(), interleaved.rbegin(), interleaved.rend());
  const ModelParameters device = Yang2012Truth();
  const Vec3 sigma = Yang2012SigmaRaw(device);
  const BiasModel linear{BiasModelKind::kLinear, 0};
  const PlannedDriftCost bad =
      PredictDriftCost(device, ModelKind::kLinear, kYang2012Gravity_ms2, grouped, sigma, linear);
  const PlannedDriftCost early = PredictDriftCost(device, ModelKind::kLinear, kYang2012Gravity_ms2,
                                                  interleaved, sigma, linear);
  const PlannedDriftCost good = PredictDriftCost(device, ModelKind::kLinear, kYang2012Gravity_ms2,
                                                 there_and_back, sigma, linear);
  ASSERT_TRUE(bad.observable && early.observable && good.observable);
  EXPECT_GT(bad.inflation(0), 5.0);    // K_xx
  EXPECT_GT(early.inflation(1), 3.0);  // b_x
  EXPECT_LT(good.inflation.maxCoeff(), 1.5) << good.inflation.transpose();
  EXPECT_GE(good.inflation.minCoeff(), 1.0 - 1e-9);  // a drift never helps
  // The same plan in the z-first frame costs the same (the mirrored problem, slot by slot).
  const PlannedDriftCost mirrored = PredictDriftCost(
      MirrorAxes(device), ModelKind::kLinear, kYang2012Gravity_ms2,
      [&] {
        std::vector<Vec3> m;
        for (const Vec3& c : grouped) m.push_back(MirrorAxes(c));
        return m;
      }(),
      Vec3(MirrorAxes(sigma).cwiseAbs()), linear);
  ASSERT_TRUE(mirrored.observable);
  EXPECT_NEAR((mirrored.inflation - bad.inflation).cwiseAbs().maxCoeff(), 0.0, 1e-6);
  EXPECT_THROW(PredictDriftCost(device, ModelKind::kLinear, kYang2012Gravity_ms2, grouped, sigma,
                                BiasModel{}),
               std::invalid_argument);
}

}  // namespace
}  // namespace accelcal
