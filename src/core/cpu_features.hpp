#pragma once
// What the CPU offers beyond the baseline the project is built for (x86-64: SSE2), asked once.
// The kernels built for more (the solver's AVX kernel, the SHA extensions, the row template's
// SSSE3 and AVX2, the detection window's AVX) are chosen by it at run time.

namespace accelcal::internal {

struct CpuFeatures {
  bool ssse3 = false;
  bool sse41 = false;
  bool avx = false;  // the CPU's flag and the operating system's saving of the AVX state
  bool avx2 = false;
  bool sha = false;  // the SHA extensions (SHA-1 and SHA-256)
};

/// This CPU's features (all false off x86-64), capped by the environment's ACCELCAL_CPU: "baseline"
/// (none), "sse4.1" (SSSE3 and SSE4.1 only), "avx" (and AVX: no AVX2, no SHA).
const CpuFeatures& Cpu();

}  // namespace accelcal::internal
