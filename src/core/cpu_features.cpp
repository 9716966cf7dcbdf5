#include "core/cpu_features.hpp"

#include <cstdlib>
#include <cstring>

#if defined(__x86_64__) && defined(__GNUC__)
#include <cpuid.h>
#endif

namespace accelcal::internal {

const CpuFeatures& Cpu() {
  static const CpuFeatures features = [] {
    CpuFeatures f;
#if defined(__x86_64__) && defined(__GNUC__)
    __builtin_cpu_init();
    f.ssse3 = __builtin_cpu_supports("ssse3") != 0;
    f.sse41 = __builtin_cpu_supports("sse4.1") != 0;
    f.avx = __builtin_cpu_supports("avx") != 0;  // checks the OS's XSAVE of the AVX state too
    f.avx2 = __builtin_cpu_supports("avx2") != 0;
    // CPUID leaf 7, EBX bit 29. No OS state is involved (XMM registers only).
    unsigned eax = 0, ebx = 0, ecx = 0, edx = 0;
    f.sha = __get_cpuid_count(7, 0, &eax, &ebx, &ecx, &edx) != 0 && (ebx & (1u << 29)) != 0;
#endif
    // ACCELCAL_CPU caps what is used: "baseline" (none), "sse4.1" (SSSE3 and SSE4.1), "avx" (and
    // AVX). Every kernel's builds give the same bits; this is for the tests, and to rule a CPU's
    // extensions out.
    if (const char* cap = std::getenv("ACCELCAL_CPU"); cap != nullptr) {
      const bool baseline = std::strcmp(cap, "baseline") == 0;
      const bool sse41 = std::strcmp(cap, "sse4.1") == 0, avx = std::strcmp(cap, "avx") == 0;
      if (baseline || sse41 || avx) {
        f.ssse3 = f.ssse3 && !baseline;
        f.sse41 = f.sse41 && !baseline;
        f.avx = f.avx && avx;
        f.avx2 = false;
        f.sha = false;
      }
    }
    return f;
  }();
  return features;
}

}  // namespace accelcal::internal
