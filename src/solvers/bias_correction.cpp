// The curvature offsets of the bias-corrected estimator (calibrate.hpp, Estimator).
#include <Eigen/Geometry>  // cross
#include <Eigen/LU>

#include "solvers/solver_common.hpp"

namespace accelcal::internal {

// Near the foot point x₀ = μ(θ, g c), parametrise the surface by tangent coordinates s of the unit
// sphere, c(s) = c + E s − ½|s|² c + …, so x(s) = x₀ + T s + ½ sᵀ(∂²x)s with T = g J E and
// ∂²x/∂s_i∂s_j = 2 g² k2 ∘ E_i ∘ E_j − δ_ij g J c (J = ∂μ/∂f). A reading p = x₀ + e has the foot
// s* = G⁻¹Tᵀe + O(e²) and the signed distance d = n·e − ½ s*ᵀ L s* + O(e³), L_ij =
// n·∂²x/∂s_i∂s_j. So E[d] = −½ tr(L G⁻¹ TᵀΣT G⁻¹); for a sphere of radius R, σ²/R.
SurfaceOffsets ExpectedSurfaceOffsets(const Problem& problem, const ModelParameters& params,
                                      const std::vector<Vec3>& dirs,
                                      const std::vector<Vec3>& sigmas) {
  const double g = problem.gravity;
  const std::size_t m = dirs.size();
  SurfaceOffsets out;
  out.offset.resize(m);
  out.normal.resize(m);
  out.normal_sigma.resize(m);
  for (std::size_t k = 0; k < m; ++k) {
    const Vec3& c = dirs[k];
    Mat33 J;
    PredictRaw(params, Vec3(g * c), &J);
    const Mat32 E = TangentBasis(c);
    const Mat32 T = g * J * E;
    const Vec3 n = T.col(0).cross(T.col(1)).normalized();
    const double radial = g * n.dot(J * c);
    Eigen::Matrix2d L;
    for (int i = 0; i < 2; ++i) {
      for (int j = 0; j < 2; ++j) {
        const Vec3 curvature =
            2.0 * g * g * params.k2.cwiseProduct(E.col(i)).cwiseProduct(E.col(j));
        L(i, j) = n.dot(curvature) - (i == j ? radial : 0.0);
      }
    }
    const Eigen::Matrix2d G_inverse = (T.transpose() * T).inverse();
    const Vec3 variance = sigmas[k].cwiseAbs2();
    const Eigen::Matrix2d M = G_inverse * T.transpose() * variance.asDiagonal() * T * G_inverse;
    out.offset[k] = -0.5 * (L * M).trace();
    out.normal[k] = n;
    out.normal_sigma[k] = std::sqrt(n.cwiseAbs2().dot(variance));
  }
  return out;
}

}  // namespace accelcal::internal
