#!/usr/bin/env bash
# The Python package's entry points called with hostile arguments (python/fuzz/
# fuzz_entry_points.py) for FUZZ_SECONDS seconds (default 60; run much longer by hand, with
# several seeds: FUZZ_SEED). Needs the Release build of scripts/test.sh (build/python).
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHONPATH="$PWD/build/python" ACCELCAL_DATA_DIR="$PWD/data" /usr/bin/python3 \
  python/fuzz/fuzz_entry_points.py --seconds "${FUZZ_SECONDS:-60}" --seed "${FUZZ_SEED:-1}"
