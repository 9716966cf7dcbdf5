#include "accelcal/ellipsoid_fit.hpp"

#include "core/text_format.hpp"
#include "model/ellipsoid_quadric.hpp"
#include "solvers/smallest_eigenvector.hpp"

#include <cmath>
#include <cstdio>
#include <optional>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

namespace accelcal {

std::string_view ToString(EllipsoidFitKind kind) {
  return kind == EllipsoidFitKind::kAlgebraic ? "algebraic" : "constrained (Li & Griffiths 2004)";
}

namespace {

using Vec10 = Eigen::Matrix<double, 10, 1>;
using Mat10 = Eigen::Matrix<double, 10, 10>;
using Mat66 = Eigen::Matrix<double, 6, 6>;

/// Paper 001 eq. (17)-(18) fix one coefficient; the unit-norm minimiser is invariant to that
/// choice: the eigenvector of DᵀD with the smallest eigenvalue.
Vec10 AlgebraicQuadric(const Mat10& scatter) {
  if (const std::optional<Vec10> v = internal::SmallestEigenvector(scatter)) return *v;
  Eigen::SelfAdjointEigenSolver<Mat10> eig(scatter);
  return eig.eigenvectors().col(0);
}

/// Li & Griffiths (2004): min vᵀ S v subject to v₁ᵀ C v₁ = 1 with v₁ the quadratic coefficients
/// and v₁ᵀ C v₁ = 4J − I². Eliminating the linear part, v₂ = −S₂₂⁻¹ S₂₁ v₁, leaves the 6x6
/// generalised eigenproblem M v₁ = λ C v₁, M = S₁₁ − S₁₂ S₂₂⁻¹ S₂₁, whose one admissible solution
/// (v₁ᵀ C v₁ > 0) has the smallest cost λ ≥ 0. std::nullopt when there is none.
std::optional<Vec10> EllipsoidSpecificQuadric(const Mat10& scatter) {
  Mat66 C = Mat66::Zero();
  C.topLeftCorner<3, 3>().setConstant(1.0);  // k/2 − 1 with k = 4
  C.topLeftCorner<3, 3>().diagonal().setConstant(-1.0);
  C.bottomRightCorner<3, 3>().diagonal().setConstant(-4.0);  // −k (h, g, f carry a factor 2)
  const Eigen::Matrix4d S22 = scatter.bottomRightCorner<4, 4>();
  const Eigen::Matrix<double, 4, 6> S22_inv_S21 =
      S22.ldlt().solve(scatter.bottomLeftCorner<4, 6>());
  const Mat66 M = scatter.topLeftCorner<6, 6>() - scatter.topRightCorner<6, 4>() * S22_inv_S21;
  // C⁻¹ M is similar to a symmetric matrix when M ≻ 0 but may be slightly non-normal in floating
  // point: take the real parts of a general eigen decomposition and keep the admissible vector.
  Eigen::EigenSolver<Mat66> eig(C.inverse() * M);
  if (eig.info() != Eigen::Success) return std::nullopt;
  std::optional<Vec10> best;
  double best_cost = 0;
  for (int i = 0; i < 6; ++i) {
    const Eigen::Matrix<double, 6, 1> v1 = eig.eigenvectors().col(i).real();
    const double norm = v1.dot(C * v1);
    if (!(norm > 0)) continue;
    const double cost = v1.dot(M * v1) / norm;
    if (best && cost >= best_cost) continue;
    Vec10 v;
    v << v1, -S22_inv_S21 * v1;
    best = v / std::sqrt(norm);
    best_cost = cost;
  }
  return best;
}

/// K and b from a quadric in the scaled coordinates q = (p − mean) / scale, or the reason why the
/// quadric is not a real ellipsoid.
std::optional<std::string> ToParameters(const Vec10& v, const Vec3& mean, double scale,
                                        double gravity, ModelParameters* params) {
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
    internal::FormatTo(buf, sizeof buf,
                       "the fitted quadric is not an ellipsoid (eigenvalues %.3g, %.3g, %.3g)",
                       ev(0), ev(1), ev(2));
    return std::string(buf);
  }
  const Vec3 centre = -Q.ldlt().solve(L);
  const double s = centre.dot(Q * centre) - c;
  if (!(s > 0)) return std::string("the fitted quadric is an empty (imaginary) ellipsoid");
  // K Kᵀ = (s / g²) Q⁻¹ in the scaled coordinates; K lower-triangular is the Cholesky factor.
  const Mat33 KKt = (s / (gravity * gravity)) * Q.inverse();
  Eigen::LLT<Mat33> llt(KKt);
  if (llt.info() != Eigen::Success) {
    return std::string("Cholesky factorisation of the fitted ellipsoid failed");
  }
  params->K = scale * Mat33(llt.matrixL());
  params->bias = mean + scale * centre;
  params->k2.setZero();
  if (!params->K.allFinite() || !params->bias.allFinite()) {
    return std::string("the ellipsoid fit produced non-finite parameters");
  }
  return std::nullopt;
}

/// The scatter matrix DᵀD of the readings centred on `mean` and divided by `scale`, or the reason
/// why there is none.
std::optional<std::string> Scatter(const std::vector<Vec3>& readings, Mat10* scatter, Vec3* mean,
                                   double* scale) {
  const int m = static_cast<int>(readings.size());
  if (m < 9) return "an ellipsoid needs at least 9 readings, got " + std::to_string(m);
  // Centre and scale the readings so the quadric's coefficients are of similar size (raw counts
  // around 33000 would otherwise make the design matrix hopelessly ill-conditioned). One common
  // scale keeps the shape: the constrained fit depends on it.
  *mean = Vec3::Zero();
  for (const Vec3& p : readings) *mean += p;
  *mean /= m;
  *scale = 0;
  for (const Vec3& p : readings) *scale = std::max(*scale, (p - *mean).lpNorm<Eigen::Infinity>());
  if (!(*scale > 0)) return std::string("all readings are identical");
  // In the centred, scaled coordinates DᵀD is well enough conditioned for an initial estimate,
  // and a 10x10 scatter matrix is far cheaper than an SVD of the m x 10 design matrix. Four
  // readings at a time (SIMD); lanes past the end have weight 0.
  using Lanes = Eigen::Array<double, 4, 1>;
  Lanes sums[55];
  for (Lanes& s : sums) s.setZero();
  for (int first = 0; first < m; first += 4) {
    Lanes q[3], weight;
    for (int l = 0; l < 4; ++l) {
      const bool valid = first + l < m;
      const Vec3 p =
          (readings[static_cast<std::size_t>(valid ? first + l : first)] - *mean) / *scale;
      for (int d = 0; d < 3; ++d) q[d](l) = p(d);
      weight(l) = valid ? 1.0 : 0.0;
    }
    // The design row: the quadric's coefficients v = (a, b, c, h, g, f, p, q, r, d) of
    // a x² + b y² + c z² + 2h xy + 2g xz + 2f yz + 2p x + 2q y + 2r z + d = 0 multiply it.
    const Lanes row[10] = {q[0] * q[0],       q[1] * q[1],       q[2] * q[2], 2.0 * q[0] * q[1],
                           2.0 * q[0] * q[2], 2.0 * q[1] * q[2], 2.0 * q[0],  2.0 * q[1],
                           2.0 * q[2],        Lanes::Ones()};
    int n = 0;
    for (int j = 0; j < 10; ++j) {
      const Lanes weighted = weight * row[j];
      for (int i = j; i < 10; ++i) sums[n++] += row[i] * weighted;
    }
  }
  int n = 0;
  for (int j = 0; j < 10; ++j) {
    for (int i = j; i < 10; ++i) (*scatter)(i, j) = sums[n++].sum();
  }
  scatter->triangularView<Eigen::StrictlyUpper>() = scatter->transpose();
  return std::nullopt;
}

/// Fills `result` from the constrained fit; `failure` gets the reason appended when it fails.
void FitConstrained(const Mat10& scatter, const Vec3& mean, double scale, double gravity,
                    EllipsoidFitResult* result) {
  result->kind = EllipsoidFitKind::kConstrained;
  const std::string separator = result->failure.empty() ? "" : "; ";
  const std::optional<Vec10> v = EllipsoidSpecificQuadric(scatter);
  if (!v) {
    result->failure += separator + "the constrained fit found no admissible ellipsoid";
    return;
  }
  if (const auto why = ToParameters(*v, mean, scale, gravity, &result->params)) {
    result->failure += separator + "constrained fit: " + *why;
    return;
  }
  result->ok = true;
}

// The algebraic fit when it is an ellipsoid (algebraic_first), else the constrained one.
EllipsoidFitResult Fit(const std::vector<Vec3>& readings, double gravity, bool algebraic_first) {
  EllipsoidFitResult result;
  if (!algebraic_first) result.kind = EllipsoidFitKind::kConstrained;
  Mat10 scatter;
  Vec3 mean;
  double scale = 0;
  if (auto why = Scatter(readings, &scatter, &mean, &scale)) {
    result.failure = std::move(*why);
    return result;
  }
  if (algebraic_first) {
    const std::optional<std::string> algebraic_failure =
        ToParameters(AlgebraicQuadric(scatter), mean, scale, gravity, &result.params);
    if (!algebraic_failure) {
      result.ok = true;
      return result;
    }
    result.failure = *algebraic_failure;
  }
  FitConstrained(scatter, mean, scale, gravity, &result);
  return result;
}

}  // namespace

EllipsoidFitResult FitEllipsoid(const std::vector<Vec3>& readings, double gravity) {
  return Fit(readings, gravity, /*algebraic_first=*/true);
}

EllipsoidFitResult FitEllipsoidConstrained(const std::vector<Vec3>& readings, double gravity) {
  return Fit(readings, gravity, /*algebraic_first=*/false);
}

namespace internal {
std::optional<std::string> QuadricToParameters(const Vec10& v, const Vec3& mean, double scale,
                                               double gravity, ModelParameters* params) {
  return ToParameters(v, mean, scale, gravity, params);
}
}  // namespace internal

}  // namespace accelcal
