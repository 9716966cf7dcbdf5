"""What the scripts that test the log formats share (rosbag_test.py, rosbag2_test.py,
mat_test.py): the checks they count, accelcal run as a user runs it, a calibration file compared
less its input's name and digest, and a simulated session's samples."""
import json
import os
import subprocess
import sys


class Checks:
    def __init__(self, accelcal):
        self.accelcal = accelcal
        self.failures = []

    def check(self, condition, what):
        if not condition:
            self.failures.append(what)
            print("FAIL:", what)

    def run(self, *args, expect=0, stdin=None, timeout=None):
        """accelcal with `args`; a failure when it does not exit with `expect` (None: any), or
        run past `timeout` seconds (then killed: its exit status is None)."""
        try:
            p = subprocess.run([self.accelcal, *args], capture_output=True, text=True,
                               stdin=stdin, timeout=timeout)
        except subprocess.TimeoutExpired as e:
            self.check(False, f"accelcal {' '.join(args)}: still running after {timeout} s")
            return subprocess.CompletedProcess(e.cmd, None, e.stdout or "", e.stderr or "")
        if expect is not None and p.returncode != expect:
            self.check(False, f"accelcal {' '.join(args)}: exit {p.returncode}, wanted {expect}\n"
                              f"{p.stdout}{p.stderr}")
        return p

    def finish(self, name):
        if self.failures:
            print(f"{len(self.failures)} failure(s)")
            sys.exit(1)
        print(f"{name}: all checks passed")


def calibration(path):
    """The calibration file less the input's name and its provenance."""
    with open(path) as f:
        j = json.load(f)
    j.pop("provenance", None)
    j["sensors"]["accelerometer"].pop("source", None)
    return json.dumps(j, indent=1, sort_keys=True)


def simulated_rows(path):
    """(time in integer µs, x, y, z) of `accelcal simulate --raw`'s CSV."""
    rows = []
    with open(path) as f:
        next(f)
        for line in f:
            t, x, y, z = line.split(",")
            rows.append((round(float(t) * 1e6), float(x), float(y), float(z)))
    return rows


def simulated_session(ck, work, t0_us):
    """A simulated session (`accelcal simulate --raw`, yang2012, 20 s positions) in `work`: its
    rows (simulated_rows), and the calibration of its samples written as CSV with their times in
    µs from `t0_us` (a live recording's stamps) in m/s2, which each log format must give."""
    sim, same, cal = (os.path.join(work, n) for n in ("sim.csv", "same.csv", "csv.json"))
    ck.run("simulate", "--scenario", "yang2012", "--raw", "--duration", "20", "-o", sim)
    rows = simulated_rows(sim)
    with open(same, "w") as f:
        f.write("time_us,x,y,z\n")
        for t_us, x, y, z in rows:
            f.write(f"{t0_us + t_us},{x!r},{y!r},{z!r}\n")
    ck.run("calibrate", same, "--time-unit", "us", "--raw-units", "m/s2", "-o", cal)
    return rows, calibration(cal)
