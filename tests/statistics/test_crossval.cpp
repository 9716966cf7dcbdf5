// Leave-one-position-out validation in every result, and starting from given parameters.
#include <cmath>
#include <cstdio>
#include <optional>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "accelcal/calibrate.hpp"
#include "accelcal/error.hpp"
#include "accelcal/log_reader.hpp"
#include "accelcal/positions.hpp"
#include "accelcal/simulate.hpp"
#include "accelcal/static_detection.hpp"
#include "statistics/held_out.hpp"
#include "support/jacobian_check.hpp"
#include "support/paths.hpp"

namespace accelcal {
namespace {

constexpr double kG = kYang2012Gravity_ms2;
const std::string kData = ACCELCAL_DATA_DIR;

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

// --- The held-out fits from an expansion of the full fit (held_out.hpp) -------------------------

// A device in g units with every parameter of order 1 (finite differences with steps relative to
// max(1, |θ_j|) then resolve all of them), squared coefficients large enough to matter.
ModelParameters SquaredDevice() {
  ModelParameters p;
  p.K << 1.02, 0, 0, 0.03, 0.97, 0, -0.02, 0.04, 1.05;
  p.bias << 0.05, -0.03, 0.02;
  p.k2 << 0.02, -0.015, 0.03;
  return p;
}

// A reading 0.02 g off the surface at the foot point c: a residual whose terms in the Hessian of
// the profile are of order 0.02 of the Gauss-Newton part, far above the finite differences' error.
Vec3 ReadingOffTheSurface(const ModelParameters& device, const Vec3& c) {
  Mat33 J;
  const Vec3 foot = PredictRaw(device, c, &J);
  const internal::Mat32 T = J * internal::TangentBasis(c);
  return foot + 0.02 * T.col(0).cross(T.col(1)).normalized();
}

// A per-position term's gradient and Hessian of e² (over the model's free columns of the 12
// parameters) against finite differences of e² and of the gradient.
template <typename TermAt>
void ExpectTermDerivativesMatch(const TermAt& term, const Eigen::VectorXd& x,
                                const std::vector<int>& free, const std::string& what) {
  const auto t = term(x);
  Eigen::RowVectorXd gradient(free.size());
  Eigen::MatrixXd hessian(free.size(), free.size());
  for (std::size_t i = 0; i < free.size(); ++i) {
    gradient(Eigen::Index(i)) = t.gradient(free[i]);
    for (std::size_t j = 0; j < free.size(); ++j) {
      hessian(Eigen::Index(i), Eigen::Index(j)) = t.hessian(free[i], free[j]);
    }
  }
  const auto value = [&](const Eigen::VectorXd& y) {
    const auto u = term(y);
    return Eigen::VectorXd::Constant(1, u.e * u.e);
  };
  const auto grad = [&](const Eigen::VectorXd& y) {
    const internal::Vec12 g = term(y).gradient;
    Eigen::VectorXd out(free.size());
    for (std::size_t i = 0; i < free.size(); ++i) out(Eigen::Index(i)) = g(free[i]);
    return out;
  };
  EXPECT_TRUE(testing::JacobianMatches(value, x, gradient)) << what;
  EXPECT_TRUE(testing::JacobianMatches(grad, x, hessian)) << what;
}

// HeldOutErrors whose refits leave a note instead (a test that needs none then sees it).
void HeldOutWithoutRefits(const std::vector<Vec3>& readings, const CalibrationOptions& o,
                          CalibrationResult* result, internal::HeldOutPaths* paths) {
  internal::HeldOutErrors(
      readings, o,
      [](std::size_t) {
        return internal::HeldOutRefit{0.0, "refitted"};
      },
      result, paths);
}

TEST(HeldOut, ProfiledTermDerivativesMatchFiniteDifferences) {
  // f(θ) = min over |c| = 1 of ‖p − μ(θ, c)‖²: its gradient against central differences of f,
  // its Hessian against central differences of the gradient (JacobianMatches' tolerance).
  const ModelParameters device = SquaredDevice();
  for (ModelKind model : {ModelKind::kQuadratic, ModelKind::kLinear}) {
    ModelParameters at = device;
    if (model == ModelKind::kLinear) at.k2.setZero();
    for (const Vec3& c : {Vec3(0.3, -0.5, 0.8).normalized(), Vec3(-0.9, 0.1, 0.3).normalized()}) {
      const Vec3 p = ReadingOffTheSurface(at, c);
      const std::vector<int>& free = ActiveColumns(model);
      const auto full = [&](const Eigen::VectorXd& x) {
        internal::Vec12 theta = internal::ToVec12(at);
        for (std::size_t i = 0; i < free.size(); ++i) theta(free[i]) = x(Eigen::Index(i));
        return internal::ProfiledPosition(internal::FromVec12(theta), 1.0, model, p, c, true);
      };
      Eigen::VectorXd x(free.size());
      for (std::size_t i = 0; i < free.size(); ++i) {
        x(Eigen::Index(i)) = internal::ToVec12(at)(free[i]);
      }
      const internal::ProfiledTerm t = full(x);
      ASSERT_TRUE(t.ok);
      EXPECT_NEAR(t.e * t.e, (p - PredictRaw(at, t.dir)).squaredNorm(), 1e-15);
      ExpectTermDerivativesMatch(full, x, free, std::string(ToString(model)));
      // The residual's terms matter: the Gauss-Newton Hessian 2 u uᵀ misses them by far more
      // than the tolerance.
      const internal::Mat12 gauss_newton = 2.0 * t.u * t.u.transpose();
      EXPECT_GT((t.hessian - gauss_newton).norm(), 1e-3 * t.hessian.norm()) << ToString(model);
      // The bias correction's offset per unit variance is ExpectedSurfaceOffsets' for σ = 1.
      const std::vector<Vec3> one = {p};
      const internal::Problem problem{one, 1.0, model};
      const internal::SurfaceOffsets offsets =
          internal::ExpectedSurfaceOffsets(problem, at, {t.dir}, {Vec3::Ones()});
      EXPECT_NEAR(t.omega, offsets.offset[0], 1e-14 * std::abs(offsets.offset[0]));
    }
  }
}

TEST(HeldOut, ModulusTermDerivativesMatchFiniteDifferences) {
  ModelParameters device = SquaredDevice();
  device.k2.setZero();
  const Vec3 p = PredictRaw(device, Vec3(0.3, -0.5, 0.8).normalized()) + Vec3(0.01, -0.02, 0.015);
  const std::vector<int>& free = ActiveColumns(ModelKind::kLinear);
  for (bool squared : {true, false}) {
    const auto term = [&](const Eigen::VectorXd& x) {
      return internal::ModulusPosition(Unpack(x, ModelKind::kLinear), 1.0, squared, p, true);
    };
    const Eigen::VectorXd x = Pack(device, ModelKind::kLinear);
    const internal::ModulusTerm t = term(x);
    ASSERT_TRUE(t.ok);
    // The residual is the modulus solver's own.
    const std::vector<Vec3> one = {p};
    EXPECT_NEAR(t.e,
                internal::ModulusResiduals({one, 1.0, ModelKind::kLinear}, x, squared, nullptr)(0),
                1e-15);
    ExpectTermDerivativesMatch(term, x, free, squared ? "squared" : "norm");
  }
}

// Position k's held-out error from the refit CrossValidate always made (the other positions in
// the fit, started from the full fit), restarted from its own result until it stops moving: a
// Levenberg-Marquardt refit may stop on a damped step short of its optimum (the joint solver when
// a step's predicted change of J is below 1e-13 J, the modulus solver on a step of 1e-14 after
// rejected ones: measured up to 3.7e-9 g and 1e-10 g from it on the bundled recordings), and the
// maximum-likelihood methods, which share one optimum, are refitted with the joint solver (the
// two-step and Newton-Lagrange refits of some positions reach their iteration caps); the
// bias-corrected estimator's shifts are settled to 1e-11 of the noise instead of 1e-6 (a refit's
// held-out error then moves by up to 3e-8 of the noise, measured at 3 % of the signal).
// std::nullopt with `why` when the refit fails.
std::optional<double> ConvergedRefit(const std::vector<Vec3>& readings,
                                     const CalibrationOptions& options,
                                     const CalibrationResult& full, std::size_t k,
                                     std::string* why) {
  std::vector<Vec3> subset;
  for (std::size_t j = 0; j < readings.size(); ++j) {
    if (j != k && !full.excluded(j)) subset.push_back(readings[j]);
  }
  CalibrationOptions held = options;
  held.cross_validate = false;
  held.outliers.policy = OutlierPolicy::kOff;
  held.reading_sigmas.clear();
  if (IsMaximumLikelihood(options.method)) held.method = SolverMethod::kJoint;
  if (options.method != SolverMethod::kEllipsoid) {
    held.initialization = Initialization::kGiven;
    held.initial_params = full.params;
  }
  // The bias correction's shifts settled far beyond the 1e-6 of the noise a refit stops at.
  held.bias_correction.tolerance = 1e-11;
  held.bias_correction.max_rounds = 100;
  double previous = std::nan("");
  for (int restart = 0; restart < 8; ++restart) {
    CalibrationResult fit;
    try {
      fit = Calibrate(subset, held);
    } catch (const DataError& e) {
      *why = e.what();
      return std::nullopt;
    }
    if (!fit.summary.converged()) {
      *why = fit.summary.termination_message;
      return std::nullopt;
    }
    const double e = GravityNormErrors(fit.params, {readings[k]}, options.gravity)[0];
    if (options.method == SolverMethod::kEllipsoid || e == previous) return e;
    previous = e;
    held.initial_params = fit.params;
  }
  return previous;
}

// The agreement asked of the held-out errors: the refits' optimum is determined to round-off,
// measured (converged refits from the full fit and from the ellipsoid fit) to 1e-11 g for the
// maximum-likelihood methods and 1e-10 g for the modulus methods (CTU 49, modulus-norm: their
// residuals are differences of nearly equal norms); ten times that. The ellipsoid fit is closed
// form: the same scatter matrix to round-off, its eigenvector to 4e-14 g.
double Tolerance(SolverMethod method, double gravity) {
  switch (method) {
    case SolverMethod::kEllipsoid:
      return 1e-12 * gravity;
    case SolverMethod::kModulus:
    case SolverMethod::kModulusNorm:
      return 1e-9 * gravity;
    default:
      return 1e-10 * gravity;
  }
}

struct Recording {
  std::string name;
  std::vector<Vec3> means, sigmas;
  double gravity;
  bool served_without_refits;  // every position of every method within the expansion's reach
};

Recording Load(const std::string& file, double gravity, bool served_without_refits) {
  const InputData d = ReadInput(kData + "/" + file, {});
  const std::vector<Position> positions =
      d.kind == InputKind::kRaw ? PositionsFromIntervals(DetectStaticIntervals(d.raw, {}).intervals)
                                : d.positions;
  return {file, Means(positions), SigmasOfMeans(positions), gravity, served_without_refits};
}

TEST(HeldOut, AgreesWithRefitsOnEveryBundledRecording) {
  // The command line's calibration of each recording (the readings' sigmas included), every
  // method, estimator, model and frame: the held-out errors of the refits, or their failure note.
  // The T265 recordings are poorly conditioned (reciprocal condition 7e-7 quadratic): a position
  // moves the fit by up to 1 % of the signal, beyond the expansion, and many are refitted.
  const std::vector<Recording> recordings = {
      Load("imutk-xsens-mti/xsens_acc.mat", 9.81744, true),
      Load("imutk-xsens-mti/derived_static_means.csv", 9.81744, true),
      Load("imutk-t265/t265_acc.mat", 9.8016, false),
      Load("imutk-t265/derived_static_means.csv", 9.8016, false),
      Load("ctu-innalabs-ahrs-m3/measured_accelerations_24pos.csv", 1.0, true),
      Load("ctu-innalabs-ahrs-m3/measured_accelerations_49pos.csv", 1.0, true),
      Load("ctu-innalabs-ahrs-m3/hassan_subset_31pos.csv", 1.0, false),
      Load("imucal-ferraris/ferraris_raw_means.csv", 9.81, false),
      Load("imucal-ferraris/derived_static_means_example_session.csv", 9.81, false)};
  int compared = 0, served = 0, notes = 0;
  for (const Recording& rec : recordings) {
    for (ModelKind model : {ModelKind::kLinear, ModelKind::kQuadratic}) {
      for (SolverMethod method :
           {SolverMethod::kJoint, SolverMethod::kTwoStep, SolverMethod::kNewtonLagrange,
            SolverMethod::kModulus, SolverMethod::kModulusNorm, SolverMethod::kEllipsoid}) {
        for (Estimator estimator : {Estimator::kMaximumLikelihood, Estimator::kBiasCorrected}) {
          for (Frame frame : {Frame::kXFirst, Frame::kZFirst}) {
            // Two-step refits take thousands of sweeps each; its held-out fits are the joint
            // solver's (one optimum), so one recording shows the options reach it.
            if (method == SolverMethod::kTwoStep && rec.name.find("24pos") == std::string::npos) {
              continue;
            }
            // Under the sanitizers (ten times slower) one frame: the other is the same fit
            // renamed, and the normal build compares both.
            if (ACCELCAL_TESTS_SANITIZED && frame == Frame::kZFirst) continue;
            CalibrationOptions o;
            o.model = model;
            o.method = method;
            o.estimator = estimator;
            o.frame = frame;
            o.gravity = rec.gravity;
            o.reading_sigmas = rec.sigmas;
            if (o.Validate()) continue;
            const std::string what = rec.name + " " + std::string(ToString(model)) + " " +
                                     std::string(ToString(method)) + " " +
                                     std::string(ToString(estimator)) + " " +
                                     std::string(ToString(frame));
            CalibrationResult full;
            try {
              full = Calibrate(rec.means, o);
            } catch (const DataError&) {
              continue;  // too few or coplanar positions: nothing to validate
            }
            if (!full.summary.converged()) continue;
            CalibrationResult fast = full, refitted = full;
            internal::HeldOutPaths paths;
            internal::HeldOutErrors(
                rec.means, o,
                [&](std::size_t k) { return internal::RefitWithout(rec.means, o, full, k); }, &fast,
                &paths);
            internal::CrossValidateByRefits(rec.means, o, &refitted);
            if (!refitted.crossval_rms) {
              // A refit that failed: the same note, unless the refit's solver stopped at its
              // iteration cap (two-step, Newton-Lagrange), which the expansion does not run.
              if (refitted.crossval_note.find("did not converge") == std::string::npos) {
                EXPECT_EQ(fast.crossval_note, refitted.crossval_note) << what;
                ++notes;
                continue;
              }
            } else {
              EXPECT_EQ(fast.crossval_note, "") << what;
            }
            if (!fast.crossval_rms) continue;
            for (std::size_t k = 0; k < rec.means.size(); ++k) {
              if (full.excluded(k)) continue;
              std::string why;
              const std::optional<double> e = ConvergedRefit(rec.means, o, full, k, &why);
              if (!e) continue;  // a joint refit of a poorly determined T265 fit at its cap
              EXPECT_NEAR(fast.crossval_errors[k], *e, Tolerance(method, rec.gravity))
                  << what << " position " << k + 1;
              ++compared;
            }
            served += paths.from_expansion + paths.corrected;
            if (rec.served_without_refits) {
              EXPECT_EQ(paths.refitted, 0) << what;
            }
          }
        }
      }
    }
  }
  // Not vacuous: most held-out errors came from the expansion, and failures were compared too.
  std::printf("compared %d held-out errors, %d served without a refit, %d notes\n", compared,
              served, notes);
  EXPECT_GT(compared, ACCELCAL_TESTS_SANITIZED ? 2000 : 4000);
  EXPECT_GT(served, 3 * compared / 4);
  EXPECT_GT(notes, 0);
}

// Yang's device, `m` random positions, noise `sigma_relative` of each axis' signal.
std::vector<Vec3> RandomReadings(ModelKind model, int m, double sigma_relative,
                                 std::uint64_t seed) {
  ModelParameters truth = Yang2012Truth();
  if (model == ModelKind::kLinear) truth.k2.setZero();
  Vec3 sigma;
  for (int i = 0; i < 3; ++i) sigma(i) = truth.K(i, i) * kG * sigma_relative;
  return SimulatePositions(truth, kG, RandomDirections(m, seed), sigma, seed + 1);
}

TEST(HeldOut, AgreesWithRefitsOnSimulatedPositions) {
  // Both models, from few positions (large leverages: corrected or refitted) to many (the
  // expansion alone), quiet and noisy; bias-corrected too, where the readings' shifts and σ̂ move
  // with the held-out fit.
  struct Case {
    ModelKind model;
    int m;
    double sigma;
    Estimator estimator;
  };
  for (const Case& c : {Case{ModelKind::kLinear, 20, 1e-3, Estimator::kMaximumLikelihood},
                        Case{ModelKind::kLinear, 400, 1e-2, Estimator::kMaximumLikelihood},
                        Case{ModelKind::kQuadratic, 30, 1e-4, Estimator::kMaximumLikelihood},
                        Case{ModelKind::kQuadratic, 400, 1e-3, Estimator::kBiasCorrected},
                        Case{ModelKind::kLinear, 150, 3e-2, Estimator::kBiasCorrected}}) {
    const std::vector<Vec3> readings = RandomReadings(c.model, c.m, c.sigma, 21);
    CalibrationOptions o = Options(c.model);
    o.estimator = c.estimator;
    const CalibrationResult full = Calibrate(readings, o);
    ASSERT_TRUE(full.summary.converged());
    CalibrationResult fast = full;
    internal::HeldOutPaths paths;
    HeldOutWithoutRefits(readings, o, &fast, &paths);
    ASSERT_TRUE(fast.crossval_rms) << fast.crossval_note;  // no refit was needed
    // A refit per position: under the sanitizers (220 s for all) every seventh of the large
    // cases', each position's comparison being as demanding as another's.
    const std::size_t stride = ACCELCAL_TESTS_SANITIZED && c.m > 50 ? 7 : 1;
    for (std::size_t k = 0; k < readings.size(); k += stride) {
      std::string why;
      const std::optional<double> e = ConvergedRefit(readings, o, full, k, &why);
      ASSERT_TRUE(e) << why;
      EXPECT_NEAR(fast.crossval_errors[k], *e, Tolerance(o.method, kG))
          << ToString(c.model) << " m = " << c.m << " position " << k + 1;
    }
    if (c.m >= 400) {
      EXPECT_EQ(paths.refitted, 0) << c.m;
    }
  }
}

TEST(HeldOut, TheExpansionAloneIsAsAccurateAsItsEstimate) {
  // Without exact passes, each number keeps the expansion's error, which HeldOutPaths estimates
  // in ‖·‖_s: |f| moves by at most Σ_j g |Δθ_j| s_j ≤ P g ‖Δθ‖_s, P = 9.
  const std::vector<Vec3> readings = RandomReadings(ModelKind::kLinear, 300, 1e-3, 5);
  const CalibrationOptions o = Options(ModelKind::kLinear);
  const CalibrationResult full = Calibrate(readings, o);
  CalibrationResult fast = full;
  internal::HeldOutPaths paths;
  internal::HeldOutSettings settings;
  settings.correct = false;
  internal::HeldOutErrors(
      readings, o,
      [](std::size_t) {
        return internal::HeldOutRefit{0.0, "refitted"};
      },
      &fast, &paths, settings);
  ASSERT_TRUE(fast.crossval_rms);
  EXPECT_EQ(paths.from_expansion, 300);
  EXPECT_GT(paths.largest_estimate, settings.tolerance);  // some beyond the tolerance: a test
  double worst = 0;
  for (std::size_t k = 0; k < readings.size(); k += 7) {
    std::string why;
    const std::optional<double> e = ConvergedRefit(readings, o, full, k, &why);
    ASSERT_TRUE(e) << why;
    worst = std::max(worst, std::abs(fast.crossval_errors[k] - *e));
  }
  EXPECT_LE(worst, 9 * kG * paths.largest_estimate);
  EXPECT_GT(worst, 0.0);
}

TEST(HeldOut, ManyPositionsNeedNoPassOverThem) {
  // 20,000 positions (each held-out fit moves θ by ~1e-7 of the signal): every number from the
  // expansion, no exact pass, no refit; a sample agrees with refits.
  const std::vector<Vec3> readings = RandomReadings(ModelKind::kLinear, 20000, 1e-3, 8);
  CalibrationOptions o = Options(ModelKind::kLinear);
  const CalibrationResult full = Calibrate(readings, o);
  CalibrationResult fast = full;
  internal::HeldOutPaths paths;
  HeldOutWithoutRefits(readings, o, &fast, &paths);
  ASSERT_TRUE(fast.crossval_rms) << fast.crossval_note;
  EXPECT_EQ(paths.from_expansion, 20000);
  EXPECT_EQ(paths.exact_passes, 0);
  EXPECT_LE(paths.largest_estimate, internal::HeldOutSettings().tolerance);
  for (std::size_t k : {std::size_t{0}, std::size_t{7777}, std::size_t{19999}}) {
    std::string why;
    const std::optional<double> e = ConvergedRefit(readings, o, full, k, &why);
    ASSERT_TRUE(e) << why;
    EXPECT_NEAR(fast.crossval_errors[k], *e, Tolerance(o.method, kG)) << k;
  }
}

TEST(HeldOut, ExcludedPositionsAreHeldOutOfEveryFit) {
  // Position 5 read 50 sigma off: the screening excludes it; its error is the final fit's, and the
  // others' are those of fits without it as well.
  std::vector<Vec3> readings = RandomReadings(ModelKind::kQuadratic, 60, 1e-4, 3);
  readings[4] += Vec3::Constant(50 * 1e-4 * 4800 * kG);
  CalibrationOptions o = Options(ModelKind::kQuadratic);
  o.cross_validate = true;
  const CalibrationResult r = Calibrate(readings, o);
  ASSERT_TRUE(r.excluded(4));
  ASSERT_TRUE(r.crossval_rms) << r.crossval_note;
  EXPECT_EQ(r.crossval_errors[4], GravityNormErrors(r.params, {readings[4]}, kG)[0]);
  for (std::size_t k = 0; k < readings.size(); ++k) {
    if (k == 4) continue;
    std::string why;
    const std::optional<double> e = ConvergedRefit(readings, o, r, k, &why);
    ASSERT_TRUE(e) << why;
    EXPECT_NEAR(r.crossval_errors[k], *e, Tolerance(o.method, kG)) << k + 1;
  }
}

TEST(HeldOut, APositionTheOthersCannotDoWithoutIsRefittedForItsNote) {
  // 30 positions on the equator and four off it: without one of those the others do not
  // determine the model (three off a plane leave a direction of the fit free). The readings are
  // noise-free, so every fit without a position is the full fit and the expansion finds it at
  // once: only the check of the held-out information sends the positions off the plane to the
  // refit, which says why, as before.
  ModelParameters truth = Yang2012Truth();
  truth.k2.setZero();
  std::vector<Vec3> directions;
  for (int i = 0; i < 30; ++i) {
    const double a = 2 * M_PI * i / 30;
    directions.emplace_back(std::cos(a), std::sin(a), 0.0);
  }
  directions.emplace_back(0.0, 0.0, 1.0);
  directions.emplace_back(Vec3(0.3, 0.2, -0.93).normalized());
  directions.emplace_back(Vec3(-0.5, 0.4, 0.77).normalized());
  directions.emplace_back(Vec3(0.6, -0.6, 0.5).normalized());
  const std::vector<Vec3> readings = SimulatePositions(truth, kG, directions, Vec3::Zero(), 2);
  CalibrationOptions o = Options(ModelKind::kLinear);
  o.outliers.policy = OutlierPolicy::kOff;
  CalibrationResult fast = Calibrate(readings, o), refitted = fast;
  ASSERT_TRUE(fast.summary.converged());
  CrossValidate(readings, o, &fast);
  internal::CrossValidateByRefits(readings, o, &refitted);
  EXPECT_FALSE(fast.crossval_rms.has_value());
  EXPECT_EQ(fast.crossval_note, refitted.crossval_note);
  EXPECT_NE(fast.crossval_note.find("without position 31: "), std::string::npos)
      << fast.crossval_note;
}

}  // namespace
}  // namespace accelcal
