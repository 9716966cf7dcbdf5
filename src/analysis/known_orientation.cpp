#include "accelcal/known_orientation.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "accelcal/error.hpp"
#include "accelcal/frame.hpp"
#include "core/text_format.hpp"
#include "solvers/solver_common.hpp"
#include "statistics/fit.hpp"
#include "statistics/held_out.hpp"
#include "statistics/outliers.hpp"
#include "statistics/screening.hpp"
#include "statistics/student_t.hpp"

namespace accelcal {

namespace {

using Mat5 = Eigen::Matrix<double, 5, 5>;
using Vec5 = Eigen::Matrix<double, 5, 1>;

// The positions determine an axis' parameters when the reciprocal condition of its Jacobi-scaled
// normal matrix is at least the orientation-free fit's threshold (kMinInformationRcond): one
// observability threshold for both fits.
using internal::kMinInformationRcond;

// One output axis' least squares, in its first n ≤ 5 unknowns (K_i0, K_i1, K_i2, b_i, k2_i).
struct AxisFit {
  Vec5 theta = Vec5::Zero();
  Mat5 normal_inverse = Mat5::Zero();  // (Σ w a aᵀ)⁻¹ on the first n entries
};

Vec5 Regressors(const Vec3& f, int axis) {
  Vec5 a;
  a << f, 1.0, f(axis) * f(axis);
  return a;
}

// Solves axis `axis` over the positions with weight > 0; throws DataError naming the parameter
// the positions do not determine.
AxisFit FitAxis(const std::vector<Vec3>& readings, const std::vector<Vec3>& forces,
                const std::vector<double>& weights, int axis, int n) {
  Mat5 normal = Mat5::Zero();
  Vec5 rhs = Vec5::Zero();
  for (std::size_t k = 0; k < readings.size(); ++k) {
    if (weights[k] == 0) continue;
    const Vec5 a = Regressors(forces[k], axis);
    normal.noalias() += weights[k] * a.lazyProduct(a.transpose());
    rhs += weights[k] * readings[k](axis) * a;
  }
  const Eigen::MatrixXd N = normal.topLeftCorner(n, n);
  // Jacobi scaling: the columns (g c, 1, g² c²) differ in size by g².
  Eigen::VectorXd s = N.diagonal().cwiseSqrt();
  for (Eigen::Index j = 0; j < n; ++j) s(j) = s(j) > 0 ? 1.0 / s(j) : 1.0;
  const Eigen::MatrixXd scaled = s.asDiagonal() * N * s.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(scaled);
  const double largest = eig.eigenvalues().maxCoeff();
  if (!(eig.eigenvalues().minCoeff() > kMinInformationRcond * largest)) {
    Eigen::Index weakest = 0;
    eig.eigenvectors().col(0).cwiseAbs().maxCoeff(&weakest);
    static const char* const kNames[5] = {"K_%cx", "K_%cy", "K_%cz", "b_%c", "k2_%c"};
    char name[16];
    internal::FormatTo(name, sizeof name, kNames[weakest], "xyz"[axis]);
    char buf[256];
    internal::FormatTo(buf, sizeof buf,
                       "the known orientations do not determine parameter %s (reciprocal condition "
                       "%.2g): add positions with gravity along other axes",
                       name, std::max(0.0, eig.eigenvalues().minCoeff() / largest));
    throw DataError(buf);
  }
  const Eigen::MatrixXd inverse = s.asDiagonal() * eig.eigenvectors() *
                                  eig.eigenvalues().cwiseInverse().asDiagonal() *
                                  eig.eigenvectors().transpose() * s.asDiagonal();
  AxisFit fit;
  fit.normal_inverse.topLeftCorner(n, n) = inverse;
  fit.theta.head(n) = inverse * rhs.head(n);
  return fit;
}

struct Fit {
  ModelParameters params;
  AxisFit axes[3];
};

Fit FitAll(const std::vector<Vec3>& readings, const std::vector<Vec3>& forces,
           const std::vector<Vec3>& weights, ModelKind model) {
  const int n = model == ModelKind::kLinear ? 4 : 5;
  Fit fit;
  for (int i = 0; i < 3; ++i) {
    std::vector<double> w(readings.size());
    for (std::size_t k = 0; k < readings.size(); ++k) w[k] = weights[k](i);
    fit.axes[i] = FitAxis(readings, forces, w, i, n);
    fit.params.K.row(i) = fit.axes[i].theta.head<3>().transpose();
    fit.params.bias(i) = fit.axes[i].theta(3);
    fit.params.k2(i) = n == 5 ? fit.axes[i].theta(4) : 0.0;
  }
  return fit;
}

// The discordant-position test of one fit (OutlierStatistic::kFisherF). Each axis is its own
// least squares, so adding three mean-shift parameters for position k (one per axis) lowers the
// weighted sum of squares by Δ_k = Σ_i w_ki r_ki² / (1 − h_ki), h_ki = w_ki a_kiᵀ N_i⁻¹ a_ki its
// leverage in axis i; the fit without k has SSE − Δ_k on ν − 3 degrees of freedom, and
// F_k = (Δ_k / 3) / ((SSE − Δ_k) / (ν − 3)) is Fisher F(3, ν − 3) under normal noise.
struct FTest {
  bool ran = false;
  int position = -1;  // the largest F_k
  double F = 0;
  double p = 1;               // its upper-tail probability
  double residual = 0;        // |p_k − μ_k| [raw]
  double scatter = 0;         // per-axis scale of the fit without it
  int dof = 0;                // ν − 3
  std::vector<int> untested;  // positions the others do not determine the fit without (1-based)
};

FTest MostDiscordant(const std::vector<Vec3>& readings, const std::vector<Vec3>& forces,
                     const std::vector<Vec3>& weights, const Fit& fit, int P) {
  FTest test;
  int used = 0;
  double sse = 0, largest_residual = 0;
  std::vector<Vec3> residuals(readings.size());
  for (std::size_t k = 0; k < readings.size(); ++k) {
    residuals[k] = readings[k] - PredictRaw(fit.params, forces[k]);
    if (weights[k](0) == 0) continue;
    ++used;
    sse += residuals[k].cwiseAbs2().dot(weights[k]);
    largest_residual = std::max(largest_residual, residuals[k].cwiseAbs().maxCoeff());
  }
  const int nu = 3 * used - P;
  test.dof = nu - 3;
  // Positions fitted to round-off (simulated exact data) have no scatter to test against.
  const double signal = internal::SignalAmplitude(fit.params, forces[0].norm());
  if (test.dof < 1 || !(largest_residual > 64 * std::numeric_limits<double>::epsilon() * signal)) {
    return test;
  }
  const int n = P / 3;
  for (std::size_t k = 0; k < readings.size(); ++k) {
    if (weights[k](0) == 0) continue;
    double delta = 0;
    bool testable = true;
    for (int i = 0; i < 3; ++i) {
      const Vec5 a = Regressors(forces[k], i);
      const double h =
          weights[k](i) * a.head(n).dot(fit.axes[i].normal_inverse.topLeftCorner(n, n) * a.head(n));
      if (!(1.0 - h > internal::kMinUntestedMargin)) {
        testable = false;
        break;
      }
      delta += weights[k](i) * residuals[k](i) * residuals[k](i) / (1.0 - h);
    }
    if (!testable) {  // the others do not determine the fit without it
      test.untested.push_back(static_cast<int>(k) + 1);
      continue;
    }
    const double rest = std::max(sse - delta, 0.0);
    const double F = rest > 0 ? (delta / 3.0) / (rest / test.dof) : INFINITY;
    if (!test.ran || F > test.F) {
      test.ran = true;
      test.position = static_cast<int>(k);
      test.F = F;
      test.residual = residuals[k].norm();
      test.scatter = std::sqrt(rest / test.dof);
    }
  }
  if (test.ran) test.p = internal::FisherFSurvival(test.F, 3.0, test.dof);
  return test;
}

// OutlierOptions' generalised ESD (statistics/screening.hpp) with the F test. Returns the findings
// (excluded as the policy allows) and sets `weights` of the excluded positions to 0.
std::vector<OutlierFinding> Screen(const std::vector<Vec3>& readings,
                                   const std::vector<Vec3>& forces, const OutlierOptions& options,
                                   ModelKind model, int P, std::vector<Vec3>* weights,
                                   std::string* note) {
  std::vector<Vec3> w = *weights;
  int used = static_cast<int>(readings.size());
  int removed = -1;  // the previous step's position
  const internal::EsdOutcome outcome =
      internal::GeneralisedEsd(options, [&](std::size_t step) -> std::optional<internal::EsdStep> {
        if (removed >= 0) {
          w[static_cast<std::size_t>(removed)].setZero();
          --used;
        }
        Fit fit;
        try {
          fit = FitAll(readings, forces, w, model);
        } catch (const DataError&) {
          return std::nullopt;  // without the positions removed so far the model is not determined
        }
        const FTest test = MostDiscordant(readings, forces, w, fit, P);
        if (step == 0 && !test.untested.empty()) {
          *note = test.untested.size() > 1 ? "positions " : "position ";
          for (std::size_t i = 0; i < test.untested.size(); ++i) {
            *note += (i ? ", " : "") + std::to_string(test.untested[i]);
          }
          *note += " not screened: the other positions do not determine the fit without them";
        }
        if (!test.ran) {
          if (step == 0 && test.dof < 1) {
            *note = "outlier screening needs at least " + std::to_string((P + 4 + 2) / 3) +
                    " positions for the " + std::string(ToString(model)) + " model, got " +
                    std::to_string(used);
          }
          return std::nullopt;
        }
        const double per_position = options.false_alarm_probability / used;
        internal::EsdStep s;
        s.finding.position = test.position;
        s.finding.statistic = OutlierStatistic::kFisherF;
        s.finding.t = test.F;
        s.finding.threshold = internal::FisherFQuantile(per_position, 3.0, test.dof);
        s.finding.degrees_of_freedom = test.dof;
        s.finding.normal_residual = test.residual;
        s.finding.scatter = test.scatter;
        s.significant = test.p < per_position;
        removed = test.position;
        return s;
      });
  for (std::size_t i = 0; i < outcome.excluded; ++i) {
    (*weights)[static_cast<std::size_t>(outcome.steps[i].finding.position)].setZero();
  }
  return internal::DiscordantFindings(outcome);
}

}  // namespace

std::optional<std::string> KnownOrientationOptions::Validate() const {
  if (!(gravity > 0) || !std::isfinite(gravity)) return "gravity must be a positive number";
  if (auto why = outliers.Validate()) return why;
  return std::nullopt;
}

CalibrationResult CalibrateKnownOrientations(const std::vector<Vec3>& readings,
                                             const std::vector<Vec3>& directions,
                                             const KnownOrientationOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  if (auto why = options.Validate()) throw OptionError(*why);
  const std::size_t m = readings.size();
  if (directions.size() != m) {
    throw std::invalid_argument(std::to_string(directions.size()) + " known directions for " +
                                std::to_string(m) + " readings");
  }
  internal::CheckReadingSigmas(options.reading_sigmas, m);
  for (std::size_t k = 0; k < m; ++k) {
    if (!(std::abs(directions[k].norm() - 1.0) <= 1e-6)) {
      throw std::invalid_argument("known direction " + std::to_string(k + 1) +
                                  " is not a unit vector");
    }
    if (!readings[k].allFinite()) {
      throw DataError("position " + std::to_string(k + 1) + " has a non-finite reading");
    }
  }
  const auto& slots = ParameterSlots(options.model, Frame::kPlatform);
  const int P = static_cast<int>(slots.size());
  // Each position gives 3 equations; each axis needs as many as its own 4 or 5 unknowns.
  const int per_axis = P / 3;
  if (static_cast<int>(m) < per_axis) {
    throw DataError("the " + std::string(ToString(options.model)) +
                    " model with known orientations needs at least " + std::to_string(per_axis) +
                    " positions, got " + std::to_string(m));
  }
  std::vector<Vec3> forces(m);
  for (std::size_t k = 0; k < m; ++k) forces[k] = options.gravity * directions[k];
  std::vector<Vec3> weights(m, Vec3::Ones());
  const bool sample_noise = !options.reading_sigmas.empty();
  if (sample_noise) {
    for (std::size_t k = 0; k < m; ++k) {
      weights[k] = options.reading_sigmas[k].cwiseAbs2().cwiseInverse();
    }
  }
  std::string outlier_note;
  const std::vector<OutlierFinding> outliers =
      options.outliers.policy == OutlierPolicy::kOff
          ? std::vector<OutlierFinding>{}
          : Screen(readings, forces, options.outliers, options.model, P, &weights, &outlier_note);
  int used = 0;
  for (const Vec3& w : weights) used += w(0) != 0 ? 1 : 0;
  const Fit fit = FitAll(readings, forces, weights, options.model);

  CalibrationResult result;
  result.model = options.model;
  result.frame = Frame::kPlatform;
  result.gravity = options.gravity;
  result.params = fit.params;
  result.directions = directions;
  result.outliers = outliers;
  result.outlier_note = outlier_note;
  result.screening = options.outliers.policy;
  double cost = 0, chi2 = 0;
  for (std::size_t k = 0; k < m; ++k) {
    const Vec3 r = readings[k] - PredictRaw(fit.params, forces[k]);
    result.residuals.push_back(r);
    if (weights[k](0) == 0) continue;  // left out by the screening
    cost += r.squaredNorm();
    chi2 += r.cwiseAbs2().dot(weights[k]);
  }
  result.degrees_of_freedom = 3 * used - P;
  if (result.degrees_of_freedom > 0) {
    const double dof = result.degrees_of_freedom;
    result.residual_sigma = std::sqrt(cost / dof);
    double factor = cost / dof;  // σ̂² times the unweighted (AᵀA)⁻¹
    if (sample_noise) {
      result.noise_source = "samples";
      result.scatter_ratio = std::sqrt(chi2 / dof);
      factor = std::max(1.0, chi2 / dof);  // (AᵀWA)⁻¹ inflated as calibrate.hpp says
    }
    result.covariance = Eigen::MatrixXd::Zero(P, P);
    for (int i = 0; i < 3; ++i) {
      result.covariance.block(i * per_axis, i * per_axis, per_axis, per_axis) =
          factor * fit.axes[i].normal_inverse.topLeftCorner(per_axis, per_axis);
    }
  }
  Summary& s = result.summary;
  s.method = SolverMethod::kKnownOrientation;
  s.termination = TerminationType::kClosedForm;
  s.termination_message =
      "linear least squares with known orientations (paper 003 eq. (7), general turntable case)";
  s.initial_cost = s.final_cost = cost;

  if (options.cross_validate) {
    internal::LeaveOneOut(
        readings,
        [&](std::size_t k) -> internal::HeldOutRefit {
          std::vector<Vec3> held_out = weights;
          held_out[k].setZero();
          try {
            const ModelParameters without =
                FitAll(readings, forces, held_out, options.model).params;
            return internal::HeldOutErrorUnder(without, readings[k], options.gravity, k);
          } catch (const DataError& e) {
            return {0.0, "without position " + std::to_string(k + 1) + ": " + e.what()};
          }
        },
        &result);
  }
  s.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace accelcal
