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
