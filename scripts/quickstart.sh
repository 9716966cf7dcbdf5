#!/usr/bin/env bash
# Quick start on a fresh Debian 12 machine: installs the missing Debian packages, builds accelcal
# and calibrates the bundled imu_tk Xsens MTi recording (raw 16-bit counts, g = 9.81744 m/s²).
set -euo pipefail
cd "$(dirname "$0")/.."
if [ "$(id -u)" -eq 0 ]; then bash scripts/install-deps.sh; else sudo bash scripts/install-deps.sh; fi
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)" --target accelcal_cli
build/accelcal calibrate data/imutk-xsens-mti/xsens_acc.mat --gravity 9.81744 --raw-units counts \
  -o xsens_calibration.json
