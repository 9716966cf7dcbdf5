"""accelcal.cli: every command of the tool as a function, against the tool itself.

The in-process runner gives the tool's bytes for every golden case (tests/golden, run with
--in-process by ctest); here the keyword arguments are checked: each function gives the numbers
the tool gives for the same options, its errors and warnings are the tool's, its stubs and
docstrings are complete."""
import json
import os
import pathlib
import pickle
import subprocess
import threading
import warnings

import numpy as np
import pytest

import accelcal
import accelcal.cli

DATA = pathlib.Path(os.environ.get("ACCELCAL_DATA_DIR", "data"))
CLI = os.environ.get("ACCELCAL_CLI", "accelcal")
XSENS = DATA / "imutk-xsens-mti" / "xsens_acc.mat"
XSENS_GYRO = DATA / "imutk-xsens-mti" / "xsens_gyro.mat"
CTU24 = DATA / "ctu-innalabs-ahrs-m3" / "measured_accelerations_24pos.csv"
FERRARIS = DATA / "imucal-ferraris"
GOLDEN_INPUTS = pathlib.Path(__file__).resolve().parents[2] / "tests" / "golden" / "inputs"


def tool(*args, cwd=None):
    """The tool's stdout for ARGS (status 0 or 6)."""
    r = subprocess.run([CLI, *map(str, args)], capture_output=True, cwd=cwd)
    assert r.returncode in (0, 6), r.stderr.decode()
    return r.stdout


def tool_json(*args):
    return json.loads(tool(*args, "--json"))


@pytest.fixture(scope="module")
def cal(tmp_path_factory):
    path = tmp_path_factory.mktemp("cli") / "xsens-imu.json"
    tool("calibrate", XSENS, "--gravity", "9.81744", "--gyro", XSENS_GYRO, "-o", path)
    return path


def test_every_command_is_a_function_with_the_tools_options():
    described = json.loads(subprocess.run([CLI, "--describe-options"], capture_output=True,
                                          check=True).stdout)
    names = {c["name"].replace("-", "_") for c in described["commands"]}
    assert names == set(accelcal.cli.__all__) - {"ToolWarning"}
    assert {"calibrate", "compare", "design", "montecarlo", "simulate", "gimbal",
            "system_level", "export", "report", "apply", "verify", "noise"} <= names
    for command in described["commands"]:
        function = getattr(accelcal.cli, command["name"].replace("-", "_"))
        import inspect
        parameters = inspect.signature(function).parameters
        for option in command["options"]:
            if option["name"] == "json":
                continue  # always given: the function returns the document
            name = option["name"].replace("-", "_").lower()
            assert name in parameters, (command["name"], name)
            assert f"\n{name}: " in function.__doc__, (command["name"], name)
        assert "--" not in function.__doc__.replace("--json", ""), function.__doc__


def test_the_stubs_are_the_description():
    stubs = pathlib.Path(accelcal.cli.__file__).with_name("cli.pyi").read_text()
    assert stubs == accelcal.cli._stubs()


# ---------------------------------------------------------------------------------------------
# The same numbers as the tool, option by option

def test_calibrate_with_every_kind_of_option_is_the_tools_file(tmp_path):
    cases = [
        ((XSENS,), dict(gravity=9.81744, gyro=XSENS_GYRO, raw_units="counts"),
         [XSENS, "--gravity", "9.81744", "--gyro", XSENS_GYRO, "--raw-units", "counts"]),
        ((CTU24,), dict(units="g", model="auto", estimator="bias-corrected", latitude=50.1,
                        height=300),
         [CTU24, "--units", "g", "--model", "auto", "--estimator", "bias-corrected",
          "--latitude", "50.1", "--height", "300"]),
        ((FERRARIS / "ferraris_raw_means.csv",),
         dict(orientations=FERRARIS / "ferraris_orientations.csv", raw_units="counts"),
         [FERRARIS / "ferraris_raw_means.csv", "--orientations",
          FERRARIS / "ferraris_orientations.csv", "--raw-units", "counts"]),
        ((DATA / "imutk-t265" / "t265_acc.mat",), dict(model="quadratic", gravity=9.8016),
         [DATA / "imutk-t265" / "t265_acc.mat", "--model", "quadratic", "--gravity", "9.8016"]),
        # A double that needs all 17 digits goes through exactly.
        ((XSENS,), dict(gravity=9.817441234567891, no_crossval=True, outliers="flag",
                        frame="z-first"),
         [XSENS, "--gravity", "9.817441234567891", "--no-crossval", "--outliers", "flag",
          "--frame", "z-first"]),
    ]
    for args, options, argv in cases:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = accelcal.cli.calibrate(*args, **options)
        # The provenance names the options as given: --name=value here, --name value there.
        want = json.loads(tool("calibrate", *argv, "--json"))
        got = json.loads(result.text)
        for doc in (want, got):
            doc["provenance"]["options"] = sorted(doc["provenance"]["options"].items())
        assert got == want, argv
        np.testing.assert_array_equal(result.K, np.array(want["sensors"]["accelerometer"]["K"]))
        assert pickle.loads(pickle.dumps(result)).text == result.text


def test_several_inputs_and_a_report_and_a_file(tmp_path):
    a = tmp_path / "a.csv"
    b = tmp_path / "b.csv"
    a.write_text(tool("simulate", "--scenario", "yang2012", "--seed", "1").decode())
    b.write_text(tool("simulate", "--scenario", "yang2012", "--seed", "2").decode())
    out = tmp_path / "py.json"
    report = tmp_path / "py.html"
    result = accelcal.cli.calibrate([a, b], output=out, report=report, date="2026-11-28")
    assert out.read_text() == result.text
    want = tool("calibrate", a, b, "--date", "2026-11-28", "--json").decode()
    assert json.loads(want)["sensors"] == json.loads(result.text)["sensors"]
    assert report.read_text().startswith("<!DOCTYPE html>")


@pytest.mark.parametrize("name, function, kwargs, argv", [
    ("compare", "compare", dict(methods=["joint", "two-step"], model="quadratic"),
     ["--methods", "joint,two-step", "--model", "quadratic"]),
    ("detect", "detect", dict(window=0.25, threshold_factor=8.0),
     ["--window", "0.25", "--threshold-factor", "8"]),
    ("noise", "noise", dict(still=True), ["--still"]),
])
def test_log_commands_give_the_tools_document(name, function, kwargs, argv):
    path = CTU24 if name == "compare" else XSENS
    got = getattr(accelcal.cli, function)(path, **kwargs)
    assert got == tool_json(name, path, *argv)


def test_design_montecarlo_simulate_and_the_platform(cal, tmp_path):
    assert accelcal.cli.design(positions="yang18", device=cal, noise=[1.0]) == tool_json(
        "design", "--positions", "yang18", "--device", cal, "--noise", "1")
    assert accelcal.cli.design(positions="yang18", device=cal, noise=[1.0, 2.0, 3.0],
                               temperatures=[10, 25, 40]) == tool_json(
        "design", "--positions", "yang18", "--device", cal, "--noise", "1,2,3",
        "--temperatures", "10,25,40")
    # A plan that determines nothing raises, and says why.
    with pytest.raises(accelcal.InputError, match="these positions do not determine parameter"):
        accelcal.cli.design(positions="six", device=cal, noise=0.1)
    assert accelcal.cli.montecarlo(runs=20, seed=7, threads=2) == tool_json(
        "montecarlo", "--runs", "20", "--seed", "7", "--threads", "2")
    assert accelcal.cli.simulate(scenario="sunxu2020", seed=3) == tool(
        "simulate", "--scenario", "sunxu2020", "--seed", "3").decode()
    ulog = accelcal.cli.simulate(scenario="yang2012", raw=True, format="ulog", duration=2.0)
    assert isinstance(ulog, bytes) and ulog == tool(
        "simulate", "--scenario", "yang2012", "--raw", "--format", "ulog", "--duration", "2")
    coarse = GOLDEN_INPUTS / "coarse.csv"
    fine = GOLDEN_INPUTS / "fine.csv"
    assert accelcal.cli.gimbal(coarse, fine=fine, latitude=40) == tool_json(
        "gimbal", coarse, "--fine", fine, "--latitude", "40")


def test_the_documents_tables_are_the_tools_numbers(cal, tmp_path):
    import pandas
    compared = accelcal.cli.compare(XSENS, gravity=9.81744)
    assert compared == tool_json("compare", XSENS, "--gravity", "9.81744")
    frame = compared.to_frame()
    assert list(frame.index) == [m["method"] for m in compared["methods"]]
    np.testing.assert_array_equal(frame["parameters_K_xx"].to_numpy(),
                                  [m["parameters"]["K_xx"] for m in compared["methods"]])
    # A design's parameters: each one's 1 sigma, the square root of the bound's diagonal, is
    # the document's own std of that parameter.
    design = accelcal.cli.design(positions="yang18", device=cal, noise=10, choose=12)
    assert design.tables == ["parameters", "crlb", "chosen"]
    std = design.to_frame()["std"]
    assert std["K_xx"] == pytest.approx(design["std"]["K"][0][0], rel=1e-12)
    assert std["b_z"] == pytest.approx(design["std"]["bias"][2], rel=1e-12)
    crlb = design.to_frame("crlb")
    assert list(crlb.index) == list(crlb.columns) == design["parameter_order"]
    assert len(design.to_frame("chosen")) == 12
    # The noise's terms: five per axis; its Allan deviation, one row per axis and time.
    noise = accelcal.cli.noise(XSENS, still=True)
    terms = noise.to_frame()
    assert len(terms) == 15 and set(terms["term"]) == {
        "quantization", "white", "bias_instability", "random_walk", "rate_ramp"}
    allan = noise.to_frame("allan")
    assert len(allan) == sum(len(a["allan"]) for a in noise["accelerometer"]["axes"])
    # A batch's units are summary.csv's rows, the same numbers.
    batch = accelcal.cli.batch([CTU24, XSENS], output=tmp_path / "batch", no_report=True,
                               gravity=9.81744)
    frame = batch.to_frame()
    csv = pandas.read_csv(tmp_path / "batch" / "summary.csv", index_col="unit",
                          float_precision="round_trip")
    assert list(frame.index) == list(csv.index) == ["measured_accelerations_24pos", "xsens_acc"]
    quantities = [c for c in csv.columns if c.startswith("accelerometer.")]
    assert len(quantities) > 20
    np.testing.assert_array_equal(frame[quantities].to_numpy(dtype=float),
                                  csv[quantities].to_numpy(dtype=float))
    assert list(frame.columns) == list(csv.columns)
    for text in ("status", "failed", "files", "verdict", "worst_finding", "message", "sha256"):
        assert list(frame[text].fillna("")) == list(csv[text].fillna("")), text
    # store get gives the calibration stored, as calibrate does.
    accelcal.cli.store("add", tmp_path / "store", tmp_path / "batch")
    got = accelcal.cli.store("get", tmp_path / "store", "xsens_acc")
    assert isinstance(got, accelcal.Calibration)
    assert got.text == (tmp_path / "batch" / "units" / "xsens_acc" / "calibration.json").read_text()
    # A command's document that has no table says so.
    with pytest.raises(KeyError, match="has no table"):
        accelcal.cli.gimbal(GOLDEN_INPUTS / "coarse.csv").to_frame()


def test_the_calibration_file_commands(cal, tmp_path):
    log = tmp_path / "log.csv"
    log.write_text(tool("simulate", "--scenario", "yang2012", "--raw", "--duration", "3").decode())
    assert accelcal.cli.export(cal, to="yaml") == tool("export", cal, "--to", "yaml").decode()
    # The Xsens's counts are no unit PX4 takes, nor m/s2 when said to be (issue 47): refused by
    # both, with the same reason.
    for unit, reason in ((None, "calibrate readings in m/s2 or g"),
                         ("m/s2", "does not fit these readings")):
        given = ["--raw-unit", unit] if unit else []
        refused = subprocess.run([CLI, "export", cal, "--to", "px4", *given], capture_output=True)
        assert refused.returncode == 3 and reason.encode() in refused.stderr, refused.stderr
        with pytest.raises(accelcal.InputError, match=reason):
            accelcal.cli.export(cal, to="px4", **({"raw_unit": unit} if unit else {}))
    assert accelcal.cli.report(cal) == tool("report", cal).decode()
    assert accelcal.cli.apply(cal, log) == tool("apply", cal, log).decode()
    corrected = tmp_path / "corrected.csv"
    assert accelcal.cli.apply(cal, log, output=corrected) is None
    assert corrected.read_bytes() == tool("apply", cal, log)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        got = accelcal.cli.verify(cal, XSENS, gyro=XSENS_GYRO)
    assert got == tool_json("verify", cal, XSENS, "--gyro", XSENS_GYRO)


def test_inspect_reads_a_binary_log():
    ulog = next((DATA / "px4-ulog").glob("*.ulg"))
    assert accelcal.cli.inspect(ulog) == tool_json("inspect", ulog)


# ---------------------------------------------------------------------------------------------
# Errors and warnings, as the tool's, in Python's words

def test_errors_are_raised_as_the_tools_exit_status_says(tmp_path):
    with pytest.raises(ValueError, match=r"^gravity excludes latitude \(see help\(accelcal.cli"):
        accelcal.cli.calibrate(XSENS, gravity=9.8, latitude=40)
    with pytest.raises(ValueError, match=r"model: 'cubic' is not|model"):
        accelcal.cli.calibrate(XSENS, model="cubic")
    with pytest.raises(accelcal.InputError, match="no-such.csv: cannot open"):
        accelcal.cli.calibrate(tmp_path / "no-such.csv")
    with pytest.raises(TypeError, match="unexpected keyword argument 'gravty'"):
        accelcal.cli.calibrate(XSENS, gravty=9.8)
    with pytest.raises(TypeError, match="missing the argument 'input'"):
        accelcal.cli.calibrate()
    with pytest.raises(TypeError, match="no_crossval: True or False"):
        accelcal.cli.calibrate(XSENS, no_crossval="yes")
    with pytest.raises(ValueError, match="columns: an empty list"):
        accelcal.cli.calibrate(XSENS, columns=[])
    # A value that starts with a dash is a value, not an option.
    with pytest.raises(ValueError, match="latitude"):
        accelcal.cli.calibrate(XSENS, latitude=-95.0)


def test_the_tools_warnings_are_python_warnings():
    with pytest.warns(accelcal.cli.ToolWarning, match="gravity is 99 m/s2"):
        accelcal.cli.calibrate(XSENS, gravity=99.0)


def test_a_failed_calibration_is_returned_with_a_warning():
    # The T265's gyroscope under the two-stage linear model: its turns do not fit (golden case
    # cal-t265-gyro-two-stage, exit status 6).
    t265 = DATA / "imutk-t265"
    options = dict(gravity=9.8016, gyro=t265 / "t265_gyr.mat", gyro_units="rad/s",
                   gyro_estimator="two-stage", gyro_model="linear")
    with pytest.warns(accelcal.CalibrationCheckFailed, match="failed check") as caught:
        result = accelcal.cli.calibrate(t265 / "t265_acc.mat", **options)
    assert result.verdict == "failed"
    failed = [w.message for w in caught if isinstance(w.message, accelcal.CalibrationCheckFailed)]
    assert failed[0].result is result


def test_commands_run_concurrently_in_threads(tmp_path):
    outputs = [None] * 4

    def run(i):
        outputs[i] = accelcal.cli.compare(CTU24, methods=["joint", "modulus"])

    threads = [threading.Thread(target=run, args=(i,)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert outputs == [tool_json("compare", CTU24, "--methods", "joint,modulus")] * 4


def test_batch_returns_the_summary_and_warns_of_the_units_that_failed(tmp_path):
    line = tmp_path / "line"
    line.mkdir()
    (line / "SN1.csv").write_bytes(CTU24.read_bytes())
    (line / "SN2.csv").write_text("x,y,z\n1,2,3\n")  # too few positions: an error, not a stop
    limits = tmp_path / "limits.yaml"
    limits.write_text("format: accelcal-limits\nversion: 1\nunits: {specific_force: g}\n"
                      "limits:\n  accelerometer.heldout_rms: {max: 0.01}\n")
    with pytest.warns(accelcal.CalibrationCheckFailed, match="1 could not be calibrated"):
        doc = accelcal.cli.batch(line, output=tmp_path / "out", limits=limits, units="g", jobs=2)
    assert doc["counts"] == {"units": 2, "pass": 1, "fail": 0, "error": 1}
    assert [u["status"] for u in doc["units"]] == ["pass", "error"]
    assert doc == json.loads((tmp_path / "out" / "summary.json").read_text())
    # The tool's own bytes, from the same options.
    tool("batch", line, "-o", tmp_path / "tool", "--limits", limits, "--units", "g")
    for name in ("summary.json", "summary.csv", "units/SN1/calibration.json"):
        assert (tmp_path / "tool" / name).read_bytes() == (tmp_path / "out" / name).read_bytes()
