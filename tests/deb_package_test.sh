#!/usr/bin/env bash
# The Debian package CPack builds from the build directory, unpacked in a scratch root (no root
# needed: dpkg -x): its metadata, then the tool, its man page, a consumer build with CMake and with
# pkg-config, and the Python package, all from that root.
# Arguments: the CMake build directory.
set -euo pipefail
build_dir=$1
source_dir=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
(cd "$build_dir" && cpack -G DEB -B "$work/deb" > "$work/cpack.log") ||
  { cat "$work/cpack.log"; exit 1; }
deb=$(ls "$work"/deb/accelcal_*.deb)
info=$(dpkg-deb --info "$deb")
grep -q "^ Package: accelcal$" <<< "$info"
grep -q "^ Version: $("$build_dir/accelcal" --version | awk '{print $2}')$" <<< "$info"
grep -q "^ Depends: .*libeigen3-dev.*python3-numpy" <<< "$info" ||
  { echo "Depends is not complete: $info"; exit 1; }
root="$work/root"
dpkg-deb -x "$deb" "$root"
contents=$(dpkg-deb --contents "$deb")
for path in ./usr/bin/accelcal ./usr/share/man/man1/accelcal.1 ./usr/include/accelcal/calibrate.hpp \
  ./usr/share/doc/accelcal/README.md ./usr/share/doc/accelcal/calibration-file.md; do
  grep -q " $path$" <<< "$contents" || { echo "the package lacks $path"; exit 1; }
done
grep -q "/pkgconfig/accelcal.pc$" <<< "$contents"
grep -q "/cmake/accelcal/accelcalConfig.cmake$" <<< "$contents"
grep -q "dist-packages/accelcal/_accelcal.*\.so$" <<< "$contents"

# The tool calibrates the bundled recording, as the build's does.

# No LD_LIBRARY_PATH: the tool finds a shared library by its RPATH ($ORIGIN/../lib).
recording="$source_dir/data/imutk-xsens-mti/xsens_acc.mat"
"$root/usr/bin/accelcal" calibrate "$recording" --gravity 9.81744 --json > "$work/installed.json"
"$build_dir/accelcal" calibrate "$recording" --gravity 9.81744 --json > "$work/built.json"
cmp "$work/installed.json" "$work/built.json"
if command -v man > /dev/null; then MANWIDTH=100 man -l "$root/usr/share/man/man1/accelcal.1" > /dev/null; fi

# A consumer builds against the root with CMake and with pkg-config.
cmake -S "$source_dir/tests/consumer" -B "$work/consumer" -DCMAKE_PREFIX_PATH="$root/usr" \
  -DCMAKE_BUILD_TYPE=Release > /dev/null
cmake --build "$work/consumer" > /dev/null
"$work/consumer/consumer"
pc_dir=$(dirname "$(find "$root" -name accelcal.pc)")
flags=$(PKG_CONFIG_PATH="$pc_dir" pkg-config --cflags --libs --static accelcal)
# shellcheck disable=SC2086
c++ -O1 -o "$work/consumer-pc" "$source_dir/tests/consumer/main.cpp" $flags
# A shared library outside the loader's directories is found as a user's program would find it.
LD_LIBRARY_PATH="$(dirname "$(find "$root/usr/lib" -name 'libaccelcal.*' | head -1)")" \
  "$work/consumer-pc"

# The Python package imports from the root and calibrates to the tool's numbers.
site=$(dirname "$(dirname "$(find "$root/usr/lib" -name '_accelcal*.so' | head -1)")")
(cd "$work" && PYTHONPATH="$site" /usr/bin/python3 - "$recording" "$work/built.json" "$site" <<'PY'
import json, pathlib, sys
import numpy as np
import accelcal
recording, built, site = sys.argv[1:]
assert pathlib.Path(accelcal.__file__).resolve().is_relative_to(pathlib.Path(site).resolve())
result, _ = accelcal.calibrate_log(recording, gravity=9.81744)
doc = json.loads(pathlib.Path(built).read_text())["sensors"]["accelerometer"]
np.testing.assert_array_equal(result.K, np.array(doc["K"]))
assert accelcal.cli.calibrate(recording, gravity=9.81744).text == pathlib.Path(built).read_text()
PY
)
echo "$(basename "$deb"): installs and runs from a scratch root"
