"""The library under a host program's decimal-comma locale (issue 16): a Python program that calls
locale.setlocale(locale.LC_NUMERIC, "de_DE.UTF-8"), as GUIs do, gets the same files and the same
numbers from accelcal. The locale must be installed (scripts/install-deps.sh generates it): without
it the test fails, it does not skip."""

import contextlib
import json
import re
import locale
import os

import numpy as np

import accelcal

DATA = os.environ["ACCELCAL_DATA_DIR"]
XSENS = os.path.join(DATA, "imutk-xsens-mti", "xsens_acc.mat")
T265 = os.path.join(DATA, "imutk-t265", "t265_acc.mat")
FORMATS = ["json", "yaml", "kalibr", "px4", "ardupilot", "c-header", "imutk"]


@contextlib.contextmanager
def decimal_comma():
    previous = locale.setlocale(locale.LC_NUMERIC)
    locale.setlocale(locale.LC_NUMERIC, "de_DE.UTF-8")  # locale.Error when it is not installed
    try:
        # The premise: C's printf (which Python's locale module uses) writes a decimal comma now.
        assert locale.localeconv()["decimal_point"] == ","
        assert locale.format_string("%.1f", 0.5) == "0,5"
        yield
    finally:
        locale.setlocale(locale.LC_NUMERIC, previous)


def exports(text):
    # The T265's readings are in m/s2: PX4 and ArduPilot take its calibration, with scales of
    # 0.99... and offsets of 0.0... (the INS_ACCSCAL_X,0,000208474897 had a comma).
    return {f: accelcal.export_calibration(text, f) for f in FORMATS}


def test_exports_file_and_report_are_the_same_bytes_in_a_decimal_comma_locale():
    data = accelcal.read_input(XSENS)
    result, positions = accelcal.calibrate_log(XSENS, gravity=9.81744)
    text = result.to_json(positions, raw_units="counts", source="xsens_acc.mat")
    t265, t265_positions = accelcal.calibrate_log(T265, gravity=9.8016)
    t265_text = t265.to_json(t265_positions, raw_units="m/s2", source="t265_acc.mat")
    before = exports(t265_text)
    html = accelcal.render_report(text, data["samples"], data["time"])
    with decimal_comma():
        after = exports(t265_text)
        text_after = result.to_json(positions, raw_units="counts", source="xsens_acc.mat")
        html_after = accelcal.render_report(text, data["samples"], data["time"])
        loaded = accelcal.parse_calibration_json(text)
    assert after == before
    assert re.search(r"\nINS_ACCSCAL_X,[01]\.[0-9]+\n", after["ardupilot"]["text"])
    assert re.search(r"\t1\tCAL_ACC0_XSCALE\t[01]\.[0-9]+\t9\n", after["px4"]["text"])
    assert text_after == text
    assert html_after == html
    np.testing.assert_array_equal(loaded.K, result.K)
    np.testing.assert_array_equal(loaded.bias, result.bias)


def test_calibrating_in_a_decimal_comma_locale_gives_the_same_numbers_and_findings():
    result, positions = accelcal.calibrate_log(XSENS, gravity=9.81744, model="auto")
    with decimal_comma():
        comma, comma_positions = accelcal.calibrate_log(XSENS, gravity=9.81744, model="auto")
    np.testing.assert_array_equal(comma_positions, positions)  # the log read with its points
    np.testing.assert_array_equal(comma.K, result.K)
    np.testing.assert_array_equal(comma.bias, result.bias)
    np.testing.assert_array_equal(comma.covariance, result.covariance)
    assert comma.diagnostics == result.diagnostics
    messages = " ".join(f["message"] for f in result.diagnostics)
    assert "scatter 3.07 times" in messages  # the means' noise from batch means (position_noise.hpp)
    selection = json.loads(result.to_json())["sensors"]["accelerometer"]["model_selection"]["reason"]
    assert json.loads(comma.to_json())["sensors"]["accelerometer"]["model_selection"]["reason"] == selection
    assert "held-out rms |f|-g 0.0" in selection
    # The whole file, the solvers' termination messages included ("|dtheta|_s = 1.363e-15", not
    # "1,363e-15"); the brief report (its timing differs from run to run) has no decimal comma.
    assert comma.to_json() == result.to_json()
    assert re.search(r"\d,\d", comma.summary["brief_report"]) is None, comma.summary
    assert "J " in comma.summary["brief_report"]


def test_the_tools_commands_in_a_decimal_comma_locale(tmp_path):
    """accelcal.cli runs the tool's code in this process: its options are read (CLI11) and its
    numbers written in "C" whatever the host's locale."""
    import warnings
    before = accelcal.cli.calibrate(XSENS, gravity=9.81744, model="auto").text
    device = tmp_path / "device.json"
    device.write_text(before)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with decimal_comma():
            after = accelcal.cli.calibrate(XSENS, gravity=9.81744, model="auto").text
            accelcal.cli.calibrate(XSENS, gravity=99.5)
            design = accelcal.cli.design(positions="yang18", device=device, noise=[0.5])
    assert after == before
    assert any("gravity is 99.5 m/s2" in str(w.message) for w in caught), caught
    assert design == accelcal.cli.design(positions="yang18", device=device, noise=[0.5])
