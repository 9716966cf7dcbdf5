#pragma once
// The per-sample loops of static detection (static_detection.cpp) on x, y, z at once: the smallest
// step between samples, the sliding window's variances, and the samples at the log's extremes.
// Each is written once with GCC's vector extensions and compiled twice, for AVX and for the
// baseline, the CPU choosing (RunKernel).

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "accelcal/types.hpp"
#include "core/cpu_features.hpp"

namespace accelcal::internal::detection {

#if !defined(__GNUC__)
#error "the detection kernels are written with GCC's vector extensions (GCC, Clang)"
#endif
// GCC and Clang warn that a function passing a 32-byte vector has another ABI with AVX: these are
// all inlined into their kernels, never called across that boundary. (Not popped at the end: GCC
// warns about the templates' instances at the end of the file that includes this one.)
#if defined(__clang__)
#pragma clang diagnostic ignored "-Wunknown-warning-option"
#endif
#pragma GCC diagnostic ignored "-Wpsabi"
#define ACCELCAL_INLINE __attribute__((always_inline)) inline

// x, y, z and a zero: one 32-byte vector for the AVX build (V = Wide), two 16-byte vectors for
// the baseline's SSE2 (V = Narrow). Each operation of the kernels below is one of the Eigen
// 3-vector (or per-axis scalar) operations it replaces, on the same operands in the same order,
// so the same bits.
using Wide = double __attribute__((vector_size(32)));
using Narrow = double __attribute__((vector_size(16)));
template <typename V>
struct Xyz {
  static constexpr int kPer = sizeof(V) / sizeof(double), kParts = 4 / kPer;
  using Mask = decltype(V{} < V{});
  V part[kParts];
  double Lane(int i) const { return part[i / kPer][i % kPer]; }
};
template <typename V>
ACCELCAL_INLINE Xyz<V> Load(const Vec3& v) {
  // x, y in one 16-byte load, z and a zero in another: a 32-byte vector written as doubles would
  // be built on the stack and read back whole, which stalls (its store cannot be forwarded).
  Narrow xy;
  std::memcpy(&xy, v.data(), sizeof xy);
  const Narrow z0 = {v(2), 0.0};
  Xyz<V> r;
  if constexpr (Xyz<V>::kParts == 1) {
    r.part[0] = __builtin_shufflevector(xy, z0, 0, 1, 2, 3);
  } else {
    r.part[0] = xy;
    r.part[1] = z0;
  }
  return r;
}
template <typename V>
ACCELCAL_INLINE Xyz<V> Splat(double x) {
  Xyz<V> r;
  for (V& p : r.part) p = V{} + x;
  return r;
}
#define ACCELCAL_LANEWISE(op)                                                    \
  template <typename V>                                                          \
  ACCELCAL_INLINE Xyz<V> operator op(const Xyz<V>& a, const Xyz<V>& b) {         \
    Xyz<V> r;                                                                    \
    for (int i = 0; i < Xyz<V>::kParts; ++i) r.part[i] = a.part[i] op b.part[i]; \
    return r;                                                                    \
  }
ACCELCAL_LANEWISE(+)
ACCELCAL_LANEWISE(-)
ACCELCAL_LANEWISE(*)
#undef ACCELCAL_LANEWISE
template <typename V>
ACCELCAL_INLINE Xyz<V> operator/(const Xyz<V>& a, double b) {
  Xyz<V> r;
  for (int i = 0; i < Xyz<V>::kParts; ++i) r.part[i] = a.part[i] / b;
  return r;
}
// A comparison's lanes as plain bits. The empty asm hides that they are a comparison: GCC would
// otherwise turn a select back into a conditional, and combine comparisons as booleans, which it
// splits into scalar code without SSE4.1's blend.
template <typename M>
ACCELCAL_INLINE M Bits(M comparison) {
  // Only the 16-byte vectors need it (AVX has a blend), and only they fit an XMM register for
  // Clang outside an AVX function.
  if constexpr (sizeof(M) == 16) __asm__("" : "+x"(comparison));
  return comparison;
}
// Lanes where `keep` is set from `a`, others from `b` (bit by bit).
template <typename V>
ACCELCAL_INLINE V Select(typename Xyz<V>::Mask keep, V a, V b) {
  using M = typename Xyz<V>::Mask;
  keep = Bits(keep);
  return reinterpret_cast<V>((reinterpret_cast<M>(a) & keep) | (reinterpret_cast<M>(b) & ~keep));
}
// cwiseMax(0.0): a NaN stays, as in Eigen's.
template <typename V>
ACCELCAL_INLINE Xyz<V> NotNegative(const Xyz<V>& a) {
  Xyz<V> r;
  for (int i = 0; i < Xyz<V>::kParts; ++i) r.part[i] = Select<V>(a.part[i] < 0.0, V{}, a.part[i]);
  return r;
}
// sum(): (x + y) + z.
template <typename V>
ACCELCAL_INLINE double Sum(const Xyz<V>& a) {
  return a.Lane(0) + a.Lane(1) + a.Lane(2);
}

// A kernel (a struct with its Args and a template On<V>) compiled for AVX on 32-byte vectors and
// for the baseline on 16-byte ones, run as the CPU allows.
template <typename Kernel>
__attribute__((target("avx"))) void RunOnAvx(typename Kernel::Args& args) {
  Kernel::template On<Wide>(args);
}
template <typename Kernel>
void RunOnBaseline(typename Kernel::Args& args) {
  Kernel::template On<Narrow>(args);
}
template <typename Kernel>
void RunKernel(typename Kernel::Args& args) {
#if defined(__x86_64__)
  if (internal::Cpu().avx) return RunOnAvx<Kernel>(args);
#endif
  RunOnBaseline<Kernel>(args);
}

// The smallest nonzero change between successive samples of each axis (infinity for an axis that
// never changes).
struct SmallestSteps {
  const std::vector<Vec3>* samples;
  Vec3 step;  // out
};
struct FindSmallestSteps {
  using Args = SmallestSteps;
  template <typename V>
  ACCELCAL_INLINE static void On(SmallestSteps& io);
};
template <typename V>
ACCELCAL_INLINE void FindSmallestSteps::On(SmallestSteps& io) {
  const std::vector<Vec3>& s = *io.samples;
  Xyz<V> step = Splat<V>(INFINITY);
  if (!s.empty()) {
    Xyz<V> before = Load<V>(s[0]);
    for (std::size_t i = 1; i < s.size(); ++i) {
      const Xyz<V> x = Load<V>(s[i]), change = x - before;
      for (int p = 0; p < Xyz<V>::kParts; ++p) {
        using M = typename Xyz<V>::Mask;
        const V d = reinterpret_cast<V>(reinterpret_cast<M>(change.part[p]) &
                                        (M{} + INT64_MAX));  // |change|: the sign bit cleared
        step.part[p] = Select<V>(Bits(d > 0.0) & Bits(d < step.part[p]), d, step.part[p]);
      }
      before = x;
    }
  }
  io.step = Vec3(step.Lane(0), step.Lane(1), step.Lane(2));
}

// The sliding window's sums of one segment: of the samples less `shift` and of their squares, and
// of the successive differences and their squares, over the first window (begin to begin + w);
// the score (the sum of the axes' window variances) and whiteness of the windows centred at
// begin + h, ..., end - h - 1 come out, and how many scores are numbers is added to `valid`.
struct WindowSums {
  const Vec3* samples;
  std::size_t begin, end, h;  // the segment, and half the window
  Vec3 shift, sum, sum2, dsum, dsum2;
  double wn, max_noise_ratio, quantisation_variance;
  double* score;
  char* white;
  std::size_t valid;
};
struct SlideWindows {
  using Args = WindowSums;
  template <typename V>
  ACCELCAL_INLINE static void On(WindowSums& io);
};
template <typename V>
ACCELCAL_INLINE void SlideWindows::On(WindowSums& io) {
  const Vec3* const s = io.samples;
  const Xyz<V> shift = Load<V>(io.shift);
  Xyz<V> sum = Load<V>(io.sum), sum2 = Load<V>(io.sum2), dsum = Load<V>(io.dsum),
         dsum2 = Load<V>(io.dsum2);
  // Locals: the stores to `score` and `white` could otherwise change `io` for the compiler.
  const double wn = io.wn, ratio = io.max_noise_ratio, floor = io.quantisation_variance;
  const std::size_t h = io.h, end = io.end;
  double* const score = io.score;
  char* const white = io.white;
  std::size_t valid = 0;
  std::size_t c = io.begin + h;
  Xyz<V> first = Load<V>(s[c - h]), before_last = Load<V>(s[c + h]);
  for (;; ++c) {
    const Xyz<V> var = (sum2 - sum * sum / wn) / (wn - 1);
    const Xyz<V> dvar = (dsum2 - dsum * dsum / (wn - 1)) / (wn - 2);
    score[c] = Sum(NotNegative(var));
    valid += score[c] == score[c];
    white[c] = score[c] <= ratio * std::max(0.5 * Sum(NotNegative(dvar)), floor);
    if (c + h + 1 >= end) break;
    const Xyz<V> second = Load<V>(s[c - h + 1]), last = Load<V>(s[c + h + 1]);
    const Xyz<V> out = first - shift, added = last - shift;
    sum = sum + (added - out);
    sum2 = sum2 + (added * added - out * out);
    const Xyz<V> dout = second - first, din = last - before_last;
    dsum = dsum + (din - dout);
    dsum2 = dsum2 + (din * din - dout * dout);
    first = second;
    before_last = last;
  }
  io.valid += valid;
}

// How many samples of `begin` to `end` read each axis's largest and smallest value in the log.
struct ExtremeCounts {
  const Vec3* samples;
  std::size_t begin, end;
  Vec3 largest, smallest;
  std::size_t at[3][2];  // out: [axis][0: largest, 1: smallest]
};
struct CountExtremes {
  using Args = ExtremeCounts;
  template <typename V>
  ACCELCAL_INLINE static void On(ExtremeCounts& io);
};
template <typename V>
ACCELCAL_INLINE void CountExtremes::On(ExtremeCounts& io) {
  const Xyz<V> largest = Load<V>(io.largest), smallest = Load<V>(io.smallest);
  // The counts as doubles (exact to 2^53): 1.0 where a lane is equal, else 0.0.
  const Xyz<V> one = Splat<V>(1.0);
  Xyz<V> at_largest = Splat<V>(0.0), at_smallest = Splat<V>(0.0);
  for (std::size_t i = io.begin; i < io.end; ++i) {
    const Xyz<V> x = Load<V>(io.samples[i]);
    for (int p = 0; p < Xyz<V>::kParts; ++p) {
      at_largest.part[p] += Select<V>(x.part[p] == largest.part[p], one.part[p], V{});
      at_smallest.part[p] += Select<V>(x.part[p] == smallest.part[p], one.part[p], V{});
    }
  }
  for (int a = 0; a < 3; ++a) {
    io.at[a][0] = static_cast<std::size_t>(at_largest.Lane(a));
    io.at[a][1] = static_cast<std::size_t>(at_smallest.Lane(a));
  }
}
#undef ACCELCAL_INLINE

}  // namespace accelcal::internal::detection
