#!/usr/bin/python3
"""Regenerates the hostile-input corpus in tests/hostile/ (issue 7). Usage:
    scripts/make-hostile-corpus.py BUILD_DIR
The raw logs start from `accelcal simulate --scenario yang2012 --raw` at 20 Hz (small files),
rounded to 0.01 count, then each is damaged in one way. Deterministic: the same bytes every run.
The expected messages live in tests/hostile/cases.json, checked by the Cli.HostileCorpus test."""
import math
import os
import random
import subprocess
import sys

build = sys.argv[1]
here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "hostile")


def simulate(noise_density_ug, still_s):
    path = os.path.join(here, "_base.csv")
    subprocess.run([os.path.join(build, "accelcal"), "simulate", "--scenario", "yang2012", "--raw",
                    "--rate", "20", "--duration", str(still_s), "--transition", "1",
                    "--noise-density", str(noise_density_ug), "--seed", "3", "-o", path],
                   check=True)
    with open(path) as f:
        next(f)
        out = [[float(v) for v in line.split(",")] for line in f]
    os.remove(path)
    return out


rows = simulate(2000, 3)


def write(name, text, mode="w"):
    with open(os.path.join(here, name), mode) as f:
        f.write(text)


def log_text(rows):
    return "time,x,y,z\n" + "".join("%.2f,%.2f,%.2f,%.2f\n" % tuple(r) for r in rows)


write("empty.csv", "")
rng = random.Random(7)
write("garbage.bin", bytes(rng.randrange(256) for _ in range(300)), "wb")
write("nan.csv", "x,y,z\n1,2,3\n4,NaN,6\n")
write("inf.csv", "x,y,z\n1,2,3\n4,5,inf\n")
write("mixed-delimiters.csv", "x,y,z\n1,2,3\n4 5 6\n")
write("wrong-columns.csv", "time,x,y,z\n0,1,2,3\n0.05,1,2\n")
write("backwards.csv", log_text(rows[:40] + [[rows[39][0] - 1.0] + rows[40][1:]] + rows[41:60]))
# One position and the turn after it: a single static interval.
write("single-interval.csv", log_text(rows[:80]))
# Sixteen positions on one great circle (x-z plane), averaged readings of a unit-gain sensor.
write("one-plane.csv", "x,y,z\n" + "".join(
    "%.6f,0.001,%.6f\n" % (9.8 * math.cos(0.4 * k), 9.8 * math.sin(0.4 * k)) for k in range(16)))
# The y axis saturates at +40000 counts: the positions whose y reading lies near or beyond it.
write("clipped.csv", log_text([[r[0], r[1], min(r[2], 40000.0), r[3]] for r in rows]))
# A position whose sensor moved during its interval: its mean is off the others. (A creep slow
# enough for static detection to accept moves the mean by θ²/24 of g, so this is written as the
# positions it leaves: 30 simulated positions with position 7 pulled 40 counts (0.0085 m/s²,
# 100 times its noise) inwards. The raw-log case, a real recording with one creeping interval, is a library test.)
path = os.path.join(here, "_positions.csv")
subprocess.run([os.path.join(build, "accelcal"), "simulate", "--scenario", "yang2012",
                "--positions", "random:30:4", "-o", path], check=True)
with open(path) as f:
    header = next(f)
    positions = [[float(v) for v in line.split(",")] for line in f]
os.remove(path)
bias = [sum(p[i] for p in positions) / len(positions) for i in range(3)]
radial = [positions[6][i] - bias[i] for i in range(3)]
norm = math.sqrt(sum(v * v for v in radial))
for i in range(3):
    positions[6][i] -= 40.0 * radial[i] / norm
write("moved.csv", header + "".join(
    "%.3f,%.3f,%.3f,%d,%.4f,%.4f,%.4f\n" % tuple(p) for p in positions))
write("clean.csv", log_text(rows))

# Issue 15: logs as users really have them.
# PX4's ulog2csv: `timestamp` in µs. Read in its unit; read as seconds, refused.
write("time-us.csv", "timestamp,x,y,z\n" + "".join(
    "%d,%.2f,%.2f,%.2f\n" % (round(r[0] * 1e6), r[1], r[2], r[3]) for r in rows))
# Two sessions joined: the clock jumps by 1000 s in the middle of a turn.
half = len(rows) // 2 + 25
write("gap.csv", log_text(rows[:half] + [[r[0] + 1000.0] + r[1:] for r in rows[half:]]))
# ArduPilot's IMU messages of two instances, interleaved, with the instance column I.
write("two-sensors.csv", "TimeUS,I,AccX,AccY,AccZ\n" + "".join(
    "%d,%d,%.2f,%.2f,%.2f\n" % (round(r[0] * 1e6) + 1000 * i, i, *(v * (1 + 0.01 * i) for v in r[1:]))
    for r in rows for i in (0, 1)))
# A positions file concatenated with itself.
with open(os.path.join(here, "moved.csv")) as f:
    moved = f.read()
write("repeated-rows.csv", moved + moved.split("\n", 1)[1])
