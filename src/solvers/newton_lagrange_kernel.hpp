// The per-position work of paper 001's Newton-Lagrange step (see newton_lagrange.cpp for the
// algebra), four positions at a time, built twice: for the baseline x86-64 (SSE2, two positions
// per instruction) and for AVX (four), chosen at run time. Both builds do the same IEEE operations
// lane by lane, in the same order, so they give the same bits (tested).
//
// This interface is plain data on purpose: the AVX build must share no inline function with the
// rest of the library (an out-of-line copy compiled for AVX could be the one the linker keeps and
// then run on a CPU without it), so neither Eigen nor the standard library crosses it.
#pragma once

namespace accelcal::internal::newton_kernel {

constexpr int kLanes = 4;

/// kLanes positions as structure of arrays, lane l of every field belonging to one position. Lanes
/// past the last position repeat a real one with weight 0: they stay finite and add nothing.
struct alignas(32) Block {
  double dir[3][kLanes];      ///< c_k (not normalised during the iteration)
  double reading[3][kLanes];  ///< p_k
  double lambda[kLanes];      ///< λ_k
  double weight[kLanes];      ///< 1, or 0 for padding
  double d_dir[3][kLanes];    ///< Δc_k of the last step (BackSubstitute)
  double d_lambda[kLanes];    ///< Δλ_k of the last step
  double kept[19][kLanes];    ///< what Accumulate leaves for BackSubstitute
};

/// Per-lane partial sums of the reduced Newton system (the caller adds the lanes).
struct LaneSums {
  double S[45][kLanes];      ///< −Σ G W Gᵀ, lower triangle by columns
  double rhs[9][kLanes];     ///< Σ (h/(2|c|²)) C c + G W e
  double grad[9][kLanes];    ///< ½ ∇_θ J = Σ J_θᵀ r
  double moment[9][kLanes];  ///< Σ f_a f_b (a ≥ b), then Σ f_a
  double count[kLanes];      ///< number of positions
  double cost[kLanes];       ///< Σ |r|²
};

/// θ = (K00, b0, K10, K11, b1, K20, K21, K22, b2) of the linear model, K lower triangular.
struct Kernel {
  /// First pass: the sums of the reduced system at θ; fills each block's `kept`.
  void (*accumulate)(const double* theta, double gravity, Block* blocks, int n_blocks,
                     LaneSums* sums);
  /// Second pass: each position's Δc, Δλ for the parameter step Δθ (θ as given to accumulate).
  void (*back_substitute)(const double* theta, const double* d_theta, double gravity, Block* blocks,
                          int n_blocks);
  /// Adds Δc, Δλ to c, λ; returns max |Δc_i| over all lanes (+∞ if any is not finite).
  double (*apply)(Block* blocks, int n_blocks);
};

namespace baseline {
extern const Kernel kKernel;
}
namespace avx {
extern const Kernel kKernel;  // defined only when ACCELCAL_HAVE_AVX_KERNEL
}

}  // namespace accelcal::internal::newton_kernel
