#!/usr/bin/env bash
# Whole-process timing of `accelcal calibrate` on the bundled Xsens recording and a 1-hour log (read, parse, detect,
# calibrate, write the JSON file), with hyperfine (no shell in between), plus the instruction count
# from callgrind, which does not depend on the machine's load.
set -euo pipefail
cd "$(dirname "$0")/.."
exe=build/accelcal
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
cmd="$exe calibrate data/imutk-xsens-mti/xsens_acc.mat --gravity 9.81744 -o $out/cal.json"
hyperfine -N --warmup 5 --runs "${1:-50}" "$cmd" "$exe --version"
if command -v valgrind >/dev/null; then
  valgrind --tool=callgrind --callgrind-out-file="$out/cg" $cmd >/dev/null 2>"$out/log"
  grep -o "Collected : [0-9]*" "$out/log" | sed 's/Collected :/instructions:/'
fi
# A 1-hour 1 kHz log (3.6 million rows, 231 MB of text; issue 7: <= 2 s, <= 200 MB).
build/accelcal simulate --scenario yang2012 --raw --rate 1000 --duration 196 --transition 4 \
  -o "$out/hour.csv"
hyperfine -N --warmup 1 --runs 5 "$exe calibrate $out/hour.csv -q --model quadratic -o $out/h.json"
