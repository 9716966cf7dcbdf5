// Shared pieces of the solvers: cost, metrics, tangent spaces, normal equations, information.
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include "solvers/solver_common.hpp"

namespace accelcal::internal {

Vec12 FreeMask(ModelKind model) {
  Vec12 mask = Vec12::Ones();
  if (model == ModelKind::kLinear) mask(2) = mask(6) = mask(11) = 0.0;
  return mask;
}

Vec12 ToVec12(const ModelParameters& p) {
  Vec12 t;
  t << p.K(0, 0), p.bias(0), p.k2(0), p.K(1, 0), p.K(1, 1), p.bias(1), p.k2(1), p.K(2, 0),
      p.K(2, 1), p.K(2, 2), p.bias(2), p.k2(2);
  return t;
}

ModelParameters FromVec12(const Vec12& t) {
  ModelParameters p;
  p.K << t(0), 0, 0, t(3), t(4), 0, t(7), t(8), t(9);
  p.bias << t(1), t(5), t(10);
  p.k2 << t(2), t(6), t(11);
  return p;
}

double Cost(const Problem& problem, const ModelParameters& params, const std::vector<Vec3>& dirs) {
  double cost = 0;
  for (int k = 0; k < problem.positions(); ++k) {
    cost +=
        (problem.readings[k] - PredictRaw(params, Vec3(problem.gravity * dirs[k]))).squaredNorm();
  }
  return cost;
}

double CostChange(const Problem& problem, const ModelParameters& params_a,
                  const std::vector<Vec3>& dirs_a, const ModelParameters& params_b,
                  const std::vector<Vec3>& dirs_b) {
  double change = 0;
  for (int k = 0; k < problem.positions(); ++k) {
    const Vec3 mu_a = PredictRaw(params_a, Vec3(problem.gravity * dirs_a[k]));
    const Vec3 mu_b = PredictRaw(params_b, Vec3(problem.gravity * dirs_b[k]));
    change += (mu_b - mu_a).dot(mu_b + mu_a - 2.0 * problem.readings[k]);
  }
  return change;
}

Vec12 ParameterScales(const Problem& problem, const ModelParameters& params) {
  const double g = problem.gravity;
  Vec12 s;
  const double ax = 1.0 / (std::abs(params.K(0, 0)) * g);
  const double ay = 1.0 / (std::abs(params.K(1, 1)) * g);
  const double az = 1.0 / (std::abs(params.K(2, 2)) * g);
  s << g * ax, ax, g * g * ax, g * ay, g * ay, ay, g * g * ay, g * az, g * az, g * az, az,
      g * g * az;
  return s;
}

double ScaledNorm(const Vec12& delta, const Vec12& scales) {
  return delta.cwiseAbs().cwiseProduct(scales).maxCoeff();
}

double SignalAmplitude(const ModelParameters& params, double gravity) {
  double signal = 0;
  for (int i = 0; i < 3; ++i) {
    signal = std::max(signal, std::abs(params.K(i, i)) * gravity + std::abs(params.bias(i)));
  }
  return signal;
}

double ZeroResidualCost(const Problem& problem, const ModelParameters& params) {
  const double unit =
      8.0 * std::numeric_limits<double>::epsilon() * SignalAmplitude(params, problem.gravity);
  return unit * unit * 3.0 * problem.positions();
}

Mat32 TangentBasis(const Vec3& c) {
  // Start from the coordinate axis least aligned with c so the cross products are well conditioned.
  Eigen::Index axis = 0;
  c.cwiseAbs().minCoeff(&axis);
  const Vec3 e = Vec3::Unit(axis);
  Mat32 basis;
  basis.col(0) = c.cross(e).normalized();
  basis.col(1) = c.cross(basis.col(0));  // unit: c is a unit vector ⟂ col(0)
  return basis;
}

Vec3 Retract(const Vec3& c, const Mat32& basis, const Eigen::Vector2d& delta) {
  return (c + basis * delta).normalized();
}

void BuildNormalEquations(const Problem& problem, const ModelParameters& params,
                          const std::vector<Vec3>& dirs, NormalEquations* ne) {
  const int m = problem.positions();
  const double g = problem.gravity;
  ne->A.setZero();
  ne->g_theta.setZero();
  ne->f.resize(m);
  ne->J_c.resize(m);
  ne->D.resize(m);
  ne->g_c.resize(m);
  ne->tangent.resize(m);
  ne->cost = 0;
  // A is block diagonal, A_ii += v_i v_iᵀ, with the regressors v_i of axis i.
  for (int k = 0; k < m; ++k) {
    const Vec3 f = g * dirs[k];
    Mat33 J_p_f;
    const Vec3 r = PredictRaw(params, f, &J_p_f) - problem.readings[k];
    ne->tangent[k] = TangentBasis(dirs[k]);
    const Mat32 J_c = g * J_p_f * ne->tangent[k];
    const Regressors v(f);
    ne->A.block<3, 3>(kGroupStart[0], kGroupStart[0]).noalias() += v.x * v.x.transpose();
    ne->A.block<4, 4>(kGroupStart[1], kGroupStart[1]).noalias() += v.y * v.y.transpose();
    ne->A.block<5, 5>(kGroupStart[2], kGroupStart[2]).noalias() += v.z * v.z.transpose();
    ne->g_theta.segment<3>(kGroupStart[0]) += r(0) * v.x;
    ne->g_theta.segment<4>(kGroupStart[1]) += r(1) * v.y;
    ne->g_theta.segment<5>(kGroupStart[2]) += r(2) * v.z;
    ne->f[k] = f;
    ne->J_c[k] = J_c;
    ne->D[k].noalias() = J_c.transpose() * J_c;
    ne->g_c[k].noalias() = J_c.transpose() * r;
    ne->cost += r.squaredNorm();
  }
}

Vec12 BTimes(const NormalEquations& ne, std::size_t k, const Eigen::Vector2d& d) {
  const Regressors v(ne.f[k]);
  const Vec3 w = ne.J_c[k] * d;
  Vec12 out;
  out << w(0) * v.x, w(1) * v.y, w(2) * v.z;
  return out;
}

Eigen::Vector2d BTransposeTimes(const NormalEquations& ne, std::size_t k, const Vec12& t) {
  const Regressors v(ne.f[k]);
  const Vec3 u(v.x.dot(t.segment<3>(kGroupStart[0])), v.y.dot(t.segment<4>(kGroupStart[1])),
               v.z.dot(t.segment<5>(kGroupStart[2])));
  return ne.J_c[k].transpose() * u;
}

Mat12x2 B(const NormalEquations& ne, std::size_t k) {
  Mat12x2 out;
  out.col(0) = BTimes(ne, k, Eigen::Vector2d(1.0, 0.0));
  out.col(1) = BTimes(ne, k, Eigen::Vector2d(0.0, 1.0));
  return out;
}

Mat12 ReducedMatrix(const NormalEquations& ne, double lambda, const Vec12& mask) {
  Mat12 S = ne.A;
  S.diagonal() += lambda * ne.A.diagonal();
  // B_k D⁻¹ B_kᵀ has the blocks W_ij v_i v_jᵀ with W = J_c D⁻¹ J_cᵀ (3x3): a quarter of the
  // work of the dense 12x2 product. Only the lower blocks are accumulated.
  for (std::size_t k = 0; k < ne.f.size(); ++k) {
    Eigen::Matrix2d D = ne.D[k];
    D.diagonal() += lambda * ne.D[k].diagonal();
    const Mat33 W = ne.J_c[k] * D.inverse() * ne.J_c[k].transpose();
    const Regressors v(ne.f[k]);
    S.block<3, 3>(0, 0).noalias() -= W(0, 0) * v.x * v.x.transpose();
    S.block<4, 3>(3, 0).noalias() -= W(1, 0) * v.y * v.x.transpose();
    S.block<4, 4>(3, 3).noalias() -= W(1, 1) * v.y * v.y.transpose();
    S.block<5, 3>(7, 0).noalias() -= W(2, 0) * v.z * v.x.transpose();
    S.block<5, 4>(7, 3).noalias() -= W(2, 1) * v.z * v.y.transpose();
    S.block<5, 5>(7, 7).noalias() -= W(2, 2) * v.z * v.z.transpose();
  }
  S.triangularView<Eigen::StrictlyUpper>() = S.transpose();
  for (int j = 0; j < kMaxParameters; ++j) {
    if (mask(j) == 0.0) {
      S.row(j).setZero();
      S.col(j).setZero();
      S(j, j) = 1.0;
    }
  }
  return S;
}

InformationRows ReducedInformationRows(const Problem& problem, const ModelParameters& params,
                                       const std::vector<Vec3>& dirs) {
  // The Gauss-Newton blocks give S = Σ_k [A_k − B_k D_k⁻¹ B_kᵀ], whose (i, j) block is
  // (δ_ij − W_ij) v_i v_jᵀ with W = J_c D⁻¹ J_cᵀ the projector onto the span of J_c. That span is
  // the plane J_p_f c⊥, so δ_ij − W_ij = n_i n_j with n its unit normal, n ∝ J_p_f⁻ᵀ c: only the
  // residual component normal to the fitted surface carries information. S = Σ u_k u_kᵀ with
  // u_k = (n_x v_x, n_y v_y, n_z v_z): a sum of squares, free of the cancellation in A − B D⁻¹ Bᵀ.
  const int m = problem.positions();
  InformationRows rows;
  rows.U.resize(m, kMaxParameters);
  rows.normals.resize(static_cast<std::size_t>(m));
  rows.A_diagonal.setZero();
  for (int k = 0; k < m; ++k) {
    const Vec3 f = problem.gravity * dirs[k];
    Mat33 J;
    PredictRaw(params, f, &J);
    // J⁻ᵀ c up to the factor 1 / det J: the columns of J⁻ᵀ det J are cross products of J's.
    const Vec3 n = (dirs[k](0) * J.col(1).cross(J.col(2)) + dirs[k](1) * J.col(2).cross(J.col(0)) +
                    dirs[k](2) * J.col(0).cross(J.col(1)))
                       .normalized();
    rows.normals[static_cast<std::size_t>(k)] = n;
    const Regressors v(f);
    rows.U.row(k) << n(0) * v.x.transpose(), n(1) * v.y.transpose(), n(2) * v.z.transpose();
    rows.A_diagonal.segment<3>(kGroupStart[0]) += v.x.cwiseAbs2();
    rows.A_diagonal.segment<4>(kGroupStart[1]) += v.y.cwiseAbs2();
    rows.A_diagonal.segment<5>(kGroupStart[2]) += v.z.cwiseAbs2();
  }
  return rows;
}

namespace {
// S = Uᵀ U on the model's free parameters (the others stay 0), as dot products of U's contiguous
// columns: a quarter of the instructions of Eigen's rank update, whose GEMM path packs and blocks
// a 12-column product it cannot profit from (measured on 300 rows).
Mat12 SumOfRows(const InformationRows& rows, ModelKind model) {
  const Vec12 mask = FreeMask(model);
  Mat12 S = Mat12::Zero();
  for (int j = 0; j < kMaxParameters; ++j) {
    if (mask(j) == 0.0) continue;
    for (int i = j; i < kMaxParameters; ++i) {
      if (mask(i) != 0.0) S(i, j) = S(j, i) = rows.U.col(i).dot(rows.U.col(j));
    }
  }
  return S;
}
}  // namespace

Mat12 ReducedInformation(const Problem& problem, const ModelParameters& params,
                         const std::vector<Vec3>& dirs, Vec12* A_diagonal) {
  const InformationRows rows = ReducedInformationRows(problem, params, dirs);
  *A_diagonal = rows.A_diagonal;
  return SumOfRows(rows, problem.model);
}

Information ComputeInformation(const Problem& problem, const ModelParameters& params,
                               const std::vector<Vec3>& dirs, InformationRows* rows_out) {
  InformationRows rows = ReducedInformationRows(problem, params, dirs);
  Information info;
  info.reduced = SumOfRows(rows, problem.model);
  FinishInformation(problem.model, rows.A_diagonal, &info);
  if (rows_out) *rows_out = std::move(rows);
  return info;
}

void FinishInformation(ModelKind model, const Vec12& A_diagonal, Information* out) {
  Information& info = *out;
  const Vec12 mask = FreeMask(model);
  for (int j = 0; j < kMaxParameters; ++j) {
    if (mask(j) == 0.0) {
      info.reduced.row(j).setZero();
      info.reduced.col(j).setZero();
      info.reduced(j, j) = 1.0;
    }
  }
  // Jacobi scaling with A's diagonal makes the condition independent of the parameters' units; a
  // parameter that the directions absorb completely then has a scaled diagonal near 0.
  for (int j = 0; j < kMaxParameters; ++j) {
    info.scale(j) = mask(j) != 0.0 && A_diagonal(j) > 0 ? 1.0 / std::sqrt(A_diagonal(j)) : 1.0;
  }
  const Mat12 scaled = info.scale.asDiagonal() * info.reduced * info.scale.asDiagonal();
  info.factor.compute(scaled);
  const bool positive = info.factor.info() == Eigen::Success && info.factor.isPositive() &&
                        (info.factor.vectorD().array() > 0).all();
  info.rcond = positive ? info.factor.rcond() : 0.0;
  if (info.rcond < kPoorInformationRcond) {
    // Rare path: name the parameter that dominates the weakest direction of the information.
    Eigen::SelfAdjointEigenSolver<Mat12> eig(scaled);
    double lo = std::numeric_limits<double>::infinity();
    int lo_index = 0;
    for (int i = 0; i < kMaxParameters; ++i) {
      // Eigenvectors of the fixed (identity) block live on masked entries: skip them.
      if (eig.eigenvectors().col(i).cwiseProduct(mask).norm() < 0.5) continue;
      if (eig.eigenvalues()(i) < lo) {
        lo = eig.eigenvalues()(i);
        lo_index = i;
      }
    }
    eig.eigenvectors().col(lo_index).cwiseProduct(mask).cwiseAbs().maxCoeff(&info.weakest);
  }
}

Mat12 Information::Inverse() const {
  return scale.asDiagonal() * factor.solve(Mat12::Identity()) * scale.asDiagonal();
}

std::vector<Vec3> DirectionsFromParams(const Problem& problem, const ModelParameters& params) {
  std::vector<Vec3> dirs;
  dirs.reserve(problem.readings.size());
  for (const Vec3& p : problem.readings) {
    std::optional<Vec3> f = SpecificForce(params, p);
    Vec3 d = f ? *f : Vec3(p - params.bias);
    if (!(d.norm() > 0) || !d.allFinite()) d = Vec3::UnitZ();
    dirs.push_back(d.normalized());
  }
  return dirs;
}

namespace {

// Solves one axis' least-squares problem (eq. (15) rows v_kᵀ x = y_k) from its normal equations,
// Jacobi-scaled: the columns (g c, 1, (g c)²) differ in size by g², which the scaling absorbs.
template <int N>
Eigen::Matrix<double, N, 1> SolveAxis(const Eigen::Matrix<double, N, N>& normal,
                                      const Eigen::Matrix<double, N, 1>& rhs) {
  const Eigen::Matrix<double, N, 1> s = normal.diagonal().cwiseSqrt().cwiseInverse();
  const Eigen::Matrix<double, N, N> scaled = s.asDiagonal() * normal * s.asDiagonal();
  return s.cwiseProduct(scaled.ldlt().solve(s.cwiseProduct(rhs)));
}

// Fixed-size per-axis accumulation: axis `Axis` of the model with (`Quadratic`) squared term.
template <int Axis, bool Quadratic>
void FitAxis(const Problem& problem, const std::vector<Vec3>& dirs, ModelParameters* params) {
  constexpr int N = Axis + 2 + (Quadratic ? 1 : 0);
  Eigen::Matrix<double, N, N> normal = Eigen::Matrix<double, N, N>::Zero();
  Eigen::Matrix<double, N, 1> rhs = Eigen::Matrix<double, N, 1>::Zero();
  for (int k = 0; k < problem.positions(); ++k) {
    const Vec3 f = problem.gravity * dirs[k];
    Eigen::Matrix<double, N, 1> v;
    for (int j = 0; j <= Axis; ++j) v(j) = f(j);
    v(Axis + 1) = 1.0;
    if constexpr (Quadratic) v(Axis + 2) = f(Axis) * f(Axis);
    normal.noalias() += v * v.transpose();
    rhs += problem.readings[k](Axis) * v;
  }
  const Eigen::Matrix<double, N, 1> x = SolveAxis<N>(normal, rhs);
  for (int j = 0; j <= Axis; ++j) params->K(Axis, j) = x(j);
  params->bias(Axis) = x(Axis + 1);
  if constexpr (Quadratic) params->k2(Axis) = x(Axis + 2);
}

template <bool Quadratic>
void FitAllAxes(const Problem& problem, const std::vector<Vec3>& dirs, ModelParameters* params) {
  FitAxis<0, Quadratic>(problem, dirs, params);
  FitAxis<1, Quadratic>(problem, dirs, params);
  FitAxis<2, Quadratic>(problem, dirs, params);
}

}  // namespace

ModelParameters SolveParametersGivenDirections(const Problem& problem,
                                               const std::vector<Vec3>& dirs) {
  // Row of eq. (15) for axis i: [g c_1 .. g c_i, 1, (g c_i)²]: three independent problems.
  ModelParameters params;
  params.K.setZero();
  if (problem.model == ModelKind::kQuadratic) {
    FitAllAxes<true>(problem, dirs, &params);
  } else {
    FitAllAxes<false>(problem, dirs, &params);
  }
  return params;
}

}  // namespace accelcal::internal
