#!/usr/bin/env bash
# The Python package as a user installs it, offline, from Debian's packages:
#  1. `cmake --install` of the build puts it under the prefix, where Python imports it;
#  2. `pip wheel --no-build-isolation` builds a wheel from a copy of the source (setup.py runs the
#     project's CMake), and `pip install --no-build-isolation .` installs it in a virtual
#     environment (the README's commands);
# each then calibrates the bundled recording to the command line's numbers.
# Arguments: the CMake build directory, the accelcal tool.
set -euo pipefail
build_dir=$1
cli=$2
source_dir=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
python=/usr/bin/python3
recording="$source_dir/data/imutk-xsens-mti/xsens_acc.mat"
"$cli" calibrate "$recording" --gravity 9.81744 --json > "$work/cli.json" 2>/dev/null

# Calibrates with the installed package (from a directory that holds no accelcal) and checks its
# version, stubs and numbers against the tool's.
check() {
  local interpreter=$1 expected_prefix=$2
  (cd "$work" && "$interpreter" - "$recording" "$work/cli.json" "$expected_prefix" <<'PY'
import json, pathlib, sys
import numpy as np
import accelcal
recording, cli_json, prefix = sys.argv[1:]
where = pathlib.Path(accelcal.__file__).resolve()
assert str(where).startswith(str(pathlib.Path(prefix).resolve())), where
assert (where.parent / "__init__.pyi").is_file() and (where.parent / "py.typed").is_file()
result, _ = accelcal.calibrate_log(recording, gravity=9.81744)
cli = json.loads(pathlib.Path(cli_json).read_text())["sensors"]["accelerometer"]
np.testing.assert_array_equal(result.K, np.array(cli["K"]))
np.testing.assert_array_equal(result.bias, np.array(cli["bias"]))
print(f"accelcal {accelcal.__version__} from {where.parent}: K and b as the tool's")
PY
  )
}

# 1. cmake --install
cmake --install "$build_dir" --prefix "$work/prefix" --component python > /dev/null
site=$(find "$work/prefix" -name _accelcal*.so -printf '%h\n' | head -1)
test -n "$site" || { echo "cmake --install put no Python module under the prefix"; exit 1; }
PYTHONPATH=$(dirname "$site") check "$python" "$work/prefix"

# 2. a wheel, and pip install . in a virtual environment that sees Debian's numpy
mkdir "$work/src"
# The wheel's CMake build compiles the library once more. With the build's compiler cache
# (scripts/compiler-cache.sh) and its warning flags, in a directory as deep in the copy as the
# build's is in the tree, every compile of the library is the build's own (the same command line
# relative to the tree): a cache hit, where it had been a whole second build of the library
# (16 minutes beside the other tests on 2 cores).
launcher=$(sed -n 's/^CMAKE_CXX_COMPILER_LAUNCHER:[A-Z]*=//p' "$build_dir/CMakeCache.txt")
if [ -n "$launcher" ] && [ "$(dirname "$(realpath "$build_dir")")" = "$source_dir" ]; then
  werror=$(sed -n 's/^ACCELCAL_WERROR:BOOL=//p' "$build_dir/CMakeCache.txt")
  export ACCELCAL_CMAKE_BUILD_DIR="$work/src/$(basename "$(realpath "$build_dir")")"
  export ACCELCAL_CMAKE_ARGS="-DCMAKE_CXX_COMPILER_LAUNCHER=$launcher -DACCELCAL_WERROR=${werror:-OFF}"
  export CCACHE_BASEDIR="$work/src" CCACHE_NOHASHDIR=1
fi
tar -C "$source_dir" --exclude='./build*' --exclude=./.git --exclude='./python/*.egg-info' \
  --exclude=./dist -cf - . | tar -C "$work/src" -xf -
"$python" -m venv --system-site-packages "$work/venv"
pip=("$work/venv/bin/python" -m pip --disable-pip-version-check --no-input -q)
(cd "$work/src" && "${pip[@]}" wheel --no-build-isolation --no-deps --no-index -w "$work/dist" .)
wheel=$(ls "$work"/dist/accelcal-*.whl)
"$python" - "$wheel" <<'PY'
import sys, zipfile
names = zipfile.ZipFile(sys.argv[1]).namelist()
for needed in ("accelcal/__init__.py", "accelcal/__init__.pyi", "accelcal/py.typed"):
    assert needed in names, (needed, names)
assert any(n.startswith("accelcal/_accelcal") and n.endswith(".so") for n in names), names
PY
# The README's command (the CMake build of the wheel is reused: only the install is new).
(cd "$work/src" && "${pip[@]}" install --no-build-isolation --no-deps --no-index .)
check "$work/venv/bin/python" "$work/venv"
"$work/venv/bin/python" -c '
import importlib.metadata, accelcal
assert importlib.metadata.version("accelcal") == accelcal.__version__, accelcal.__version__'
