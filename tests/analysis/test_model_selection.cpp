// --model auto: the model the data support, chosen on held-out error over the same positions and
// kept quadratic only on evidence (model_selection.hpp).
#include <cmath>

#include <gtest/gtest.h>

#include "accelcal/model_selection.hpp"
#include "accelcal/simulate.hpp"

namespace accelcal {
namespace {

constexpr double kG = kYang2012Gravity_ms2;

std::vector<Vec3> Readings(const ModelParameters& truth, const std::vector<Vec3>& dirs,
                           std::uint64_t seed) {
  const Vec3 sigma = Yang2012SigmaRaw(truth);
  return SimulatePositions(truth, kG, dirs, sigma, seed);
}

CalibrationOptions Options() {
  CalibrationOptions o;
  o.gravity = kG;
  return o;
}

ModelParameters LinearDevice() {
  ModelParameters linear = Yang2012Truth();
  linear.k2.setZero();
  return linear;
}

bool StartsWith(const std::string& text, const std::string& prefix) {
  return text.rfind(prefix, 0) == 0;
}

// How many of `runs` seeds (1, 2, ...) choose the quadratic model for `device` on `positions`
// random positions.
int QuadraticChosen(const ModelParameters& device, int positions, int runs) {
  int chosen = 0;
  for (int seed = 1; seed <= runs; ++seed) {
    const auto s64 = static_cast<std::uint64_t>(seed);
    const ModelSelection s =
        SelectModel(Readings(device, RandomDirections(positions, s64), s64), Options());
    EXPECT_TRUE(s.quadratic.has_value()) << s.quadratic_error;
    if (s.chosen == ModelKind::kQuadratic) {
      ++chosen;
      EXPECT_TRUE(StartsWith(s.reason,
                             "it predicts held-out positions better beyond sampling "
                             "error"))
          << s.reason;
    } else {
      EXPECT_TRUE(StartsWith(s.reason,
                             "the quadratic model does not predict held-out positions better "
                             "beyond sampling error") ||
                  StartsWith(s.reason, "no squared coefficient is significant"))
          << s.reason;
    }
  }
  return chosen;
}

TEST(ModelSelection, ChoosesQuadraticWhenTheSquaredTermsAreReal) {
  // Paper 000's Table-3 device: k2 of 1e-5 to 3e-5 g/g², 4 to 10 σ at Table-4 noise on 30
  // positions (measured t = 4.4, 9.5, 7.3 for this seed).
  const ModelSelection s =
      SelectModel(Readings(Yang2012Truth(), RandomDirections(30, 2), 3), Options());
  EXPECT_EQ(s.chosen, ModelKind::kQuadratic) << s.reason;
  ASSERT_TRUE(s.quadratic.has_value());
  EXPECT_GT(s.k2_t.cwiseAbs().minCoeff(), 3.0) << s.k2_t.transpose() << " | " << s.reason;
  EXPECT_LT(*s.quadratic->crossval_rms, *s.linear.crossval_rms);
  // Both conditions, with the thresholds of the documented probabilities at 30 positions: the
  // one-sided 5 % point of t with 29 degrees of freedom (1.70) and the two-sided 5 %/3 point with
  // 30 − 12 = 18 (2.64).
  EXPECT_GT(s.improvement, s.improvement_threshold);
  EXPECT_NEAR(s.improvement_threshold / s.improvement_se, 1.699, 1e-3);
  EXPECT_NEAR(s.k2_t_threshold, 2.64, 0.01);
  EXPECT_EQ(s.screened_with, ModelKind::kQuadratic);
  EXPECT_EQ(s.positions_used.size(), 30u);
  EXPECT_TRUE(StartsWith(s.reason, "it predicts held-out positions better beyond sampling error"))
      << s.reason;
  EXPECT_NE(s.reason.find("largest |k2/sigma|"), std::string::npos) << s.reason;
  EXPECT_EQ(&s.chosen_result(), &*s.quadratic);
}

TEST(ModelSelection, RarelyChoosesTheQuadraticModelForALinearDevice) {
  // A linear device's quadratic fit predicts held-out positions better by chance in 12.6 % (30
  // positions) and 10.4 % (18) of runs: the lower held-out RMS alone, the rule before this one,
  // chose it that often (measured on these seeds). The paired test and the significance of a
  // squared coefficient together choose it in 3 of 1000 runs on 30 positions and 12 of 1000 on
  // 18 (measured), each test alone in 0.6 % and 5.2 % of 2000 runs on 30 positions.
  // The bound: at most 5 % false selections with 95 % confidence, i.e. fewer than a 5 % rate
  // would give in 95 % of such experiments (normal approximation, 50 − 1.645·6.9 = 38.7 of 1000).
  constexpr int kRuns = 1000;
  const double bound = 0.05 * kRuns - 1.645 * std::sqrt(0.05 * 0.95 * kRuns);
  const int on_30 = QuadraticChosen(LinearDevice(), 30, kRuns);
  EXPECT_LT(on_30, bound) << on_30 << " of " << kRuns;
  const int on_18 = QuadraticChosen(LinearDevice(), 18, kRuns);
  EXPECT_LT(on_18, bound) << on_18 << " of " << kRuns;
}

TEST(ModelSelection, DetectsRealSquaredTermsInMostRuns) {
  // The Table-3 device on 18 random positions (the largest |k2/σ| 11 to 37 in 80 % of runs, the
  // paired test's z 1.9 to 3.5): measured 185 of 200.
  constexpr int kRuns = 200;
  const int yang = QuadraticChosen(Yang2012Truth(), 18, kRuns);
  EXPECT_GE(yang, 0.85 * kRuns) << yang << " of " << kRuns;
  // Squared terms 0.15 of Table 3's on 30 positions, near the edge of detection (the largest
  // |k2/σ| 3.3 to 7.7 in 80 % of runs): measured 150 of 200 (323 of 400; 0.1 of Table 3: 173 of
  // 400, 0.2: 381 of 400). The bound leaves 3 binomial standard deviations for the solvers'
  // stopping points to move, and fails a rule asking twice the standard errors (14 of 200). The
  // paired test is what limits it (a held-out improvement of a few standard errors needs a stronger
  // effect than a significant coefficient does); the lower held-out RMS alone detects 394 of 400,
  // at the cost of 12.6 % false selections.
  ModelParameters weak = Yang2012Truth();
  weak.k2 *= 0.15;
  const int weak_chosen = QuadraticChosen(weak, 30, kRuns);
  EXPECT_GE(weak_chosen, 0.65 * kRuns) << weak_chosen << " of " << kRuns;
}

TEST(ModelSelection, ComparesBothModelsOnTheSamePositions) {
  // A linear device, 30 positions, position 1 displaced a·σ along its direction. With a = 5 the
  // quadratic screening excludes it and the linear screening keeps it; with a = 4 (another seed)
  // the other way round; with a = 20 both exclude it (checked first: else the case tests
  // nothing). Both fits must use the positions of the quadratic screening, and the held-out
  // comparison be over those.
  struct Case {
    std::uint64_t seed;
    double a;
    bool linear_alone_excludes, quadratic_excludes;
  };
  for (const Case& c :
       {Case{10, 5.0, false, true}, Case{1, 4.0, true, false}, Case{3, 20.0, true, true}}) {
    SCOPED_TRACE("seed " + std::to_string(c.seed) + ", a = " + std::to_string(c.a));
    const ModelParameters device = LinearDevice();
    const std::vector<Vec3> dirs = RandomDirections(30, c.seed);
    std::vector<Vec3> readings = Readings(device, dirs, c.seed);
    readings[0] += c.a * Yang2012SigmaRaw(device).cwiseProduct(dirs[0]);

    CalibrationOptions options = Options();
    const CalibrationResult linear_alone = Calibrate(readings, options);
    options.model = ModelKind::kQuadratic;
    const CalibrationResult quadratic_alone = Calibrate(readings, options);
    ASSERT_EQ(linear_alone.excluded(0), c.linear_alone_excludes);
    ASSERT_EQ(quadratic_alone.excluded(0), c.quadratic_excludes);

    const ModelSelection s = SelectModel(readings, Options());
    ASSERT_TRUE(s.quadratic.has_value()) << s.quadratic_error;
    EXPECT_EQ(s.screened_with, ModelKind::kQuadratic);
    const CalibrationResult& lin = s.linear;
    const CalibrationResult& quad = *s.quadratic;
    // The quadratic result is Calibrate's; the linear one lists the same findings.
    ASSERT_EQ(quad.outliers.size(), quadratic_alone.outliers.size());
    ASSERT_EQ(lin.outliers.size(), quad.outliers.size());
    for (std::size_t i = 0; i < quad.outliers.size(); ++i) {
      EXPECT_EQ(quad.outliers[i].position, quadratic_alone.outliers[i].position);
      EXPECT_EQ(quad.outliers[i].excluded, quadratic_alone.outliers[i].excluded);
      EXPECT_EQ(lin.outliers[i].position, quad.outliers[i].position);
      EXPECT_EQ(lin.outliers[i].excluded, quad.outliers[i].excluded);
    }
    std::vector<int> expected;
    for (int k = 0; k < 30; ++k) {
      EXPECT_EQ(lin.excluded(std::size_t(k)), quad.excluded(std::size_t(k))) << "position " << k;
      if (!quad.excluded(std::size_t(k))) expected.push_back(k);
    }
    EXPECT_EQ(s.positions_used, expected);
    EXPECT_EQ(lin.positions_used(), static_cast<int>(expected.size()));
    EXPECT_EQ(quad.positions_used(), static_cast<int>(expected.size()));
    EXPECT_EQ(lin.degrees_of_freedom + 9 - 12, quad.degrees_of_freedom);
    // Per-position vectors keep one entry per reading, as Calibrate's.
    EXPECT_EQ(lin.residuals.size(), 30u);
    EXPECT_EQ(lin.directions.size(), 30u);
    ASSERT_EQ(lin.crossval_errors.size(), 30u);
    ASSERT_EQ(quad.crossval_errors.size(), 30u);
    // The paired comparison is over exactly those positions.
    double mean = 0;
    for (int k : s.positions_used) {
      const auto i = std::size_t(k);
      mean += lin.crossval_errors[i] * lin.crossval_errors[i] -
              quad.crossval_errors[i] * quad.crossval_errors[i];
    }
    mean /= static_cast<double>(s.positions_used.size());
    EXPECT_NEAR(s.improvement, mean, 1e-12 * std::abs(mean));
    EXPECT_NEAR(*lin.crossval_rms, Rms(lin.InFit(lin.crossval_errors)), 1e-15);
    EXPECT_NE(s.reason.find("over " + std::to_string(expected.size()) + " positions"),
              std::string::npos)
        << s.reason;
    EXPECT_EQ(s.chosen, ModelKind::kLinear) << s.reason;
  }
}

TEST(ModelSelection, SaysWhyWhenTheQuadraticModelCannotBeValidated) {
  // 12 positions determine the quadratic model exactly: no fit is left without one of them.
  const ModelSelection s =
      SelectModel(Readings(Yang2012Truth(), RandomDirections(12, 4), 5), Options());
  EXPECT_EQ(s.chosen, ModelKind::kLinear);
  EXPECT_EQ(s.reason,
            "the quadratic model cannot be validated (without position 1: the quadratic model "
            "needs at least 12 positions, got 11)");
  // Nothing compared: the linear result is Calibrate's own, screened by itself.
  EXPECT_EQ(s.screened_with, ModelKind::kLinear);
  EXPECT_TRUE(std::isnan(s.improvement));
}

}  // namespace
}  // namespace accelcal
