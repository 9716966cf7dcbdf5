"""The package as Python users meet it: its version, its type stubs, pickling, repr, file names
as os.PathLike, docstrings, and the GIL released while it computes."""
import ast
import hashlib
import inspect
import json
import math
import os
import pathlib
import pickle
import re
import struct
import subprocess
import threading
import warnings

import numpy as np
import pytest

import accelcal

DATA = pathlib.Path(os.environ.get("ACCELCAL_DATA_DIR", "data"))
CLI = os.environ.get("ACCELCAL_CLI", "accelcal")
XSENS = DATA / "imutk-xsens-mti" / "xsens_acc.mat"
XSENS_GYRO = DATA / "imutk-xsens-mti" / "xsens_gyro.mat"
G = 9.81744
STUBS = pathlib.Path(accelcal.__file__).with_name("__init__.pyi")


@pytest.fixture(scope="module")
def with_gyro():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return accelcal.calibrate_log(XSENS, gravity=G, gyro=XSENS_GYRO)


def test_version_is_the_tools():
    out = subprocess.run([CLI, "--version"], capture_output=True, text=True, check=True).stdout
    assert re.fullmatch(r"\d+\.\d+\.\d+", accelcal.__version__)
    assert accelcal.__version__ in out.split()


# ---------------------------------------------------------------------------------------------
# Pickling

def same(a, b):
    """Deep equality, NaN equal to NaN and arrays compared element by element (exactly)."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return (isinstance(a, np.ndarray) and isinstance(b, np.ndarray) and a.shape == b.shape
                and np.array_equal(a, b, equal_nan=True))
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)):
        return type(a) is type(b) and len(a) == len(b) and all(map(same, a, b))
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return type(a) is type(b) and a == b


def attributes(obj):
    return {name: getattr(obj, name) for name in dir(type(obj))
            if isinstance(inspect.getattr_static(type(obj), name), property)}


def test_a_result_pickles_exactly(with_gyro):
    result, positions = with_gyro
    for protocol in range(pickle.HIGHEST_PROTOCOL + 1):
        back = pickle.loads(pickle.dumps(result, protocol))
        before, after = attributes(result), attributes(back)
        assert len(before) >= 25 and before.keys() == after.keys()
        for name in before:
            assert same(before[name], after[name]), name
        assert back.to_json() == result.to_json()
        assert back.to_json(units="g") == result.to_json(units="g")
        np.testing.assert_array_equal(back.apply(positions), result.apply(positions))
        assert accelcal.diagnose(back) == accelcal.diagnose(result)


def test_every_kind_of_result_pickles_exactly():
    rng = np.random.default_rng(3)
    _, positions = accelcal.calibrate_log(XSENS, gravity=G)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        results = [
            accelcal.calibrate(positions, gravity=G, model="auto"),  # a model selection
            accelcal.calibrate(positions, gravity=G, model="quadratic", cross_validate=False),
            accelcal.calibrate(positions + rng.normal(0, 40, positions.shape), gravity=G),
            accelcal.calibrate(positions, gravity=G, method="modulus"),  # no covariance
        ]
    for result in results:
        back = pickle.loads(pickle.dumps(result))
        for name, value in attributes(result).items():
            assert same(value, getattr(back, name)), name
        assert back.to_json() == result.to_json()


def test_a_damaged_pickle_is_an_error(with_gyro):
    result, _ = with_gyro
    restore, (state,) = result.__reduce__()
    assert restore is accelcal._restore_result
    assert restore(state).to_json() == result.to_json()
    with pytest.raises(ValueError, match="not a pickled accelcal"):
        restore(b"\x00" * 8)
    with pytest.raises(ValueError, match="pickled"):
        restore(state[: len(state) // 2])
    with pytest.raises(ValueError, match="damaged"):
        restore(state.replace(b"gravity", b"gravitx"))


# The pickled state's CBOR (RFC 8949: the major types it uses), to damage it as an attacker
# would and seal it again with its digest.
def _cbor_load(data, at=0):
    major, info = data[at] >> 5, data[at] & 31
    at += 1
    if major == 7:
        simple = {20: False, 21: True, 22: None}
        if info in simple:
            return simple[info], at
        return struct.unpack(">d", data[at:at + 8])[0], at + 8  # float64: the only float written
    if info >= 24:
        size = 1 << (info - 24)
        info, at = int.from_bytes(data[at:at + size], "big"), at + size
    if major in (0, 1):
        return info if major == 0 else -1 - info, at
    if major in (2, 3):
        chunk = data[at:at + info]
        return (bytes(chunk) if major == 2 else chunk.decode()), at + info
    items = []
    for _ in range(info * (2 if major == 5 else 1)):
        item, at = _cbor_load(data, at)
        items.append(item)
    return (dict(zip(items[::2], items[1::2])) if major == 5 else items), at


def _cbor_dump(value):
    def head(major, n):
        if n < 24:
            return bytes([major << 5 | n])
        size = next(s for s in (1, 2, 4, 8) if n < 1 << (8 * s))
        return bytes([major << 5 | (24 + size.bit_length() - 1)]) + n.to_bytes(size, "big")
    if value is None or isinstance(value, bool):
        return {None: b"\xf6", True: b"\xf5", False: b"\xf4"}[value]
    if isinstance(value, int):
        return head(0, value) if value >= 0 else head(1, -1 - value)
    if isinstance(value, float):
        return b"\xfb" + struct.pack(">d", value)
    if isinstance(value, (str, bytes)):
        raw = value.encode() if isinstance(value, str) else value
        return head(3 if isinstance(value, str) else 2, len(raw)) + raw
    if isinstance(value, list):
        return head(4, len(value)) + b"".join(map(_cbor_dump, value))
    return head(5, len(value)) + b"".join(_cbor_dump(k) + _cbor_dump(v) for k, v in value.items())


def test_a_pickled_gyroscope_tampered_with_is_an_error_never_a_crash(with_gyro):
    # The gyroscope is pickled as its section of the calibration file, read back by the file's
    # reader: what it refuses in a file, it refuses here, with a message (a hostile round found
    # a section that crashed to_json, and a message lost to broken UTF-8).
    result, _ = with_gyro
    restore, (state,) = result.__reduce__()
    magic = b"accelcal-state-1:"
    body = state[len(magic) + 64:]
    fields, end = _cbor_load(body)
    assert end == len(body) and _cbor_dump(fields) == body

    def sealed(text):
        damaged = dict(fields, result=dict(fields["result"], gyroscope=text))
        cbor = _cbor_dump(damaged)
        return magic + hashlib.sha256(cbor).hexdigest().encode() + cbor

    assert restore(sealed(fields["result"]["gyroscope"])).to_json() == result.to_json()
    section = json.loads(fields["result"]["gyroscope"])
    section["thermal"] = {"t_ref": 25, "degree": 3, "temperature_range": [20, 30],
                          "coefficients": [[1, 1, 1]] * 3, "std": [[0, 0, 0]] * 3,
                          "covariance": None}
    for text, says in [("x", "not JSON"), ("\u00e9", "not JSON"), ("", "not JSON"),
                       ('"text"', "must be an object"), (json.dumps(section), "covariance")]:
        with pytest.raises(ValueError, match=says):
            restore(sealed(text))


def test_a_calibration_file_pickles_as_its_text(with_gyro, tmp_path):
    result, _ = with_gyro
    path = tmp_path / "cal.json"
    path.write_text(result.to_json())
    loaded = accelcal.load_calibration(path)
    back = pickle.loads(pickle.dumps(loaded))
    assert back.text == loaded.text == path.read_text()
    assert back.source == loaded.source and back.has_gyroscope
    for name, value in attributes(loaded).items():
        assert same(value, getattr(back, name)), name


# ---------------------------------------------------------------------------------------------
# repr, file names, docstrings

def test_repr_shows_the_parameters_with_their_sigma(with_gyro):
    result, _ = with_gyro
    text = repr(result)
    sigma = np.sqrt(np.diag(result.covariance))
    names = result.parameter_names
    assert text.startswith("<accelcal.CalibrationResult: linear model, 38 positions")
    assert f"{result.K[0, 0]:.7g} ± {sigma[names.index('K_xx')]:.2g}" in text
    assert f"{result.bias[2]:.7g} ± {sigma[names.index('b_z')]:.2g}" in text
    assert "gyroscope: g-sensitive model" in text
    loaded = accelcal.parse_calibration_json(result.to_json())
    assert f"{loaded.K[1, 0]:.7g} ± {sigma[names.index('K_yx')]:.2g}" in repr(loaded)


def test_file_names_may_be_path_like(tmp_path):
    by_str, _ = accelcal.calibrate_log(str(XSENS), gravity=G)
    by_path, _ = accelcal.calibrate_log(XSENS, gravity=G)
    by_bytes, _ = accelcal.calibrate_log(os.fsencode(XSENS), gravity=G)
    assert by_str.to_json() == by_path.to_json() == by_bytes.to_json()
    assert accelcal.read_input(XSENS)["samples"].shape == accelcal.read_input(str(XSENS))[
        "samples"].shape
    path = tmp_path / "cal.json"
    path.write_text(by_path.to_json())
    assert accelcal.load_calibration(path).text == path.read_text()
    with pytest.raises(TypeError, match="calibrate_log: a file name .* not int"):
        accelcal.calibrate_log(3)
    with pytest.raises(TypeError, match="gyro: a file name"):
        accelcal.calibrate_log(XSENS, gyro=1.5)


def test_a_positions_file_is_calibrated_as_on_the_command_line(tmp_path):
    _, positions = accelcal.calibrate_log(XSENS, gravity=G)
    csv = tmp_path / "positions.csv"
    np.savetxt(csv, positions, delimiter=",", header="x,y,z", comments="", fmt="%.17g")
    result, read = accelcal.calibrate_log(csv, gravity=G)
    np.testing.assert_array_equal(read, positions)
    cli = subprocess.run([CLI, "calibrate", str(csv), "--gravity", str(G), "--json"],
                         capture_output=True, text=True, check=True).stdout
    np.testing.assert_array_equal(result.K, np.array(
        __import__("json").loads(cli)["sensors"]["accelerometer"]["K"]))


def test_every_public_function_and_attribute_has_a_docstring():
    missing = []
    for name in accelcal.__all__:
        obj = getattr(accelcal, name)
        if name == "__version__":
            continue
        if not (obj.__doc__ or "").strip():
            missing.append(name)
        if isinstance(obj, type) and obj.__module__.startswith("accelcal"):
            for attr, value in vars(obj).items():
                if attr.startswith("_"):
                    continue
                doc = value.__doc__ or ""
                # pybind11 starts a method's docstring with its signature: the text follows.
                text = doc.split("\n", 1)[1] if doc.startswith(f"{attr}(") else doc
                if not text.strip():
                    missing.append(f"{name}.{attr}")
    assert not missing, missing


# ---------------------------------------------------------------------------------------------
# Type stubs

def stub_tree():
    return ast.parse(STUBS.read_text())


def runtime_parameters(obj):
    """(name, kind, default) of each parameter: inspect's for Python functions, the signature
    line pybind11 writes first in the docstring for the module's."""
    try:
        signature = inspect.signature(obj)
    except (ValueError, TypeError):
        signature = None
    if signature is not None:
        return [(p.name, p.kind == p.KEYWORD_ONLY,
                 None if p.default is p.empty else repr(p.default))
                for p in signature.parameters.values()]
    line = obj.__doc__.splitlines()[0]
    tree = ast.parse("def " + re.sub(r"\) -> .*$", "): pass", line).replace("numpy.ndarray", "x")
                     .replace("accelcal._accelcal.", ""))
    return function_parameters(tree.body[0])


def function_parameters(node):
    args = node.args
    result = []
    positional = args.args
    defaults = [None] * (len(positional) - len(args.defaults)) + list(args.defaults)
    for arg, default in zip(positional, defaults):
        result.append((arg.arg, False, None if default is None else literal(default)))
    for arg, default in zip(args.kwonlyargs, args.kw_defaults):
        result.append((arg.arg, True, None if default is None else literal(default)))
    return result


def literal(node):
    value = ast.literal_eval(node)
    if isinstance(value, (tuple, list)) and not value:
        value = ()  # an empty sequence either way
    return repr(value)


def normalise(parameters):
    return [(n, kw, repr(()) if d in ("[]", "()") else d) for n, kw, d in parameters
            if n != "self"]


def test_the_stubs_name_what_the_package_has():
    tree = stub_tree()
    names = {node.name for node in tree.body if isinstance(node, (ast.FunctionDef, ast.ClassDef))}
    names |= {node.target.id for node in tree.body if isinstance(node, ast.AnnAssign)}
    names |= {alias.asname or alias.name for node in tree.body
              if isinstance(node, ast.ImportFrom) and node.module is None
              for alias in node.names}
    public = set(accelcal.__all__)
    assert names - {"PathLike", "ArrayLike", "Array", "Finding"} >= public
    assert not (names - public - {"PathLike", "ArrayLike", "Array", "Finding"}), \
        names - public


def test_the_stubs_have_the_functions_parameters_and_defaults():
    for node in stub_tree().body:
        if isinstance(node, ast.FunctionDef):
            assert normalise(function_parameters(node)) == normalise(
                runtime_parameters(getattr(accelcal, node.name))), node.name


def test_the_stubs_have_every_attribute_and_method_of_the_classes():
    for node in stub_tree().body:
        if not isinstance(node, ast.ClassDef) or not hasattr(accelcal, node.name):
            continue
        cls = getattr(accelcal, node.name)
        if not cls.__module__.startswith("accelcal._accelcal"):
            continue
        stubbed = {item.name: item for item in node.body if isinstance(item, ast.FunctionDef)}
        runtime = {name for name in vars(cls) if not name.startswith("_")}
        assert set(stubbed) == runtime, (node.name, set(stubbed) ^ runtime)
        for name, item in stubbed.items():
            value = inspect.getattr_static(cls, name)
            is_property = any(isinstance(d, ast.Name) and d.id == "property"
                              for d in item.decorator_list)
            assert is_property == isinstance(value, property), (node.name, name)
            if not is_property:
                assert normalise(function_parameters(item)) == normalise(
                    runtime_parameters(getattr(cls, name))), (node.name, name)


# ---------------------------------------------------------------------------------------------
# The GIL

def python_share_during(call):
    """The share of its own pace a pure-Python counting thread keeps while `call` runs in this
    thread: about 0 when the call holds the GIL throughout (the thread waits for it), near 1
    when the call releases it (two cores: the call on one, the thread on the other)."""
    import time
    counter = [0]
    stop = threading.Event()

    def count():
        while not stop.is_set():
            counter[0] += 1

    thread = threading.Thread(target=count)
    thread.start()
    try:
        while counter[0] == 0:
            pass
        start, t0 = counter[0], time.perf_counter()
        time.sleep(0.1)  # releases the GIL: the thread's own pace
        pace = (counter[0] - start) / (time.perf_counter() - t0)
        before, t0 = counter[0], time.perf_counter()
        call()
        elapsed = time.perf_counter() - t0
        return (counter[0] - before) / (pace * elapsed), elapsed
    finally:
        stop.set()
        thread.join()


@pytest.fixture(scope="module")
def long_log(tmp_path_factory):
    """A raw log that takes about 0.3 s to read and 0.1 s to detect: 18 positions, 60 s each at
    1 kHz."""
    path = tmp_path_factory.mktemp("gil") / "long.csv"
    subprocess.run([CLI, "simulate", "--scenario", "yang2012", "--raw", "--rate", "1000",
                    "--duration", "60", "-o", str(path)], check=True, capture_output=True)
    return path


@pytest.mark.parametrize("what", ["calibrate_log", "read_input", "detect_static_intervals",
                                  "calibrate"])
def test_the_long_computations_release_the_gil(what, long_log):
    rng = np.random.default_rng(1)
    directions = rng.normal(size=(20000, 3))
    directions /= np.linalg.norm(directions, axis=1)[:, None]
    positions = 400 * 9.81 * directions + 32000 + rng.normal(0, 0.5, directions.shape)
    log = accelcal.read_input(long_log)
    calls = {
        "calibrate_log": lambda: accelcal.calibrate_log(long_log),
        "read_input": lambda: accelcal.read_input(long_log),
        # Detection is fast (20 to 80 ms here): three calls, so that the measurement spans the
        # 0.1 s it needs (held, each call would give the thread one switch interval at most).
        "detect_static_intervals": lambda: [accelcal.detect_static_intervals(
            log["samples"], log["time"]) for _ in range(3)],
        "calibrate": lambda: accelcal.calibrate(positions, gravity=9.81),
    }
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        share, elapsed = python_share_during(calls[what])
    # Held, the thread could run at most before the call enters C++ (one switch interval, 5 ms,
    # of a call of 100 ms or more: a share of 0.05 at most; 0.03 measured with the release
    # removed); released, it keeps its pace, less what a loaded machine takes: 0.9 alone, 0.29
    # seen while the package test compiled on both cores beside it.
    assert elapsed > 0.1, elapsed
    assert share > 0.12, share


def test_threads_calibrate_concurrently_to_the_same_bytes():
    results = [None] * 4

    def run(i):
        result, _ = accelcal.calibrate_log(XSENS, gravity=G)
        results[i] = result.to_json()

    threads = [threading.Thread(target=run, args=(i,)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    alone, _ = accelcal.calibrate_log(XSENS, gravity=G)
    assert results == [alone.to_json()] * 4


# ---------------------------------------------------------------------------------------------
# pandas

def test_dataframes_in_and_out():
    import pandas
    result, positions = accelcal.calibrate_log(XSENS, gravity=G)
    frame = result.to_frame()
    assert list(frame.index) == list(range(1, 39)) and frame.index.name == "position"
    np.testing.assert_array_equal(frame[["mean_x", "mean_y", "mean_z"]].to_numpy(), positions)
    np.testing.assert_array_equal(frame[["direction_x", "direction_y", "direction_z"]].to_numpy(),
                                  result.directions)
    np.testing.assert_array_equal(frame["crossval_error"].to_numpy(), result.crossval_errors)
    assert frame.equals(accelcal.parse_calibration_json(result.to_json()).to_frame())
    # A DataFrame of readings is taken as its values.
    readings = pandas.DataFrame(positions, columns=["ax", "ay", "az"])
    assert accelcal.calibrate(readings, gravity=G).to_json() == accelcal.calibrate(
        positions, gravity=G).to_json()
    np.testing.assert_array_equal(result.apply(readings), result.apply(positions))


def test_documents_give_their_tables_as_dataframes():
    # A raw log's samples, indexed from 0 as the file's sample indices are.
    raw = accelcal.read_input(XSENS)
    assert isinstance(raw, dict) and raw.kind == "readings" and raw.tables == ["samples"]
    frame = raw.to_frame()
    assert list(frame.columns) == ["time_s", "x", "y", "z"] and frame.index.name == "sample"
    assert frame.index[0] == 0 and len(frame) == len(raw["samples"])
    np.testing.assert_array_equal(frame[["x", "y", "z"]].to_numpy(), raw["samples"])
    np.testing.assert_array_equal(frame["time_s"].to_numpy(), raw["time"])
    # A positions file's positions, numbered from 1.
    means = accelcal.read_input(DATA / "ctu-innalabs-ahrs-m3" / "measured_accelerations_24pos.csv")
    frame = means.to_frame()
    assert means.tables == ["positions"] and list(frame.index) == list(range(1, 25))
    np.testing.assert_array_equal(frame[["x", "y", "z"]].to_numpy(), means["positions"])
    np.testing.assert_array_equal(frame["samples"].to_numpy(), means["counts"])
    # The intervals found, numbered from 1 as the positions they become.
    found = accelcal.detect_static_intervals(raw["samples"], raw["time"])
    frame = found.to_frame()
    assert found.tables == ["intervals", "rejected"] and frame.index[0] == 1
    assert len(frame) == len(found["intervals"]) == 38
    np.testing.assert_array_equal(frame[["mean_x", "mean_y", "mean_z"]].to_numpy(),
                                  [i["mean"] for i in found["intervals"]])
    np.testing.assert_array_equal(frame["begin"].to_numpy(),
                                  [i["begin"] for i in found["intervals"]])
    # A document pickles with its kind, and is still the dict the tool writes.
    again = pickle.loads(pickle.dumps(found))
    assert again.kind == "detection" and again.to_frame().equals(frame)
    assert found.copy().kind == "detection" and found.copy().to_frame().equals(frame)
    with pytest.raises(KeyError, match=r"no table 'allan' \(its tables: intervals, rejected\)"):
        found.to_frame("allan")


# ---------------------------------------------------------------------------------------------
# From a hostile test of the package

def test_damaged_or_crafted_pickles_are_refused_not_crashes(with_gyro):
    result, _ = with_gyro
    restore, (state,) = result.__reduce__()
    for bad in (b"\x81" * 10 ** 6 + b"\x00",  # nested a million deep: the parser's recursion
                state[:-1], state[:40], state + b"\x00",
                state[:100] + bytes([state[100] ^ 1]) + state[101:]):
        with pytest.raises(ValueError):
            restore(bad)


def test_file_names_as_the_system_takes_them(tmp_path):
    with pytest.raises(ValueError, match="embedded null byte"):
        accelcal.calibrate_log(str(XSENS) + "\0junk", gravity=G)
    with pytest.raises(ValueError, match="embedded null byte"):
        accelcal.read_input(str(XSENS) + "\0junk")
    with pytest.raises(ValueError, match="embedded null byte"):
        accelcal.cli.calibrate(str(XSENS) + "\0junk")
    # A name that is not UTF-8, as bytes or as os.fsdecode gives it.
    odd = tmp_path / os.fsdecode(b"acc_\xff\xfe.mat")
    odd.write_bytes(XSENS.read_bytes())
    for name in (os.fsencode(odd), str(odd), odd):
        assert accelcal.read_input(name)["samples"].shape == (accelcal.read_input(XSENS)[
            "samples"].shape)


def test_columns_as_numbers_or_one_string_and_a_topic():
    positions = DATA / "imutk-xsens-mti" / "derived_static_means.csv"
    by_name = accelcal.read_input(positions, columns=["4", "5", "6"])["positions"]
    np.testing.assert_array_equal(accelcal.read_input(positions, columns=[4, 5, 6])["positions"],
                                  by_name)
    np.testing.assert_array_equal(accelcal.read_input(positions, columns="4,5,6")["positions"],
                                  by_name)
    with pytest.raises(TypeError, match="columns: column numbers"):
        accelcal.read_input(positions, columns=[4.0, 5, 6])
    ulog = DATA / "px4-ulog" / "sample_log_small.ulg"
    with pytest.raises(accelcal.InputError, match="topic"):
        accelcal.read_input(ulog)
    assert accelcal.read_input(ulog, topic="sensor_accel", instance=0)["samples"].shape[1] == 3
    # frame_id chooses among a ROS topic's frames: a ULog's topics have none; empty is no name.
    with pytest.raises(accelcal.InputError, match="messages name no frame"):
        accelcal.read_input(ulog, topic="sensor_accel", instance=0, frame_id="imu_link")
    with pytest.raises(ValueError, match="frame_id: an empty name"):
        accelcal.read_input(ulog, frame_id="")
    with pytest.raises(accelcal.InputError, match="messages name no frame"):
        accelcal.calibrate_log(ulog, topic="sensor_accel", instance=0, frame_id="imu_link")
