"""Never silently wrong, from Python: the diagnosis rides on every result, warnings and failures
become Python warnings, the command line's options reach the reader and the screening, and any
array given to the detection gives a result or a clean exception."""

import json
import math
import os
import subprocess
import warnings

import numpy as np
import pytest

import accelcal

DATA = os.environ["ACCELCAL_DATA_DIR"]
CLI = os.environ["ACCELCAL_CLI"]
XSENS = os.path.join(DATA, "imutk-xsens-mti", "xsens_acc.mat")
G = 9.81744  # the Xsens recording's local gravity


@pytest.fixture(scope="module")
def xsens():
    data = accelcal.read_input(XSENS)
    result, positions = accelcal.calibrate_log(XSENS, gravity=G)
    return data, result, positions


def write_log(path, header, time, samples):
    """A raw log as text, every double written to round trip."""
    with open(path, "w") as f:
        if header:
            f.write(header + "\n")
        for t, (x, y, z) in zip(time, samples):
            f.write(f"{t!r} {x!r} {y!r} {z!r}\n")


def relative_difference(a, b):
    return np.max(np.abs(a - b)) / np.max(np.abs(b))


# --- the time column ---------------------------------------------------------------------------

def test_a_log_in_microseconds_gives_the_same_calibration(tmp_path, xsens):
    # PX4-style integer microseconds under a header that says so: read as µs, not as seconds
    # (which would make a 100 Hz log 1e-4 Hz), and the same calibration as the original.
    _, reference, _ = xsens
    raw = np.loadtxt(XSENS)
    log = tmp_path / "xsens_us.txt"
    with open(log, "w") as f:
        f.write("timestamp_us x y z\n")
        for t, x, y, z in raw:
            f.write(f"{int(round(t * 1e6))} {x:.0f} {y:.0f} {z:.0f}\n")
    data = accelcal.read_input(str(log))
    axis = data["time_axis"]
    assert axis["unit"] == "us" and "timestamp_us" in axis["unit_reason"]
    assert axis["origin_s"] == pytest.approx(0.02984, rel=1e-12)
    assert axis["rate_hz"] == pytest.approx(100.01, rel=1e-4) and axis["gaps"] == []
    assert data["time"][0] == 0.0  # seconds from the first sample
    result, positions = accelcal.calibrate_log(str(log), gravity=G)
    assert positions.shape == (38, 3)
    assert relative_difference(result.K, reference.K) < 1e-9
    assert relative_difference(result.bias, reference.bias) < 1e-9
    assert result.verdict == reference.verdict == "ok"
    time_note = [f for f in result.diagnostics if f["code"] == "time_unit"]
    assert len(time_note) == 1 and "time in us" in time_note[0]["message"]
    # The unit given overrides the name: in seconds the log would be 1e-4 Hz, slower than any
    # log's 1 mHz: refused as the file's.
    with pytest.raises(accelcal.InputError, match="outside the 0.001 Hz-1 MHz of any log"):
        accelcal.calibrate_log(str(log), gravity=G, time_unit="s")
    same, _ = accelcal.calibrate_log(str(log), gravity=G, time_unit="us")
    np.testing.assert_array_equal(same.K, result.K)
    with pytest.raises(ValueError, match="unknown time unit 'minutes'"):
        accelcal.read_input(str(log), time_unit="minutes")


def test_instance_picks_one_sensor_of_an_interleaved_file(tmp_path, xsens):
    _, reference, _ = xsens
    raw = np.loadtxt(XSENS)
    log = tmp_path / "two_sensors.csv"
    with open(log, "w") as f:
        f.write("time,instance,x,y,z\n")
        for t, x, y, z in raw:
            f.write(f"{t!r},0,{x!r},{y!r},{z!r}\n{t!r},1,{1.01 * x!r},{y!r},{z!r}\n")
    with pytest.raises(accelcal.InputError, match="2 sensors"):
        accelcal.calibrate_log(str(log), gravity=G)
    result, _ = accelcal.calibrate_log(str(log), gravity=G, instance=0)
    np.testing.assert_array_equal(result.K, reference.K)
    assert accelcal.read_input(str(log), instance=1)["samples"].shape == (51175, 3)


# --- the verdict and the warnings --------------------------------------------------------------

def test_a_calibration_that_failed_its_checks_warns_and_says_failed(tmp_path):
    # 18 readings whose magnitudes scatter by 5 %: no single sensor gives them, and no sample
    # noise explains it. The command line writes the file marked failed and exits 6; Python
    # returns the same calibration, verdict "failed", with a CalibrationCheckFailed warning.
    rng = np.random.default_rng(3)
    d = rng.normal(size=(18, 3))
    readings = d / np.linalg.norm(d, axis=1)[:, None] * (1 + 0.05 * rng.normal(size=(18, 1)))
    with pytest.warns(accelcal.CalibrationCheckFailed, match="misfit") as record:
        result = accelcal.calibrate(readings, gravity=1.0)
    assert result.verdict == "failed"
    assert result.diagnostics[0]["code"] == "misfit"
    assert result.diagnostics[0]["severity"] == "failure"
    assert result.diagnostics[0]["numbers"]["rms_fraction_of_g"] > 0.02
    failed = [w.message for w in record if w.category is accelcal.CalibrationCheckFailed]
    assert len(failed) == 1 and failed[0].result is not None
    assert [f["code"] for f in failed[0].findings] == ["misfit"]
    # Warnings of the same diagnosis are CalibrationWarnings, each naming its code.
    warned = [w.message for w in record if w.category is accelcal.CalibrationWarning]
    assert sorted(w.finding["code"] for w in warned) == ["coverage_gap", "poorly_determined"]

    # Exactly the command line's result and diagnosis.
    csv = tmp_path / "misfit.csv"
    np.savetxt(csv, readings, delimiter=",", header="x,y,z", comments="", fmt="%.17g")
    cli = subprocess.run([CLI, "calibrate", str(csv), "--units", "g", "-q", "--json"],
                         capture_output=True, text=True)
    assert cli.returncode == 6
    assert json.loads(cli.stdout)["sensors"]["accelerometer"]["verdict"] == "failed"
    with pytest.warns(accelcal.CalibrationCheckFailed, match=str(csv)):
        from_file, _ = accelcal.calibrate_log(str(csv), gravity=1.0, input_kind="positions")
    assert from_file.units == "g"
    # The same file but its provenance (what made it), the last key.
    cut = '  "provenance": {'
    assert from_file.to_json()[:from_file.to_json().index(cut)] == cli.stdout[:cli.stdout.index(cut)]

    # As an exception, on request; the exception carries the result.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", accelcal.CalibrationWarning)
        warnings.simplefilter("error", accelcal.CalibrationCheckFailed)
        with pytest.raises(accelcal.CalibrationCheckFailed) as e:
            accelcal.calibrate(readings, gravity=1.0)
    assert e.value.result.verdict == "failed"


def test_a_solver_that_did_not_converge_is_a_failed_result():
    _, positions = accelcal.calibrate_log(XSENS, gravity=G)
    with pytest.warns(accelcal.CalibrationCheckFailed, match="not_converged"):
        result = accelcal.calibrate(positions, gravity=G, max_iterations=1)
    assert not result.summary["converged"]
    assert result.verdict == "failed"
    assert [f["code"] for f in result.diagnostics if f["severity"] == "failure"] == [
        "not_converged"]
    with pytest.raises(ValueError, match="max_iterations"):
        accelcal.calibrate(positions, gravity=G, max_iterations=-1)


def test_notes_are_not_emitted_and_warnings_are_not_failures():
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        result, _ = accelcal.calibrate_log(XSENS, gravity=G)
    assert result.verdict == "ok"
    assert {f["severity"] for f in result.diagnostics} == {"note"}  # two notes, none emitted
    assert [str(w.message) for w in record] == []
    # Silencing the warnings never silences a failure: separate categories.
    assert not issubclass(accelcal.CalibrationCheckFailed, accelcal.CalibrationWarning)
    assert not issubclass(accelcal.CalibrationWarning, accelcal.CalibrationCheckFailed)


# --- the screening's options -------------------------------------------------------------------

def two_moved_positions(positions, bias):
    moved = positions.copy()
    for k, amount in ((7, 20.0), (20, -25.0)):
        moved[k] -= amount * (moved[k] - bias) / np.linalg.norm(moved[k] - bias)
    return moved


def test_max_outliers_and_outlier_probability_reach_the_screening(xsens):
    _, reference, positions = xsens
    moved = two_moved_positions(positions, reference.bias)
    with pytest.warns(accelcal.CalibrationWarning):
        both = accelcal.calibrate(moved, gravity=G)
    assert sorted(o["position"] for o in both.outliers) == [8, 21]
    assert "outlier_limit" not in [f["code"] for f in both.diagnostics]
    # One allowed: one left out, and a warning that the limit was reached.
    with pytest.warns(accelcal.CalibrationWarning, match="outlier_limit"):
        one = accelcal.calibrate(moved, gravity=G, max_outliers=1)
    assert [o["excluded"] for o in one.outliers] == [True]
    assert "outlier_limit" in [f["code"] for f in one.diagnostics]
    # A smaller false-alarm probability raises the threshold of the test.
    with pytest.warns(accelcal.CalibrationWarning):
        strict = accelcal.calibrate(moved, gravity=G, outlier_probability=1e-12)
    assert strict.outliers[0]["threshold"] > 2 * both.outliers[0]["threshold"]
    for bad in (0.0, 1.0, math.nan):
        with pytest.raises(ValueError, match="^outlier_probability must be in"):
            accelcal.calibrate(moved, gravity=G, outlier_probability=bad)
    with pytest.raises(ValueError, match="^max_outliers must be non-negative"):
        accelcal.calibrate(moved, gravity=G, max_outliers=-1)
    # calibrate_log takes them too (the Xsens has no outlier: nothing changes).
    result, _ = accelcal.calibrate_log(XSENS, gravity=G, outliers="off", max_outliers=0,
                                       outlier_probability=0.01)
    np.testing.assert_array_equal(result.K, reference.K)


# --- diagnose() --------------------------------------------------------------------------------

def test_diagnose_judges_a_result_again_with_arrays_and_detection(xsens):
    data, result, positions = xsens
    again = accelcal.diagnose(result)  # the fitted positions, without the log
    assert again["verdict"] == "ok"
    assert [f["code"] for f in again["diagnostics"]] == ["scatter_ratio"]
    # With the raw log and its detection: the time column's note as well, as calibrate_log has.
    detection = accelcal.detect_static_intervals(data["samples"], data["time"])
    with_log = accelcal.diagnose(result, positions, samples=data["samples"], time=data["time"],
                                 detection=detection)
    assert [f["code"] for f in with_log["diagnostics"]] == [
        f["code"] for f in result.diagnostics]
    assert with_log["diagnostics"][0] == result.diagnostics[0]
    # In another unit the same gravity is no gravity on Earth.
    in_g = accelcal.diagnose(result, units="g")
    assert in_g["verdict"] == "warnings"
    assert "gravity_value" in [f["code"] for f in in_g["diagnostics"]]
    # Still periods not used come from the detection alone.
    detection["rejected"].append({"begin": 0, "end": 20, "t_begin": 0.0, "t_end": 0.2,
                                  "cause": "clipped", "reason": "made up"})
    rejected = accelcal.diagnose(result, detection=detection)
    assert [f["code"] for f in rejected["diagnostics"] if f["severity"] == "warning"] == [
        "rejected_period"]
    with pytest.raises(ValueError, match="5 positions for a calibration of 38"):
        accelcal.diagnose(result, positions[:5])
    with pytest.raises(ValueError, match="outside the 10 samples"):
        accelcal.diagnose(result, samples=data["samples"][:10], rate_hz=100.0,
                          detection=detection)


# --- arrays into the detection -----------------------------------------------------------------

def still_log(n=1000):
    rng = np.random.default_rng(0)
    return rng.normal(0, 1, (n, 3)) + [0, 0, 1000], np.arange(n) * 0.01


@pytest.mark.parametrize("rate_hz", [-2.0, 0.0, math.nan, math.inf, -math.inf])
def test_a_rate_that_is_no_rate_is_refused(rate_hz):
    samples, _ = still_log()
    with pytest.raises(accelcal.InputError, match="rate_hz: the sample rate must be a positive"):
        accelcal.detect_static_intervals(samples, rate_hz=rate_hz)
    with pytest.raises(accelcal.InputError, match="rate_hz"):
        accelcal.render_report("{}", samples, rate_hz=rate_hz)


def test_time_arrays_are_checked_before_use():
    samples, time = still_log()
    backwards = time.copy()
    backwards[500] = backwards[499] - 0.005
    with pytest.raises(accelcal.InputError, match=r"time\[500\] = 4\.985 is before time\[499\]"):
        accelcal.detect_static_intervals(samples, backwards)
    with pytest.raises(accelcal.InputError, match="timestamps must not decrease"):
        accelcal.detect_static_intervals(samples, time[::-1].copy())
    for bad in (math.nan, math.inf):
        broken = time.copy()
        broken[3] = bad
        with pytest.raises(accelcal.InputError, match=r"time\[3\] is not finite"):
            accelcal.detect_static_intervals(samples, broken)
    with pytest.raises(accelcal.InputError, match="do not advance"):
        accelcal.detect_static_intervals(samples, np.full(len(time), 7.0))
    with pytest.raises(accelcal.InputError, match="999 timestamps for 1000 samples"):
        accelcal.detect_static_intervals(samples, time[1:])
    with pytest.raises(accelcal.InputError, match="at least two"):
        accelcal.detect_static_intervals(samples[:1], time[:1])
    with pytest.raises(accelcal.InputError, match="contradicts the time array"):
        accelcal.detect_static_intervals(samples, time, rate_hz=200.0)
    with pytest.raises(ValueError, match="unknown time unit"):
        accelcal.detect_static_intervals(samples, time, time_unit="fortnights")


def test_samples_are_checked_before_use():
    samples, time = still_log()
    with pytest.raises(accelcal.InputError, match=r"samples: row 0 is not finite \(nan"):
        accelcal.detect_static_intervals(np.full((1000, 3), np.nan), time)
    broken = samples.copy()
    broken[123, 2] = math.inf
    with pytest.raises(accelcal.InputError, match="row 123 is not finite"):
        accelcal.detect_static_intervals(broken, rate_hz=100.0)
    with pytest.raises(accelcal.DataError, match="no time column and no sample rate"):
        accelcal.detect_static_intervals(samples)
    with pytest.raises(accelcal.DataError):
        accelcal.detect_static_intervals(np.zeros((0, 3)), rate_hz=100.0)
    # A well-formed array is detected, with the time axis described.
    found = accelcal.detect_static_intervals(samples, time)
    assert len(found["intervals"]) == 1 and found["time_axis"]["unit"] == "s"
    ms = accelcal.detect_static_intervals(samples, time * 1e3, time_unit="ms")
    assert ms["time_axis"]["unit"] == "ms" and ms["rate_hz"] == pytest.approx(100.0)


def test_a_gap_in_the_time_array_splits_detection_as_in_a_file(tmp_path, xsens):
    data, _, _ = xsens
    samples, time = data["samples"], data["time"]
    detected = accelcal.detect_static_intervals(samples, time)
    sixth = detected["intervals"][5]
    k = (sixth["begin"] + sixth["end"]) // 2  # a pause of 100 s in the middle of a still period
    paused = time.copy()
    paused[k:] += 100.0
    split = accelcal.detect_static_intervals(samples, paused)
    assert split["segments"] == 2
    assert [g[0] for g in split["time_axis"]["gaps"]] == [k]
    assert split["time_axis"]["rate_hz"] == pytest.approx(detected["rate_hz"], rel=1e-6)
    assert all(i["end"] <= k or i["begin"] >= k for i in split["intervals"])
    assert len(split["intervals"]) == 39
    # The command line, reading the same log from a file, finds the same intervals.
    log = tmp_path / "paused.txt"
    write_log(log, "t x y z", paused, samples)
    cli = subprocess.run([CLI, "detect", str(log), "--json"], capture_output=True, text=True,
                         check=True)
    from_file = json.loads(cli.stdout)["intervals"]
    assert [(i["begin"], i["end"]) for i in from_file] == [
        (i["begin"], i["end"]) for i in split["intervals"]]
    assert [i["samples"] for i in from_file] == [i["samples"] for i in split["intervals"]]


def test_rejected_periods_carry_their_cause(tmp_path, xsens):
    data, _, _ = xsens
    samples, time = data["samples"], data["time"]
    detected = accelcal.detect_static_intervals(samples, time)
    assert detected["rejected"] == []
    # Too short: a minimum longer than some still periods.
    longer = accelcal.detect_static_intervals(samples, time, min_static_s=6)
    assert longer["rejected"] and {r["cause"] for r in longer["rejected"]} == {"too_short"}
    # Clipped: axis x saturated at the level of the still period that reads it highest.
    j = int(np.argmax([i["mean"][0] for i in detected["intervals"]]))
    clipped = samples.copy()
    clipped[:, 0] = np.minimum(clipped[:, 0], detected["intervals"][j]["mean"][0])
    found = accelcal.detect_static_intervals(clipped, time)
    assert [r["cause"] for r in found["rejected"]] == ["clipped"]
    assert "saturated" in found["rejected"][0]["reason"]
    # ... and calibrate_log warns of it (a position the user meant to record is not used).
    log = tmp_path / "clipped.txt"
    write_log(log, "", time + data["time_axis"]["origin_s"], clipped)
    with pytest.warns(accelcal.CalibrationWarning, match="saturated"):
        result, positions = accelcal.calibrate_log(str(log), gravity=G)
    assert len(positions) == 37 and result.verdict == "warnings"
    rejected = [f for f in result.diagnostics if f["code"] == "rejected_period"]
    assert len(rejected) == 1 and rejected[0]["severity"] == "warning"
    # Moving: a still-looking period (each window quiet) through which the sensor turns
    # 12 degrees in 8 s, as slow continuous turning by hand does.
    rng = np.random.default_rng(1)
    directions = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
    rows, previous = [], None
    for n, d in enumerate(directions):
        d = np.array(d, float)
        if previous is not None:
            for a in np.linspace(0, 1, 200):
                v = (1 - a) * previous + a * d
                rows.append(v / np.linalg.norm(v))
        if n == 3:
            rows += [np.array([math.sin(a), -math.cos(a), 0.0])
                     for a in np.linspace(0, math.radians(12), 800)]
            d = rows[-1]
        else:
            rows += [d] * 2000
        previous = d
    turning = 1000 * np.array(rows) + rng.normal(0, 2.0, (len(rows), 3))
    moving = accelcal.detect_static_intervals(turning, rate_hz=100.0)
    assert len(moving["intervals"]) == 5
    assert [r["cause"] for r in moving["rejected"]] == ["moving"]
    assert "turning" in moving["rejected"][0]["reason"]


def test_a_detection_that_is_no_detection_is_a_value_error():
    # Issue 16, found by python/fuzz/fuzz_entry_points.py: a dict without the keys of
    # detect_static_intervals' result raised KeyError (a cast of a wrong type, RuntimeError).
    positions = np.loadtxt(os.path.join(DATA, "imutk-xsens-mti", "derived_static_means.csv"),
                           delimiter=",", skiprows=1)[:, 3:6]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = accelcal.calibrate(positions, gravity=9.81744)
    for detection in ({}, {"intervals": []}, {"intervals": [{"begin": "x"}], "rejected": []},
                      {"intervals": 3, "rejected": []}):
        with pytest.raises(ValueError, match="detection"):
            accelcal.diagnose(result, detection=detection)
