"""The Python bindings: the same results as the library and the CLI, numpy in and out, the same
error messages, and the example script running end to end."""

import hashlib
import json
import os
import subprocess
import sys

import numpy as np
import pytest

import accelcal

DATA = os.environ["ACCELCAL_DATA_DIR"]
CLI = os.environ["ACCELCAL_CLI"]
XSENS = os.path.join(DATA, "imutk-xsens-mti", "xsens_acc.mat")


def sensor(text):
    """The accelerometer's keys of a calibration file's text (version 2)."""
    doc = json.loads(text)
    assert doc["format"] == "accelcal-calibration" and doc["version"] == 2
    return doc["sensors"]["accelerometer"]


def without_provenance(text):
    """A calibration file's text up to its provenance, the last key."""
    return text[:text.index('  "provenance": {')]


def cli_calibration(tmp_path, *args):
    out = tmp_path / "cal.json"
    subprocess.run([CLI, "calibrate", XSENS, "-q", "-o", str(out), *args], check=True)
    return sensor(out.read_text())


def cli_json(*args):
    """`accelcal calibrate ... --json`: the exit status and the calibration file's text."""
    run = subprocess.run([CLI, "calibrate", *args, "-q", "--json"], capture_output=True, text=True)
    return run.returncode, run.stdout


def test_calibrate_log_gives_the_cli_calibration_exactly(tmp_path):
    # Same reading, detection, averaging and solver: the same doubles as `accelcal calibrate`.
    cli = cli_calibration(tmp_path, "--gravity", "9.81744")
    result, positions = accelcal.calibrate_log(XSENS, gravity=9.81744)
    assert result.model == "linear" and result.frame == "x-first"
    assert result.summary["converged"]
    np.testing.assert_array_equal(result.K, np.array(cli["K"]))
    np.testing.assert_array_equal(result.bias, np.array(cli["bias"]))
    assert positions.shape == (38, 3)
    np.testing.assert_array_equal(positions, np.array([p["mean"] for p in cli["positions"]]))
    assert result.crossval_rms == cli["crossval_rms"]
    assert result.parameter_names == cli["parameter_order"]
    np.testing.assert_array_equal(result.covariance, np.array(cli["covariance"]))
    # And the same judgement: verdict and findings, codes and numbers, as `--json` prints them.
    status, text = cli_json(XSENS, "--gravity", "9.81744")
    assert status == 0
    doc = sensor(text)
    np.testing.assert_array_equal(result.K, np.array(doc["K"]))
    np.testing.assert_array_equal(result.bias, np.array(doc["bias"]))
    assert result.verdict == doc["verdict"] == "ok"
    assert [f["code"] for f in result.diagnostics] == [f["code"] for f in doc["diagnostics"]]
    assert [f["code"] for f in result.diagnostics] == ["scatter_ratio", "time_unit"]
    assert result.diagnostics == doc["diagnostics"]
    # The whole file, byte for byte, but its provenance (what made it: the tool or Python).
    assert without_provenance(result.to_json()) == without_provenance(text)
    assert json.loads(text)["provenance"]["command"] == "accelcal calibrate"


def test_calibrate_log_model_auto_is_the_cli_model_auto():
    # --model auto: both models fitted on the quadratic screening's positions, chosen on held-out
    # evidence; the Xsens keeps the linear model, and says why.
    status, text = cli_json(XSENS, "--gravity", "9.81744", "--model", "auto")
    assert status == 0
    result, _ = accelcal.calibrate_log(XSENS, gravity=9.81744, model="auto")
    assert result.model == "linear" and result.model_selection["chosen"] == "linear"
    assert result.model_selection["reason"] == sensor(text)["model_selection"]["reason"]
    assert without_provenance(result.to_json()) == without_provenance(text)
    with pytest.raises(ValueError, match="cross_validate"):
        accelcal.calibrate_log(XSENS, model="auto", cross_validate=False)


def test_a_corrupted_position_is_excluded_as_the_cli_excludes_it(tmp_path):
    # One position pushed 20 counts (0.05 m/s2) inside the ellipsoid: the screening leaves it out
    # in Python and in the CLI alike, and "flag" keeps it in the fit.
    _, positions = accelcal.calibrate_log(XSENS, gravity=9.81744)
    bias = accelcal.calibrate(positions, gravity=9.81744).bias
    moved = positions.copy()
    moved[7] -= 20.0 * (moved[7] - bias) / np.linalg.norm(moved[7] - bias)
    csv = tmp_path / "moved.csv"
    np.savetxt(csv, moved, delimiter=",", header="x,y,z", comments="", fmt="%.17g")
    cli = tmp_path / "cal.json"
    subprocess.run([CLI, "calibrate", str(csv), "-q", "--gravity", "9.81744", "-o", str(cli)],
                   check=True)
    doc = sensor(cli.read_text())
    with pytest.warns(accelcal.CalibrationWarning, match="position 8 disagrees"):
        result = accelcal.calibrate(moved, gravity=9.81744)
    # Position numbers count from 1 everywhere: the result, the diagnosis, the file, the messages.
    assert [o["position"] for o in result.outliers] == [8]
    outlier = [f for f in result.diagnostics if f["code"] == "outlier"]
    assert len(outlier) == 1 and outlier[0]["numbers"]["position"] == 8
    assert result.verdict == "warnings"
    assert result.outliers[0]["excluded"]
    assert [o["position"] for o in doc["outliers"]] == [8]  # the file counts from 1
    assert doc["positions"][7]["excluded"]
    np.testing.assert_array_equal(result.K, np.array(doc["K"]))
    with pytest.warns(accelcal.CalibrationWarning, match="kept in the fit"):
        flagged = accelcal.calibrate(moved, gravity=9.81744, outliers="flag")
    assert not flagged.outliers[0]["excluded"]
    with pytest.raises(ValueError):
        accelcal.calibrate(moved, outliers="sometimes")


def test_apply_inverts_the_model_and_matches_the_calibration_file(tmp_path):
    ModelLike = accelcal.calibrate(
        np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1],
                  [0.6, 0.8, 0], [0, 0.6, -0.8], [-0.8, 0, 0.6], [0.577, 0.577, 0.578],
                  [-0.577, 0.577, -0.578], [0.577, -0.577, -0.578]]) * 1.01 + 0.02,
        gravity=1.0, cross_validate=False)
    readings = np.array([[1.03, 0.02, 0.02], [0.02, 0.02, -0.99]])
    f = accelcal.apply(ModelLike, readings)
    # f solves p = K f + b exactly.
    np.testing.assert_allclose(f @ ModelLike.K.T + ModelLike.bias, readings, rtol=0, atol=1e-14)
    # Through the file (of the fitted positions, in g: gravity 1 means g): the JSON round trip
    # keeps every double.
    assert ModelLike.units == "g"
    text = ModelLike.to_json(raw_units="g")
    assert sensor(text)["units"] == {"raw": "g", "specific_force": "g"}
    loaded = accelcal.parse_calibration_json(text)
    np.testing.assert_array_equal(loaded.K, ModelLike.K)
    np.testing.assert_array_equal(loaded.apply(readings), f)
    # Other positions than the fit's 12 would make the file inconsistent (and read past the
    # residuals): refused.
    with pytest.raises(ValueError, match="2 positions for a calibration of 12"):
        ModelLike.to_json(readings)


def test_errors_carry_the_cli_messages(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("x,y,z\n1,2,3\n1,2,oops\n")
    with pytest.raises(accelcal.InputError) as e:
        accelcal.read_input(str(bad), "positions")
    cli = subprocess.run([CLI, "calibrate", str(bad), "--input-kind", "positions"],
                         capture_output=True, text=True)
    assert cli.returncode == 3
    assert cli.stderr.strip() == "accelcal: " + str(e.value)
    with pytest.raises(accelcal.DataError, match="at least 9 positions, got 3"):
        accelcal.calibrate(np.eye(3), cross_validate=False)
    with pytest.raises(ValueError, match="unknown model 'cubic'"):
        accelcal.calibrate(np.eye(3), model="cubic")


def test_detect_export_and_report_from_python(tmp_path):
    data = accelcal.read_input(XSENS)
    assert data["kind"] == "raw" and data["samples"].shape == (51175, 3)
    detected = accelcal.detect_static_intervals(data["samples"], data["time"])
    assert len(detected["intervals"]) == 38
    result, positions = accelcal.calibrate_log(XSENS, gravity=9.81744)
    text = result.to_json(positions, raw_units="counts", source="xsens_acc.mat")
    exported = accelcal.export_calibration(text, "imutk")
    assert exported["loss"]["dropped"] == ""
    html = accelcal.render_report(text, data["samples"], data["time"])
    assert html.count('<circle class="direction"') == 38 and '<svg id="raw-signal"' in html


def test_the_example_runs_and_draws_its_figure(tmp_path):
    example = os.path.join(os.environ["ACCELCAL_EXAMPLES"], "calibrate_xsens.py")
    run = subprocess.run([sys.executable, example, str(tmp_path)], capture_output=True, text=True,
                         env=dict(os.environ))
    assert run.returncode == 0, run.stderr
    assert "held-out RMS of |f| - g" in run.stdout
    png = (tmp_path / "xsens_calibration.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 20000


# --- the calibration file's provenance and version 1 ---------------------------------------------

V1 = os.path.join(os.path.dirname(DATA), "tests", "data", "calibration-v1")


def test_the_file_says_what_made_it(tmp_path):
    result, _ = accelcal.calibrate_log(XSENS, gravity=9.81744)
    doc = json.loads(result.to_json())
    provenance = doc["provenance"]
    assert provenance["command"] == "accelcal Python calibrate_log"
    assert provenance["options"]["gravity"] == 9.81744 and provenance["options"]["model"] == "linear"
    assert [i["name"] for i in provenance["inputs"]] == [XSENS]
    raw = open(XSENS, "rb").read()
    assert provenance["inputs"][0]["bytes"] == len(raw)
    assert provenance["inputs"][0]["sha256"] == hashlib.sha256(raw).hexdigest()
    assert "date" not in provenance  # none given: the same input gives the same bytes
    dated = result.to_json(date="2026-11-23")
    assert json.loads(dated)["provenance"]["date"] == "2026-11-23"
    with pytest.raises(ValueError, match="that month has no day 31"):
        result.to_json(date="2026-11-31")
    loaded = accelcal.parse_calibration_json(dated)
    assert loaded.version == 2 and loaded.verdict == "ok"
    assert loaded.provenance["date"] == "2026-11-23"
    assert loaded.provenance["options"] == provenance["options"]
    _, positions = accelcal.calibrate_log(XSENS, gravity=9.81744)
    from_arrays = json.loads(accelcal.calibrate(positions, gravity=9.81744).to_json())
    assert from_arrays["provenance"]["command"] == "accelcal Python calibrate"
    assert from_arrays["provenance"]["inputs"] == []


def test_version_1_files_still_load():
    for name in ["xsens-linear.json", "ctu49-auto-z-first.json", "ferraris-known.json",
                 "two-sessions.json", "failed.json"]:
        path = os.path.join(V1, name)
        doc = json.load(open(path))
        loaded = accelcal.load_calibration(path)
        assert loaded.version == 1 and loaded.provenance is None
        assert loaded.verdict == doc["verdict"]
        np.testing.assert_array_equal(loaded.K, np.array(doc["K"]))
        np.testing.assert_array_equal(loaded.bias, np.array(doc["bias"]))

def test_calibrate_log_with_the_gyroscope_is_the_cli_calibration(tmp_path):
    # `calibrate --gyro`: the same gyroscope, the joint fit's accelerometer, the same diagnosis and
    # the same file but its provenance.
    gyro = XSENS.replace("xsens_acc.mat", "xsens_gyro.mat")
    status, text = cli_json(XSENS, "--gravity", "9.81744", "--gyro", gyro)
    assert status == 0
    result, positions = accelcal.calibrate_log(XSENS, gravity=9.81744, gyro=gyro)
    g = result.gyroscope
    doc = json.loads(text)["sensors"]["gyroscope"]
    assert g["model"] == doc["model"] == "g-sensitive"
    np.testing.assert_array_equal(g["K"], np.array(doc["K"]))
    np.testing.assert_array_equal(g["bias"], np.array(doc["bias"]))
    assert len(g["rotations"]) == len(doc["rotations"]) == 37
    assert g["rotations"][0]["from"] == doc["rotations"][0]["from"] == 1
    assert g["rotations"] == doc["rotations"]  # every key and value the file has
    assert g["heldout_rms_deg"] == doc["validation"]["heldout_rms_deg"]
    np.testing.assert_array_equal(result.K, np.array(sensor(text)["K"]))
    assert result.verdict == sensor(text)["verdict"]
    assert without_provenance(result.to_json()) == without_provenance(text)
    # Without a gyroscope there is none; gyro options alone are refused, as the CLI's.
    assert accelcal.calibrate_log(XSENS, gravity=9.81744)[0].gyroscope is None
    with pytest.raises(ValueError, match="gyro_units"):
        accelcal.calibrate_log(XSENS, gyro_units="rad/s")
    with pytest.raises(ValueError, match="gyro_estimator"):
        accelcal.calibrate_log(XSENS, gyro=gyro, gyro_estimator="both")
    # imu_tk's method has one model: no validation needed to choose it.
    imutk = accelcal.calibrate_log(XSENS, gravity=9.81744, gyro=gyro, gyro_estimator="imutk",
                                   cross_validate=False)[0].gyroscope
    assert imutk["model"] == "linear" and imutk["estimator"] == "imutk"
