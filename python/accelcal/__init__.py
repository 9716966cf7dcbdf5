"""accelcal: calibration of triaxial accelerometers from static multi-position recordings.

The C++ library's API under the same names in snake_case (``calibrate``, ``read_input``,
``detect_static_intervals``, ``export_calibration``, ``render_report``), numpy arrays for readings
(n x 3) and matrices, and the library's errors as ``InputError`` / ``DataError`` (both
``ValueError``) with the command-line tool's messages.
"""

from ._accelcal import (  # noqa: F401
    Calibration,
    CalibrationResult,
    DataError,
    InputError,
    calibrate,
    detect_static_intervals,
    export_calibration,
    load_calibration,
    parse_calibration_json,
    read_input,
    render_report,
)


def apply(calibration, readings):
    """Corrected specific force (n x 3) of raw readings (n x 3) under a calibration."""
    return calibration.apply(readings)


def calibrate_log(path, model="linear", method="joint", frame="x-first", gravity=9.80665,
                  estimator="ml", columns=(), rate_hz=None, window_s=0.5, min_static_s=1.0,
                  threshold_factor=10.0, init_rest_s=0.0, cross_validate=True):
    """What ``accelcal calibrate LOG`` does: read, detect the static intervals, average them and
    calibrate with each interval's noise. Returns (result, positions) with positions the
    (m x 3) averaged readings, in the order of the result's directions and residuals."""
    import numpy as np

    data = read_input(path, "raw", list(columns), rate_hz)
    detected = detect_static_intervals(data["samples"], data["time"], data["rate_hz"], window_s,
                                       min_static_s, threshold_factor, init_rest_s)
    intervals = detected["intervals"]
    if not intervals:
        raise DataError(f"{path}: no static interval found (threshold {detected['threshold']:.3g} raw^2)")
    positions = np.array([i["mean"] for i in intervals])
    counts = np.array([i["end"] - i["begin"] for i in intervals], dtype=float)
    sigmas = np.array([i["std"] for i in intervals]) / np.sqrt(counts)[:, None]
    try:
        result = calibrate(positions, model, method, frame, gravity, estimator, sigmas,
                           cross_validate)
    except DataError as e:
        raise DataError(f"{path}: {e}") from None
    return result, positions
