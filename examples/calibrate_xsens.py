"""Calibrate the bundled Xsens recording from Python and look at the result.

Run from a build: PYTHONPATH=build/python python3 examples/calibrate_xsens.py [OUTPUT_DIR]
It prints the calibration and saves xsens_calibration.png: the raw signal with the static
intervals, and |f| - g per position after calibration and held out (each position corrected by a
fit without it).
"""

import os
import sys

import matplotlib

matplotlib.use("Agg")  # files, not windows
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import accelcal  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
LOG = os.path.join(HERE, "..", "data", "imutk-xsens-mti", "xsens_acc.mat")
GRAVITY = 9.81744  # local gravity of the recording (imu_tk's example)

out_dir = sys.argv[1] if len(sys.argv) > 1 else "."

# 1. The log: time and raw 16-bit counts.
data = accelcal.read_input(LOG)
t, raw = data["time"], data["samples"]

# 2. What `accelcal calibrate` does, in one call: detection, averaging, maximum likelihood.
result, positions = accelcal.calibrate_log(LOG, gravity=GRAVITY)
print(f"{len(positions)} static positions, solver: {result.summary['brief_report']}")
print("K [counts per m/s2] =\n", result.K, "\nbias [counts] =", result.bias)
sigma = np.sqrt(np.diag(result.covariance))  # in the order of result.parameter_names
print("1 sigma:", ", ".join(f"{n} {s:.3g}" for n, s in zip(result.parameter_names, sigma)))

# 3. Apply it: corrected specific force of every sample, and |f| - g of each position.
f = accelcal.apply(result, positions)
after = np.linalg.norm(f, axis=1) - GRAVITY
held_out = np.array(result.crossval_errors)
print(f"RMS of |f| - g: {np.sqrt(np.mean(after**2)):.3g} m/s2, "
      f"held-out RMS of |f| - g: {result.crossval_rms:.3g} m/s2")

# 4. The figure.
detected = accelcal.detect_static_intervals(raw, t)
fig, (top, bottom) = plt.subplots(2, 1, figsize=(10, 7))
for i, axis in enumerate("xyz"):
    top.plot(t, raw[:, i], lw=0.6, label=axis)
for interval in detected["intervals"]:
    top.axvspan(interval["t_begin"], interval["t_end"], color="0.85", zorder=0)
top.set(xlabel="time [s]", ylabel="raw [counts]", title="raw signal, static intervals shaded")
top.legend(loc="upper right")
k = np.arange(1, len(positions) + 1)
bottom.axhline(0, color="0.5", lw=0.8)
bottom.plot(k, after * 1e3, "o", label="after calibration")
bottom.plot(k, held_out * 1e3, "o", mfc="none", label="held out")
bottom.set(xlabel="position", ylabel="|f| - g [mm/s2]")
bottom.legend()
fig.tight_layout()
path = os.path.join(out_dir, "xsens_calibration.png")
fig.savefig(path, dpi=100)
print(f"wrote {path}")
