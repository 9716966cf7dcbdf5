#!/usr/bin/env bash
# Installs the built project into a scratch prefix and builds and runs tests/consumer against it.
set -euo pipefail
build_dir=$1
source_dir=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cmake --install "$build_dir" --prefix "$work/prefix" >/dev/null
cmake -S "$source_dir/tests/consumer" -B "$work/build" -DCMAKE_PREFIX_PATH="$work/prefix" \
  -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$work/build" >/dev/null
"$work/build/consumer"
test -x "$work/prefix/bin/accelcal"
# The man page is installed and names every command the tool has.
man_page="$work/prefix/share/man/man1/accelcal.1"
test -f "$man_page"
for command in $("$work/prefix/bin/accelcal" --help | sed -n '/^Subcommands:/,$p' | awk 'NR > 1 {print $1}'); do
  grep -q "^\.B $command" "$man_page" || { echo "man page lacks command '$command'"; exit 1; }
done
if command -v man > /dev/null; then
  # Renders without groff warnings.
  warnings=$(MANWIDTH=100 man --warnings -l "$man_page" 2>&1 > /dev/null || true)
  [ -z "$warnings" ] || { echo "man page warnings: $warnings"; exit 1; }
fi
# pkg-config gives what a Makefile needs (the static library with what it links, or the shared).
pc_dir=$(dirname "$(find "$work/prefix" -name accelcal.pc | head -1)")
flags=$(PKG_CONFIG_PATH="$pc_dir" pkg-config --cflags --libs --static accelcal)
# shellcheck disable=SC2086
c++ -O1 -o "$work/consumer-pc" "$source_dir/tests/consumer/main.cpp" $flags
LD_LIBRARY_PATH="$(dirname "$(find "$work/prefix" -name 'libaccelcal.*' | head -1)")" \
  "$work/consumer-pc"
test "$(PKG_CONFIG_PATH="$pc_dir" pkg-config --modversion accelcal)" = \
  "$("$work/prefix/bin/accelcal" --version | awk '{print $2}')"
# The documentation is installed beside the licence.
for doc in README.md LICENSE calibration-file.md model.md conventions.md; do
  test -f "$work/prefix/share/doc/accelcal/$doc" || { echo "docs: $doc not installed"; exit 1; }
done
