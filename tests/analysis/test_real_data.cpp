// Real recordings against the published or source reference calibrations (data/README.md).
#include <cmath>
#include <fstream>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "accelcal/calibrate.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/static_detection.hpp"
#include "support/paths.hpp"

namespace accelcal {
namespace {

const std::string kData = ACCELCAL_DATA_DIR;

CalibrationResult CalibrateMeans(const std::vector<Vec3>& means, double gravity,
                                 SolverMethod method = SolverMethod::kJoint) {
  CalibrationOptions o;
  o.gravity = gravity;
  o.method = method;
  const CalibrationResult r = Calibrate(means, o);
  EXPECT_TRUE(r.summary.converged()) << r.summary.BriefReport();
  return r;
}

std::vector<Position> DetectedPositions(const std::string& path) {
  const InputData d = ReadInput(path, {});
  EXPECT_EQ(d.kind, InputKind::kRaw);
  return PositionsFromIntervals(DetectStaticIntervals(d.raw, {}).intervals);
}

// imu_tk's model a = T K (raw − b) with T upper unit-triangular: RMS of |a| − g.
double ImuTkRms(const Mat33& T, const Vec3& K, const Vec3& b, const std::vector<Vec3>& raw,
                double g) {
  std::vector<double> e;
  for (const Vec3& p : raw) e.push_back((T * K.asDiagonal() * (p - b)).norm() - g);
  return Rms(e);
}

TEST(RealData, XsensDetectionFindsTheStaticIntervals) {
  const std::vector<Position> detected =
      DetectedPositions(kData + "/imutk-xsens-mti/xsens_acc.mat");
  const InputData ref = ReadInput(kData + "/imutk-xsens-mti/derived_static_means.csv", {});
  ASSERT_EQ(ref.positions.size(), 38u);
  ASSERT_EQ(detected.size(), 38u);
  // Same positions in the same order: the means agree to within the noise.
  for (std::size_t k = 0; k < 38; ++k) {
    EXPECT_LT((detected[k].mean - ref.positions[k].mean).lpNorm<Eigen::Infinity>(), 3.0) << k;
  }
  EXPECT_NEAR(detected[0].interval->t_end_s - detected[0].interval->t_begin_s, 51, 1.0);
}

TEST(RealData, XsensMatchesImuTk) {
  const double g = 9.81744;
  const std::vector<Vec3> means =
      Means(DetectedPositions(kData + "/imutk-xsens-mti/xsens_acc.mat"));
  for (SolverMethod method : {SolverMethod::kJoint, SolverMethod::kTwoStep}) {
    const CalibrationResult r = CalibrateMeans(means, g, method);
    EXPECT_LE(Rms(GravityNormErrors(r.params, means, g)), 0.0012);
    // Biases are in raw counts, independent of the body frame.
    EXPECT_NEAR(r.params.bias(0), 33124.2, 3.0);
    EXPECT_NEAR(r.params.bias(1), 33275.2, 3.0);
    EXPECT_NEAR(r.params.bias(2), 32364.4, 3.0);
    // Scale factors compared frame-independently: the row norms of the map M from specific force
    // to raw counts (M Mᵀ does not depend on the body frame). imu_tk: M = K⁻¹ T⁻¹.
    Mat33 T;
    T << 1, -0.0033593, -0.0089064, 0, 1, -0.0213341, 0, 0, 1;
    const Mat33 M_imutk = Vec3(414.459, 412.010, 414.649).asDiagonal() * T.inverse();
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(r.params.K.row(i).norm() / M_imutk.row(i).norm(), 1.0, 0.002) << "axis " << i;
    }
  }
}

TEST(RealData, T265WithinFivePercentOfImuTk) {
  const double g = 9.8016;
  Mat33 T;
  T << 1, 0.0194692, -0.0574956, 0, 1, -0.00366816, 0, 0, 1;
  const Vec3 K(1.00773, 1.01848, 1.01499), b(-0.19119, 0.57394, -0.231325);
  // On our own detected intervals and on the collection's derived interval means.
  const std::vector<Vec3> detected = Means(DetectedPositions(kData + "/imutk-t265/t265_acc.mat"));
  EXPECT_GE(detected.size(), 40u);
  const InputData derived = ReadInput(kData + "/imutk-t265/derived_static_means.csv", {});
  for (const std::vector<Vec3>& means : {detected, Means(derived.positions)}) {
    const CalibrationResult r = CalibrateMeans(means, g);
    const double ours = Rms(GravityNormErrors(r.params, means, g));
    // imu_tk's result applied to the same means as X' = T K (X − B); the data README quotes 0.0063
    // on the derived means, where this gives 0.00645: hold ours to the smaller of the two.
    const double reference = std::min(ImuTkRms(T, K, b, means, g), 0.0063);
    EXPECT_LE(ours, 1.05 * reference) << "ours " << ours << ", imu_tk " << reference;
  }
}

TEST(RealData, CtuSetsWithinFivePercentOfHassanBao) {
  Mat33 S;
  S << 1.0075137, -0.0077310, 0.0265508, -0.0077310, 0.9969319, 0.0017604, 0.0265508, 0.0017604,
      0.9933545;
  const Vec3 B(0.00085323, -0.00518429, 0.01353838);
  const struct {
    const char* file;
    double published_rms;
  } sets[] = {{"measured_accelerations_24pos.csv", 0.00043},
              {"measured_accelerations_49pos.csv", 0.00093}};
  for (const auto& set : sets) {
    const InputData d = ReadInput(kData + "/ctu-innalabs-ahrs-m3/" + set.file, {});
    ASSERT_EQ(d.kind, InputKind::kPositions);
    const std::vector<Vec3> means = Means(d.positions);
    std::vector<double> e;
    for (const Vec3& v : means) e.push_back((S * (v - B)).norm() - 1.0);
    const double reference = Rms(e);
    EXPECT_NEAR(reference, set.published_rms, 0.00001) << set.file;
    const CalibrationResult r = CalibrateMeans(means, 1.0);
    EXPECT_LE(Rms(GravityNormErrors(r.params, means, 1.0)), 1.05 * reference) << set.file;
  }
}

}  // namespace
}  // namespace accelcal
