// Parameters that follow temperature (thermal.hpp, thermal_calibration.hpp): the derivatives,
// exact recovery, Monte Carlo statistics against the Cramér-Rao bound, and held-out errors
// against offset-only compensation, on a simulated BMI088-like device (issue 21: no public
// temperature recording exists).
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "accelcal/calibrate.hpp"
#include "accelcal/design.hpp"
#include "accelcal/error.hpp"
#include "accelcal/simulate.hpp"
#include "accelcal/thermal.hpp"
#include "accelcal/thermal_calibration.hpp"
#include "solvers/thermal_fit.hpp"
#include "support/jacobian_check.hpp"

namespace accelcal {
namespace {

constexpr double kG = kYang2012Gravity_ms2;

// Paper 000's device (raw pulses, f in m/s²) with BMI088-like temperature coefficients: scale
// 0.03 %/K, misalignment 1e-6 per K, biases 0.1, 0.5 and 1 mg/K (issue 21), and for the quadratic
// model squared terms 1e-3 of theirs per K.
ThermalParameters Device(ModelKind model, const ThermalDegrees& degrees) {
  ThermalParameters p;
  p.t_ref_c = 20;
  p.degrees = degrees;
  ModelParameters at_ref = Yang2012Truth();
  if (model == ModelKind::kLinear) at_ref.k2.setZero();
  ModelParameters zero;
  zero.K.setZero();
  p.coefficients.assign(static_cast<std::size_t>(degrees.Max() + 1), zero);
  p.coefficients[0] = at_ref;
  const Vec3 mg_per_K(0.1, 0.5, 1.0);
  for (int d = 1; d <= degrees.Max(); ++d) {
    ModelParameters& c = p.coefficients[static_cast<std::size_t>(d)];
    const double shrink = std::pow(0.02, d - 1);  // higher powers of ΔT smaller
    if (degrees.K >= d) {
      for (int i = 0; i < 3; ++i) {
        c.K(i, i) = 3e-4 * shrink * at_ref.K(i, i);
        for (int j = 0; j < i; ++j) c.K(i, j) = 1e-6 * shrink * at_ref.K(i, i);
      }
    }
    if (degrees.bias >= d) {
      for (int i = 0; i < 3; ++i) c.bias(i) = mg_per_K(i) * 1e-3 * kG * at_ref.K(i, i) * shrink;
    }
    if (degrees.k2 >= d) c.k2 = 1e-3 * shrink * at_ref.k2;
  }
  return p;
}

// 150 µg/√Hz at 100 Hz, 10 s per position.
Vec3 Sigma(const ThermalParameters& device) {
  return RawNoiseFromDensity(device.At(device.t_ref_c), kG, 150, 100, 1000);
}

// `per` random orientations at each of the temperatures.
struct Schedule {
  std::vector<Vec3> dirs;
  std::vector<double> temps;
};
Schedule Chamber(const std::vector<double>& temperatures, int per, std::uint64_t seed) {
  Schedule s;
  for (std::size_t i = 0; i < temperatures.size(); ++i) {
    for (const Vec3& c : RandomDirections(per, seed + 97 * i)) {
      s.dirs.push_back(c);
      s.temps.push_back(temperatures[i]);
    }
  }
  return s;
}

ThermalOptions Options(ModelKind model, const ThermalDegrees& degrees,
                       const std::vector<double>& temps) {
  ThermalOptions o;
  o.base.model = model;
  o.base.gravity = kG;
  o.degrees = degrees;
  o.temperatures_c = temps;
  o.t_ref_c = 20;
  o.cross_validate = false;
  return o;
}

TEST(ThermalProblem, JacobiansMatchFiniteDifferences) {
  const ThermalDegrees degrees{2, 2, 1};
  const ThermalParameters truth = Device(ModelKind::kQuadratic, degrees);
  const Schedule s = Chamber({-10, 20, 50}, 4, 3);
  const std::vector<Vec3> readings =
      SimulateThermalPositions(truth, kG, s.dirs, s.temps, Vec3::Ones(), 5);
  const internal::Problem problem{readings, kG, ModelKind::kQuadratic};
  const internal::ThermalProblem lsq(problem, degrees, truth.t_ref_c, s.temps);
  Eigen::VectorXd x = Pack(truth, ModelKind::kQuadratic);
  ASSERT_EQ(x.size(), 12 + 9 + 9 + 3 /* d = 1 */ - 0 + 0);
  for (int k : {0, 5, 11}) {
    const Eigen::VectorXd c = s.dirs[std::size_t(k)];
    Eigen::VectorXd r;
    Eigen::MatrixXd J_x, J_y;
    ASSERT_TRUE(lsq.Evaluate(k, x, c, &r, &J_x, &J_y));
    const auto of_x = [&](const Eigen::VectorXd& xx) {
      Eigen::VectorXd rr;
      lsq.Evaluate(k, xx, c, &rr, nullptr, nullptr);
      return rr;
    };
    EXPECT_TRUE(testing::JacobianMatches(of_x, x, J_x)) << k;
    const auto of_delta = [&](const Eigen::VectorXd& delta) {
      Eigen::VectorXd rr;
      lsq.Evaluate(k, x, lsq.PlusLocal(k, c, delta), &rr, nullptr, nullptr);
      return rr;
    };
    EXPECT_TRUE(testing::JacobianMatches(of_delta, Eigen::Vector2d::Zero(), J_y)) << k;
  }
}

TEST(ThermalCalibration, NoiseFreeReadingsGiveTheTruth) {
  for (ModelKind model : {ModelKind::kLinear, ModelKind::kQuadratic}) {
    const ThermalDegrees degrees{1, 2, model == ModelKind::kQuadratic ? 1 : 0};
    const ThermalParameters truth = Device(model, degrees);
    const Schedule s = Chamber({-10, 5, 20, 35, 50}, 10, 11);
    const std::vector<Vec3> readings =
        SimulateThermalPositions(truth, kG, s.dirs, s.temps, Vec3::Constant(1e-300), 7);
    const ThermalResult r = CalibrateThermal(readings, Options(model, degrees, s.temps));
    ASSERT_TRUE(r.summary.converged()) << r.summary.termination_message;
    const Eigen::VectorXd e = Pack(r.params, model) - Pack(truth, model);
    const Eigen::VectorXd t = Pack(truth, model);
    for (Eigen::Index i = 0; i < e.size(); ++i) {
      EXPECT_LE(std::abs(e(i)), 1e-7 * std::max(1.0, std::abs(t(i)))) << i;
    }
  }
}

// Temperatures that cannot separate a degree: refused, naming what to record.
TEST(ThermalCalibration, OneTemperatureDoesNotDetermineASlope) {
  const ThermalDegrees degrees{1, 1, 0};
  const ThermalParameters truth = Device(ModelKind::kLinear, degrees);
  const Schedule s = Chamber({25}, 30, 1);
  const std::vector<Vec3> readings =
      SimulateThermalPositions(truth, kG, s.dirs, s.temps, Sigma(truth), 1);
  try {
    (void)CalibrateThermal(readings, Options(ModelKind::kLinear, degrees, s.temps));
    ADD_FAILURE() << "no error";
  } catch (const DataError& e) {
    EXPECT_NE(std::string(e.what()).find("at 2 temperatures or more"), std::string::npos)
        << e.what();
  }
  ThermalOptions bad = Options(ModelKind::kLinear, ThermalDegrees{0, 0, 1}, s.temps);
  EXPECT_THROW((void)CalibrateThermal(readings, bad), std::invalid_argument);  // no k2
  bad = Options(ModelKind::kLinear, degrees, s.temps);
  bad.temperatures_c[3] = std::nan("");
  EXPECT_THROW((void)CalibrateThermal(readings, bad), std::invalid_argument);
  bad = Options(ModelKind::kLinear, degrees, s.temps);
  bad.temperatures_c.pop_back();
  EXPECT_THROW((void)CalibrateThermal(readings, bad), std::invalid_argument);
  bad = Options(ModelKind::kLinear, degrees, s.temps);
  bad.base.frame = Frame::kZFirst;
  EXPECT_THROW((void)CalibrateThermal(readings, bad), std::invalid_argument);
}

// The Cramér-Rao bound of the thermal vector for `schedule` at the truth: S = Σ u_k u_kᵀ / σ_n²,
// σ_n² = Σ n_i² σ_i² the noise along position k's normal.
Eigen::MatrixXd Crlb(const ThermalParameters& truth, ModelKind model, const Schedule& schedule,
                     const Vec3& sigma) {
  const std::vector<Vec3> readings =
      SimulateThermalPositions(truth, kG, schedule.dirs, schedule.temps, Vec3::Constant(1e-300), 1);
  const internal::Problem problem{readings, kG, model};
  const internal::ThermalProblem lsq(problem, truth.degrees, truth.t_ref_c, schedule.temps);
  const Eigen::VectorXd x = Pack(truth, model);
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(x.size(), x.size());
  for (std::size_t k = 0; k < readings.size(); ++k) {
    Vec3 n;
    const Eigen::VectorXd u =
        internal::InformationRow(lsq, x, static_cast<int>(k), schedule.dirs[k].normalized(), &n);
    S += u * u.transpose() / n.cwiseAbs2().dot(sigma.cwiseAbs2());
  }
  return S.inverse();
}

// Monte Carlo over 200 noise draws of a chamber schedule (5 temperatures, 12 orientations at
// each): the estimates within 4σ of the truth (as often as Student's t allows), the RMSE of every
// coefficient within 10 % of its Cramér-Rao bound, and 1σ intervals covering as Student's t
// predicts.
TEST(ThermalCalibration, MonteCarloMeetsTheCramerRaoBound) {
  const ModelKind model = ModelKind::kLinear;
  const ThermalDegrees degrees{1, 1, 0};
  const ThermalParameters truth = Device(model, degrees);
  const Vec3 sigma = Sigma(truth);
  const Schedule s = Chamber({-10, 5, 20, 35, 50}, 12, 41);
  const Eigen::MatrixXd crlb = Crlb(truth, model, s, sigma);
  const Eigen::VectorXd t = Pack(truth, model);
  const int runs = 200, n = static_cast<int>(t.size());
  Eigen::VectorXd sum2 = Eigen::VectorXd::Zero(n);
  int inside = 0, count = 0, beyond4 = 0;
  double z2 = 0;
  for (int run = 1; run <= runs; ++run) {
    const std::vector<Vec3> readings = SimulateThermalPositions(truth, kG, s.dirs, s.temps, sigma,
                                                                static_cast<std::uint64_t>(run));
    const ThermalResult r = CalibrateThermal(readings, Options(model, degrees, s.temps));
    ASSERT_TRUE(r.summary.converged()) << run << ": " << r.summary.termination_message;
    ASSERT_EQ(r.covariance.rows(), n);
    const Eigen::VectorXd e = Pack(r.params, model) - t;
    sum2 += e.cwiseAbs2();
    for (int i = 0; i < n; ++i) {
      const double z = e(i) / std::sqrt(r.covariance(i, i));
      beyond4 += std::abs(z) >= 4.0 ? 1 : 0;
      z2 += z * z;
      inside += std::abs(z) < 1.0 ? 1 : 0;
      ++count;
    }
  }
  // RMSE over 200 runs estimates σ to ±5 % (1/√(2·200)): 1.1 is two of those above the bound.
  for (int i = 0; i < n; ++i) {
    const double ratio = std::sqrt(sum2(i) / runs / crlb(i, i));
    EXPECT_LE(ratio, 1.1) << "parameter " << i;
    EXPECT_GE(ratio, 0.9) << "parameter " << i;
  }
  // σ̂ from 60 − 18 = 42 degrees of freedom: z is Student's t, E z² = 42/40 = 1.05 and
  // P(|z| < 1) = 0.677; 3600 values, correlated within a run (SE of the fraction ≤ 0.019 even if
  // only 600 were independent).
  EXPECT_NEAR(std::sqrt(z2 / count), std::sqrt(1.05), 0.06);
  EXPECT_NEAR(static_cast<double>(inside) / count, 0.677, 0.04);
  // Within 4σ: Student's t with 42 degrees of freedom leaves 2.5e-4 beyond it, 0.9 of 3600.
  EXPECT_LE(beyond4, 4);
  // Measured: rms z 1.046, coverage 0.670, one |z| beyond 4; RMSE/CRLB 0.954-1.086.
}

// Held out over the temperature range, the full thermal model predicts |f| − g better than the
// offset-only compensation PX4 and ArduPilot apply (the bias alone a polynomial in T), which in
// turn beats one calibration for all temperatures: on a chamber schedule and on one session
// during a ramp from 10 to 45 °C.
TEST(ThermalCalibration, HeldOutBeatsOffsetOnlyCompensation) {
  const ModelKind model = ModelKind::kLinear;
  const ThermalDegrees full{1, 1, 0}, offsets{0, 1, 0}, none{0, 0, 0};
  const ThermalParameters truth = Device(model, full);
  const Vec3 sigma = Sigma(truth);
  Schedule ramp;
  ramp.dirs = RandomDirections(48, 77);
  for (int k = 0; k < 48; ++k) ramp.temps.push_back(10.0 + 35.0 * k / 47.0);
  for (const Schedule& s : {Chamber({-10, 5, 20, 35, 50}, 10, 5), ramp}) {
    const std::vector<Vec3> readings =
        SimulateThermalPositions(truth, kG, s.dirs, s.temps, sigma, 3);
    double rms[3];
    int i = 0;
    for (const ThermalDegrees& d : {full, offsets, none}) {
      ThermalOptions o = Options(model, d, s.temps);
      o.cross_validate = true;
      const ThermalResult r = CalibrateThermal(readings, o);
      ASSERT_TRUE(r.crossval_rms) << d.ToString() << ": " << r.crossval_note;
      rms[i++] = *r.crossval_rms;
      if (d == full) {  // and the truth within 4σ
        const Eigen::VectorXd e = Pack(r.params, model) - Pack(truth, model);
        for (Eigen::Index j = 0; j < e.size(); ++j) {
          EXPECT_LT(std::abs(e(j)) / std::sqrt(r.covariance(j, j)), 4.0) << j;
        }
      }
    }
    // The scale's 0.03 %/K over ±30 K leaves up to 0.09 m/s² to offset-only compensation.
    // Measured (m/s², full / offsets / none): chamber 6.5e-4 / 0.079 / 0.138, ramp 7.6e-4 /
    // 0.040 / 0.085; the full model's is the noise's.
    EXPECT_LT(rms[0], 0.1 * rms[1]) << rms[0] << " " << rms[1] << " " << rms[2];
    EXPECT_LT(rms[1], rms[2]) << rms[0] << " " << rms[1] << " " << rms[2];
  }
}

// Held-out error chooses each group's degree: the truth's degrees are found, and a device whose
// parameters do not change with temperature keeps none.
TEST(ThermalCalibration, HeldOutChoosesTheDegrees) {
  const ModelKind model = ModelKind::kLinear;
  const Schedule s = Chamber({-10, 5, 20, 35, 50}, 10, 9);
  for (const ThermalDegrees& truth_degrees :
       {ThermalDegrees{1, 1, 0}, ThermalDegrees{0, 1, 0}, ThermalDegrees{0, 0, 0}}) {
    ThermalParameters truth = Device(model, truth_degrees);
    const std::vector<Vec3> readings =
        SimulateThermalPositions(truth, kG, s.dirs, s.temps, Sigma(truth), 13);
    const ThermalDegreeSelection selection =
        SelectThermalDegrees(readings, Options(model, ThermalDegrees{}, s.temps));
    EXPECT_EQ(selection.chosen, truth_degrees)
        << truth_degrees.ToString() << ": " << selection.reason;
    EXPECT_EQ(selection.result.params.degrees, truth_degrees);
  }
}

// design's bound for a temperature schedule is the Cramér-Rao bound the Monte Carlo test meets,
// and it says when the temperatures cannot determine a degree.
TEST(ThermalDesign, PlannedBoundIsTheScheduleCramerRaoBound) {
  const ModelKind model = ModelKind::kLinear;
  const ThermalDegrees degrees{1, 2, 0};
  const ThermalParameters truth = Device(model, ThermalDegrees{});
  const Vec3 sigma = Sigma(truth);
  const std::vector<double> temperatures = {-10, 5, 20, 35, 50};
  const std::vector<Vec3> orientations = Yang18Directions();
  Schedule s;
  for (double t : temperatures) {
    for (const Vec3& c : orientations) {
      s.dirs.push_back(c);
      s.temps.push_back(t);
    }
  }
  const ThermalParameters at_zero =
      ConstantOverTemperature(truth.coefficients[0], model, degrees, 20);
  const Eigen::MatrixXd expected = Crlb(at_zero, model, s, sigma);
  const PlannedThermal planned = PredictThermalUncertainty(
      truth.coefficients[0], model, kG, orientations, temperatures, sigma, degrees);
  ASSERT_TRUE(planned.observable);
  EXPECT_DOUBLE_EQ(planned.t_ref_c, 20);
  ASSERT_EQ(planned.sigma.size(), expected.rows());
  for (Eigen::Index i = 0; i < expected.rows(); ++i) {
    EXPECT_NEAR(planned.sigma(i), std::sqrt(expected(i, i)), 1e-8 * std::sqrt(expected(i, i))) << i;
  }
  // Two temperatures cannot determine a quadratic bias; three can.
  EXPECT_FALSE(PredictThermalUncertainty(truth.coefficients[0], model, kG, orientations, {0, 40},
                                         sigma, degrees)
                   .observable);
  EXPECT_TRUE(PredictThermalUncertainty(truth.coefficients[0], model, kG, orientations, {0, 20, 40},
                                        sigma, degrees)
                  .observable);
  // Temperatures closer than a sensor's resolution are one (kMinThermalSeparation_K).
  EXPECT_FALSE(PredictThermalUncertainty(truth.coefficients[0], model, kG, orientations,
                                         {0, 20, 20.05}, sigma, degrees)
                   .observable);
}

}  // namespace
}  // namespace accelcal
