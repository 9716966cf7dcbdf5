#include "accelcal/known_orientation.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "accelcal/error.hpp"
#include "accelcal/frame.hpp"

namespace accelcal {

namespace {

using Mat5 = Eigen::Matrix<double, 5, 5>;
using Vec5 = Eigen::Matrix<double, 5, 1>;

/// Below this reciprocal condition of an axis' Jacobi-scaled normal matrix the positions do not
/// determine that axis' parameters (the threshold calibrate.hpp uses).
constexpr double kMinRcond = 1e-10;

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
  if (!(eig.eigenvalues().minCoeff() > kMinRcond * largest)) {
    Eigen::Index weakest = 0;
    eig.eigenvectors().col(0).cwiseAbs().maxCoeff(&weakest);
    static const char* const kNames[5] = {"K_%cx", "K_%cy", "K_%cz", "b_%c", "k2_%c"};
    char name[16];
    std::snprintf(name, sizeof name, kNames[weakest], "xyz"[axis]);
    char buf[256];
    std::snprintf(buf, sizeof buf,
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

}  // namespace

std::optional<std::string> KnownOrientationOptions::Validate() const {
  if (!(gravity > 0) || !std::isfinite(gravity)) return "gravity must be a positive number";
  return std::nullopt;
}

CalibrationResult CalibrateKnownOrientations(const std::vector<Vec3>& readings,
                                             const std::vector<Vec3>& directions,
                                             const KnownOrientationOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  if (auto why = options.Validate()) throw std::invalid_argument(*why);
  const std::size_t m = readings.size();
  if (directions.size() != m) {
    throw std::invalid_argument(std::to_string(directions.size()) + " known directions for " +
                                std::to_string(m) + " readings");
  }
  if (!options.reading_sigmas.empty() && options.reading_sigmas.size() != m) {
    throw std::invalid_argument("reading_sigmas has " +
                                std::to_string(options.reading_sigmas.size()) + " entries for " +
                                std::to_string(m) + " readings");
  }
  for (std::size_t k = 0; k < m; ++k) {
    if (!(std::abs(directions[k].norm() - 1.0) <= 1e-6)) {
      throw std::invalid_argument("known direction " + std::to_string(k + 1) +
                                  " is not a unit vector");
    }
    if (!readings[k].allFinite()) {
      throw DataError("position " + std::to_string(k + 1) + " has a non-finite reading");
    }
    if (!options.reading_sigmas.empty() &&
        !(options.reading_sigmas[k].allFinite() && options.reading_sigmas[k].minCoeff() > 0)) {
      throw std::invalid_argument("reading_sigmas must be finite and positive");
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
  const Fit fit = FitAll(readings, forces, weights, options.model);

  CalibrationResult result;
  result.model = options.model;
  result.frame = Frame::kPlatform;
  result.gravity = options.gravity;
  result.params = fit.params;
  result.directions = directions;
  double cost = 0, chi2 = 0;
  for (std::size_t k = 0; k < m; ++k) {
    const Vec3 r = readings[k] - PredictRaw(fit.params, forces[k]);
    result.residuals.push_back(r);
    cost += r.squaredNorm();
    chi2 += r.cwiseAbs2().dot(weights[k]);
  }
  result.degrees_of_freedom = 3 * static_cast<int>(m) - P;
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
    std::vector<double> errors;
    for (std::size_t k = 0; k < m; ++k) {
      std::vector<Vec3> held_out = weights;
      held_out[k].setZero();
      ModelParameters without;
      try {
        without = FitAll(readings, forces, held_out, options.model).params;
      } catch (const DataError& e) {
        result.crossval_note = "without position " + std::to_string(k + 1) + ": " + e.what();
        break;
      }
      const double e = GravityNormErrors(without, {readings[k]}, options.gravity)[0];
      if (!std::isfinite(e)) {
        result.crossval_note =
            "position " + std::to_string(k + 1) + " lies outside the range of the fit without it";
        break;
      }
      errors.push_back(e);
    }
    if (result.crossval_note.empty()) {
      result.crossval_rms = Rms(errors);
      result.crossval_errors = std::move(errors);
    }
  }
  s.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace accelcal
