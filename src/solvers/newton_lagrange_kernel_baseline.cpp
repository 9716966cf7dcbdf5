// The Newton-Lagrange kernel for any x86-64 (or other) CPU: see newton_lagrange_kernel.hpp.
#define ACCELCAL_KERNEL_ISA baseline
#include "solvers/newton_lagrange_kernel_impl.hpp"
