#!/usr/bin/env bash
# The reliability checks of issue 7, with clang:
#  1. the whole test suite built with AddressSanitizer and UndefinedBehaviorSanitizer (any report
#     is fatal, leaks included);
#  2. every libFuzzer harness (fuzz/, built with the same sanitizers and coverage instrumentation)
#     run on its committed seed corpus for FUZZ_SECONDS seconds each (default 60; run much longer
#     by hand). New inputs go to a scratch directory, never into the repository; an input that
#     once failed is kept in fuzz/regressions/<harness> (and as a unit test) and replayed.
# Two build trees: the fuzzers' coverage instrumentation would slow the tests several times over.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/compiler-cache.sh
seconds=${FUZZ_SECONDS:-60}
# Line tables are all a report's stack trace needs (file, line, inlined frames): full debug
# information made the two builds about a fifth slower and their objects ten times larger.
common=(-DCMAKE_BUILD_TYPE=RelWithDebInfo
  "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -gline-tables-only -DNDEBUG" -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++
  -DACCELCAL_WERROR=ON -DACCELCAL_SANITIZE=ON -DACCELCAL_BUILD_PYTHON=OFF
  -DACCELCAL_BUILD_BENCHMARKS=OFF -DACCELCAL_INSTALL=OFF "${cache_args[@]}")
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:strict_string_checks=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1

if [ -z "${SKIP_SANITIZED_TESTS:-}" ]; then
  # The library shared here (BUILD_SHARED_LIBS): the suite checks that build too, at no cost.
  cmake -S . -B build-sanitize "${common[@]}" -DBUILD_SHARED_LIBS=ON > /dev/null
  cmake --build build-sanitize -j"$(nproc)"
  ctest --test-dir build-sanitize --output-on-failure -j"$(nproc)"
fi

cmake -S . -B build-fuzz "${common[@]}" -DACCELCAL_FUZZ=ON -DACCELCAL_BUILD_TESTS=OFF \
  -DACCELCAL_BUILD_CLI=OFF > /dev/null
cmake --build build-fuzz -j"$(nproc)"
scratch=$(mktemp -d)
# A finding ends the script: the other harness still running goes with it.
trap 'kill $(jobs -p) 2> /dev/null || true; wait; rm -rf "$scratch"' EXIT
# One harness for FUZZ_SECONDS, its log in the scratch directory; the exit status is the fuzzer's.
run_harness() {
  local harness=$1
  mkdir -p "$scratch/$harness"
  # The command line's own stdout and stderr are not the fuzzer's.
  local extra=()
  [ "$harness" = cli_options ] && extra=(-close_fd_mask=3)
  # libmatio sizes an allocation from a MAT-file's claim (8 GB for a 2 kB file's dimensions) and
  # fills it only from the file: virtual, never resident (accelcal inspect: 15 MB). The resident
  # memory stays limited by -rss_limit_mb.
  [ "$harness" = file_log ] && extra=(-malloc_limit_mb=16384)
  # Its inputs are choices, not bytes: a few hundred make a bag or a MAT-file of every kind.
  [ "$harness" = file_schema ] && extra=(-max_len=4096)
  # Inputs that once failed (fuzz/regressions) are replayed with the seeds.
  local regressions=()
  [ -d "fuzz/regressions/$harness" ] && regressions=("$PWD/fuzz/regressions/$harness")
  # Absolute paths: cli_options works in a directory of its own.
  "build-fuzz/fuzz/fuzz_$harness" "$scratch/$harness" "$PWD/fuzz/corpus/$harness" \
    "${regressions[@]}" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
    -max_len=20000 -print_final_stats=1 "${extra[@]}" > "$scratch/$harness.log" 2>&1
}
# The harnesses run as many at a time as there are cores (each is one process on one core), so
# every one still fuzzes for its full FUZZ_SECONDS; a finding stops the script with its log.
harnesses=(log_reader native_log file_log file_schema orientations calibration_file
  calibration_keys series calibrate cli_options limits)
jobs=$(nproc)
for ((first = 0; first < ${#harnesses[@]}; first += jobs)); do
  batch=("${harnesses[@]:first:jobs}")
  pids=()
  for harness in "${batch[@]}"; do
    run_harness "$harness" &
    pids+=($!)
  done
  for i in "${!batch[@]}"; do
    harness=${batch[$i]}
    wait "${pids[$i]}" || { tail -60 "$scratch/$harness.log"; exit 1; }
    echo "fuzz_$harness: $(grep -E '^stat::number_of_executed_units' "$scratch/$harness.log" |
      awk '{print $2}') executions in ${seconds} s, no finding"
  done
done
