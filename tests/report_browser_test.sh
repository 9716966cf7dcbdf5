#!/usr/bin/env bash
# The report as a person sees it: headless Chromium renders the page of the bundled Xsens
# calibration to a PNG (and the noise report of its rest to a DOM); the test fails on any console error (a failed resource load, a script
# error), on a missing plot in the rendered DOM, or on a blank screenshot.
# Usage: report_browser_test.sh ACCELCAL_CLI DATA_DIR
set -euo pipefail
cli=$1
data=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
command -v chromium > /dev/null || { echo "chromium is not installed (scripts/install-deps.sh)"; exit 1; }

"$cli" calibrate "$data/imutk-xsens-mti/xsens_acc.mat" --gravity 9.81744 --raw-units counts \
  -o "$work/cal.json" --report "$work/report.html" > /dev/null

# Chromium refuses to run as root without --no-sandbox; the page has nothing to sandbox.
browser=(chromium --headless --no-sandbox --disable-gpu --hide-scrollbars --user-data-dir="$work/profile"
  --enable-logging=stderr --v=0 --window-size=1000,2600)
timeout 120 "${browser[@]}" --screenshot="$work/report.png" "file://$work/report.html" \
  > "$work/screenshot.log" 2>&1
timeout 120 "${browser[@]}" --dump-dom "file://$work/report.html" > "$work/dom.html" 2> "$work/dom.log"

# Console messages are logged as CONSOLE lines; a self-contained page without scripts has none.
if grep -h "CONSOLE" "$work/screenshot.log" "$work/dom.log"; then
  echo "FAIL: console messages while rendering the report"
  exit 1
fi
for id in raw-signal norm-error sphere residuals; do
  grep -q "<svg id=\"$id\"" "$work/dom.html" || { echo "FAIL: no <svg id=\"$id\"> in the rendered DOM"; exit 1; }
done
[ "$(grep -o '<circle class="direction"' "$work/dom.html" | wc -l)" -eq 38 ] ||
  { echo "FAIL: expected 38 directions on the sphere"; exit 1; }
grep -q '<table id="parameters">' "$work/dom.html" || { echo "FAIL: no parameter table"; exit 1; }

# A PNG of the requested size that is not blank: plots and text make it far larger than an
# empty page of one colour (a blank 1000x2600 PNG compresses to a few kB).
png_header=$(head -c 24 "$work/report.png" | od -An -tx1 | tr -d ' \n')
[ "${png_header:0:16}" = "89504e470d0a1a0a" ] || { echo "FAIL: not a PNG"; exit 1; }
width=$((16#${png_header:32:8}))
height=$((16#${png_header:40:8}))
[ "$width" -eq 1000 ] && [ "$height" -eq 2600 ] || { echo "FAIL: PNG is ${width}x${height}"; exit 1; }
size=$(stat -c %s "$work/report.png")
[ "$size" -gt 100000 ] || { echo "FAIL: screenshot of $size bytes looks blank"; exit 1; }
echo "report rendered: ${width}x${height} PNG of $size bytes, no console message"

# The noise report (accelcal noise --report) of the Xsens rest, both sensors: no console message,
# both Allan deviation plots with their bands in the rendered DOM.
"$cli" noise "$data/imutk-xsens-mti/xsens_acc.mat" --still --gyro "$data/imutk-xsens-mti/xsens_gyro.mat" \
  --report "$work/noise.html" -o "$work/noise.txt"
timeout 120 "${browser[@]}" --dump-dom "file://$work/noise.html" > "$work/noise-dom.html" 2> "$work/noise-dom.log"
if grep -h "CONSOLE" "$work/noise-dom.log"; then
  echo "FAIL: console messages while rendering the noise report"
  exit 1
fi
for id in allan-0 allan-1; do
  grep -q "<svg id=\"$id\"" "$work/noise-dom.html" || { echo "FAIL: no <svg id=\"$id\"> in the noise report"; exit 1; }
done
[ "$(grep -o '<polygon class="band"' "$work/noise-dom.html" | wc -l)" -eq 6 ] ||
  { echo "FAIL: expected 6 confidence bands (3 axes, 2 sensors)"; exit 1; }
echo "noise report rendered: 2 plots, 6 bands, no console message"
