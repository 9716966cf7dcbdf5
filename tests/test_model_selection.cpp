// --model auto: the model the data support, chosen on held-out error.
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

TEST(ModelSelection, ChoosesQuadraticWhenTheSquaredTermsAreReal) {
  // Paper 000's Table-3 device: k2 of 1e-5 to 3e-5 g/g², 4 to 10 σ at Table-4 noise on 30
  // positions (measured t = 4.4, 9.5, 7.3 for this seed).
  const ModelSelection s =
      SelectModel(Readings(Yang2012Truth(), RandomDirections(30, 2), 3), Options());
  EXPECT_EQ(s.chosen, ModelKind::kQuadratic) << s.reason;
  ASSERT_TRUE(s.quadratic.has_value());
  EXPECT_GT(s.k2_t.cwiseAbs().minCoeff(), 3.0) << s.k2_t.transpose() << " | " << s.reason;
  EXPECT_LT(*s.quadratic->crossval_rms, *s.linear.crossval_rms);
  EXPECT_EQ(s.reason.rfind("it predicts held-out positions better", 0), 0u) << s.reason;
  EXPECT_EQ(&s.chosen_result(), &*s.quadratic);
}

TEST(ModelSelection, KeepsTheLinearModelForALinearDevice) {
  ModelParameters linear = Yang2012Truth();
  linear.k2.setZero();
  int linear_chosen = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const ModelSelection s =
        SelectModel(Readings(linear, RandomDirections(30, seed), seed), Options());
    ASSERT_TRUE(s.quadratic.has_value()) << s.quadratic_error;
    if (s.chosen == ModelKind::kLinear) {
      ++linear_chosen;
      EXPECT_EQ(s.reason.rfind("the quadratic model does not predict held-out positions better", 0),
                0u)
          << s.reason;
    }
  }
  // Three extra parameters fitted to noise predict held-out positions worse in most runs; held-out
  // error is itself noisy, so not in all: measured 17 of 20 here (the quadratic model wins by
  // chance in about 15 % of runs). 15 leaves room for the solvers' stopping points to move,
  // and still fails a rule that picks the quadratic model as often as not.
  EXPECT_GE(linear_chosen, 15) << linear_chosen;
}

TEST(ModelSelection, SaysWhyWhenTheQuadraticModelCannotBeValidated) {
  // 12 positions determine the quadratic model exactly: no fit is left without one of them.
  const ModelSelection s =
      SelectModel(Readings(Yang2012Truth(), RandomDirections(12, 4), 5), Options());
  EXPECT_EQ(s.chosen, ModelKind::kLinear);
  EXPECT_EQ(s.reason,
            "the quadratic model cannot be validated (without position 1: the quadratic model "
            "needs at least 12 positions, got 11)");
}

}  // namespace
}  // namespace accelcal
