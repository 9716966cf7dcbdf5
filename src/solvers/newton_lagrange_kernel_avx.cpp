// The Newton-Lagrange kernel compiled with -mavx (CMakeLists.txt), used when the CPU has AVX: see
// newton_lagrange_kernel.hpp.
#define ACCELCAL_KERNEL_ISA avx
#include "solvers/newton_lagrange_kernel_impl.hpp"
