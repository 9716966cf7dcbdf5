#include "accelcal/gimbal_platform.hpp"

#include <cmath>
#include <cstdio>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "accelcal/error.hpp"
#include "accelcal/known_orientation.hpp"
#include "core/text_format.hpp"
#include "platform/gimbal_internal.hpp"

namespace accelcal {

namespace {

constexpr int kParameters = 14;  // s(3), δb(3), β(6), θ20, θ30
using Vec14 = Eigen::Matrix<double, kParameters, 1>;
using Mat14 = Eigen::Matrix<double, kParameters, kParameters>;

PlatformAccelerometer Unpack14(const Vec14& p) {
  PlatformAccelerometer d;
  d.s = p.segment<3>(0);
  d.bias = p.segment<3>(3);
  d.beta = p.segment<6>(6);
  return d;
}

}  // namespace

namespace internal {

Eigen::VectorXd CoarsePrediction(const std::vector<Vec3>& commanded, double gravity,
                                 const CoarseParameters& q, CoarseJacobian* J) {
  const std::size_t m = commanded.size();
  const PlatformAccelerometer d = Unpack14(q);
  const Mat33 C = InstallationMatrix(d.beta);
  Eigen::VectorXd predicted(3 * m);
  if (J != nullptr) J->resize(static_cast<Eigen::Index>(3 * m), kParameters);
  for (std::size_t k = 0; k < m; ++k) {
    Mat33 du;
    const Vec3 angles = commanded[k] + Vec3(0.0, q(12), q(13));
    const Vec3 f = gravity * PlatformUp(angles, &du);
    const Vec3 Cf = C * f;
    const auto row = static_cast<Eigen::Index>(3 * k);
    predicted.segment<3>(row) = d.s.cwiseProduct(Cf) + d.bias;
    if (J == nullptr) continue;
    auto Jk = J->middleRows<3>(row);
    Jk.setZero();
    for (int i = 0; i < 3; ++i) {
      Jk(i, i) = Cf(i);    // ∂/∂s_i
      Jk(i, 3 + i) = 1.0;  // ∂/∂δb_i
    }
    Jk(0, 6) = d.s(0) * f(1);    // β_xz
    Jk(0, 7) = -d.s(0) * f(2);   // β_xy
    Jk(1, 8) = -d.s(1) * f(0);   // β_yz
    Jk(1, 9) = d.s(1) * f(2);    // β_yx
    Jk(2, 10) = d.s(2) * f(0);   // β_zy
    Jk(2, 11) = -d.s(2) * f(1);  // β_zx
    const Mat33 dC = d.s.asDiagonal() * C * gravity * du;
    Jk.col(12) = dC.col(1);  // θ20
    Jk.col(13) = dC.col(2);  // θ30
  }
  return predicted;
}

Eigen::VectorXd FineObservation(const std::vector<Vec3>& outputs, const PlatformAccelerometer& d,
                                double gravity, Eigen::Matrix<double, Eigen::Dynamic, 12>* A) {
  const std::size_t m = outputs.size();
  const Mat33 C_inverse = InstallationMatrix(d.beta).inverse();  // Ĉ_a^p
  Eigen::VectorXd z(m);
  if (A != nullptr) A->resize(static_cast<Eigen::Index>(m), 12);
  for (std::size_t j = 0; j < m; ++j) {
    // v = ŜF (f^a − δ̂b) with the nonlinear term of eq. (8) removed as far as it is known.
    const Vec3 deviation = outputs[j] - d.bias;
    const Vec3 v = (deviation - d.k_nl.cwiseProduct(deviation.cwiseAbs2())).cwiseQuotient(d.s);
    const Vec3 f_p = C_inverse * v;
    const auto row = static_cast<Eigen::Index>(j);
    z(row) = 0.5 * (gravity * gravity - f_p.squaredNorm());
    if (A == nullptr) continue;
    A->row(row) << v(0) * v(0), v(1) * v(1), v(2) * v(2), -v(0), -v(1), -v(2), -v(0) * v(0) * v(0),
        -v(1) * v(1) * v(1), -v(2) * v(2) * v(2), v(0) * v(1), v(0) * v(2), v(1) * v(2);
  }
  return z;
}

void ApplyFineUpdate(const Eigen::Matrix<double, 12, 1>& dx, PlatformAccelerometer* device) {
  PlatformAccelerometer& d = *device;
  // Full-value update (the paper's "using scale factors to convert the solved dx").
  for (int i = 0; i < 3; ++i) {
    const double sf = 1.0 / d.s(i);  // ŜF_i
    d.bias(i) += dx(3 + i) / sf;
    d.k_nl(i) += dx(6 + i) * sf;
    d.s(i) /= 1.0 + dx(i);
  }
  d.beta(2) += dx(9) / 2;   // β_yz
  d.beta(0) -= dx(9) / 2;   // β_xz
  d.beta(1) += dx(10) / 2;  // β_xy
  d.beta(4) -= dx(10) / 2;  // β_zy
  d.beta(5) += dx(11) / 2;  // β_zx
  d.beta(3) -= dx(11) / 2;  // β_yx
}

}  // namespace internal

CoarseCalibrationResult CoarseCalibration(const std::vector<Vec3>& outputs,
                                          const std::vector<Vec3>& commanded, double gravity) {
  const std::size_t m = outputs.size();
  if (commanded.size() != m) {
    throw DataError(std::to_string(commanded.size()) + " commanded positions for " +
                    std::to_string(m) + " outputs");
  }
  if (3 * m < kParameters + 1) {
    throw DataError("the coarse stage needs at least 5 positions, got " + std::to_string(m));
  }
  // Start: the known-orientation least squares at the commanded angles (offsets zero), K = diag(s)
  // C_p^a read to first order.
  std::vector<Vec3> directions;
  for (const Vec3& a : commanded) directions.push_back(PlatformUp(a));
  KnownOrientationOptions start_options;
  start_options.gravity = gravity;
  const ModelParameters start =
      CalibrateKnownOrientations(outputs, directions, start_options).params;
  Vec14 p = Vec14::Zero();
  for (int i = 0; i < 3; ++i) p(i) = start.K(i, i);
  p.segment<3>(3) = start.bias;
  p(6) = start.K(0, 1) / start.K(0, 0);
  p(7) = -start.K(0, 2) / start.K(0, 0);
  p(8) = -start.K(1, 0) / start.K(1, 1);
  p(9) = start.K(1, 2) / start.K(1, 1);
  p(10) = start.K(2, 0) / start.K(2, 2);
  p(11) = -start.K(2, 1) / start.K(2, 2);

  CoarseCalibrationResult result;
  Eigen::Matrix<double, Eigen::Dynamic, kParameters> J(3 * m, kParameters);
  Eigen::VectorXd r(3 * m);
  const auto linearise = [&](const Vec14& q) {
    const Eigen::VectorXd predicted = internal::CoarsePrediction(commanded, gravity, q, &J);
    for (std::size_t k = 0; k < m; ++k) {
      r.segment<3>(static_cast<Eigen::Index>(3 * k)) =
          outputs[k] - predicted.segment<3>(static_cast<Eigen::Index>(3 * k));
    }
  };
  for (int it = 0; it < 50; ++it) {
    linearise(p);
    // Jacobi-scaled normal equations (s ~ 1, angles ~ 1e-4, biases in output units).
    const Vec14 scale = J.colwise().norm().cwiseInverse().transpose();
    const Mat14 N = scale.asDiagonal() * (J.transpose() * J) * scale.asDiagonal();
    Eigen::SelfAdjointEigenSolver<Mat14> eig(N);
    if (!(eig.eigenvalues().minCoeff() > 1e-12 * eig.eigenvalues().maxCoeff())) {
      throw DataError(
          "the positions do not determine the coarse-stage parameters (reciprocal "
          "condition " +
          internal::Format("%.3g", eig.eigenvalues().minCoeff() / eig.eigenvalues().maxCoeff()) +
          "): use Table 1's 18 positions");
    }
    const Vec14 step =
        scale.cwiseProduct(eig.eigenvectors() * eig.eigenvalues().cwiseInverse().asDiagonal() *
                           eig.eigenvectors().transpose() * scale.cwiseProduct(J.transpose() * r));
    p += step;
    ++result.iterations;
    // Converged when no step moves a prediction by more than 1e-13 of the signal.
    if ((J * step).cwiseAbs().maxCoeff() <= 1e-13 * gravity * p.head<3>().maxCoeff()) {
      result.converged = true;
      break;
    }
  }
  linearise(p);
  result.device = Unpack14(p);
  result.offsets = Vec3(0.0, p(12), p(13));
  const double dof = static_cast<double>(3 * m - kParameters);
  const double sigma2 = r.squaredNorm() / dof;
  result.residual_rms = std::sqrt(r.squaredNorm() / static_cast<double>(3 * m));
  result.covariance = sigma2 * (J.transpose() * J).inverse();
  result.std = result.covariance.diagonal().cwiseSqrt();
  result.note =
      "theta10 (the platform's own axis) is not separable from the installation angles: held at "
      "0, its effect is in beta_xz and beta_yz";
  return result;
}

CoarseCalibrationResult IteratedCoarseCalibration(
    const std::function<std::vector<Vec3>(const std::vector<Vec3>& commanded)>& measure,
    double gravity, double tolerance_rad, int max_rounds) {
  Vec3 correction = Vec3::Zero();
  CoarseCalibrationResult result;
  const std::vector<Vec3> nominal = Wu2018Table1Angles();
  for (int round = 0; round < max_rounds; ++round) {
    // Re-zeroing the angle sensors by the offsets found so far: the gimbals turn to the nominal
    // angles minus the correction in the original readings, and the fit, given the nominal
    // angles, sees only the offset that is left.
    std::vector<Vec3> commanded = nominal;
    for (Vec3& a : commanded) a -= correction;
    result = CoarseCalibration(measure(commanded), nominal, gravity);
    correction += result.offsets;
    if (result.offsets.cwiseAbs().maxCoeff() < tolerance_rad) break;
  }
  result.offsets = correction;
  return result;
}

FineCalibrationResult FineCalibration(const std::vector<Vec3>& outputs,
                                      const PlatformAccelerometer& coarse, double gravity) {
  const std::size_t m = outputs.size();
  if (m < 13) {
    throw DataError("the fine stage needs at least 13 positions (12 unknowns), got " +
                    std::to_string(m));
  }
  using Vec12 = Eigen::Matrix<double, 12, 1>;
  FineCalibrationResult result;
  result.device = coarse;
  PlatformAccelerometer& d = result.device;
  Eigen::Matrix<double, Eigen::Dynamic, 12> A(m, 12);
  Eigen::VectorXd z(m);
  const auto linearise = [&]() { z = internal::FineObservation(outputs, d, gravity, &A); };
  Eigen::Matrix<double, 12, 12> normal_inverse;
  for (int it = 0; it < 20; ++it) {
    linearise();
    const Vec12 scale = A.colwise().norm().cwiseInverse().transpose();
    const Eigen::Matrix<double, 12, 12> N =
        scale.asDiagonal() * (A.transpose() * A) * scale.asDiagonal();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 12, 12>> eig(N);
    if (!(eig.eigenvalues().minCoeff() > 1e-12 * eig.eigenvalues().maxCoeff())) {
      throw DataError("the positions do not determine the fine-stage error vector (eq. (17))");
    }
    normal_inverse = scale.asDiagonal() * eig.eigenvectors() *
                     eig.eigenvalues().cwiseInverse().asDiagonal() *
                     eig.eigenvectors().transpose() * scale.asDiagonal();
    const Vec12 dx = normal_inverse * (A.transpose() * z);
    result.dx += dx;
    internal::ApplyFineUpdate(dx, &d);
    ++result.iterations;
    if ((A * dx).cwiseAbs().maxCoeff() <= 1e-13 * gravity * gravity) {
      result.converged = true;
      break;
    }
  }
  linearise();
  const double dof = static_cast<double>(m) - 12;
  const double sigma2 = dof > 0 ? z.squaredNorm() / dof : 0.0;
  result.dx_std = (sigma2 * normal_inverse.diagonal()).cwiseSqrt();
  result.residual_rms = std::sqrt(z.squaredNorm() / static_cast<double>(m)) / gravity;
  result.note =
      "the pairs (beta_xz, beta_yz), (beta_zy, beta_xy), (beta_yx, beta_zx) are not separable here "
      "(paper 003 section 4): gravity magnitudes determine only beta_yz - beta_xz, beta_xy - "
      "beta_zy, beta_zx - beta_yx; each pair was moved symmetrically, its sum kept from the coarse "
      "stage";
  return result;
}

}  // namespace accelcal
