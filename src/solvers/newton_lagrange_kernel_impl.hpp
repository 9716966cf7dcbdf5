// The Newton-Lagrange per-position kernel (newton_lagrange_kernel.hpp), included once per
// instruction set by newton_lagrange_kernel_<isa>.cpp with ACCELCAL_KERNEL_ISA naming it. All of it
// has internal linkage except kKernel, and it includes no header with inline functions: see the
// interface's comment. The algebra is derived in newton_lagrange.cpp.
#ifndef ACCELCAL_KERNEL_ISA
#error "define ACCELCAL_KERNEL_ISA (the instruction set's namespace) before including this file"
#endif

#include "solvers/newton_lagrange_kernel.hpp"

namespace accelcal::internal::newton_kernel::ACCELCAL_KERNEL_ISA {
namespace {

// One double per position (a GCC/Clang vector: one AVX register, or two SSE2 ones).
typedef double Lanes __attribute__((vector_size(kLanes * sizeof(double))));

Lanes Splat(double x) { return Lanes{x, x, x, x}; }
Lanes Load(const double* p) {
  Lanes v;
  __builtin_memcpy(&v, p, sizeof v);
  return v;
}
void Store(double* p, const Lanes& v) { __builtin_memcpy(p, &v, sizeof v); }
Lanes Sqrt(Lanes x) {
  for (int l = 0; l < kLanes; ++l) x[l] = __builtin_sqrt(x[l]);
  return x;
}

struct Lanes3 {
  Lanes v[3];
  Lanes& operator[](int i) { return v[i]; }
  const Lanes& operator[](int i) const { return v[i]; }
};
Lanes3 Load3(const double (*p)[kLanes]) { return {{Load(p[0]), Load(p[1]), Load(p[2])}}; }
Lanes Dot(const Lanes3& a, const Lanes3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// θ's K (lower triangular) times a scale; x ↦ scale K x and scale Kᵀ x.
struct LowerTriangular {
  LowerTriangular(const double* theta, double scale)
      : k00(scale * theta[0]),
        k10(scale * theta[2]),
        k11(scale * theta[3]),
        k20(scale * theta[5]),
        k21(scale * theta[6]),
        k22(scale * theta[7]) {}
  Lanes3 operator*(const Lanes3& x) const {
    return {{k00 * x[0], k10 * x[0] + k11 * x[1], k20 * x[0] + k21 * x[1] + k22 * x[2]}};
  }
  Lanes3 TransposeTimes(const Lanes3& x) const {
    return {{k00 * x[0] + k10 * x[1] + k20 * x[2], k11 * x[1] + k21 * x[2], k22 * x[2]}};
  }
  double k00, k10, k11, k20, k21, k22;
};

// Rows of Block::kept.
enum Kept { kE0 = 0, kE1 = 3, kY = 6, kR = 9, kCc = 12, kH, kW00, kW01, kW11, kE0Rhs, kE1Rhs };

// What both passes need of a block: the pieces of the elimination (newton_lagrange.cpp).
struct Local {
  Local(const Block& in, const LowerTriangular& gK, const double* bias, double g)
      : c(Load3(in.dir)), lam(Load(in.lambda)), weight(Load(in.weight)) {
    cc = Dot(c, c);
    h = cc - 1.0;
    const Lanes inv_norm = 1.0 / Sqrt(cc);
    // Orthonormal basis of the plane ⟂ n without branches (Duff et al. 2017, "Building an
    // orthonormal basis, revisited", JCGT 6(1)); any basis gives the same step.
    const Lanes nx = c[0] * inv_norm, ny = c[1] * inv_norm, nz = c[2] * inv_norm;
    const Lanes s = nz >= Splat(0.0) ? Splat(1.0) : Splat(-1.0);
    const Lanes a = -1.0 / (s + nz);
    const Lanes b = nx * ny * a;
    E[0] = {{1.0 + s * nx * nx * a, s * b, -s * nx}};
    E[1] = {{b, s + ny * ny * a, -ny}};
    f = {{g * c[0], g * c[1], g * c[2]}};
    y = gK * c;
    const Lanes3 reading = Load3(in.reading);
    for (int d = 0; d < 3; ++d) {
      r[d] = y[d] + bias[d] - reading[d];
      gr[d] = g * r[d];
    }
    T[0] = gK * E[0];
    T[1] = gK * E[1];
    const Lanes a00 = 2.0 * (Dot(T[0], T[0]) + lam);
    const Lanes a01 = 2.0 * Dot(T[0], T[1]);
    const Lanes a11 = 2.0 * (Dot(T[1], T[1]) + lam);
    const Lanes inv_det = 1.0 / (a00 * a11 - a01 * a01);
    w00 = a11 * inv_det;
    w01 = -a01 * inv_det;
    w11 = a00 * inv_det;
    const Lanes h_cc = h / cc;
    const Lanes3 q = {
        {2.0 * r[0] - h_cc * y[0], 2.0 * r[1] - h_cc * y[1], 2.0 * r[2] - h_cc * y[2]}};
    e0 = Dot(T[0], q);
    e1 = Dot(T[1], q);
  }
  void Keep(Block* out) const {
    for (int d = 0; d < 3; ++d) {
      Store(out->kept[kE0 + d], E[0][d]);
      Store(out->kept[kE1 + d], E[1][d]);
      Store(out->kept[kY + d], y[d]);
      Store(out->kept[kR + d], r[d]);
    }
    Store(out->kept[kCc], cc);
    Store(out->kept[kH], h);
    Store(out->kept[kW00], w00);
    Store(out->kept[kW01], w01);
    Store(out->kept[kW11], w11);
    Store(out->kept[kE0Rhs], e0);
    Store(out->kept[kE1Rhs], e1);
  }
  Lanes3 c;
  Lanes lam, weight;
  Lanes3 E[2], f, y, r, gr, T[2];
  Lanes cc, h, w00, w01, w11, e0, e1;
};

// The 9 entries of ½ C x for x (with y = gK x); the factor 2 is applied to the sums instead.
void HalfCoupling(const Local& p, const Lanes3& x, const Lanes3& gKx, Lanes* out) {
  out[0] = p.f[0] * gKx[0] + p.gr[0] * x[0];
  out[1] = gKx[0];
  out[2] = p.f[0] * gKx[1] + p.gr[1] * x[0];
  out[3] = p.f[1] * gKx[1] + p.gr[1] * x[1];
  out[4] = gKx[1];
  out[5] = p.f[0] * gKx[2] + p.gr[2] * x[0];
  out[6] = p.f[1] * gKx[2] + p.gr[2] * x[1];
  out[7] = p.f[2] * gKx[2] + p.gr[2] * x[2];
  out[8] = gKx[2];
}

// Running sums of the first pass, one lane per position slot.
struct Sums {
  Lanes S[45] = {};
  Lanes rhs[9] = {};
  Lanes grad[9] = {};
  Lanes moment[9] = {};
  Lanes count = {}, cost = {};
  // With G = 2G', u = 2u': G W Gᵀ = G' (4W) G'ᵀ, (h/(2|c|²)) u + G W e = (h/|c|²) u' + G' (4W) e/2.
  void Add(const Local& p) {
    Lanes G0[9], G1[9], u[9];
    HalfCoupling(p, p.E[0], p.T[0], G0);
    HalfCoupling(p, p.E[1], p.T[1], G1);
    HalfCoupling(p, p.c, p.y, u);
    const Lanes weight4 = 4.0 * p.weight;
    const Lanes w00 = weight4 * p.w00, w01 = weight4 * p.w01, w11 = weight4 * p.w11;
    const Lanes h_cc = p.weight * p.h / p.cc;
    const Lanes half_e0 = 0.5 * p.e0, half_e1 = 0.5 * p.e1;
    int n = 0;
    for (int j = 0; j < 9; ++j) {
      const Lanes z0 = G0[j] * w00 + G1[j] * w01;
      const Lanes z1 = G0[j] * w01 + G1[j] * w11;
      for (int i = j; i < 9; ++i) S[n++] -= z0 * G0[i] + z1 * G1[i];
      rhs[j] += h_cc * u[j] + z0 * half_e0 + z1 * half_e1;
    }
    const Lanes3 r = {{p.weight * p.r[0], p.weight * p.r[1], p.weight * p.r[2]}};
    grad[0] += r[0] * p.f[0];
    grad[1] += r[0];
    grad[2] += r[1] * p.f[0];
    grad[3] += r[1] * p.f[1];
    grad[4] += r[1];
    grad[5] += r[2] * p.f[0];
    grad[6] += r[2] * p.f[1];
    grad[7] += r[2] * p.f[2];
    grad[8] += r[2];
    const Lanes3 fw = {{p.weight * p.f[0], p.weight * p.f[1], p.weight * p.f[2]}};
    n = 0;
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b <= a; ++b) moment[n++] += fw[a] * p.f[b];
    }
    for (int a = 0; a < 3; ++a) moment[6 + a] += fw[a];
    count += p.weight;
    cost += Dot(r, p.r);
  }
  void StoreTo(LaneSums* out) const {
    for (int i = 0; i < 45; ++i) Store(out->S[i], S[i]);
    for (int i = 0; i < 9; ++i) {
      Store(out->rhs[i], rhs[i]);
      Store(out->grad[i], grad[i]);
      Store(out->moment[i], moment[i]);
    }
    Store(out->count, count);
    Store(out->cost, cost);
  }
};

void Accumulate(const double* theta, double gravity, Block* blocks, int n_blocks, LaneSums* out) {
  const LowerTriangular gK(theta, gravity);
  const double bias[3] = {theta[1], theta[4], theta[8]};
  Sums sums;
  for (int i = 0; i < n_blocks; ++i) {
    const Local local(blocks[i], gK, bias, gravity);
    sums.Add(local);
    local.Keep(&blocks[i]);
  }
  sums.StoreTo(out);
}

// Back-substitution with v = Cᵀ Δθ = 2 (gK)ᵀ(ΔK f + Δb) + 2 g ΔKᵀ r.
void BackSubstitute(const double* theta, const double* d_theta, double g, Block* blocks,
                    int n_blocks) {
  const LowerTriangular gK(theta, g);
  const LowerTriangular dK(d_theta, 1.0);
  const double d_bias[3] = {d_theta[1], d_theta[4], d_theta[8]};
  for (int i = 0; i < n_blocks; ++i) {
    Block& block = blocks[i];
    const Lanes3 dir = Load3(block.dir);
    const Lanes lam = Load(block.lambda);
    const Lanes3 E0 = Load3(block.kept + kE0), E1 = Load3(block.kept + kE1);
    const Lanes3 y = Load3(block.kept + kY), r = Load3(block.kept + kR);
    const Lanes cc = Load(block.kept[kCc]), h = Load(block.kept[kH]);
    const Lanes w00 = Load(block.kept[kW00]), w01 = Load(block.kept[kW01]);
    const Lanes w11 = Load(block.kept[kW11]);
    const Lanes3 f = {{g * dir[0], g * dir[1], g * dir[2]}};
    Lanes3 w = dK * f;
    for (int d = 0; d < 3; ++d) w[d] += d_bias[d];
    const Lanes3 a = gK.TransposeTimes(w), b = dK.TransposeTimes(r);
    const Lanes3 v = {{2.0 * (a[0] + g * b[0]), 2.0 * (a[1] + g * b[1]), 2.0 * (a[2] + g * b[2])}};
    const Lanes t0 = Dot(E0, v) + Load(block.kept[kE0Rhs]);
    const Lanes t1 = Dot(E1, v) + Load(block.kept[kE1Rhs]);
    const Lanes a0 = -(w00 * t0 + w01 * t1), a1 = -(w01 * t0 + w11 * t1);
    const Lanes half_h = h / (2.0 * cc);
    Lanes3 d_c;
    for (int d = 0; d < 3; ++d) d_c[d] = -half_h * dir[d] + E0[d] * a0 + E1[d] * a1;
    const Lanes normal_rhs = 2.0 * Dot(y, r) + 2.0 * lam * cc - lam * h;
    const Lanes d_lambda = -(normal_rhs + Dot(dir, v) + 2.0 * Dot(y, gK * d_c)) / (2.0 * cc);
    for (int d = 0; d < 3; ++d) Store(block.d_dir[d], d_c[d]);
    Store(block.d_lambda, d_lambda);
  }
}

double Apply(Block* blocks, int n_blocks) {
  Lanes largest = Splat(0.0);
  Lanes finite = Splat(0.0);  // stays 0 while every |Δc_i| is finite
  for (int i = 0; i < n_blocks; ++i) {
    Block& block = blocks[i];
    for (int d = 0; d < 3; ++d) {
      const Lanes step = Load(block.d_dir[d]);
      Store(block.dir[d], Load(block.dir[d]) + step);
      const Lanes size = step < Splat(0.0) ? -step : step;
      largest = size > largest ? size : largest;
      finite += size * 0.0;  // NaN for an infinite or NaN step
    }
    Store(block.lambda, Load(block.lambda) + Load(block.d_lambda));
  }
  double out = 0;
  for (int l = 0; l < kLanes; ++l) {
    if (!(finite[l] == 0.0)) return __builtin_inf();
    out = largest[l] > out ? largest[l] : out;
  }
  return out;
}

}  // namespace

extern const Kernel kKernel = {&Accumulate, &BackSubstitute, &Apply};

}  // namespace accelcal::internal::newton_kernel::ACCELCAL_KERNEL_ISA
