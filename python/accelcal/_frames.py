"""pandas DataFrames of the package's tables: a calibration's positions (``to_frame()`` of a
result or a file) and the tables of the documents the functions return (``Document``).

One flattening for every table: a row's nested dict becomes columns ``key_sub``, a 3-vector
``key_x``, ``key_y``, ``key_z``; other lists stay one cell. Position numbers count from 1, as in
the file and the tool; sample indices from 0, as in the file.
"""

import json as _json
import numbers as _numbers


def _pandas():
    try:
        import pandas
    except ImportError as e:
        raise ImportError("to_frame needs pandas (Debian: python3-pandas)") from e
    return pandas


def _vector3(value):
    """A list, tuple or numpy array of three numbers."""
    if isinstance(value, (str, bytes, dict)) or getattr(value, "ndim", 1) != 1:
        return False
    try:
        return len(value) == 3 and all(isinstance(v, _numbers.Real) and not isinstance(v, bool)
                                       for v in value)
    except TypeError:
        return False


def _flat(row, prefix=""):
    out = {}
    for key, value in row.items():
        name = prefix + key
        if isinstance(value, dict):
            out.update(_flat(value, name + "_"))
        elif _vector3(value):
            out.update({f"{name}_{axis}": v for axis, v in zip("xyz", value)})
        else:
            out[name] = value
    return out


def _frame(rows, index=None, first=None, name=None):
    """A DataFrame of dict rows, flattened: indexed by the column `index`, or numbered from
    `first` with the index's name `name`."""
    pandas = _pandas()
    frame = pandas.DataFrame([_flat(row) for row in rows])
    if index is not None:
        if frame.empty:
            frame = pandas.DataFrame(columns=[index])
        return frame.set_index(index)
    if first is not None:
        frame.index = pandas.RangeIndex(first, first + len(rows), name=name)
    return frame


def positions_frame(text):
    """The accelerometer's positions of a calibration file's text: one row per position,
    indexed by its number (from 1), the file's per-position fields in columns."""
    positions = _json.loads(text)["sensors"]["accelerometer"].get("positions", [])
    return _frame(positions, first=1, name="position")


def _at(doc, path):
    for key in path.split("."):
        doc = doc.get(key) if isinstance(doc, dict) else None
    return doc


class _Table:
    """A table of a document: whether the document has it (cheap), and how it is built."""

    def __init__(self, name, present, build):
        self.name, self.present, self.build = name, present, build


def _list(table, path, **how):
    """The table `table`: the list of objects at `path` of the document."""
    return _Table(table, lambda doc: isinstance(_at(doc, path), list),
                  lambda doc: _frame(_at(doc, path), **how))


def _readings(doc):
    pandas = _pandas()
    frame = pandas.DataFrame(doc["samples"], columns=["x", "y", "z"])
    if doc.get("time") is not None:
        frame.insert(0, "time_s", doc["time"])
    frame.index.name = "sample"
    return frame


def _readings_positions(doc):
    pandas = _pandas()
    frame = pandas.DataFrame(doc["positions"], columns=["x", "y", "z"])
    frame["samples"] = doc["counts"]
    if doc.get("stds") is not None:
        for i, axis in enumerate("xyz"):
            frame[f"std_{axis}"] = doc["stds"][:, i]
    frame.index = pandas.RangeIndex(1, len(frame) + 1, name="position")
    return frame


def _noise_rows(doc, part):
    """The noise document's axes, one row per sensor and axis and `part`'s entry: its fitted
    terms ("terms") or its Allan deviation ("allan")."""
    rows = []
    for sensor in ("accelerometer", "gyroscope"):
        for axis in (_at(doc, sensor + ".axes") or []):
            entries = axis.get(part)
            if part == "terms":
                entries = [dict(term=k, **v) for k, v in (entries or {}).items()]
            for entry in entries or []:
                rows.append(dict(sensor=sensor, axis=axis.get("axis"), **entry))
    return rows


def _noise(name):
    return _Table(name, lambda doc: bool(_noise_rows(doc, name)),
                  lambda doc: _frame(_noise_rows(doc, name)))


def _has_crlb(doc):
    return bool(doc.get("parameter_order")) and bool(doc.get("crlb"))


def _design_parameters(doc):
    crlb = doc["crlb"]
    return _frame([{"parameter": n, "std": crlb[i][i] ** 0.5}
                   for i, n in enumerate(doc["parameter_order"])], index="parameter")


def _design_crlb(doc):
    pandas = _pandas()
    names = doc["parameter_order"]
    return pandas.DataFrame(doc["crlb"], index=pandas.Index(names, name="parameter"),
                            columns=names)


def _design_chosen(doc):
    return _frame([{"direction": d} for d in doc["chosen"]], first=1, name="position")


def _batch_units(doc):
    """summary.csv's table: a row per unit, its columns and text as the CSV has them (the failed
    limits' texts joined by "; ", the files by ";"), each quantity and its 1 sigma
    (``NAME.sigma``) as numbers, in their order of first use."""
    rows = []
    for unit in doc["units"]:
        row = {"unit": unit.get("unit"), "status": unit.get("status"),
               "failed": "; ".join(f.get("text", "") for f in unit.get("failed") or []),
               "files": ";".join(unit.get("files") or []),
               "verdict": unit.get("verdict"), "worst_finding": unit.get("worst_finding"),
               "message": unit.get("message"), "sha256": unit.get("sha256")}
        for name, q in (unit.get("quantities") or {}).items():
            row[name] = q.get("value")
            row[name + ".sigma"] = q.get("sigma")
        rows.append(row)
    pandas = _pandas()
    base = ["unit", "status", "failed", "files", "verdict", "worst_finding", "message", "sha256"]
    frame = pandas.DataFrame(rows, columns=list(dict.fromkeys(
        base + [k for row in rows for k in row])))
    numbers = [c for c in frame.columns if c not in base]
    frame[numbers] = frame[numbers].astype(float)  # a sigma no unit has is NaN, as read_csv's
    return frame.set_index("unit")


# Each document's tables, its natural one first (what to_frame() gives).
_DETECTION = [_list("intervals", "intervals", first=1, name="interval"),
              _list("rejected", "rejected", first=1, name="rejected")]
_TABLES = {
    "readings": [_Table("samples", lambda doc: doc.get("kind") == "raw", _readings),
                 _Table("positions", lambda doc: doc.get("kind") == "positions",
                        _readings_positions)],
    "detection": _DETECTION,
    "detect": _DETECTION,
    "compare": [_list("methods", "methods", index="method")],
    "noise": [_noise("terms"), _noise("allan")],
    "montecarlo": [_list("parameters", "parameters", index="name")],
    "design": [_Table("parameters", _has_crlb, _design_parameters),
               _Table("crlb", _has_crlb, _design_crlb),
               _Table("chosen", lambda doc: isinstance(doc.get("chosen"), list),
                      _design_chosen)],
    "verify": [_list("positions", "positions", index="position"),
               _list("parameters", "parameters", index="name")],
    "inspect": [_list("streams", "streams")],
    "batch": [_Table("units", lambda doc: isinstance(doc.get("units"), list), _batch_units)],
    "store": [_list("entries", "entries")],
}


class Document(dict):
    """A document a function returns: a ``dict``, as the tool's ``--json`` writes it, whose
    tables are pandas DataFrames by ``to_frame()``.

    ``doc.tables`` names the tables it has, its natural one first; ``doc.to_frame()`` gives that
    one and ``doc.to_frame(name)`` another. Rows are the document's objects, nested objects as
    columns ``key_sub`` and 3-vectors as ``key_x``, ``key_y``, ``key_z``. Positions are numbered
    from 1 (as in the file and the tool), a log's samples from 0; a batch's units are indexed by
    unit id, with each quantity's 1 sigma as ``NAME.sigma`` (as summary.csv has it)."""

    __slots__ = ("_kind",)

    def __init__(self, data=(), kind=""):
        super().__init__(data)
        self._kind = kind

    @property
    def kind(self):
        """What the document is: the command that wrote it ("compare", "batch", ...),
        "readings" (read_input's) or "detection" (detect_static_intervals')."""
        return self._kind

    def __reduce__(self):
        return (Document, (dict(self), self.kind))

    def __repr__(self):
        return f"Document({self.kind!r}, {dict.__repr__(self)})"

    @property
    def tables(self):
        """The names of the tables it has, its natural one (``to_frame()``'s) first."""
        return [t.name for t in _TABLES.get(self._kind, []) if t.present(self)]

    def to_frame(self, table=None):
        """Its table `table` (default: its natural one) as a pandas DataFrame. KeyError names
        the tables it has when it has no such table."""
        for t in _TABLES.get(self._kind, []):
            if (table is None or table == t.name) and t.present(self):
                return t.build(self)
        what = f"no table {table!r}" if table is not None else "no table"
        raise KeyError(f"the {self._kind or 'untitled'} document has {what} (its tables: "
                       f"{', '.join(self.tables) or 'none'})")

    def copy(self):
        """A shallow copy, a Document of the same kind."""
        return Document(self, self._kind)
