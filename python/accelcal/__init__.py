"""accelcal: calibration of triaxial accelerometers from static multi-position recordings.

The C++ library's API under the same names in snake_case (``calibrate``, ``read_input``,
``detect_static_intervals``, ``diagnose``, ``export_calibration``, ``render_report``), numpy arrays
for readings (n x 3) and matrices, and the library's errors as ``InputError`` / ``DataError``
(both ``ValueError``) with the command-line tool's messages. ``calibrate_log`` is
``accelcal calibrate LOG``: the same reading, detection, fit and diagnosis, the same doubles.

Never silently wrong: every ``CalibrationResult`` from ``calibrate`` and ``calibrate_log``
carries its diagnosis (diagnosis.hpp, docs/diagnostics.md), as the calibration file does:

- ``result.verdict``: ``"ok"`` (notes at most), ``"warnings"`` or ``"failed"``;
- ``result.diagnostics``: the findings, failures first, then warnings, then notes, each a dict
  ``{"code", "severity", "message", "numbers"}`` (``numbers`` a dict of floats).

Position numbers count from 1 everywhere, as in the calibration file, the messages and the
command line: ``result.outliers[i]["position"]``, a gyroscope turn's ``from`` and ``to``,
``model_selection["positions_used"]``. Rows of numpy arrays are indexed from 0 as always, so
position k is row k - 1 of ``positions``. Sample indices (``first_sample``, a detection's
``begin``) are 0-based offsets into the log, as in the file.

Results pickle (``CalibrationResult`` exactly, every double's bits; ``Calibration`` as its file's
text), print their parameters with ``repr``, and take file names as ``str`` or ``os.PathLike``.
The long computations release the GIL, so threads calibrate concurrently.

``calibrate_log`` still returns ``(result, positions)``, so the diagnosis rides on the result
rather than on a new return type: old code keeps working, and the verdict cannot be lost by
unpacking. Where the command line exits with status 6 (a result that failed its checks, written
but marked ``"verdict": "failed"``), Python returns the result with ``verdict == "failed"`` and
emits a ``CalibrationCheckFailed`` warning naming the failed checks; it raises nothing, so the
result stays available to see why. To make it an exception::

    warnings.simplefilter("error", accelcal.CalibrationCheckFailed)

(the exception raised is the warning itself: its ``result`` attribute holds the calibration).
Each warning-severity finding is emitted as a ``CalibrationWarning``; notes are not emitted.
The two categories are separate ``UserWarning`` subclasses, so silencing the warnings never
silences a failure. ``diagnose(result, ...)`` computes the diagnosis again (other units, other
positions, or a raw log and detection from arrays) and only returns it.
"""

import warnings as _warnings

import numpy as _np

from ._accelcal import (  # noqa: F401
    Calibration,
    CalibrationResult,
    DataError,
    InputError,
    __version__,
    export_calibration,
    load_calibration,
    parse_calibration_json,
    render_report,
)
from . import _accelcal
from . import _frames
from ._frames import Document

__all__ = [
    "Calibration", "CalibrationCheckFailed", "CalibrationResult", "CalibrationWarning", "cli",
    "DataError", "Document", "InputError", "__version__", "apply", "calibrate", "calibrate_log",
    "detect_static_intervals", "diagnose", "export_calibration", "load_calibration",
    "parse_calibration_json", "read_input", "render_report",
]


def _entry(value, std):
    """'value' or 'value ± std' in 7 significant digits (std in 2)."""
    text = f"{value + 0.0:.7g}"  # + 0.0: a fixed zero printed as 0, not -0
    return text if std is None or not _np.isfinite(std) else f"{text} ± {std:.2g}"


def _parameter_lines(names, K, bias, k2, covariance, model, units, raw):
    """The parameters with their 1 sigma, one matrix row per line."""
    std = {}
    if covariance is not None:
        std = dict(zip(names, _np.sqrt(_np.clip(_np.diag(covariance), 0, None))))
    axes = "xyz"
    rows = [[_entry(K[i, j], std.get(f"K_{axes[i]}{axes[j]}")) for j in range(3)]
            for i in range(3)]
    width = max(len(e) for row in rows for e in row)
    lines = [f"  K [{raw} per {units}] =" if raw else f"  K [raw per {units}] ="]
    lines += ["    [" + "  ".join(e.rjust(width) for e in row) + "]" for row in rows]
    lines.append(f"  bias [{raw or 'raw'}] = [" + ", ".join(
        _entry(bias[i], std.get(f"b_{axes[i]}")) for i in range(3)) + "]")
    if model == "quadratic":
        lines.append(f"  k2 [raw per ({units})^2] = [" + ", ".join(
            _entry(k2[i], std.get(f"k2_{axes[i]}")) for i in range(3)) + "]")
    return lines


def _result_repr(self):
    lines = [f"<accelcal.CalibrationResult: {self.model} model, {len(self.directions)} positions, "
             f"verdict {self.verdict!r}" + (f", from {self.source!r}" if self.source else "")]
    lines += _parameter_lines(self.parameter_names, self.K, self.bias, self.k2, self.covariance,
                              self.model, self.units, None)
    if self.crossval_rms is not None:
        lines.append(f"  held-out RMS of |f| - g = {self.crossval_rms:.4g} {self.units}")
    if self.gyroscope is not None:
        g = self.gyroscope
        std = dict(zip(g["parameter_names"], g["std"])) if g["std"] is not None else {}
        lines.append(f"  gyroscope: {g['model']} model, {len(g['rotations'])} turns")
        lines.append("    K diagonal [raw per rad/s] = [" + ", ".join(
            _entry(g["K"][i, i], std.get(f"Kg_{a}{a}")) for i, a in enumerate("xyz")) + "]")
        lines.append("    bias [raw] = [" + ", ".join(
            _entry(g["bias"][i], std.get(f"bg_{a}")) for i, a in enumerate("xyz")) + "]")
        if _np.isfinite(g["heldout_rms_deg"]):
            lines.append(f"    held-out RMS of the turns = {g['heldout_rms_deg']:.3g} deg")
    return "\n".join(lines) + ">"


def _calibration_repr(self):
    lines = [f"<accelcal.Calibration: {self.model} model, verdict {self.verdict or 'unknown'!r}"
             + (f", of {self.source!r}" if self.source else "")]
    lines += _parameter_lines(self.parameter_names, self.K, self.bias, self.k2, self.covariance,
                              self.model, self.units, self.raw_units if self.raw_units != "raw"
                              else None)
    if self.has_gyroscope:
        lines.append("  gyroscope: calibrated too (sensors.gyroscope of text)")
    return "\n".join(lines) + ">"


def _result_to_frame(self):
    """The positions as a pandas DataFrame, indexed by position number (from 1): each one's mean
    reading, samples, noise, interval, fitted direction, residual, |f| - g and held-out error,
    as the calibration file holds them (``to_json()``)."""
    return _frames.positions_frame(self.to_json())


def _calibration_to_frame(self):
    """The file's positions as a pandas DataFrame, indexed by position number (from 1)."""
    return _frames.positions_frame(self.text)


def _restore_result(state):
    """A CalibrationResult from its pickled state (what pickle calls: a function of the package,
    found by its name)."""
    return _accelcal._result_from_state(state)


def _restore_calibration(text, source):
    """A Calibration from its pickled state, its file's text and name."""
    return parse_calibration_json(text, source)


CalibrationResult.__repr__ = _result_repr
CalibrationResult.to_frame = _result_to_frame
Calibration.to_frame = _calibration_to_frame
Calibration.__repr__ = _calibration_repr


class CalibrationWarning(UserWarning):
    """A warning of a calibration's diagnosis: the result stands, but look at this
    (``finding`` holds the finding's dict, ``result`` the calibration)."""


class CalibrationCheckFailed(UserWarning):
    """The calibration failed its checks (``result.verdict == "failed"``): do not use it as it is.
    ``result`` holds the calibration and ``findings`` the failed findings (dicts). Turn it into an
    exception with ``warnings.simplefilter("error", accelcal.CalibrationCheckFailed)``."""


def _emit_diagnosis(result, source, stacklevel):
    """Warns of the result's warning-severity findings (CalibrationWarning, one each) and, when it
    failed, once of its failures (CalibrationCheckFailed). Notes are not emitted."""
    prefix = f"{source}: " if source else ""
    failures = []
    for finding in result.diagnostics:
        if finding["severity"] == "failure":
            failures.append(finding)
        elif finding["severity"] == "warning":
            w = CalibrationWarning(f"{prefix}{finding['message']} [{finding['code']}]")
            w.finding, w.result = finding, result
            _warnings.warn(w, stacklevel=stacklevel + 1)
    if failures:
        checks = "; ".join(f"{f['code']}: {f['message']}" for f in failures)
        w = CalibrationCheckFailed(
            f"{prefix}the calibration failed its checks (result.verdict == 'failed'); do not use "
            f"it as it is. {checks}")
        w.findings, w.result = failures, result
        _warnings.warn(w, stacklevel=stacklevel + 1)


def apply(calibration, readings):
    """Corrected specific force (n x 3) of raw readings (n x 3) under a calibration."""
    return calibration.apply(readings)


def calibrate(readings, model="linear", method="joint", frame="x-first", gravity=9.80665,
              estimator="ml", reading_sigmas=None, cross_validate=True, outliers="exclude", *,
              outlier_probability=1e-3, max_outliers=3, units=None, max_iterations=0):
    """Calibrates from averaged readings (m x 3), one per static position, and diagnoses the result.

    model: "linear", "quadratic" or "auto" (the quadratic model kept only when its held-out error
    is lower on evidence, model_selection.hpp; needs cross_validate); a quadratic fit with
    cross_validate is compared with the linear one (``result.model_selection``), as the command
    line does. gravity: the gravity magnitude in ``units``. reading_sigmas: the 1 sigma per axis of
    each averaged reading (m x 3) when known (else the noise comes from the residuals).
    outliers: "exclude", "flag" or "off", the screening of positions that disagree with the others
    (``outlier_probability``: the chance that a calibration whose positions all agree loses one;
    ``max_outliers``: the most positions it may leave out, the command line's --max-outliers).
    units: "m/s2" or "g", the unit of ``gravity`` and of the calibrated specific force, for the
    diagnosis and the file; None: "g" when gravity is below 2, else "m/s2". max_iterations: the
    solver's iteration cap (0: its default).

    Returns a ``CalibrationResult`` carrying ``verdict`` and ``diagnostics``; emits a
    ``CalibrationWarning`` per warning and a ``CalibrationCheckFailed`` when the verdict is
    "failed" (a solver that did not converge, readings that miss gravity: see the module
    docstring). Raises DataError when the readings cannot determine the model (too few, degenerate,
    non-finite) and ValueError for invalid options.
    """
    result = _accelcal.calibrate(
        readings, model, method, frame, gravity, estimator, reading_sigmas, cross_validate,
        outliers, outlier_probability=outlier_probability, max_outliers=max_outliers, units=units,
        max_iterations=max_iterations)
    _emit_diagnosis(result, None, stacklevel=2)
    return result


def calibrate_log(path, model="linear", method="joint", frame="x-first", gravity=9.80665,
                  estimator="ml", columns=(), rate_hz=None, window_s=0.5, min_static_s=1.0,
                  threshold_factor=10.0, init_rest_s=0.0, cross_validate=True, *,
                  outliers="exclude", outlier_probability=1e-3, max_outliers=3, units=None,
                  time_unit="auto", instance=None, input_kind="auto", max_iterations=0,
                  gyro=None, gyro_columns=(), gyro_units="raw", gyro_model="auto",
                  gyro_estimator=None, topic=None, frame_id=None):
    """What ``accelcal calibrate LOG`` does: read, detect the static intervals, average them,
    calibrate with each interval's noise and diagnose (the time column, still periods not used,
    interleaved sensors, the fit). Gives exactly the command line's doubles and diagnosis; with
    the defaults ``result.to_json()`` is the text of ``accelcal calibrate LOG --json``.

    Returns ``(result, positions)``: positions the (m x 3) averaged readings, in the order of the
    result's directions and residuals; ``result.verdict`` and ``result.diagnostics`` the
    diagnosis. Warnings and a failed verdict are emitted as for ``calibrate`` (prefixed with the
    path); nothing is raised for a failed verdict.

    Options as ``calibrate`` (gravity in ``units``: "m/s2", "g" or None for "g" below 2), and as
    the command line's: columns (--columns: 3 or 4 column numbers from 1 or header names, a list
    or one comma-separated string), topic (--topic: the stream of a binary log, a ULog topic or
    DataFlash message, or a MAT-file's variable), frame_id (--frame-id: of a ROS topic on which
    several sensors publish, the header.frame_id whose messages to read), rate_hz
    (--rate), time_unit ("auto", "s", "ms", "us", "ns": --time-unit; "auto" decides from the
    column's name and step, time_axis.hpp), instance (--instance: the sensor to keep of a file
    whose instance column holds several), input_kind ("auto", the default as on the command
    line, "raw" or "positions": a positions file is calibrated as it is), window_s, min_static_s, threshold_factor, init_rest_s (detection),
    max_iterations (--max-iterations). Raises InputError (unreadable or malformed file) or
    DataError (no static interval, too few positions), both naming the file.

    ``path`` and ``gyro`` are str, bytes or os.PathLike; ``"-"`` reads this process's standard
    input, as the tool does.

    One difference from the tool: a solver that does not converge is returned as a result whose
    verdict is "failed" (with a ``CalibrationCheckFailed`` warning naming ``not_converged``), so
    that it can be looked at, where ``accelcal calibrate`` writes nothing and exits with status 4
    (``accelcal.cli.calibrate`` raises ``DataError`` there).

    The gyroscope recorded through the same positions (``calibrate --gyro``): ``gyro`` its log
    on the same clock, or ``gyro_columns`` its columns in this log (or in ``gyro``'s);
    ``gyro_units`` ("raw", "rad/s", "deg/s"), ``gyro_model`` ("auto", "linear",
    "g-sensitive"), ``gyro_estimator`` ("joint", the default, or "two-stage"). Then
    ``result.gyroscope`` is its calibration (a dict; None without), the result's accelerometer
    is the joint fit's, the diagnosis judges both, and ``result.to_json()`` holds both sensors,
    as ``accelcal calibrate LOG --gyro ... --json`` writes them.
    """
    result, positions = _accelcal.calibrate_log(
        path, model, method, frame, gravity, estimator, columns, rate_hz, window_s,
        min_static_s, threshold_factor, init_rest_s, cross_validate, outliers=outliers,
        outlier_probability=outlier_probability, max_outliers=max_outliers, units=units,
        time_unit=time_unit, instance=instance, input_kind=input_kind,
        max_iterations=max_iterations,
        gyro=gyro, gyro_columns=gyro_columns,
        gyro_units=gyro_units, gyro_model=gyro_model, gyro_estimator=gyro_estimator, topic=topic,
        frame_id=frame_id)
    _emit_diagnosis(result, result.source, stacklevel=2)
    return result, positions


def diagnose(result, positions=None, units=None, samples=None, time=None, rate_hz=None,
             time_unit="s", detection=None, max_outliers=None):
    """The diagnosis of a calibration (diagnosis.hpp), computed again; emits no warning.

    result: a CalibrationResult of ``calibrate`` or ``calibrate_log``. positions: the averaged
    readings it was fitted to (m x 3, the result's order; default: those it was fitted to).
    units: "m/s2" or "g", the unit of the result's gravity (default: the result's). samples
    (n x 3), time (n, seconds unless ``time_unit`` says otherwise) or rate_hz: the raw log, for
    the time column's findings (unit, gaps, irregular sampling) and, with ``detection`` (the dict
    of ``detect_static_intervals``), for interleaved sensors; detection alone gives the findings
    of still periods not used. max_outliers: the screening's limit (default: the result's).

    Returns ``{"verdict": "ok" | "warnings" | "failed", "diagnostics": [finding, ...]}``, each
    finding a dict ``{"code", "severity", "message", "numbers"}``; position numbers in messages
    and numbers count from 1.
    """
    return _accelcal.diagnose(result, positions, units, samples, time, rate_hz, time_unit,
                              detection, max_outliers)


def _bound_doc(function, returns):
    """The library function's docstring without pybind11's signature line, and what the
    Python function returns."""
    doc = function.__doc__ or ""
    first, _, rest = doc.partition("\n")
    return (rest.strip() if first.startswith(function.__name__ + "(") else doc) + "\n\n" + returns


def read_input(path, kind="auto", columns=(), rate_hz=None, *, time_unit="auto", instance=None,
               topic=None, frame_id=None):
    return Document(_accelcal.read_input(path, kind, columns, rate_hz, time_unit=time_unit,
                                         instance=instance, topic=topic, frame_id=frame_id),
                    "readings")


read_input.__doc__ = _bound_doc(
    _accelcal.read_input,
    "The dict is a ``Document``: ``to_frame()`` gives a raw log's samples as a pandas DataFrame "
    "(columns time_s, x, y, z; rows indexed by sample from 0) or a positions file's positions "
    "(x, y, z, samples, std_x, std_y, std_z; indexed by position from 1).")


def detect_static_intervals(samples, time=None, rate_hz=None, window_s=0.5, min_static_s=1.0,
                            threshold_factor=10.0, init_rest_s=0.0, *, time_unit="s"):
    return Document(_accelcal.detect_static_intervals(
        samples, time, rate_hz, window_s, min_static_s, threshold_factor, init_rest_s,
        time_unit=time_unit), "detection")


detect_static_intervals.__doc__ = _bound_doc(
    _accelcal.detect_static_intervals,
    "The dict is a ``Document``: ``to_frame()`` gives the intervals as a pandas DataFrame (one "
    "row per interval, numbered from 1; mean and std as _x, _y, _z), ``to_frame('rejected')`` "
    "the rejected ones.")


from . import cli  # noqa: E402 - every command of the tool (it uses the names above)
