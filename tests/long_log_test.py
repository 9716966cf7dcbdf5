#!/usr/bin/python3
"""Issue 7: a 1-hour 1 kHz recording (3.6 million rows, written by the simulator) is calibrated in
bounded memory: peak resident memory of `accelcal calibrate` at most 200 MB (the text is released
as it is parsed; the samples, 36 bytes each, are what remains). Its time (target 2 s) is measured
by scripts/bench-process.sh, not here. Usage: long_log_test.py ACCELCAL TMPDIR"""
import json
import os
import subprocess
import sys

cli, tmp = sys.argv[1], sys.argv[2]
os.makedirs(tmp, exist_ok=True)
log = os.path.join(tmp, "hour.csv")
cal = os.path.join(tmp, "hour.json")
try:
    # 18 positions of 196 s and 17 turns of 4 s: 3600 s at 1 kHz.
    subprocess.run([cli, "simulate", "--scenario", "yang2012", "--raw", "--rate", "1000",
                    "--duration", "196", "--transition", "4", "-o", log], check=True)
    rows = sum(1 for _ in open(log)) - 1
    assert rows >= 3_590_000, rows
    # ru_maxrss of a process's children is the largest of them: calibrate runs as the only child
    # of a fresh interpreter, so that the simulator's (it holds the whole log) does not count.
    measure = ("import resource, subprocess, sys; subprocess.run(sys.argv[1:], check=True); "
               "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)")
    peak_kb = int(subprocess.run(
        [sys.executable, "-c", measure, cli, "calibrate", log, "-q", "--model", "quadratic",
         "-o", cal], check=True, capture_output=True, text=True).stdout)
    doc = json.load(open(cal))["sensors"]["accelerometer"]
    assert doc["solver"]["converged"] and len(doc["positions"]) == 18, doc["solver"]
    print(f"{rows} rows, calibrate peak RSS {peak_kb / 1024:.0f} MiB")
    assert peak_kb <= 200_000, f"peak RSS {peak_kb} KB > 200 MB"
finally:
    for path in (log, cal):
        if os.path.exists(path):
            os.remove(path)
