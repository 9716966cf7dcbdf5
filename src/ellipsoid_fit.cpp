#include "accelcal/ellipsoid_fit.hpp"

#include <cmath>
#include <cstdio>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

namespace accelcal {

EllipsoidFitResult FitEllipsoid(const std::vector<Vec3>& readings, double gravity) {
  EllipsoidFitResult result;
  const int m = static_cast<int>(readings.size());
  if (m < 9) {
    result.failure = "an ellipsoid needs at least 9 readings, got " + std::to_string(m);
    return result;
  }
  // Centre and scale the readings so the quadric's coefficients are of similar size (raw counts
  // around 33000 would otherwise make the design matrix hopelessly ill-conditioned).
  Vec3 mean = Vec3::Zero();
  for (const Vec3& p : readings) mean += p;
  mean /= m;
  double scale = 0;
  for (const Vec3& p : readings) scale = std::max(scale, (p - mean).lpNorm<Eigen::Infinity>());
  if (!(scale > 0)) {
    result.failure = "all readings are identical";
    return result;
  }
  // Total least squares: the quadric coefficients are the unit vector v minimising ‖D v‖, the
  // eigenvector of DᵀD with the smallest eigenvalue (paper 001 eq. (17)-(18) fixes one coefficient
  // instead; this is invariant to the choice). In the centred, scaled coordinates DᵀD is well
  // enough conditioned for an initial estimate, and a 10x10 scatter matrix is far cheaper than an
  // SVD of the m x 10 design matrix.
  using Vec10 = Eigen::Matrix<double, 10, 1>;
  Eigen::Matrix<double, 10, 10> scatter = Eigen::Matrix<double, 10, 10>::Zero();
  for (int k = 0; k < m; ++k) {
    const Vec3 q = (readings[k] - mean) / scale;
    Vec10 row;
    row << q.x() * q.x(), q.y() * q.y(), q.z() * q.z(), 2 * q.x() * q.y(), 2 * q.x() * q.z(),
        2 * q.y() * q.z(), 2 * q.x(), 2 * q.y(), 2 * q.z(), 1.0;
    scatter.selfadjointView<Eigen::Lower>().rankUpdate(row);
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 10, 10>> scatter_eig(
      scatter.selfadjointView<Eigen::Lower>());
  const Vec10 v = scatter_eig.eigenvectors().col(0);
  Mat33 Q;
  Q << v(0), v(3), v(4), v(3), v(1), v(5), v(4), v(5), v(2);
  Vec3 L(v(6), v(7), v(8));
  double c = v(9);
  Eigen::SelfAdjointEigenSolver<Mat33> eig(Q);
  Vec3 ev = eig.eigenvalues();
  if (ev(2) < 0) {  // all negative: flip the sign of the whole quadric
    Q = -Q;
    L = -L;
    c = -c;
    ev = -ev.reverse().eval();
  }
  if (!(ev(0) > 1e-9 * ev(2))) {
    char buf[160];
    std::snprintf(buf, sizeof buf,
                  "the fitted quadric is not an ellipsoid (eigenvalues %.3g, %.3g, %.3g)", ev(0),
                  ev(1), ev(2));
    result.failure = buf;
    return result;
  }
  const Vec3 centre = -Q.ldlt().solve(L);
  const double s = centre.dot(Q * centre) - c;
  if (!(s > 0)) {
    result.failure = "the fitted quadric is an empty (imaginary) ellipsoid";
    return result;
  }
  // K Kᵀ = (s / g²) Q⁻¹ in the scaled coordinates; K lower-triangular is the Cholesky factor.
  const Mat33 KKt = (s / (gravity * gravity)) * Q.inverse();
  Eigen::LLT<Mat33> llt(KKt);
  if (llt.info() != Eigen::Success) {
    result.failure = "Cholesky factorisation of the fitted ellipsoid failed";
    return result;
  }
  result.params.K = scale * Mat33(llt.matrixL());
  result.params.bias = mean + scale * centre;
  result.params.k2.setZero();
  result.ok = result.params.K.allFinite() && result.params.bias.allFinite();
  if (!result.ok) result.failure = "the ellipsoid fit produced non-finite parameters";
  return result;
}

}  // namespace accelcal
