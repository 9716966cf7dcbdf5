#!/usr/bin/env bash
# Whole-process timing of `accelcal calibrate` on the bundled Xsens recording (parse, detect,
# calibrate, write): best and median wall time of N runs.
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${1:-30}
exe=build/accelcal
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
times=()
for ((i = 0; i < runs; i++)); do
  t0=$(date +%s%N)
  "$exe" calibrate data/imutk-xsens-mti/xsens_acc.mat --gravity 9.81744 -o "$out/cal.json" >/dev/null
  t1=$(date +%s%N)
  times+=($(((t1 - t0) / 1000)))
done
sorted=($(printf '%s\n' "${times[@]}" | sort -n))
echo "accelcal calibrate xsens_acc.mat (3.3 MB, 51175 samples): best ${sorted[0]} us, median ${sorted[$((runs / 2))]} us over $runs runs"
