// The ellipsoid fit (paper 001 §3.3) and its constrained fallback (Li & Griffiths 2004), alone and
// as the start of every method.
#include <cmath>
#include <optional>
#include <random>
#include <string>

#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>

#include "accelcal/calibrate.hpp"
#include "accelcal/ellipsoid_fit.hpp"
#include "accelcal/error.hpp"
#include "accelcal/simulate.hpp"
#include "solvers/smallest_eigenvector.hpp"

namespace accelcal {
namespace {

constexpr double kPi = 3.14159265358979323846;

// The Xsens MTi of the bundled recording, roughly: raw counts per m/s² and counts.
ModelParameters XsensLikeDevice() {
  ModelParameters d;
  d.K << 414.4, 0, 0, 1.5, 412.1, 0, 3.8, 8.8, 414.5;
  d.bias << 33124, 33275, 32364;
  return d;
}

// A MEMS device in g units, as a phone reports it.
ModelParameters PhoneLikeDevice() {
  ModelParameters d;
  d.K << 1.02, 0, 0, 0.01, 0.98, 0, -0.02, 0.015, 1.01;
  d.bias << 0.03, -0.02, 0.05;
  return d;
}

// A strongly quadratic device (g units): its readings lie on no ellipsoid at all.
ModelParameters BentDevice() {
  ModelParameters d;
  d.k2 << 0.8, -0.4, 0.56;
  return d;
}

// Positions tilted at most 60° from "flat on the desk", σ = 0.03 g: the algebraic quadric is a
// hyperboloid for about half of the seeds (measured: 92 of 200).
std::vector<Vec3> DeskTiltReadings(std::uint64_t seed) {
  return SimulatePositions(PhoneLikeDevice(), 1.0, RandomDirectionsInCap(15, kPi / 3, seed),
                           Vec3::Constant(0.03), seed + 1000);
}

TEST(EllipsoidFit, RecoversALinearDeviceExactly) {
  const ModelParameters truth = XsensLikeDevice();
  const std::vector<Vec3> readings =
      SimulatePositions(truth, 9.8, RandomDirections(12, 2), Vec3::Zero(), 1);
  const EllipsoidFitResult fit = FitEllipsoid(readings, 9.8);
  ASSERT_TRUE(fit.ok) << fit.failure;
  EXPECT_EQ(fit.kind, EllipsoidFitKind::kAlgebraic);
  EXPECT_LT((fit.params.K - truth.K).norm(), 1e-7 * truth.K.norm());
  EXPECT_LT((fit.params.bias - truth.bias).norm(), 1e-7 * truth.bias.norm());
}

TEST(EllipsoidFit, ConstrainedFitRecoversALinearDeviceExactly) {
  // Noise-free readings lie on the true ellipsoid, which meets 4J − I² > 0 (gains within a factor
  // 2): the constrained minimum is the zero of the unconstrained cost, the truth.
  const ModelParameters truth = XsensLikeDevice();
  const std::vector<Vec3> readings =
      SimulatePositions(truth, 9.8, RandomDirections(12, 2), Vec3::Zero(), 1);
  const EllipsoidFitResult fit = FitEllipsoidConstrained(readings, 9.8);
  ASSERT_TRUE(fit.ok) << fit.failure;
  EXPECT_EQ(fit.kind, EllipsoidFitKind::kConstrained);
  EXPECT_TRUE(fit.failure.empty()) << fit.failure;
  EXPECT_LT((fit.params.K - truth.K).norm(), 1e-7 * truth.K.norm());
  EXPECT_LT((fit.params.bias - truth.bias).norm(), 1e-7 * truth.bias.norm());
}

bool IsProperEllipsoid(const ModelParameters& p) {
  return p.K.allFinite() && p.bias.allFinite() && (p.K.diagonal().array() > 0).all() &&
         p.K.isLowerTriangular();
}

TEST(EllipsoidFit, FallsBackToAnEllipsoidWhenTheQuadricIsAHyperboloid) {
  int hyperboloids = 0;
  for (std::uint64_t seed = 0; seed < 200; ++seed) {
    const EllipsoidFitResult fit = FitEllipsoid(DeskTiltReadings(seed), 1.0);
    ASSERT_TRUE(fit.ok) << "seed " << seed << ": " << fit.failure;
    ASSERT_TRUE(IsProperEllipsoid(fit.params)) << "seed " << seed;
    if (fit.kind == EllipsoidFitKind::kConstrained) {
      ++hyperboloids;
      EXPECT_EQ(fit.failure.rfind("the fitted quadric is not an ellipsoid", 0), 0u) << fit.failure;
    }
  }
  // The test means something only if the fallback ran: 92 of 200 measured.
  EXPECT_GT(hyperboloids, 50);
  // Readings on no ellipsoid at all still give one.
  const EllipsoidFitResult bent = FitEllipsoid(
      SimulatePositions(BentDevice(), 1.0, RandomDirections(20, 5), Vec3::Zero(), 1), 1.0);
  ASSERT_TRUE(bent.ok) << bent.failure;
  EXPECT_EQ(bent.kind, EllipsoidFitKind::kConstrained);
  EXPECT_TRUE(IsProperEllipsoid(bent.params));
}

TEST(EllipsoidFit, RefusesTooFewOrIdenticalReadings) {
  const std::vector<Vec3> eight(8, Vec3(0, 0, 1));
  EXPECT_EQ(FitEllipsoid(eight, 1.0).failure, "an ellipsoid needs at least 9 readings, got 8");
  const std::vector<Vec3> same(12, Vec3(0, 0, 1));
  EXPECT_EQ(FitEllipsoidConstrained(same, 1.0).failure, "all readings are identical");
  EXPECT_FALSE(FitEllipsoid(same, 1.0).ok);
}

TEST(Calibrate, StartsFromTheConstrainedFitWhenTheQuadricIsNoEllipsoid) {
  const ModelParameters truth = BentDevice();
  const std::vector<Vec3> readings =
      SimulatePositions(truth, 1.0, RandomDirections(20, 5), Vec3::Zero(), 1);
  CalibrationOptions o;
  o.model = ModelKind::kQuadratic;
  o.gravity = 1.0;
  const CalibrationResult r = Calibrate(readings, o);
  ASSERT_TRUE(r.summary.converged()) << r.summary.BriefReport();
  EXPECT_EQ(r.summary.initialization, Initialization::kEllipsoidFit);
  EXPECT_NE(r.summary.initialization_note.find("constrained fit of Li & Griffiths"),
            std::string::npos)
      << r.summary.initialization_note;
  EXPECT_LT((r.params.k2 - truth.k2).norm(), 1e-9);
  // The paper 000 start (normalised readings) reaches the same optimum.
  o.initialization = Initialization::kNormalizedReadings;
  const CalibrationResult paper = Calibrate(readings, o);
  ASSERT_TRUE(paper.summary.converged()) << paper.summary.BriefReport();
  EXPECT_LT((paper.params.k2 - truth.k2).norm(), 1e-9);
}

TEST(Calibrate, ConstrainedStartLeadsTheJointSolverToTheOptimum) {
  // Seed 7 of the desk-tilt set: a hyperboloid, yet a well-determined optimum (measured 71 joint
  // iterations from the constrained start, 84 from the normalised readings).
  const std::vector<Vec3> readings = DeskTiltReadings(7);
  ASSERT_EQ(FitEllipsoid(readings, 1.0).kind, EllipsoidFitKind::kConstrained);
  CalibrationOptions o;
  o.gravity = 1.0;
  o.initialization = Initialization::kNormalizedReadings;
  const CalibrationResult reference = Calibrate(readings, o);
  ASSERT_TRUE(reference.summary.converged()) << reference.summary.BriefReport();
  o.initialization = Initialization::kAuto;
  const CalibrationResult joint = Calibrate(readings, o);
  ASSERT_TRUE(joint.summary.converged()) << joint.summary.BriefReport();
  EXPECT_EQ(joint.summary.initialization, Initialization::kEllipsoidFit);
  EXPECT_FALSE(joint.summary.initialization_note.empty());
  // Same optimum: both runs stop at steps below 1e-14 in the parameter metric; 1e-8 leaves room
  // for the conditioning of this poorly spread set (reciprocal condition 8.5e-7).
  EXPECT_LT((joint.params.K - reference.params.K).norm(), 1e-8);
  EXPECT_LT((joint.params.bias - reference.params.bias).norm(), 1e-8);
  // The paper's methods start from the same fit, and are honest when it is not enough: Newton
  // without a line search (paper 001 §3.2) diverges from it, and the two-step, converging
  // linearly at a rate set by the conditioning, runs out of sweeps. Neither claims convergence.
  for (SolverMethod method : {SolverMethod::kNewtonLagrange, SolverMethod::kTwoStep}) {
    o.method = method;
    const CalibrationResult r = Calibrate(readings, o);
    EXPECT_EQ(r.summary.initialization, Initialization::kEllipsoidFit);
    EXPECT_FALSE(r.summary.converged()) << r.summary.BriefReport();
  }
}

// The algebraic fit's inverse iteration against the full decomposition: symmetric positive definite
// matrices Q diag(λ) Qᵀ with a random orthogonal Q, the smallest eigenvalue separated by a factor
// of 10 to 1e6 (as the scatter of readings on an ellipsoid is) — and refused, for the full
// decomposition to take over, when it is not separated enough to converge or not positive definite.
TEST(EllipsoidFit, SmallestEigenvectorMatchesTheFullDecomposition) {
  using Mat10 = Eigen::Matrix<double, 10, 10>;
  using Vec10 = Eigen::Matrix<double, 10, 1>;
  std::mt19937_64 rng(5);
  std::normal_distribution<double> normal;
  const auto random_matrix = [&](double smallest, double second) {
    Mat10 A;
    for (int i = 0; i < 100; ++i) A(i) = normal(rng);
    const Mat10 Q = Eigen::HouseholderQR<Mat10>(A).householderQ();
    Vec10 lambda;
    lambda(0) = smallest;
    lambda(1) = second;
    for (int i = 2; i < 10; ++i) lambda(i) = second * std::pow(10.0, i / 3.0);
    return Mat10(Q * lambda.asDiagonal() * Q.transpose());
  };
  for (int trial = 0; trial < 200; ++trial) {
    const double ratio = std::pow(10.0, 1.0 + 5.0 * (trial % 50) / 49.0);  // λ2/λ1 from 10 to 1e6
    const Mat10 S = random_matrix(1.0, ratio);
    const std::optional<Vec10> v = internal::SmallestEigenvector(S);
    ASSERT_TRUE(v.has_value()) << trial;
    const Vec10 reference = Eigen::SelfAdjointEigenSolver<Mat10>(S).eigenvectors().col(0);
    // Both are unit vectors up to sign; the angle between them is bounded by the residual over
    // the gap, ~1e-15 here.
    EXPECT_LT((*v - std::copysign(1.0, v->dot(reference)) * reference).norm(), 1e-12) << trial;
  }
  // Two nearly equal smallest eigenvalues: 30 iterations at a ratio of 1.001 cannot converge.
  EXPECT_FALSE(internal::SmallestEigenvector(random_matrix(1.0, 1.001)).has_value());
  // Indefinite: inverse iteration would find the eigenvalue nearest 0, not the smallest.
  EXPECT_FALSE(internal::SmallestEigenvector(random_matrix(-1.0, 10.0)).has_value());
}

}  // namespace
}  // namespace accelcal
