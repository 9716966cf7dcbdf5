// One position's term of the held-out objectives, with its derivatives (held_out.hpp).
#include <cmath>

#include <Eigen/Geometry>
#include <Eigen/LU>

#include "statistics/held_out.hpp"
#include "statistics/held_out_detail.hpp"

namespace accelcal::internal {

using held_out::kFootPointIterations;

ProfiledTerm ProfiledPosition(const ModelParameters& params, double gravity, ModelKind model,
                              const Vec3& reading, const Vec3& start, bool with_hessian) {
  ProfiledTerm t;
  const double g = gravity;
  const Vec3 c = KktDirection(params, g, reading, start, kFootPointIterations);
  if (!c.allFinite()) return t;
  const Vec3 f = g * c;
  Mat33 J;
  const Vec3 r = reading - PredictRaw(params, f, &J);
  const Mat32 E = TangentBasis(c);
  const Mat32 T = g * J * E;
  const Vec3 cross = T.col(0).cross(T.col(1));
  if (!(cross.norm() > 0)) return t;
  const Vec3 n = cross.normalized();
  const Vec12 mask = FreeMask(model);
  // M = ∂μ/∂θ (3 x 12) has axis i's regressors v_i = (f_x, .., f_i, 1, f_i²) in group i
  // (model.hpp), so Mᵀa has the blocks a_i v_i.
  const Regressors v(f);
  const auto M_transpose_times = [&](const Vec3& a) {
    Vec12 out;
    out << a(0) * v.x, a(1) * v.y, a(2) * v.z;
    return Vec12(out.cwiseProduct(mask));
  };
  t.dir = c;
  t.normal = n;
  t.e = n.dot(r);
  t.u = M_transpose_times(n);
  t.gradient = -2.0 * M_transpose_times(r);
  // The second fundamental form of the surface, as ExpectedSurfaceOffsets: with Σ = σ² I the
  // offset is −½ σ² tr(L G⁻¹).
  const Eigen::Matrix2d G = T.transpose() * T;
  const Eigen::Matrix2d G_inverse = G.inverse();
  const double radial = g * n.dot(J * c);
  Eigen::Matrix2d L;
  for (int a = 0; a < 2; ++a) {
    for (int b = 0; b < 2; ++b) {
      const Vec3 curvature = 2.0 * g * g * params.k2.cwiseProduct(E.col(a)).cwiseProduct(E.col(b));
      L(a, b) = n.dot(curvature) - (a == b ? radial : 0.0);
    }
  }
  t.omega = -0.5 * (L * G_inverse).trace();
  t.ok = std::isfinite(t.omega) && t.gradient.allFinite();
  if (!with_hessian) return t;
  // φ(θ, s) = ‖p − μ(θ, g c(s))‖² in tangent coordinates s of the sphere at c (c_s = E,
  // c_ss = −δ c); μ = M(f) θ is linear in θ. The profile's Hessian is φ_θθ − φ_θs φ_ss⁻¹ φ_sθ:
  //   φ_θθ = 2 MᵀM,  φ_θs = 2 MᵀT − 2 Σ_i r_i ∂M_i/∂s,
  //   φ_ss = 2 G − 2 Σ_i r_i ∂²μ_i/∂s∂s,  ∂²μ/∂s_a∂s_b = 2 g² k2 ∘ E_a ∘ E_b − δ_ab g J c,
  // with ∂v_i/∂s_a = (∂v_i/∂f) w, w = g E_a: (w_x, 0, 2 f_x w_x), (w_x, w_y, 0, 2 f_y w_y),
  // (w_x, w_y, w_z, 0, 2 f_z w_z).
  Mat12x2 C;
  for (int a = 0; a < 2; ++a) {
    const Vec3 w = g * E.col(a);
    Vec12 N;
    N << r(0) * w(0), 0.0, r(0) * 2.0 * f(0) * w(0),                           //
        r(1) * w(0), r(1) * w(1), 0.0, r(1) * 2.0 * f(1) * w(1),               //
        r(2) * w(0), r(2) * w(1), r(2) * w(2), 0.0, r(2) * 2.0 * f(2) * w(2);  //
    C.col(a) = 2.0 * (M_transpose_times(T.col(a)) - N.cwiseProduct(mask));
  }
  Eigen::Matrix2d phi_ss;
  const double radial_r = g * r.dot(J * c);
  const Vec3 rk2 = r.cwiseProduct(params.k2);
  for (int a = 0; a < 2; ++a) {
    for (int b = 0; b < 2; ++b) {
      const double second =
          2.0 * g * g * rk2.cwiseProduct(E.col(a)).dot(E.col(b)) - (a == b ? radial_r : 0.0);
      phi_ss(a, b) = 2.0 * G(a, b) - 2.0 * second;
    }
  }
  Mat12& H = t.hessian;
  H.setZero();
  H.block<3, 3>(kGroupStart[0], kGroupStart[0]).noalias() = 2.0 * v.x * v.x.transpose();
  H.block<4, 4>(kGroupStart[1], kGroupStart[1]).noalias() = 2.0 * v.y * v.y.transpose();
  H.block<5, 5>(kGroupStart[2], kGroupStart[2]).noalias() = 2.0 * v.z * v.z.transpose();
  H = (mask.asDiagonal() * H * mask.asDiagonal()).eval();
  const Mat12x2 W = C * phi_ss.inverse();
  H.noalias() -= W.lazyProduct(C.transpose());
  t.ok = t.ok && H.allFinite();
  return t;
}

ModulusTerm ModulusPosition(const ModelParameters& params, double gravity, bool squared,
                            const Vec3& reading, bool with_hessian) {
  ModulusTerm t;
  const Eigen::TriangularView<const Mat33, Eigen::Lower> K =
      params.K.triangularView<Eigen::Lower>();
  if (params.K(0, 0) == 0 || params.K(1, 1) == 0 || params.K(2, 2) == 0) return t;
  const Vec3 w = K.solve(Vec3(reading - params.bias));  // f, as ModulusResiduals
  const Mat33 Z = K.solve(Mat33::Identity());           // K⁻¹, column r = z_r
  // p = K w + b: ∂w/∂K_ij = −z_i w_j, ∂w/∂b_i = −z_i (k2 fixed at 0).
  struct Slot {
    int index, row, col;  // col −1: a bias
  };
  static constexpr Slot kSlots[9] = {{0, 0, 0}, {1, 0, -1}, {3, 1, 0}, {4, 1, 1},  {5, 1, -1},
                                     {7, 2, 0}, {8, 2, 1},  {9, 2, 2}, {10, 2, -1}};
  Mat3x12 W = Mat3x12::Zero();
  Vec12 coefficient = Vec12::Zero();  // c_s: w_j for K_ij, 1 for b_i
  for (const Slot& s : kSlots) {
    coefficient(s.index) = s.col >= 0 ? w(s.col) : 1.0;
    W.col(s.index) = -Z.col(s.row) * coefficient(s.index);
  }
  const double q = w.squaredNorm();
  const Vec12 grad_q = 2.0 * W.transpose() * w;
  Mat12 hess_q = Mat12::Zero();
  if (with_hessian) {
    // ∂²w/∂θ_s∂θ_t = [t ∈ K] z_r(t) Z(col t, r s) c_s + [s ∈ K] z_r(s) Z(col s, r t) c_t, so
    // wᵀ∂²w = [t ∈ K] y_r(t) Z(col t, r s) c_s + [s ∈ K] y_r(s) Z(col s, r t) c_t, y = Zᵀw.
    const Vec3 y = Z.transpose() * w;
    for (const Slot& s : kSlots) {
      for (const Slot& u : kSlots) {
        double value = 0;
        if (u.col >= 0) value += y(u.row) * Z(u.col, s.row) * coefficient(s.index);
        if (s.col >= 0) value += y(s.row) * Z(s.col, u.row) * coefficient(u.index);
        hess_q(s.index, u.index) = value;
      }
    }
    hess_q = 2.0 * (W.transpose() * W + hess_q);
  }
  Vec12 grad_e;
  Mat12 hess_e = Mat12::Zero();
  const double g = gravity;
  if (squared) {
    t.e = q / (g * g) - 1.0;
    grad_e = grad_q / (g * g);
    if (with_hessian) hess_e = hess_q / (g * g);
  } else {
    const double a = std::sqrt(q);
    t.e = a / g - 1.0;
    grad_e = grad_q / (2.0 * a * g);
    if (with_hessian) {
      hess_e = (hess_q / (2.0 * a) - grad_q * grad_q.transpose() / (4.0 * a * a * a)) / g;
    }
  }
  t.gradient = 2.0 * t.e * grad_e;
  if (with_hessian) t.hessian = 2.0 * (grad_e * grad_e.transpose() + t.e * hess_e);
  t.ok = t.gradient.allFinite() && (!with_hessian || t.hessian.allFinite());
  return t;
}

}  // namespace accelcal::internal
