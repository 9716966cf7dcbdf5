// accelcal: the command-line tool (cli.cpp).
#include <malloc.h>

#include "commands.hpp"

int main(int argc, char** argv) {
#if defined(__GLIBC__)
  // One short-lived process: memory freed is kept for the next allocation instead of being
  // returned to the kernel (glibc maps each block over 128 KiB apart and unmaps it when freed,
  // so every large buffer cost a page fault per 4 KiB page again: a quarter of the calibrate
  // command's faults on the bundled recording).
  mallopt(M_MMAP_THRESHOLD, 64 << 20);
  mallopt(M_TRIM_THRESHOLD, 64 << 20);
#endif
  return accelcal::cli::RunCommandLine(argc, argv);
}
