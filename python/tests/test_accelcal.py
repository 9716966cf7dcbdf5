"""The Python bindings: the same results as the library and the CLI, numpy in and out, the same
error messages, and the example script running end to end."""

import hashlib
import inspect
import json
import warnings
import re
import os
import pickle
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
    with pytest.raises(ValueError, match="no_crossval"):
        accelcal.calibrate_log(XSENS, model="auto", no_crossval=True)


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
    # The options as given, as the tool records them (`accelcal calibrate XSENS --gravity ...`).
    assert provenance["options"] == {"gravity": "9.81744"}
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
                                   no_crossval=True)[0].gyroscope
    assert imutk["model"] == "linear" and imutk["estimator"] == "imutk"


# --- calibrate_log takes every option of `accelcal calibrate` ------------------------------------

# A value for each option of `accelcal calibrate` (one the Xsens recording takes, or one it
# refuses: the tool and the package must agree either way). An option the tool gains fails the
# test below until it is given one here.
OPTION_VALUES = {
    "input_kind": "raw", "columns": ["1", "2", "3"], "rate": 100, "time_unit": "s",
    "instance": 1, "topic": "acc", "frame_id": "imu", "temperature_column": "none",
    "window": 0.4, "min_static": 2, "threshold_factor": 12, "init_rest": 1, "gravity": 9.81,
    "latitude": 45.5, "height": 100, "units": "g", "model": "quadratic", "bias_model": "linear",
    "bias_random_walk": [1e-4], "noise": "no-such-noise.json", "thermal": "auto",
    "temperatures": [20], "method": "two-step", "init": "ellipsoid", "frame": "z-first",
    "estimator": "bias-corrected", "outliers": "flag", "outlier_probability": 0.01,
    "max_outliers": 2, "orientations": "no-such-orientations.csv", "gyro": "GYRO",
    "gyro_columns": ["1", "2", "3"], "gyro_topic": "gyr", "gyro_units": "rad/s",
    "gyro_model": "linear", "gyro_estimator": "two-stage", "gyro_thermal": "auto",
    "no_crossval": True, "raw_units": "counts", "max_iterations": 50, "date": "2026-11-29",
}


def outcome(function, *args, **kwargs):
    """What a call gives: ("file", its text with the command's name left out) or the error."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            value = function(*args, **kwargs)
        except (ValueError, OSError, RuntimeError) as e:
            return (type(e).__name__, str(e))
    text = value[0].to_json() if isinstance(value, tuple) else value.text
    return ("file", re.sub(r'"command": "[^"]*"', '"command": ""', text))


def test_calibrate_log_takes_every_option_of_the_tool():
    spec = accelcal.cli._command_spec("calibrate")
    options = {accelcal.cli._keyword_name(o["name"]) for o in accelcal.cli._parameters(spec)[1]}
    taken = set(inspect.signature(accelcal.calibrate_log).parameters) - {"input"}
    assert taken == options - set(accelcal._LOG_NOT_TAKEN)
    assert set(OPTION_VALUES) == taken
    gyro = XSENS.replace("xsens_acc.mat", "xsens_gyro.mat")
    for name, value in OPTION_VALUES.items():
        given = {"gravity": 9.81744}
        if name.startswith("gyro_"):
            given["gyro"] = gyro
        given[name] = gyro if value == "GYRO" else value
        expected = outcome(accelcal.cli.calibrate, XSENS, **given)
        got = outcome(accelcal.calibrate_log, XSENS, **given)
        if got == expected:
            continue
        if expected[0] == "DataError":  # the accelerometer's fit did not converge: a result
            assert "did not converge" in expected[1], name  # marked failed, not an exception
            assert got[0] == "file" and '"not_converged"' in got[1], name
        else:  # the library's DataError: the tool's exit status 3, its InputError
            assert got[0] == "DataError" and expected == ("InputError", got[1]), name
    # Where the tool's results go is the tool's: calibrate_log returns the calibration.
    for name in accelcal._LOG_NOT_TAKEN:
        with pytest.raises(TypeError, match=f"does not take '{name}'"):
            accelcal.calibrate_log(XSENS, **{name: "x.json"})
    with pytest.raises(TypeError, match="unexpected keyword argument 'gyro_colums'"):
        accelcal.calibrate_log(XSENS, gyro_colums=["4", "5", "6"])


def test_calibrate_log_keeps_its_old_names_with_a_deprecation_warning():
    new = outcome(accelcal.calibrate_log, XSENS, gravity=9.81744, window=0.4, min_static=2,
                  init_rest=1, no_crossval=True)
    with pytest.warns(DeprecationWarning) as caught:
        old = accelcal.calibrate_log(path=XSENS, gravity=9.81744, window_s=0.4, min_static_s=2,
                                     init_rest_s=1, cross_validate=False)
    assert outcome(lambda: old) == new
    assert {str(w.message).split("'")[1] for w in caught} == {
        "path", "window_s", "min_static_s", "init_rest_s", "cross_validate"}
    with pytest.warns(DeprecationWarning, match="by position"):
        by_position = accelcal.calibrate_log(XSENS, "quadratic", "joint", "x-first", 9.81744)
    # (the file's provenance records the options given: these four)
    assert without_provenance(by_position[0].to_json()) == without_provenance(
        accelcal.calibrate_log(XSENS, model="quadratic", gravity=9.81744)[0].to_json())
    # gravity in g, as it was given before: the tool's gravity in m/s2 and units="g".
    with pytest.warns(DeprecationWarning, match="in g is deprecated"):
        in_g = accelcal.calibrate_log(XSENS, gravity=1.0)[0]
    assert without_provenance(in_g.to_json()) == without_provenance(
        accelcal.calibrate_log(XSENS, units="g")[0].to_json())
    with pytest.raises(TypeError, match="both 'rate_hz' and 'rate'"):
        accelcal.calibrate_log(XSENS, rate=100, rate_hz=100)


def test_calibrate_log_keeps_what_the_file_holds_through_pickle(tmp_path):
    # The bias model chosen; two sessions pooled (the Xsens' positions in two files), in g: the
    # file the tool writes, before and after a pickle round trip.
    _, positions = accelcal.calibrate_log(XSENS, gravity=9.81744)
    sessions = [str(tmp_path / "first.csv"), str(tmp_path / "second.csv")]
    for name, half in zip(sessions, (positions[::2], positions[1::2])):
        np.savetxt(name, half, delimiter=",", header="x,y,z", comments="", fmt="%.17g")
    for args, given in (([XSENS], {"bias_model": "auto", "gravity": 9.81744}),
                        ([sessions], {"units": "g", "raw_units": "counts"})):
        expected = outcome(accelcal.cli.calibrate, *args, **given)
        result = accelcal.calibrate_log(*args, **given)[0]
        assert expected[0] == "file" and outcome(lambda: (result,)) == expected
        assert outcome(lambda: (pickle.loads(pickle.dumps(result)),)) == expected


def test_export_calibration_refuses_an_option_its_format_has_no_use_for():
    result, _ = accelcal.calibrate_log(XSENS, gravity=9.81744)
    text = result.to_json()
    # The library's rule, named as the keyword (the tool says --c-prefix).
    with pytest.raises(ValueError, match="^c_prefix is for c-header; px4 has no use for it$"):
        accelcal.export_calibration(text, "px4", c_prefix="imu")
    with pytest.raises(ValueError, match="^instance must be >= 0$"):
        accelcal.export_calibration(text, "ardupilot", instance=-1)
    with pytest.raises(ValueError, match="c_prefix must start with a letter"):
        accelcal.export_calibration(text, "c-header", c_prefix="1imu")
    assert "imu_K" in accelcal.export_calibration(text, "c-header", c_prefix="imu")["text"]


def test_calibrate_log_refuses_what_would_make_it_silently_wrong(tmp_path):
    # An empty value took the next option for its own ("--raw-units=" then "--model=quadratic").
    with pytest.raises(ValueError, match="^raw_units: an empty value"):
        accelcal.calibrate_log(XSENS, raw_units="", model="quadratic")
    # None leaves an option out, under its old name too; only a bool says whether to validate.
    assert accelcal.calibrate_log(XSENS, cross_validate=None)[0].crossval_rms is not None
    assert accelcal.calibrate_log(XSENS, rate_hz=None, window=0.5)[0].verdict == "ok"
    with pytest.raises(TypeError, match="cross_validate: True or False"):
        accelcal.calibrate_log(XSENS, cross_validate="no")
    # A list item holding the delimiter would be split into several.
    with pytest.raises(ValueError, match="holds ','"):
        accelcal.calibrate_log(XSENS, columns=["acc_x", "acc_y,acc_z"])
    # numpy's values as Python's: a bool flag, an array for a list, a float32 gravity in g.
    flagged = accelcal.calibrate_log(XSENS, gravity=9.81744, no_crossval=np.bool_(True))[0]
    assert flagged.crossval_rms is None
    with pytest.warns(DeprecationWarning, match="in g is deprecated"):
        in_g = accelcal.calibrate_log(XSENS, gravity=np.float32(1.0))[0]
    assert json.loads(in_g.to_json())["sensors"]["accelerometer"]["units"]["specific_force"] == "g"
    # A file name that is not UTF-8, and one that looks like an option, named as they are.
    _, positions = accelcal.calibrate_log(XSENS, gravity=9.81744)
    odd = os.path.join(os.fsencode(str(tmp_path)), b"\xff.csv")
    np.savetxt(odd.decode("utf-8", "surrogateescape"), positions, delimiter=",",
               header="x,y,z", comments="", fmt="%.17g")
    assert accelcal.calibrate_log(odd, gravity=9.81744)[0].verdict == "ok"
    with pytest.raises(accelcal.InputError, match="/--model.csv: cannot open"):
        accelcal.calibrate_log(str(tmp_path / "--model.csv"))
    # The screening's options named as the keywords, not as the library's fields.
    with pytest.raises(ValueError, match="^max_outliers must be non-negative$"):
        accelcal.calibrate(positions, max_outliers=-1)
    with pytest.raises(ValueError, match="^outlier_probability must be in"):
        accelcal.calibrate_log(XSENS, outlier_probability=2)
    # Positions that are not numbers are no calibration file.
    result, _ = accelcal.calibrate_log(XSENS, gravity=9.81744)
    with pytest.raises(ValueError, match="positions: row 0 is not finite"):
        result.to_json(positions=np.full_like(positions, np.nan))
