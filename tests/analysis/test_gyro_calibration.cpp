// The gyroscope's calibration on the bundled real recordings (gyro_calibration.hpp), against
// the targets of issue 18 and the Xsens calibration sheet (data/README.md).
#include <cmath>

#include <gtest/gtest.h>

#include "accelcal/calibrate.hpp"
#include "accelcal/diagnosis.hpp"
#include "accelcal/error.hpp"
#include "accelcal/gyro_calibration.hpp"
#include "accelcal/known_orientation.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/static_detection.hpp"
#include "support/paths.hpp"

namespace accelcal {
namespace {

const std::string kData = ACCELCAL_DATA_DIR;

struct Recording {
  InputData accel, gyro;
  std::vector<Position> positions;
  CalibrationResult accel_cal;
};

// As the command line does it: positions detected, the accelerometer's maximum-likelihood fit
// (linear, x-first) with each position's noise from its samples.
Recording Load(const std::string& accel, const std::string& gyro, double gravity) {
  Recording r;
  r.accel = ReadInput(kData + accel, {});
  r.gyro = ReadInput(kData + gyro, {});
  r.positions = PositionsFromIntervals(DetectStaticIntervals(r.accel.raw, {}).intervals);
  CalibrationOptions o;
  o.gravity = gravity;
  o.reading_sigmas = SigmasOfMeans(r.positions);
  r.accel_cal = Calibrate(Means(r.positions), o);
  EXPECT_TRUE(r.accel_cal.summary.converged());
  return r;
}

const Recording& Xsens() {
  static const Recording r =
      Load("/imutk-xsens-mti/xsens_acc.mat", "/imutk-xsens-mti/xsens_gyro.mat", 9.81744);
  return r;
}
const Recording& T265() {
  static const Recording r = Load("/imutk-t265/t265_acc.mat", "/imutk-t265/t265_gyr.mat", 9.8016);
  return r;
}

GyroCalibration Calibrated(const Recording& r, GyroCalibrationOptions o) {
  return CalibrateGyro(r.accel.raw, r.gyro.raw, r.positions, r.accel_cal, o);
}

TEST(GyroCalibration, XsensMeetsTheTargetsAndTheCalibrationSheet) {
  const GyroCalibration g = Calibrated(Xsens(), {});
  // 38 still positions, 37 turns between them; the g-sensitivity chosen on held-out error.
  ASSERT_EQ(g.rotations.size(), 37u);
  EXPECT_EQ(g.model, GyroModelKind::kGSensitive) << g.model_reason;
  EXPECT_LE(g.heldout_rms_deg, 0.20);  // issue 18: ≤ 0.20° (imu_tk's method 0.60°)
  EXPECT_LE(g.rms_deg, g.heldout_rms_deg);
  // The sheet: scale diag(4778, 4758, 4766) counts per rad/s times a misalignment matrix with
  // rows (1, −0.01, −0.02), (0, 1, 0.04), (−0.01, 0.01, 1): each axis' sensitivity, the norm of
  // its row, is frame-free and comparable with the norm of the fitted K_g's row.
  const Vec3 sheet(4778 * std::sqrt(1 + 1e-4 + 4e-4), 4758 * std::sqrt(1 + 16e-4),
                   4766 * std::sqrt(1 + 1e-4 + 1e-4));
  for (int i = 0; i < 3; ++i) {
    const double relative = g.params.K.row(i).norm() / sheet(i) - 1;
    EXPECT_LT(std::abs(relative), 0.002) << "axis " << i << ": " << g.params.K.row(i);
  }
  // Every parameter has a standard deviation; the scales' are small against the 0.2 %.
  ASSERT_EQ(g.covariance.rows(), 21);
  for (int i = 0; i < 21; ++i) EXPECT_GT(g.covariance(i, i), 0) << i;
  for (int i = 0; i < 3; ++i) EXPECT_LT(std::sqrt(g.covariance(7 * i + i, 7 * i + i)), 4.0);
  // The joint fit's accelerometer is close to its own fit's (the rotations refine it).
  ASSERT_TRUE(g.accelerometer);
  EXPECT_LT((g.accelerometer->params.K - Xsens().accel_cal.params.K).norm(), 1.0);
}

TEST(GyroCalibration, ImuTkBaselineOnXsensIsTheIssuesPrototype) {
  // imu_tk's method (the bias the first still position's mean rate, K_g from the turns, the
  // accelerometer held, no g-sensitivity): the issue's independent prototype left 0.60° held out
  // (0.52° in the fit) on this recording; here 0.54° (the turns weighted by their noise). The
  // g-sensitive joint fit is four times better.
  GyroCalibrationOptions o;
  o.estimator = GyroEstimator::kImuTk;
  const GyroCalibration g = Calibrated(Xsens(), o);
  EXPECT_EQ(g.model, GyroModelKind::kLinear);
  EXPECT_GT(g.heldout_rms_deg, 0.45);
  EXPECT_LT(g.heldout_rms_deg, 0.65);
  // The bias is the first position's mean rate, with the σ of that mean: the noise of 27 counts
  // over its 5199 samples, 0.37 counts (not the 1e-7 of the weight that holds it, found by the
  // hostile test).
  const Vec3 sigma_mean = g.noise_sigma_raw / std::sqrt(5199.0);
  for (int a = 0; a < 3; ++a) {
    EXPECT_LT(std::abs(g.params.bias(a) - g.still_spans[0].mean_raw(a)), 1e-3) << a;
    EXPECT_NEAR(std::sqrt(g.covariance(4 * a + 3, 4 * a + 3)), sigma_mean(a), 1e-9) << a;
  }
  EXPECT_GT(g.heldout_rms_deg, 3 * Calibrated(Xsens(), {}).heldout_rms_deg);
  // One model, so nothing to choose: it needs no validation (it was an internal error).
  o.validate = false;
  EXPECT_EQ(Calibrated(Xsens(), o).model, GyroModelKind::kLinear);
  o.model = GyroModelKind::kGSensitive;
  EXPECT_THROW(Calibrated(Xsens(), o), OptionError);
}

// The rules between the options, stated once: the messages name the options as a unit's request
// does ({{name}}), whoever calls CalibrateGyro.
TEST(GyroCalibrationOptions, ValidateStatesEachRuleByTheOptionsNames) {
  GyroCalibrationOptions o;
  EXPECT_EQ(o.Validate(), std::nullopt);
  o.validate = false;  // the model chosen on held-out rotations needs them
  ASSERT_TRUE(o.Validate());
  EXPECT_NE(o.Validate()->find("{{gyro_model}} auto"), std::string::npos) << *o.Validate();
  o.estimator = GyroEstimator::kImuTk;  // one model: nothing to choose
  EXPECT_EQ(o.Validate(), std::nullopt);
  o.model = GyroModelKind::kGSensitive;
  ASSERT_TRUE(o.Validate());
  EXPECT_NE(o.Validate()->find("{{gyro_estimator}} imutk"), std::string::npos);
  o = GyroCalibrationOptions{};
  o.thermal.emplace();
  o.thermal->degree = kMaxThermalDegree + 1;
  ASSERT_TRUE(o.Validate());
  EXPECT_NE(o.Validate()->find("{{gyro_thermal}}: '4'"), std::string::npos);
  o.thermal->degree = -1;
  EXPECT_TRUE(o.Validate());
  o.thermal->degree = std::nullopt;  // auto: chosen on held-out rates
  EXPECT_EQ(o.Validate(), std::nullopt);
  o.validate = false;
  o.model = GyroModelKind::kLinear;
  ASSERT_TRUE(o.Validate());
  EXPECT_NE(o.Validate()->find("{{gyro_thermal}} auto"), std::string::npos);
  o = GyroCalibrationOptions{};
  for (double latitude : {91.0, -90.5, std::nan("")}) {
    o.latitude_deg = latitude;
    EXPECT_TRUE(o.Validate()) << latitude;
  }
  o.latitude_deg = -90;
  EXPECT_EQ(o.Validate(), std::nullopt);
  o.threads = -1;
  EXPECT_TRUE(o.Validate());
}

TEST(GyroCalibration, T265JointFitDeterminesTheAccelerometersMisalignment) {
  // Six axis-aligned orientations: the accelerometer alone leaves its misalignment poorly
  // determined, and the gyro fit on top of it (two-stage) inherits the error; the joint fit's
  // rotations determine it (issue 18: ≤ 0.30° held out; imu_tk about 1.6°).
  GyroCalibrationOptions o;
  o.unit = GyroUnit::kRadPerSecond;
  const GyroCalibration joint = Calibrated(T265(), o);
  EXPECT_LE(joint.heldout_rms_deg, 0.30);
  o.estimator = GyroEstimator::kTwoStage;
  const GyroCalibration two = Calibrated(T265(), o);
  EXPECT_GT(two.heldout_rms_deg, 2.0);
  ASSERT_TRUE(joint.accelerometer);
  ASSERT_EQ(joint.accelerometer->covariance.rows(), 9);
  // The misalignment K_zx, K_zy (flat 7 and 8 of the x-first linear order) with the σ the
  // rotations give: smaller than the accelerometer's own.
  const Eigen::MatrixXd& alone = T265().accel_cal.covariance;
  for (int i : {3, 6, 7}) {
    EXPECT_LT(joint.accelerometer->covariance(i, i), alone(i, i)) << i;
  }
}

TEST(GyroCalibration, FerrarisFullTurnsIntegrateToTheirKnownAngle) {
  // imucal's Ferraris session: each axis held up and down, thirteen still positions of known
  // direction (data/imucal-ferraris/ferraris_session_orientations.csv), the accelerometer
  // calibrated from them in the platform frame and the gyroscope fitted on top (two-stage). Three
  // turns are full turns about the vertical (x, y, then z up: positions 8-9, 10-11, 12-13):
  // gravity stays on the axis, so they barely inform the fit (their held-out residual equals their
  // residual), and the angle they turned through is known, 360°: an independent check of the
  // gyro's scale factors (issue 18).
  ReadOptions accel_options, gyro_options;
  accel_options.columns = {"5", "6", "7"};
  gyro_options.columns = {"2", "3", "4"};
  accel_options.rate_hz = gyro_options.rate_hz = 102.4;
  const std::string file = kData + "/imucal-ferraris/example_ferraris_session.csv";
  const InputData accel = ReadInput(file, accel_options);
  const InputData gyro = ReadInput(file, gyro_options);
  const std::vector<Position> positions =
      PositionsFromIntervals(DetectStaticIntervals(accel.raw, {}).intervals);
  const std::vector<Vec3> up = {{1, 0, 0}, {1, 0, 0},  {-1, 0, 0}, {0, 1, 0}, {0, -1, 0},
                                {0, 0, 1}, {0, 0, -1}, {1, 0, 0},  {1, 0, 0}, {0, 1, 0},
                                {0, 1, 0}, {0, 0, 1},  {0, 0, 1}};
  ASSERT_EQ(positions.size(), up.size());
  KnownOrientationOptions ko;
  ko.gravity = 9.81;
  ko.reading_sigmas = SigmasOfMeans(positions);
  const CalibrationResult accel_cal = CalibrateKnownOrientations(Means(positions), up, ko);
  GyroCalibrationOptions o;
  o.unit = GyroUnit::kDegPerSecond;
  o.estimator = GyroEstimator::kTwoStage;
  o.model = GyroModelKind::kLinear;
  const GyroCalibration g = CalibrateGyro(accel.raw, gyro.raw, positions, accel_cal, o);
  ASSERT_EQ(g.rotations.size(), 12u);
  for (std::size_t k : {7u, 9u, 11u}) {
    const GyroRotation& r = g.rotations[k];
    SCOPED_TRACE("turn " + std::to_string(r.from + 1) + "-" + std::to_string(r.to + 1));
    EXPECT_NEAR(r.heldout_deg, r.residual_deg, 1e-3);  // no leverage on the fit
    // Within 3σ of 360° (a correct σ is passed 99.7 % of the time); measured 361.5 ± 0.7,
    // 355.9 ± 1.8, 360.9 ± 0.4.
    EXPECT_LT(std::abs(r.turned_deg - 360), 3 * r.turned_std_deg) << r.turned_std_deg;
    EXPECT_LT(r.turned_std_deg, 2.0);
  }
  // The check has power: the nominal scale (180/π deg/s per rad/s) turns x 370°, 13σ away.
  const GyroRotation& x = g.rotations[7];
  const double nominal = x.turned_deg * g.params.K(0, 0) / (180 / std::acos(-1.0));
  EXPECT_GT(std::abs(nominal - 360), 10 * x.turned_std_deg) << nominal;
}

// The codes of the gyroscope's findings of at least `severity`.
std::vector<std::string> GyroCodes(const GyroCalibration& g, Severity severity) {
  std::vector<std::string> codes;
  for (const Finding& f : GyroFindings(g)) {
    if (f.severity >= severity) codes.push_back(f.code);
  }
  return codes;
}

TEST(GyroCalibration, DiagnosisFailsAGyroscopeThatDoesNotFit) {
  // The Xsens fits: nothing to warn about. The T265's two-stage fit, held to an accelerometer
  // misalignment its rotations contradict, misses by 2.7° at 101 times the rate noise: failed.
  // The Xsens gyro read as if turned 180° about z (x and y mirrored about mid-scale) had missed
  // by 122° RMS and been failed; since issue 47 the fit starts from the mount whose start turns
  // the directions best, and it fits as the Xsens does, K_g's first two rows negated.
  EXPECT_TRUE(GyroCodes(Calibrated(Xsens(), {}), Severity::kWarning).empty());
  GyroCalibrationOptions o;
  o.unit = GyroUnit::kRadPerSecond;
  o.estimator = GyroEstimator::kTwoStage;
  o.model = GyroModelKind::kLinear;
  o.validate = false;
  EXPECT_EQ(GyroCodes(Calibrated(T265(), o), Severity::kFailure),
            std::vector<std::string>{"gyro_misfit"});
  Recording turned = Xsens();
  for (Vec3& s : turned.gyro.raw.samples) {
    s(0) = 65535 - s(0);
    s(1) = 65535 - s(1);
  }
  GyroCalibrationOptions x;
  x.estimator = GyroEstimator::kTwoStage;
  x.validate = false;
  x.model = GyroModelKind::kLinear;
  const GyroCalibration g = Calibrated(turned, x);
  const GyroCalibration aligned = Calibrated(Xsens(), x);
  EXPECT_LT(g.rms_deg, 1.5 * aligned.rms_deg);
  EXPECT_TRUE(GyroCodes(g, Severity::kFailure).empty());
  const Mat33 flip = Vec3(-1, -1, 1).asDiagonal();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      EXPECT_NEAR(g.params.K(i, j), (flip * aligned.params.K)(i, j),
                  4 * std::sqrt(aligned.covariance(4 * i + j, 4 * i + j)))
          << i << j;
    }
  }
}

TEST(GyroCalibration, FirstOrderHeldOutAgreesWithFullRefits) {
  // One Gauss-Newton step from the full fit, against the fit solved in full without each
  // rotation: the held-out errors agree within 3 % of each (or 0.002°), both estimators.
  for (GyroEstimator e : {GyroEstimator::kTwoStage, GyroEstimator::kJoint}) {
    GyroCalibrationOptions o;
    o.model = GyroModelKind::kGSensitive;
    o.estimator = e;
    const GyroCalibration fast = Calibrated(Xsens(), o);
    o.heldout_refits = true;
    const GyroCalibration full = Calibrated(Xsens(), o);
    for (std::size_t k = 0; k < fast.rotations.size(); ++k) {
      EXPECT_NEAR(fast.rotations[k].heldout_deg, full.rotations[k].heldout_deg,
                  std::max(0.002, 0.03 * full.rotations[k].heldout_deg))
          << k;
    }
  }
}

TEST(GyroCalibration, SameBitsOnAnyThreadCount) {
  GyroCalibrationOptions o;
  o.threads = 1;
  const GyroCalibration one = Calibrated(Xsens(), o);
  // 2: the two models on a thread each; 4: and two threads each for their turns.
  for (int threads : {2, 3, 4}) {
    o.threads = threads;
    const GyroCalibration many = Calibrated(Xsens(), o);
    EXPECT_EQ(Pack(many.params, many.model), Pack(one.params, one.model)) << threads;
    EXPECT_EQ(many.covariance, one.covariance) << threads;
    EXPECT_EQ(many.heldout_rms_deg, one.heldout_rms_deg) << threads;
    ASSERT_TRUE(many.accelerometer && one.accelerometer);
    EXPECT_EQ(many.accelerometer->params.K, one.accelerometer->params.K) << threads;
  }
}

TEST(GyroCalibration, RefusesStreamsOnDifferentClocks) {
  const Recording& r = Xsens();
  RawLog shorter = r.gyro.raw;
  shorter.samples.pop_back();
  shorter.time_s.pop_back();
  EXPECT_THROW(CalibrateGyro(r.accel.raw, shorter, r.positions, r.accel_cal, {}), DataError);
  RawLog shifted = r.gyro.raw;
  for (double& t : shifted.time_s) t += 0.02;
  try {
    CalibrateGyro(r.accel.raw, shifted, r.positions, r.accel_cal, {});
    ADD_FAILURE() << "no error";
  } catch (const DataError& e) {
    EXPECT_NE(std::string(e.what()).find("one clock"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace accelcal
