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

import numbers as _numbers
import os as _os
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
    gyro = getattr(result, "gyroscope", None)
    gyro_prefix = f"{gyro['source']}: " if gyro and gyro.get("source") else prefix
    failures = []
    for finding in result.diagnostics:
        if finding["severity"] == "failure":
            failures.append(finding)
        elif finding["severity"] == "warning":
            about = gyro_prefix if finding["code"].startswith("gyro_") else prefix
            w = CalibrationWarning(f"{about}{finding['message']} [{finding['code']}]")
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


# calibrate_log's arguments before it took accelcal.cli.calibrate's names, still accepted with a
# DeprecationWarning: its positional parameters after the path, and its renamed keywords
# (cross_validate=False is now no_crossval=True).
_LOG_LEGACY_POSITIONAL = ("model", "method", "frame", "gravity", "estimator", "columns",
                          "rate_hz", "window_s", "min_static_s", "threshold_factor",
                          "init_rest_s", "cross_validate")
_LOG_RENAMED = {"path": "input", "rate_hz": "rate", "window_s": "window",
                "min_static_s": "min_static", "init_rest_s": "init_rest"}
# The options of ``accelcal calibrate`` that say where its results go and what it prints:
# calibrate_log returns the calibration instead (``result.to_json()`` is the file);
# ``accelcal.cli.calibrate`` writes the file and the report.
_LOG_NOT_TAKEN = ("output", "report", "json", "quiet", "verbose")


def _deprecated(message):
    _warnings.warn(DeprecationWarning("calibrate_log: " + message), stacklevel=4)


def _log_options(input, legacy, options):
    """calibrate_log's arguments under accelcal.cli.calibrate's names: (input, options)."""
    if len(legacy) > len(_LOG_LEGACY_POSITIONAL):
        raise TypeError(f"calibrate_log() takes at most {len(_LOG_LEGACY_POSITIONAL) + 1} "
                        f"positional arguments but {len(legacy) + 1} were given")
    if legacy:
        _deprecated("options given by position are deprecated: give them by keyword, as "
                    "accelcal.cli.calibrate names them")
    for name, value in zip(_LOG_LEGACY_POSITIONAL, legacy):
        if name in options:
            raise TypeError(f"calibrate_log() got multiple values for argument '{name}'")
        options[name] = value
    for old, new in _LOG_RENAMED.items():
        if old not in options:
            continue
        if options[old] is None:  # None leaves an option out, under either name
            del options[old]
            continue
        if (input if new == "input" else options.get(new)) is not None:
            raise TypeError(f"calibrate_log() got both '{old}' and '{new}'")
        _deprecated(f"'{old}' is deprecated: it is '{new}', as accelcal.cli.calibrate names it")
        if new == "input":
            input = options.pop(old)
        else:
            options[new] = options.pop(old)
    if options.get("cross_validate", None) is None:
        options.pop("cross_validate", None)
    else:
        if options.get("no_crossval") is not None:
            raise TypeError("calibrate_log() got both 'cross_validate' and 'no_crossval'")
        value = options.pop("cross_validate")
        if hasattr(value, "item") and not isinstance(value, (str, bytes)):
            value = value.item()  # numpy's bool
        if not isinstance(value, bool):
            raise TypeError(f"cross_validate: True or False, not {value!r}")
        _deprecated("'cross_validate' is deprecated: cross_validate=False is no_crossval=True, "
                    "as accelcal.cli.calibrate names it")
        options["no_crossval"] = not value
    for name in ("columns", "gyro_columns"):  # the old default, an empty list: the tool's own
        if isinstance(options.get(name), (list, tuple)) and len(options[name]) == 0:
            options[name] = None
    gravity = options.get("gravity")
    if isinstance(gravity, _numbers.Real) and not isinstance(gravity, bool) and 0 < gravity < 2:
        _deprecated(f"gravity={gravity!r} in g is deprecated: give gravity in m/s2 (the tool's "
                    "--gravity) and units='g' for a calibration in g")
        options["gravity"] = float(gravity) * 9.80665
        if options.get("units") is None:
            options["units"] = "g"
    for name in _LOG_NOT_TAKEN:
        if name in options:
            raise TypeError(f"calibrate_log() does not take '{name}': it returns the "
                            "calibration (result.to_json() is the file); accelcal.cli.calibrate "
                            "writes it and the report")
    if input is None:
        raise TypeError("calibrate_log() missing the argument 'input'")
    return input, options


def _file_name(value, what):
    """A file name as given (str, bytes or os.PathLike), or TypeError naming ``what``."""
    if isinstance(value, (str, bytes, _os.PathLike)):
        return value
    raise TypeError(f"{what}: a file name (str, bytes or os.PathLike), not "
                    f"{type(value).__name__}")


def calibrate_log(input=None, *legacy, **options):
    input, options = _log_options(input, legacy, options)
    if isinstance(input, (list, tuple)):
        input = [_file_name(name, "calibrate_log") for name in input]
    else:
        _file_name(input, "calibrate_log")
    for name in ("gyro", "orientations", "noise"):
        if options.get(name) is not None:
            _file_name(options[name], name)
    spec = cli._command_spec("calibrate")
    taken = {cli._keyword_name(o["name"]) for o in cli._parameters(spec)[1]}
    unknown = sorted(set(options) - taken)
    if unknown:
        raise TypeError(f"calibrate_log() got an unexpected keyword argument '{unknown[0]}'")
    argv = cli._arguments(spec, [input], options)
    status, result, positions, err, data_error = _accelcal._calibrate_unit(cli._native(argv))
    cli._outcome(status, err, "calibrate", stacklevel=2, data_error=data_error)
    if result is None:  # the tool's parse ran no calibration (it cannot: a defect)
        raise RuntimeError(f"calibrate_log: the tool ran no calibration (exit status {status})")
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


def _log_signature_and_doc():
    """calibrate_log's signature and docstring, from the tool's options (as accelcal.cli's)."""
    import inspect
    spec = cli._command_spec("calibrate")
    options = [o for o in cli._parameters(spec)[1]
               if cli._keyword_name(o["name"]) not in _LOG_NOT_TAKEN]
    parameters = [inspect.Parameter("input", inspect.Parameter.POSITIONAL_OR_KEYWORD)]
    parameters += [inspect.Parameter(cli._keyword_name(o["name"]), inspect.Parameter.KEYWORD_ONLY,
                                     default=None) for o in options]
    lines = [
        "What ``accelcal calibrate INPUT`` does, in this process: the same options, rules and "
        "messages (the tool's own), the same library call (CalibrateUnit: reading, detection, "
        "model and bias-model choice, thermal, known orientations, the gyroscope, the "
        "diagnosis), the same doubles; ``result.to_json()`` is the file ``accelcal calibrate "
        "INPUT --json`` writes, but for its provenance's command.",
        "",
        "input: a raw log or positions file, or a list of them (sessions of one unit, positions "
        "pooled); str, bytes or os.PathLike; \"-\" reads this process's standard input. Every "
        "other argument is a keyword, the tool's long option with _ for - (``--gyro-columns`` "
        "is ``gyro_columns``; a flag is True to give it; a list option takes a list); None "
        "(the default) leaves it out, so the tool's default applies.",
        "",
        "Returns ``(result, positions)``: a ``CalibrationResult`` (its ``verdict`` and "
        "``diagnostics`` the diagnosis; ``gyroscope`` with ``gyro``/``gyro_columns``) and the "
        "(m x 3) averaged readings in the order of the result's directions. Warnings and a "
        "failed verdict are emitted as for ``calibrate`` (prefixed with the input's name); "
        "nothing is raised for a failed verdict. An accelerometer's fit that does not converge is "
        "returned as a result whose verdict is \"failed\" (finding ``not_converged``), where "
        "the tool writes nothing and exits with status 4; a gyroscope's raises DataError. "
        "Raises ValueError for options the tool "
        "refuses (its message, options named as keywords), InputError for a file that cannot "
        "be read or used, DataError for data that do not determine a calibration (too few "
        "positions, no still interval).",
        "",
        "Not taken: " + ", ".join(_LOG_NOT_TAKEN) + " (where the tool's results go and what it "
        "prints: ``accelcal.cli.calibrate`` writes the file and the report). Deprecated, still "
        "accepted with a DeprecationWarning: options by position after ``input`` ("
        + ", ".join(_LOG_LEGACY_POSITIONAL) + "), the keywords "
        + ", ".join(f"{old} (now {new})" for old, new in _LOG_RENAMED.items())
        + ", cross_validate (now no_crossval) and gravity below 2 meaning g (now gravity in "
        "m/s2 and units='g').",
        "",
    ]
    for o in options:
        lines.append(f"{cli._keyword_name(o['name'])}: {cli._describe(o, 'calibrate')}")
    return inspect.Signature(parameters), "\n".join(lines)


calibrate_log.__signature__, calibrate_log.__doc__ = _log_signature_and_doc()
