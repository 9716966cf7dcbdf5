#!/usr/bin/env python3
"""MATLAB MAT-files written by SciPy (an independent writer), read by accelcal (issue 20).

The Xsens recording the project ships (data/imutk-xsens-mti/xsens_acc.mat, imu_tk's data, which
MATLAB wrote as text with `save -ascii`) is saved as a level-5 MAT-file, uncompressed and
compressed (MATLAB 7's default), stored as MATLAB stores a matrix and turned (4 x N): each
calibrates to the same bytes as the text file (less the input's name and digest). Then what a
user could give: several matrices (one chosen by --topic), a variable that is not a matrix, one
that does not exist, single precision, a positions matrix, a FIFO, a file cut short; and noise.

Usage: mat_test.py ACCELCAL DATA_DIR WORKDIR
"""
import json
import os
import shutil
import sys
import threading

import numpy as np
import scipy.io as sio

from log_test_support import Checks, calibration


def main():
    accelcal, data, work = sys.argv[1], sys.argv[2], sys.argv[3]
    ck = Checks(accelcal)
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    p = lambda name: os.path.join(work, name)  # noqa: E731
    text = os.path.join(data, "imutk-xsens-mti", "xsens_acc.mat")
    xsens = np.loadtxt(text)  # time [s], x, y, z [counts]
    g = ["--gravity", "9.81744"]  # imu_tk's local gravity for this recording

    ck.run("calibrate", text, *g, "-o", p("text.json"))
    want = calibration(p("text.json"))

    sio.savemat(p("v5.mat"), {"acc": xsens})
    sio.savemat(p("v7.mat"), {"acc": xsens, "note": "Xsens MTi, 100 Hz",
                              "meta": {"rate": 100.0}}, do_compression=True)
    sio.savemat(p("turned.mat"), {"acc": np.ascontiguousarray(xsens.T)})
    for name in ("v5", "v7", "turned"):
        r = ck.run("calibrate", p(f"{name}.mat"), *g, "-o", p(f"{name}.json"))
        ck.check(r.returncode == 0 and calibration(p(f"{name}.json")) == want,
              f"the {name} MAT-file calibrates as the text file")
        ck.check("MAT-file variable acc" in r.stdout, f"the summary names the variable:\n{r.stdout}")
    ck.check("read turned" in ck.run("calibrate", p("turned.mat"), *g, "-o", p("t.json")).stdout,
          "a 4 x N matrix is said to be read turned")

    # Several matrices: the error lists them; --topic chooses one.
    sio.savemat(p("two.mat"), {"acc": xsens, "gyr": xsens[:, :3] * 0.5})
    r = ck.run("calibrate", p("two.mat"), *g, "-o", p("x.json"), expect=3)
    ck.check("acc (51175x4 double), gyr (51175x3 double)" in r.stderr and "--topic" in r.stderr,
          f"several matrices are listed: {r.stderr}")
    r = ck.run("calibrate", p("two.mat"), "--topic", "acc", *g, "-o", p("two.json"))
    ck.check(calibration(p("two.json")) == want, "--topic chooses the variable")
    r = ck.run("calibrate", p("v7.mat"), "--topic", "note", *g, "-o", p("x.json"), expect=3)
    ck.check("is 1x17 char, not a real numeric matrix" in r.stderr, f"a char variable: {r.stderr}")
    r = ck.run("calibrate", p("v7.mat"), "--topic", "nothing", *g, "-o", p("x.json"), expect=3)
    ck.check("no variable nothing (its variables: acc (51175x4 double), note (1x17 char), "
          "meta (1x1 struct))" in r.stderr, f"a missing variable: {r.stderr}")

    # inspect lists the variables.
    r = ck.run("inspect", p("v7.mat"))
    ck.check("acc      51175x4 double (51175 rows read)" in r.stdout and "meta     1x1 struct" in
          r.stdout, f"inspect:\n{r.stdout}")
    doc = json.loads(ck.run("inspect", p("v7.mat"), "--json").stdout)
    ck.check(doc["format"] == "mat" and doc["streams"][0]["samples"] == len(xsens),
          f"inspect --json: {doc}")

    # Single precision: the numbers are float32's, read exactly as such (the time column's
    # float32 steps are irregular to 1e-6 s, which the reader takes as any text's).
    sio.savemat(p("single.mat"), {"acc": xsens.astype(np.float32)})
    r = ck.run("calibrate", p("single.mat"), *g, "-o", p("single.json"))
    ck.check(r.returncode == 0, "single precision reads")

    # Positions: a simulated 18-position file (x, y, z, n, sx, sy, sz) as a matrix is a
    # positions file by its 18 rows, as headerless text is, and calibrates as the text does.
    ck.run("simulate", "--scenario", "yang2012", "-o", p("positions.csv"))
    sio.savemat(p("positions.mat"),
                {"positions": np.loadtxt(p("positions.csv"), delimiter=",", skiprows=1)})
    a = ck.run("calibrate", p("positions.csv"), "-o", p("pos_text.json"))
    b = ck.run("calibrate", p("positions.mat"), "-o", p("pos_mat.json"))
    ck.check("18 rows <= 200 is a positions file" in b.stdout and
          calibration(p("pos_text.json")) == calibration(p("pos_mat.json")),
          f"a positions matrix:\n{b.stdout}{b.stderr}")

    # noise: a MAT-file read whole, as the text (its still rest).
    a = ck.run("noise", text, "--still", "--json")
    b = ck.run("noise", p("v7.mat"), "--still", "--json")
    ja, jb = json.loads(a.stdout), json.loads(b.stdout)
    for j in (ja, jb):
        j.pop("source")
        j["accelerometer"].pop("source")
    ck.check(ja == jb, "noise of the MAT-file is the noise of the text file")

    # A FIFO: libmatio opens a file by its path; refused with the reason.
    fifo = p("pipe.mat")
    os.mkfifo(fifo)

    def feed():
        with open(fifo, "wb") as f, open(p("v5.mat"), "rb") as src:
            try:
                f.write(src.read())
            except BrokenPipeError:
                pass
    t = threading.Thread(target=feed, daemon=True)
    t.start()
    r = ck.run("calibrate", fifo, "-o", p("x.json"), expect=3)
    ck.check("read from its file" in r.stderr, f"a FIFO: {r.stderr}")

    # Cut short: said before libmatio reads it (naming where), nothing written.
    with open(p("v7.mat"), "rb") as f:
        whole = f.read()
    with open(p("cut.mat"), "wb") as f:
        f.write(whole[: len(whole) // 3])
    r = ck.run("calibrate", p("cut.mat"), "-o", p("cut.json"), expect=3)
    ck.check("corrupt or cut short" in r.stderr and "byte" in r.stderr and
             not os.path.exists(p("cut.json")),
          f"a cut MAT-file: {r.stderr}")

    # accelcal's own writer (simulate --format mat), read by SciPy: the 4 x N matrix "imu" holds
    # the simulation's times and readings, the same doubles as its CSV.
    ck.run("simulate", "--scenario", "yang2012", "--raw", "--duration", "5", "-o", p("sim.csv"))
    ck.run("simulate", "--scenario", "yang2012", "--raw", "--duration", "5", "--format", "mat",
           "-o", p("sim.mat"))
    m = sio.loadmat(p("sim.mat"))
    csv = np.loadtxt(p("sim.csv"), delimiter=",", skiprows=1)
    ck.check(m["imu"].shape == (4, len(csv)) and np.array_equal(m["imu"].T, csv) and
             m["__header__"].startswith(b"MATLAB 5.0 MAT-file"),
             "SciPy reads accelcal's MAT-file as the simulation's samples")

    ck.finish("mat")


if __name__ == "__main__":
    main()
