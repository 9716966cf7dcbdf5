#pragma once
// Internal pieces shared by the two solvers. Everything works in the 12-parameter (quadratic)
// layout of model.hpp; for the linear model the k2 entries are held at zero by a mask, so all
// matrices have fixed size and the hot loops allocate nothing.

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "accelcal/calibration_types.hpp"
#include "accelcal/model.hpp"

namespace accelcal::internal {

using Vec12 = Eigen::Matrix<double, kMaxParameters, 1>;
using Mat12 = Eigen::Matrix<double, kMaxParameters, kMaxParameters>;
using Mat3x12 = Eigen::Matrix<double, 3, kMaxParameters>;
using Mat12x2 = Eigen::Matrix<double, kMaxParameters, 2>;
using Mat32 = Eigen::Matrix<double, 3, 2>;

/// The data and fixed settings of one calibration problem.
struct Problem {
  const std::vector<Vec3>& readings;  ///< p_k [raw]
  double gravity;                     ///< g in the specific-force unit
  ModelKind model;
  int positions() const { return static_cast<int>(readings.size()); }
};

/// 1 for free parameters, 0 for the k2 entries of the linear model.
Vec12 FreeMask(ModelKind model);
Vec12 ToVec12(const ModelParameters& params);
ModelParameters FromVec12(const Vec12& theta);

/// J = Σ_k ‖p_k − μ(θ, g c_k)‖² (paper 000 eq. (13)).
double Cost(const Problem& problem, const ModelParameters& params, const std::vector<Vec3>& dirs);

/// J(b) − J(a) computed from the change of each residual, Σ (r_b − r_a)ᵀ(r_b + r_a): accurate
/// to the digits of the change itself, where the difference of two costs loses them all once the
/// change falls below J·1e-16 (large residuals near the optimum).
double CostChange(const Problem& problem, const ModelParameters& params_a,
                  const std::vector<Vec3>& dirs_a, const ModelParameters& params_b,
                  const std::vector<Vec3>& dirs_b);

/// Multiplying a parameter change by its scale gives the change of the prediction it causes on a
/// unit-gravity input, relative to the axis' signal amplitude |K_ii|·g. See TerminationType.
Vec12 ParameterScales(const Problem& problem, const ModelParameters& params);
/// max_j |Δθ_j| s_j
double ScaledNorm(const Vec12& delta, const Vec12& scales);

/// Cost below which the data are fitted to round-off (TerminationType::kZeroResidual).
/// The largest raw reading an axis sees from gravity, max_i |K_ii| g + |b_i| [raw]: the scale of
/// round-off in the readings.
double SignalAmplitude(const ModelParameters& params, double gravity);
double ZeroResidualCost(const Problem& problem, const ModelParameters& params);

/// Orthonormal basis of the plane tangent to the unit sphere at the unit vector c (columns ⟂ c).
Mat32 TangentBasis(const Vec3& c);
/// normalize(c + B δ): the retraction used by the joint solver.
Vec3 Retract(const Vec3& c, const Mat32& basis, const Eigen::Vector2d& delta);

/// Gauss-Newton normal equations of the joint problem in the variables (θ, δ_1..δ_m), δ_k the
/// tangent coordinates of c_k: A = Σ J_θᵀJ_θ, B_k = J_θᵀ J_c, D_k = J_cᵀ J_c, g = Jᵀ r.
/// J_θ is block-sparse (output axis i depends only on its own parameter group, with the regressors
/// v_i(f) of Regressors()), so B_k is kept implicit as J_c and f: its rows in group i are
/// v_i ⊗ (row i of J_c). BTimes / BTransposeTimes / B apply it.
struct NormalEquations {
  Mat12 A;
  Vec12 g_theta;
  std::vector<Vec3> f;     ///< g c_k, the specific force of each position
  std::vector<Mat32> J_c;  ///< ∂μ/∂δ_k
  std::vector<Eigen::Matrix2d> D;
  std::vector<Eigen::Vector2d> g_c;
  std::vector<Mat32> tangent;
  double cost = 0;
};
void BuildNormalEquations(const Problem& problem, const ModelParameters& params,
                          const std::vector<Vec3>& dirs, NormalEquations* ne);

/// Where each output axis' parameter group starts in the 12-parameter layout (3, 4, 5 entries).
inline constexpr int kGroupStart[3] = {0, 3, 7};
/// ∂μ_i/∂θ restricted to group i: (f_x, 1, f_x²), (f_x, f_y, 1, f_y²), (f_x, f_y, f_z, 1, f_z²).
struct Regressors {
  explicit Regressors(const Vec3& f) : x(f(0), 1.0, f(0) * f(0)), y(f(0), f(1), 1.0, f(1) * f(1)) {
    z << f(0), f(1), f(2), 1.0, f(2) * f(2);
  }
  Eigen::Vector3d x;
  Eigen::Vector4d y;
  Eigen::Matrix<double, 5, 1> z;
};
/// B_k d
Vec12 BTimes(const NormalEquations& ne, std::size_t k, const Eigen::Vector2d& d);
/// B_kᵀ t
Eigen::Vector2d BTransposeTimes(const NormalEquations& ne, std::size_t k, const Vec12& t);
/// B_k itself (tests)
Mat12x2 B(const NormalEquations& ne, std::size_t k);

/// Schur complement S = A_λ − Σ B_k D_kλ⁻¹ B_kᵀ with Marquardt damping X_λ = X + λ diag(X), the
/// fixed parameters' rows and columns replaced by the identity.
Mat12 ReducedMatrix(const NormalEquations& ne, double lambda, const Vec12& mask);

/// The rows u_k of the reduced information S = Σ u_k u_kᵀ (see ReducedInformation), with the unit
/// normals n_k of the fitted surface (a reading error moves the fit only through n_kᵀ e) and A's
/// diagonal.
struct InformationRows {
  Eigen::Matrix<double, Eigen::Dynamic, kMaxParameters> U;
  std::vector<Vec3> normals;
  Vec12 A_diagonal;
};
InformationRows ReducedInformationRows(const Problem& problem, const ModelParameters& params,
                                       const std::vector<Vec3>& dirs);

/// ReducedMatrix(ne, 0, all free) computed directly as Σ u_k u_kᵀ (see the definition) on the
/// problem model's free parameters (zero rows and columns elsewhere), and the
/// diagonal of A for the Jacobi scaling.
Mat12 ReducedInformation(const Problem& problem, const ModelParameters& params,
                         const std::vector<Vec3>& dirs, Vec12* A_diagonal);

/// The reduced information matrix at a point, factorised once for the observability check and
/// the covariance.
struct Information {
  Mat12 reduced;              ///< S at λ = 0 (fixed parameters: identity rows)
  Vec12 scale;                ///< Jacobi scaling 1/√A_jj
  Eigen::LDLT<Mat12> factor;  ///< of diag(scale) S diag(scale)
  double rcond = 0;           ///< reciprocal condition estimate of the scaled free block
  int weakest = -1;           ///< 12-layout index of the least determined parameter (rcond < 1e-6)
  Mat12 Inverse() const;      ///< S⁻¹ (the fixed parameters' block is the identity)
};
/// rcond below this: some parameter is not determined by the positions.
inline constexpr double kMinInformationRcond = 1e-10;
/// rcond below this: some parameter is poorly determined (named when a solver fails to converge).
/// Measured at the solution: 1.7e-5 to 0.16 on the bundled recordings and the Table-3 problem
/// (linear), 7.5e-7 on the T265 set with the quadratic model.
inline constexpr double kPoorInformationRcond = 1e-6;
/// `rows`, when given, receives the rows S was summed from (the outlier screening uses them).
Information ComputeInformation(const Problem& problem, const ModelParameters& params,
                               const std::vector<Vec3>& dirs, InformationRows* rows = nullptr);
/// Completes `info` whose `reduced` holds a (weighted) information matrix: masks the fixed
/// parameters, scales with A's diagonal, factorises, estimates rcond and names the weakest.
void FinishInformation(ModelKind model, const Vec12& A_diagonal, Information* info);

/// Unit directions of the readings under params: normalize(f(p_k)), falling back to p_k − b.
std::vector<Vec3> DirectionsFromParams(const Problem& problem, const ModelParameters& params);

/// Linear least squares for θ given the directions (paper 000 eq. (14)-(15)): three independent
/// per-axis problems.
ModelParameters SolveParametersGivenDirections(const Problem& problem,
                                               const std::vector<Vec3>& dirs);

/// Levenberg-Marquardt damping λ (relative to the normal matrix' diagonal) with Nielsen's update,
/// shared by the joint and modulus solvers.
class Damping {
 public:
  explicit Damping(double initial) : lambda_(initial) {}
  double lambda() const { return lambda_; }
  void Set(double lambda) { lambda_ = lambda, nu_ = 2.0; }
  /// After an accepted step with gain ratio ρ = actual / predicted reduction.
  void Accept(double rho) {
    lambda_ = std::max(1e-16, lambda_ * std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3)));
    nu_ = 2.0;
  }
  /// After a rejected step; false once the damping exceeds 1e16 (no step reduces the cost).
  bool Reject() {
    lambda_ *= nu_;
    nu_ *= 2.0;
    return lambda_ <= 1e16;
  }

 private:
  double lambda_;
  double nu_ = 2.0;
};

/// Result of a solver run, before the common post-processing in Calibrate().
/// The shifts of the bias-corrected estimator (calibrate.hpp, Estimator::kBiasCorrected) at a
/// fit: per position the expected signed distance m_k of a reading with per-axis noise sigma_k
/// (1σ, independent axes) from the fitted surface, the surface's unit normal n_k (m_k n_k does not
/// depend on n_k's sign) and the noise along it, sqrt(Σ n_i² σ_i²).
struct SurfaceOffsets {
  std::vector<double> offset;
  std::vector<Vec3> normal;
  std::vector<double> normal_sigma;
};
SurfaceOffsets ExpectedSurfaceOffsets(const Problem& problem, const ModelParameters& params,
                                      const std::vector<Vec3>& dirs,
                                      const std::vector<Vec3>& sigmas);

struct SolverOutput {
  ModelParameters params;
  std::vector<Vec3> dirs;
  Summary summary;
};

SolverOutput SolveTwoStep(const Problem& problem, const ModelParameters& init_params,
                          std::vector<Vec3> init_dirs, const CalibrationOptions& options);
SolverOutput SolveJoint(const Problem& problem, const ModelParameters& init_params,
                        std::vector<Vec3> init_dirs, const CalibrationOptions& options);

/// The modulus methods (options.method kModulus or kModulusNorm), linear model: Levenberg-Marquardt
/// on the 9 parameters, directions set to the normalised corrected readings.
SolverOutput SolveModulus(const Problem& problem, const ModelParameters& init_params,
                          const CalibrationOptions& options);

/// Residuals e_k of the modulus methods for the linear flat parameters θ (9): e_k = |f_k|²/g² − 1
/// (squared) or |f_k|/g − 1, f_k = K⁻¹(p_k − b); optionally their Jacobian (m x 9). Exposed for the
/// finite-difference tests.
Eigen::VectorXd ModulusResiduals(const Problem& problem, const Eigen::VectorXd& theta, bool squared,
                                 Eigen::MatrixXd* jacobian);

/// Paper 001 eq. (12): L = Σ_k ‖p_k − μ(θ, g c_k)‖² + λ_k (‖c_k‖² − 1) for the linear model,
/// θ the 9 linear flat parameters, z_k = (c_k, λ_k). Gradient and Hessian in blocks (eq. (14)-(15)
/// in the x-first gauge): the θθ block, and per position the θz coupling and the 4x4 zz block. The
/// solver does not form them (ComputeNewtonLagrangeStep); the tests check them by finite
/// differences and the solver's step against the dense Newton step they define.
using Vec9 = Eigen::Matrix<double, 9, 1>;
struct LagrangianBlocks {
  double value = 0;  ///< L
  double cost = 0;   ///< J = Σ ‖r_k‖²
  Vec9 g_theta;
  Eigen::Matrix<double, 9, 9> H_theta;
  std::vector<Eigen::Vector4d> g_z;
  std::vector<Eigen::Matrix<double, 9, 4>> H_theta_z;
  std::vector<Eigen::Matrix4d> H_z;
};
void LagrangianDerivatives(const Problem& problem, const Vec9& theta, const std::vector<Vec3>& c,
                           const std::vector<double>& lambda, LagrangianBlocks* blocks);

/// The Newton step of eq. (13), −H⁻¹∇L for the full Lagrangian of LagrangianDerivatives, computed
/// without its blocks: each position's (Δc_k, Δλ_k) is eliminated in the plane tangent to c_k,
/// where the 4x4 KKT block reduces to the 2x2 W_k⁻¹ = Eᵀ H_cc E (E ⟂ c_k orthonormal) and the
/// coupling to G_k = H_θc E (9x2, from the structure of J_θ: no dense 9x4 block). See the .cpp.
struct NewtonLagrangeStep {
  Vec9 d_theta;
  std::vector<Vec3> d_c;
  std::vector<double> d_lambda;
  double cost = 0;  ///< J at the point the step starts from
};
/// The instruction sets the step's per-position kernel is built for (newton_lagrange_kernel.hpp);
/// they give the same bits.
enum class KernelIsa { kBaseline, kAvx };
/// kAvx when this build has the AVX kernel (x86-64) and the CPU and OS support AVX.
KernelIsa BestKernelIsa();
bool KernelAvailable(KernelIsa isa);
void ComputeNewtonLagrangeStep(const Problem& problem, const Vec9& theta,
                               const std::vector<Vec3>& c, const std::vector<double>& lambda,
                               NewtonLagrangeStep* step, KernelIsa isa = BestKernelIsa());

/// Paper 001 §3.2: Newton's method on the Lagrangian (linear model), each position's block
/// eliminated (ComputeNewtonLagrangeStep).
SolverOutput SolveNewtonLagrange(const Problem& problem, const ModelParameters& init_params,
                                 std::vector<Vec3> init_dirs, const CalibrationOptions& options);

/// Per-position constrained Newton (paper 000 eq. (18)-(24), Hessian per docs/errata.md#000-eq25):
/// minimises ‖p − μ(g c)‖² on |c| = 1 starting from c0. Exposed for tests.
Vec3 KktDirection(const ModelParameters& params, double gravity, const Vec3& p, const Vec3& c0,
                  int max_iterations);

/// Gradient (eq. (24) with u = 0) and Hessian (corrected eq. (25) without the 2u I term) of
/// f(c) = ‖p − μ(g c)‖². Exposed for the finite-difference tests.
void DirectionCostDerivatives(const ModelParameters& params, double gravity, const Vec3& p,
                              const Vec3& c, Vec3* gradient, Mat33* hessian);

}  // namespace accelcal::internal
