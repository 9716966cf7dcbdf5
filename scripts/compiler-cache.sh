# Sourced by the build scripts (test.sh, sanitize.sh): with ccache installed (install-deps.sh
# installs it), every compile goes through it, keyed on paths relative to the source tree, so a
# fresh clone anywhere reuses the objects an earlier build of the same sources made. CI builds
# three trees (Release, sanitized, fuzzing) from a fresh clone at each run: each TU whose
# preprocessed text, flags and compiler are unchanged is a cache hit (the figures: BENCHMARKS.md).
# `cache_args` is what CMake's configure step takes; empty without ccache.
cache_args=()
if command -v ccache > /dev/null && [ -z "${ACCELCAL_NO_CCACHE:-}" ]; then
  # Paths under the source tree hashed relative to it; the build directory not hashed (the
  # line tables' compile directory is then the first build's: a report's file names are the
  # tree's own paths all the same).
  export CCACHE_BASEDIR="$PWD" CCACHE_NOHASHDIR=1
  cache_args=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
