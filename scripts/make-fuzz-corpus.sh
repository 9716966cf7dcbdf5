#!/usr/bin/env bash
# Regenerates the committed libFuzzer seed corpora (fuzz/corpus/*) from the bundled recordings,
# the tool's own outputs and a few hand-written files. Usage: scripts/make-fuzz-corpus.sh BUILD_DIR
set -euo pipefail
cd "$(dirname "$0")/.."
cli=${1:-build}/accelcal
c=fuzz/corpus
# Its seeds are (re)written; the seeds added by hand or by tests (native_log, calibration_keys,
# cli_options, the *_v2.json and printf_* ones) are kept, never deleted.
mkdir -p "$c"/{log_reader,orientations,calibration_file,series,calibrate,file_log,file_schema}
# Logs and positions files: heads of the real recordings (seeds stay under 16 KB).
head -c 12000 data/imutk-xsens-mti/xsens_acc.mat | sed '$d' > "$c/log_reader/xsens_head.mat"
head -c 12000 data/imutk-t265/t265_acc.mat | sed '$d' > "$c/log_reader/t265_head.mat"
for f in data/imutk-xsens-mti/derived_static_means.csv data/ctu-innalabs-ahrs-m3/measured_accelerations_24pos.csv \
  data/ctu-innalabs-ahrs-m3/hassan_subset_31pos.csv data/imucal-ferraris/ferraris_raw_means.csv; do
  head -c 12000 "$f" > "$c/log_reader/$(basename "$f")"
done
printf 'time,ax,ay,az\n0,0.01,0.02,9.81\n0.01,0.011,0.021,9.812\n' > "$c/log_reader/header_time.csv"
printf 'x,y,z,n,sx,sy,sz\n0,0,1,100,0.01,0.01,0.01\n1,0,0,100,0.01,0.01,0.01\n' > "$c/log_reader/positions.csv"
printf '1\t2\t3\n4\t5\t6\n' > "$c/log_reader/tabs.tsv"
# Orientation files, every layout.
cp data/imucal-ferraris/ferraris_orientations.csv "$c/orientations/"
printf 'x,y,z\n0,0,1\n0,1,0\n' > "$c/orientations/directions.csv"
printf 'roll_deg,pitch_deg,yaw_deg\n10,20,30\n-90,0,0\n' > "$c/orientations/rpy.csv"
printf 'qw,qx,qy,qz\n1,0,0,0\n0.7071,0.7071,0,0\n' > "$c/orientations/quaternions.csv"
printf 'theta1_deg,theta2_deg,theta3_deg\n0,90,0\n180,0,90\n' > "$c/orientations/gimbal.csv"
# Calibration files: linear x-first, quadratic z-first, platform.
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$cli" simulate --scenario yang2012 -o "$tmp/yang.csv" > /dev/null
"$cli" calibrate "$tmp/yang.csv" --no-crossval -q -o "$c/calibration_file/linear.json"
"$cli" calibrate "$tmp/yang.csv" --model quadratic --frame z-first -q -o "$c/calibration_file/quadratic_z.json"
"$cli" calibrate data/imucal-ferraris/ferraris_raw_means.csv --orientations data/imucal-ferraris/ferraris_orientations.csv \
  --raw-units counts -q -o "$c/calibration_file/platform.json"
# Series: a few samples, binary and text.
"$cli" simulate --scenario wu2018-system --duration 1 --rate 50 -o "$c/series/short.bin"
printf 't,fx,fy,fz,roll,pitch\n0,0.001,0.002,9.8,1e-5,2e-5\n0.01,0.001,0.002,9.8,1e-5,2e-5\n' > "$c/series/short.csv"
# Calibrate: a control byte (method, model, frame) and the 18 averaged readings as doubles.
/usr/bin/python3 - "$tmp/yang.csv" "$c/calibrate" <<'PY'
import struct, sys
rows = [l.split(",")[:3] for l in open(sys.argv[1]) if l[:1] not in "#xn" and l.strip()]
values = b"".join(struct.pack("<3d", *map(float, r)) for r in rows)
for control in range(24):
    open(f"{sys.argv[2]}/yang18_{control:02d}", "wb").write(bytes([control]) + values)
PY
# Logs read from their file (fuzz_file_log): MAT-files (accelcal's 4 x N, SciPy's v5, v7
# compressed with a char and a struct, turned beside another matrix) and ROS 2 SQLite bags
# (Humble's and Iron's tables, as tests/rosbag2_test.py writes them, in 512-byte pages).
"$cli" simulate --scenario yang2012 --raw --duration 0.05 --transition 0.02 --format mat \
  -o "$c/file_log/simulated_4xN.mat"
/usr/bin/python3 - "$c/file_log" <<'PY'
import os, sqlite3, sys
import numpy as np
import scipy.io as sio
out = sys.argv[1]
sys.path.insert(0, "tests")
import rosbag2_test
x = np.loadtxt("data/imutk-xsens-mti/xsens_acc.mat")[:150]
sio.savemat(f"{out}/xsens_head_v5.mat", {"acc": x})
sio.savemat(f"{out}/xsens_head_v7_compressed.mat", {"acc": x, "note": "Xsens",
            "meta": {"rate": 100.0}}, do_compression=True)
sio.savemat(f"{out}/xsens_turned_two.mat", {"acc": np.ascontiguousarray(x[:60].T),
                                            "gyr": x[:5, :3]})
connect = sqlite3.connect
def small_pages(path, *args, **kwargs):
    db = connect(path, *args, **kwargs)
    db.execute("PRAGMA page_size=512")
    return db
sqlite3.connect = small_pages
rows = [(i * 10000, 9.8 * (i % 3 == 0), 0.1 * i, -0.2) for i in range(12)]
rosbag2_test.write_db3(f"{out}/ros2_iron.db3", rows, True)
rosbag2_test.write_db3(f"{out}/ros2_humble.db3", rows, False)
PY
ls -R "$c" | head -60
# Schema objects (fuzz_file_schema): its input is a list of choices that builds the bag or the
# MAT-file, so its seeds are fixed fills and the bytes of fixed pseudo-random seeds.
/usr/bin/python3 - "$c/file_schema" <<'PY'
import random, sys
out = sys.argv[1]
for k in range(12):
    r = random.Random(k)
    open(f"{out}/seed_{k:02d}", "wb").write(bytes(r.randrange(256) for _ in range(1024)))
for b in (0x00, 0x01, 0x55, 0xff):
    open(f"{out}/fill_{b:02x}", "wb").write(bytes([b]) * 512)
PY
