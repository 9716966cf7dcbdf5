// The curvature offsets of the bias-corrected estimator (calibrate.hpp, Estimator).
#include <Eigen/Geometry>  // cross
#include <Eigen/LU>

#include <algorithm>
#include <cmath>

#include "core/text_format.hpp"
#include "solvers/solve.hpp"
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

namespace {

// The bias correction's offsets at the fit to `problem`, with the noise the covariance uses
// (calibrate.hpp): σ̂ from the residuals, or the readings' sigmas inflated by the scatter ratio.
// The offsets are linear in the noise covariance, so the inflation R² (which needs the normals)
// scales those of the uninflated sigmas: one pass over the positions.
internal::SurfaceOffsets CorrectionOffsets(const Problem& problem,
                                           const internal::SolverOutput& out,
                                           const CalibrationOptions& options, int dof) {
  const std::size_t m = problem.readings.size();
  if (options.reading_sigmas.empty()) {
    const Vec3 sigma = Vec3::Constant(std::sqrt(out.summary.final_cost / dof));
    return internal::ExpectedSurfaceOffsets(problem, out.params, out.dirs,
                                            std::vector<Vec3>(m, sigma));
  }
  internal::SurfaceOffsets offsets =
      internal::ExpectedSurfaceOffsets(problem, out.params, out.dirs, options.reading_sigmas);
  double chi2 = 0;
  for (std::size_t k = 0; k < m; ++k) {
    const Vec3 residual =
        problem.readings[k] - PredictRaw(out.params, Vec3(problem.gravity * out.dirs[k]));
    chi2 += std::pow(offsets.normal[k].dot(residual) / offsets.normal_sigma[k], 2);
  }
  const double inflation2 = std::max(1.0, chi2 / dof);
  for (std::size_t k = 0; k < m; ++k) {
    offsets.offset[k] *= inflation2;
    offsets.normal_sigma[k] *= std::sqrt(inflation2);
  }
  return offsets;
}

}  // namespace

// Estimator::kBiasCorrected (calibrate.hpp): refits `out` with each reading moved inward by its
// expected offset from the fitted surface until the shifts settle; returns the readings of the
// last fit.
std::vector<Vec3> CorrectBias(const std::vector<Vec3>& readings, const CalibrationOptions& options,
                              internal::SolverOutput* out) {
  std::vector<Vec3> shifted = readings;
  Summary& summary = out->summary;
  const int dof = static_cast<int>(readings.size()) - NumParameters(options.model);
  if (dof <= 0 && options.reading_sigmas.empty()) {
    summary.termination_message +=
        "; bias correction not applied: no residual degrees of freedom to estimate the noise";
    return shifted;
  }
  const Summary ml = summary;
  int iterations = ml.iterations;
  double change = 0;
  for (int round = 0; round <= options.bias_correction.max_rounds; ++round) {
    const Problem problem{shifted, options.gravity, options.model};
    const internal::SurfaceOffsets offsets =
        CorrectionOffsets(problem, *out, options, std::max(dof, 1));
    std::vector<Vec3> next(readings.size());
    change = 0;
    for (std::size_t k = 0; k < readings.size(); ++k) {
      next[k] = readings[k] - offsets.offset[k] * offsets.normal[k];
      change = std::max(change, (next[k] - shifted[k]).norm() / offsets.normal_sigma[k]);
    }
    if (change <= options.bias_correction.tolerance) break;  // the last fit used these shifts
    if (round == options.bias_correction.max_rounds) break;
    shifted = std::move(next);
    *out = SolveFrom(Problem{shifted, options.gravity, options.model}, out->params,
                     std::move(out->dirs), options);
    iterations += summary.iterations;
    summary.correction_rounds = round + 1;
    if (!summary.converged()) break;
  }
  summary.estimator = Estimator::kBiasCorrected;
  summary.iterations = iterations;
  summary.initial_cost = ml.initial_cost;
  if (summary.converged() && change > options.bias_correction.tolerance) {
    char buf[200];
    internal::FormatTo(
        buf, sizeof buf,
        "; bias correction: a reading's shift still changed by %.2g of its noise after "
        "%d refits",
        change, summary.correction_rounds);
    summary.termination = TerminationType::kMaxIterations;
    summary.termination_message += buf;
  }
  return shifted;
}

}  // namespace accelcal::internal
