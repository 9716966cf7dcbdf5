// Leave-one-position-out validation in every result, and starting from given parameters.
#include <cmath>
#include <stdexcept>

#include <gtest/gtest.h>

#include "accelcal/calibrate.hpp"
#include "accelcal/simulate.hpp"

namespace accelcal {
namespace {

constexpr double kG = kYang2012Gravity_ms2;

std::vector<Vec3> Table3Readings(ModelKind model, std::uint64_t seed) {
  ModelParameters truth = Yang2012Truth();
  if (model == ModelKind::kLinear) truth.k2.setZero();
  const Vec3 sigma = Yang2012SigmaRaw(truth);
  return SimulatePositions(truth, kG, Yang18Directions(), sigma, seed);
}

CalibrationOptions Options(ModelKind model) {
  CalibrationOptions o;
  o.model = model;
  o.gravity = kG;
  return o;
}

TEST(Calibrate, StartsFromGivenParameters) {
  const std::vector<Vec3> readings = Table3Readings(ModelKind::kQuadratic, 5);
  CalibrationOptions o = Options(ModelKind::kQuadratic);
  const CalibrationResult cold = Calibrate(readings, o);
  o.initialization = Initialization::kGiven;
  o.initial_params = Yang2012Truth();
  const CalibrationResult warm = Calibrate(readings, o);
  ASSERT_TRUE(warm.summary.converged()) << warm.summary.BriefReport();
  EXPECT_EQ(warm.summary.initialization, Initialization::kGiven);
  EXPECT_LT((warm.params.K - cold.params.K).norm(), 1e-9 * cold.params.K.norm());
  EXPECT_LT((warm.params.k2 - cold.params.k2).norm(), 1e-6 * cold.params.k2.norm());
  // Given parameters without kGiven, or kGiven without them, is a usage error.
  o.initialization = Initialization::kAuto;
  EXPECT_THROW(Calibrate(readings, o), std::invalid_argument);
  o.initialization = Initialization::kGiven;
  o.initial_params.reset();
  EXPECT_THROW(Calibrate(readings, o), std::invalid_argument);
}

TEST(Calibrate, CrossValidationIsTheFitWithoutEachPosition) {
  for (ModelKind model : {ModelKind::kLinear, ModelKind::kQuadratic}) {
    const std::vector<Vec3> readings = Table3Readings(model, 9);
    CalibrationOptions o = Options(model);
    o.cross_validate = true;
    const CalibrationResult r = Calibrate(readings, o);
    ASSERT_TRUE(r.crossval_rms.has_value()) << r.crossval_note;
    ASSERT_EQ(r.crossval_errors.size(), readings.size());
    // Independent cold fits without each position reach the same optima, so the held-out errors
    // agree far below their size (~1e-5 m/s² here): measured to 3e-12 g, limited by the solvers'
    // stopping points on |f| ≈ g; 1e-10 g allows for that.
    std::vector<double> errors;
    for (std::size_t k = 0; k < readings.size(); ++k) {
      std::vector<Vec3> subset = readings;
      subset.erase(subset.begin() + static_cast<std::ptrdiff_t>(k));
      const CalibrationResult fit = Calibrate(subset, Options(model));
      errors.push_back(GravityNormErrors(fit.params, {readings[k]}, kG)[0]);
      EXPECT_NEAR(r.crossval_errors[k], errors.back(), 1e-10 * kG)
          << ToString(model) << " position " << k + 1;
    }
    EXPECT_NEAR(*r.crossval_rms, Rms(errors), 1e-10 * kG);
    // Held out, a position is predicted worse than when it is fitted.
    EXPECT_GT(*r.crossval_rms, Rms(GravityNormErrors(r.params, readings, kG)));
  }
}

TEST(Calibrate, CrossValidationSaysWhyWhenAPositionCannotBeLeftOut) {
  const std::vector<Vec3> readings =
      SimulatePositions(Yang2012Truth(), kG, RandomDirections(12, 3), Vec3::Constant(0.01), 4);
  CalibrationOptions o = Options(ModelKind::kQuadratic);
  o.cross_validate = true;
  const CalibrationResult r = Calibrate(readings, o);  // exactly determined: 12 positions
  EXPECT_FALSE(r.crossval_rms.has_value());
  EXPECT_EQ(r.crossval_note,
            "without position 1: the quadratic model needs at least 12 positions, got 11");
}

TEST(Calibrate, CrossValidationDoesNotDependOnTheFrameForTheLinearModel) {
  const std::vector<Vec3> readings = Table3Readings(ModelKind::kLinear, 11);
  CalibrationOptions o = Options(ModelKind::kLinear);
  o.cross_validate = true;
  const CalibrationResult x = Calibrate(readings, o);
  o.frame = Frame::kZFirst;
  const CalibrationResult z = Calibrate(readings, o);
  ASSERT_TRUE(x.crossval_rms && z.crossval_rms);
  EXPECT_NEAR(*z.crossval_rms, *x.crossval_rms, 1e-10 * kG);  // as above
}

}  // namespace
}  // namespace accelcal
