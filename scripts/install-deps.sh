#!/usr/bin/env bash
# Installs the Debian 12 packages accelcal builds and tests with, if any is missing.
# Run as root (or with sudo). Nothing is downloaded except Debian packages.
set -euo pipefail
packages=(
  build-essential cmake pkgconf dpkg-dev  # dpkg-dev: the .deb's library dependencies (cpack)
  libeigen3-dev libcli11-dev nlohmann-json3-dev libfast-float-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  clang-format hyperfine valgrind
  ccache        # the build scripts compile through it: CI's fresh clones reuse unchanged objects
  python3-yaml  # the YAML export's round-trip test reads it with PyYAML
  libyaml-dev   # batch's limits file (YAML), read by libyaml's event parser
  chromium      # the report test renders the page as a person would see it
  pybind11-dev python3-dev python3-numpy python3-pytest python3-matplotlib  # Python bindings
  python3-pip python3-setuptools python3-wheel python3-venv  # pip install . (setup.py runs CMake)
  python3-pandas  # DataFrames in and out of the Python package
  clang libclang-rt-14-dev llvm-14  # sanitizers, libFuzzer and the symbolizer (scripts/sanitize.sh)
  libbz2-dev liblz4-dev libzstd-dev  # ROS bag and MCAP chunks (bz2, lz4, zstd)
  python3-rosbag python3-sensor-msgs  # ROS's own writer makes the bags the tests read
  libmatio-dev python3-scipy  # MATLAB MAT-files; SciPy writes those the tests read
  zlib1g-dev    # a MAT-file's compressed variables, inflated to check their sizes
  libsqlite3-dev  # ROS 2 bags in SQLite (.db3)
  locales       # the locale tests write numbers under de_DE.UTF-8 (decimal comma), generated below
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "installing: ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# The locale tests (tests/cli/test_locale.cpp, python/tests/test_locale.py) run the library in a
# decimal-comma locale; they fail, not skip, without it. Generated once, when missing.
if ! locale -a 2>/dev/null | grep -qix 'de_DE\.utf-\?8'; then
  echo "generating the locale de_DE.UTF-8"
  localedef -i de_DE -f UTF-8 de_DE.UTF-8
fi
