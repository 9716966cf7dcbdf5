// Body-frame conventions (frame.hpp): the mirror map, the inverse model in both triangles, and
// calibration in the z-first frame.
#include <cmath>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "accelcal/calibrate.hpp"
#include "accelcal/frame.hpp"
#include "accelcal/simulate.hpp"

namespace accelcal {
namespace {

constexpr double kG = kYang2012Gravity_ms2;

TEST(Frame, MirrorMapsTheModelOntoTheMirroredProblem) {
  const ModelParameters x_first = Yang2012Truth();
  const ModelParameters z_first = MirrorAxes(x_first);
  EXPECT_TRUE(z_first.K.isUpperTriangular(0.0));
  EXPECT_GT(z_first.K.diagonal().minCoeff(), 0.0);
  EXPECT_EQ(FrameOf(z_first.K), Frame::kZFirst);
  EXPECT_EQ(FrameOf(x_first.K), Frame::kXFirst);
  // An involution, and P p = μ̃(P f): readings and forces mirror together.
  EXPECT_EQ(MirrorAxes(z_first).K, x_first.K);
  for (const Vec3& c : RandomDirections(20, 3)) {
    const Vec3 f = kG * c;
    EXPECT_LT((PredictRaw(z_first, MirrorAxes(f)) - MirrorAxes(PredictRaw(x_first, f))).norm(),
              1e-9);
  }
  // The z-first flat order is the mirror image of the x-first one.
  const auto& slots = ParameterSlots(ModelKind::kQuadratic, Frame::kZFirst);
  ASSERT_EQ(slots.size(), 12u);
  EXPECT_EQ(slots[0].name, "K_zz");
  EXPECT_EQ(slots[3].name, "K_yz");
  EXPECT_EQ(slots[3].row, 1);
  EXPECT_EQ(slots[3].col, 2);
  EXPECT_EQ(slots[11].name, "k2_x");
}

TEST(Frame, SpecificForceInvertsUpperTriangularAndFullMatrices) {
  const ModelParameters z_first = MirrorAxes(Yang2012Truth());  // quadratic, upper K
  ModelParameters full;
  full.K = Yang2012Truth().K + Mat33::Constant(0.01) * Yang2012Truth().K(0, 0);  // linear, full
  full.bias = Yang2012Truth().bias;
  for (const Vec3& c : RandomDirections(200, 4)) {
    const Vec3 f = 3.0 * kG * c;
    const std::optional<Vec3> back = SpecificForce(z_first, PredictRaw(z_first, f));
    ASSERT_TRUE(back.has_value());
    EXPECT_LT((*back - f).norm(), 1e-12 * f.norm());
    const std::optional<Vec3> back_full = SpecificForce(full, PredictRaw(full, f));
    ASSERT_TRUE(back_full.has_value());
    EXPECT_LT((*back_full - f).norm(), 1e-12 * f.norm());
  }
  // A full K with squared terms (platform frame): Newton from the linear solution.
  full.k2 = Yang2012Truth().k2;
  for (const Vec3& c : RandomDirections(200, 5)) {
    const Vec3 f = 3.0 * kG * c;
    const std::optional<Vec3> back = SpecificForce(full, PredictRaw(full, f));
    ASSERT_TRUE(back.has_value());
    EXPECT_LT((*back - f).norm(), 1e-12 * f.norm());
  }
  // A reading beyond the range of the model (the x row K_x·f − f_x² is bounded above): refused,
  // not guessed.
  full.k2 = Vec3(-1.0, 0, 0);
  EXPECT_FALSE(SpecificForce(full, Vec3(1e12, 0, 0)).has_value());
}

std::vector<Vec3> Table3Readings(const ModelParameters& truth, std::uint64_t seed) {
  const Vec3 sigma = Yang2012SigmaRaw(truth);
  return SimulatePositions(truth, kG, Yang18Directions(), sigma, seed);
}

TEST(Frame, LinearCalibrationIsTheSameDeviceInBothFrames) {
  ModelParameters truth = Yang2012Truth();
  truth.k2.setZero();
  const std::vector<Vec3> readings = Table3Readings(truth, 7);
  CalibrationOptions o;
  o.gravity = kG;
  const CalibrationResult x = Calibrate(readings, o);
  o.frame = Frame::kZFirst;
  const CalibrationResult z = Calibrate(readings, o);
  ASSERT_TRUE(x.summary.converged());
  ASSERT_TRUE(z.summary.converged());
  EXPECT_EQ(z.frame, Frame::kZFirst);
  EXPECT_TRUE(z.params.K.isUpperTriangular(0.0));
  // Same optimum: same cost, K related by a rotation (ChangeFrame), same bias and magnitudes.
  EXPECT_NEAR(z.summary.final_cost, x.summary.final_cost, 1e-9 * x.summary.final_cost);
  const Mat33 expected = ChangeFrame(x.params.K, Frame::kZFirst).K;
  EXPECT_LT((z.params.K - expected).norm(), 1e-9 * expected.norm());
  EXPECT_LT((z.params.bias - x.params.bias).norm(), 1e-9 * x.params.bias.norm());
  const std::vector<double> ex = GravityNormErrors(x.params, readings, kG);
  const std::vector<double> ez = GravityNormErrors(z.params, readings, kG);
  for (std::size_t k = 0; k < readings.size(); ++k) EXPECT_NEAR(ez[k], ex[k], 1e-9);
  // Residuals are frame-independent (p − μ in raw units).
  for (std::size_t k = 0; k < readings.size(); ++k) {
    EXPECT_LT((z.residuals[k] - x.residuals[k]).norm(), 1e-6 * x.residual_sigma);
  }
  // The standard deviations of the biases do not depend on the frame either.
  const auto sd = [](const CalibrationResult& r, Frame f, std::string_view name) {
    const auto& slots = ParameterSlots(r.model, f);
    for (std::size_t i = 0; i < slots.size(); ++i) {
      if (slots[i].name == name) {
        return std::sqrt(r.covariance(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(i)));
      }
    }
    return std::nan("");
  };
  for (std::string_view b : {"b_x", "b_y", "b_z"}) {
    EXPECT_NEAR(sd(z, Frame::kZFirst, b), sd(x, Frame::kXFirst, b), 1e-6 * sd(x, Frame::kXFirst, b))
        << b;
  }
}

TEST(Frame, QuadraticCalibrationInTheZFirstFrameRecoversAZFirstDevice) {
  // The quadratic model differs between frames (k2 ∘ f² squares body-frame components), so a
  // device described in the z-first frame is recovered exactly only by the z-first fit.
  const ModelParameters truth = MirrorAxes(Yang2012Truth());
  const std::vector<Vec3> readings =
      SimulatePositions(truth, kG, Yang18Directions(), Vec3::Zero(), 1);
  CalibrationOptions o;
  o.model = ModelKind::kQuadratic;
  o.gravity = kG;
  o.frame = Frame::kZFirst;
  const CalibrationResult z = Calibrate(readings, o);
  ASSERT_TRUE(z.summary.converged()) << z.summary.BriefReport();
  EXPECT_LT((z.params.K - truth.K).norm(), 1e-9 * truth.K.norm());
  EXPECT_LT((z.params.bias - truth.bias).norm(), 1e-9 * truth.bias.norm());
  EXPECT_LT((z.params.k2 - truth.k2).norm(), 1e-9 * truth.k2.norm());
  // Covariance: the mirrored problem's, with the signs of the mirror (noisy data).
  const std::vector<Vec3> noisy = Table3Readings(truth, 3);
  const CalibrationResult zn = Calibrate(noisy, o);
  std::vector<Vec3> mirrored;
  for (const Vec3& p : noisy) mirrored.push_back(MirrorAxes(p));
  o.frame = Frame::kXFirst;
  const CalibrationResult xm = Calibrate(mirrored, o);
  const Eigen::VectorXd d = MirrorSigns(ModelKind::kQuadratic);
  EXPECT_LT((zn.covariance - d.asDiagonal() * xm.covariance * d.asDiagonal()).norm(),
            1e-12 * xm.covariance.norm());
  EXPECT_EQ(zn.params.K, MirrorAxes(xm.params).K);
}

}  // namespace
}  // namespace accelcal
