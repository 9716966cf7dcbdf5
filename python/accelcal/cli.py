"""Every command of the ``accelcal`` tool as a Python function, run in this process.

``accelcal.cli.compare("log.csv", model="quadratic")`` is ``accelcal compare log.csv --model
quadratic --json``: the same code (the tool's own, linked into the module), so the same defaults,
checks, numbers and messages. The functions are made from the tool's own option definitions
(``accelcal --describe-options``), so they cannot drift from it:

- the tool's positional arguments are the functions' positional parameters (``input``, ``log``,
  ``cal``, ...; a command taking several files takes a list), in their order;
- every option is a keyword argument, its long name with ``_`` for ``-`` (``--gyro-columns`` is
  ``gyro_columns``); ``None`` (the default) leaves it out, so the tool's own default applies
  (each function's docstring states it); a flag is ``True`` to give it; a list option takes a
  list (``columns=["t", "ax", "ay", "az"]``); file names may be ``os.PathLike``;
- a command that has ``--json`` is run with it and returns the parsed document (a dict: an
  ``accelcal.Document``, whose ``to_frame()`` gives its table as a pandas DataFrame), except
  ``calibrate`` and ``store get``, which return the calibration file as an
  ``accelcal.Calibration``;
  the others return what the tool writes to standard output (``str``, or ``bytes`` when it is
  not text, such as a ULog), or ``None`` when ``output`` names a file.

Errors are raised as the tool's exit statuses say: ``ValueError`` for a usage error (status 2),
``accelcal.InputError`` for input that cannot be used (3), ``accelcal.DataError`` for a solver
that did not converge (4), ``OSError`` for an output that cannot be written (5),
``RuntimeError`` for an internal error (1); the messages are the tool's, with options named as
keywords. The tool's warnings are emitted as ``accelcal.cli.ToolWarning``; a calibration that
failed its checks (status 6: written, marked ``"verdict": "failed"``) is returned, with an
``accelcal.CalibrationCheckFailed`` warning. The GIL is released while a command runs.
"""

import inspect as _inspect
import json as _json
import keyword as _keyword
import os as _os
import re as _re
import warnings as _warnings

from . import _accelcal
from . import CalibrationCheckFailed, DataError, InputError, parse_calibration_json
from ._frames import Document


class ToolWarning(UserWarning):
    """A warning of the tool (``accelcal: warning: ...`` on its standard error): the result
    stands, but look at this."""


_DESCRIPTION = _json.loads(_accelcal._run_command(["--describe-options"])[1])
__version__ = _DESCRIPTION["version"]


def _keyword_name(option):
    """The Python name of an option or positional argument."""
    name = option.replace("-", "_").lower()
    return name + "_" if _keyword.iskeyword(name) else name


def _command_spec(name):
    """The tool's description of one command."""
    return next(c for c in _DESCRIPTION["commands"] if c["name"] == name)


def _has_json(spec):
    """Whether the command has --json: it is always given it, and returns its document."""
    return any(o["name"] == "json" and not o["positional"] for o in spec["options"])


def _parameters(spec):
    """A command's positional arguments and its keyword options (the tool's global ones
    included, --json left out: always given), in the tool's order."""
    positionals = [o for o in spec["options"] if o["positional"]]
    options = [o for o in spec["options"] if not o["positional"] and o["name"] != "json"]
    return positionals, options + _DESCRIPTION["options"]


# Every option of the tool by its long name, of any command (a message may name another's).
_OPTION_NAMES = {o["name"] for c in _DESCRIPTION["commands"] for o in c["options"]
                 if not o["positional"]} | {o["name"] for o in _DESCRIPTION["options"]}


def _python_message(text, command):
    """The tool's message with its options named as this module's keywords (only the tool's
    option names: a file name or value such as "--x.csv" is left as it is)."""
    text = text.replace("(see --help)", f"(see help(accelcal.cli.{_keyword_name(command)}))")
    return _re.sub(r"(?<![\w-])--([a-z][a-z0-9-]*)(?![\w.-])",
                   lambda m: (_keyword_name(m.group(1)) if m.group(1) in _OPTION_NAMES
                              else m.group(0)), text)


def _value(value, what):
    """One argument as the command line spells it."""
    if isinstance(value, bool):
        raise TypeError(f"{what}: a value, not {value!r}")
    if isinstance(value, (_os.PathLike, bytes)):
        return _value(_os.fsdecode(_os.fspath(value)), what)
    if isinstance(value, float):
        return repr(value)  # the shortest text that reads back as the same double
    if hasattr(value, "item") and not isinstance(value, str):  # a numpy scalar
        return _value(value.item(), what)
    if isinstance(value, (int, str)):
        if "\0" in str(value):
            raise ValueError(f"{what}: embedded null byte")
        return str(value)
    raise TypeError(f"{what}: a number, a string or a file name, not {type(value).__name__}")


def _arguments(spec, args, options):
    """The command line of one call: its options (--name=value), then -- and its positionals."""
    argv = [spec["name"]]
    positionals, keywords = _parameters(spec)
    named = {_keyword_name(o["name"]): o for o in keywords}
    for key, value in options.items():
        if value is None:
            continue
        option = named[key]
        flag = "--" + option["name"]
        if option["flag"]:
            if hasattr(value, "item") and not isinstance(value, (str, bytes)):
                value = value.item()  # numpy's bool
            if not isinstance(value, bool):
                raise TypeError(f"{key}: True or False, not {value!r}")
            if value:
                argv.append(flag)
            continue
        if option["many"] and not isinstance(value, (str, bytes, _os.PathLike)) and \
                hasattr(value, "__iter__"):
            delimiter = option["delimiter"] or ","
            items = [_value(v, key) for v in list(value)]
            if not items:
                raise ValueError(f"{key}: an empty list")
            for item in items:
                if delimiter in item:
                    raise ValueError(f"{key}: the item {item!r} holds {delimiter!r}, which "
                                     "separates the items: give each value as an item of its own")
            argv.append(flag + "=" + delimiter.join(items))
        else:
            argv.append(f"{flag}={_value(value, key)}")
    tail = []
    for option, value in zip(positionals, args):
        if value is None:
            continue
        if option["many"] and isinstance(value, (list, tuple)):
            tail += [_value(v, _keyword_name(option["name"])) for v in value]
        else:
            tail.append(_value(value, _keyword_name(option["name"])))
    return argv + (["--"] + tail if tail else [])


def _native(argv):
    """The arguments as the tool takes them: bytes, so that a file name that is not UTF-8 (os's
    surrogate escapes) passes as it is."""
    return [_os.fsencode(a) for a in argv]


def _raise(status, message, command):
    text = _python_message(message, command)
    if status == 2:
        raise ValueError(text)
    if status == 3:
        raise InputError(text)
    if status == 4:
        raise DataError(text)
    if status == 5:
        raise OSError(text)
    raise RuntimeError(f"accelcal {command}: exit status {status}: {text}")


def _outcome(status, err, command, stacklevel, data_error=False):
    """The tool's standard error: an exception for a failed status (DataError for status 3 when
    ``data_error`` says the library's DataError caused it), else its warnings emitted. Returns
    its lines."""
    err = err.decode("utf-8", "replace")
    lines = [line for line in err.splitlines() if line]
    if status not in (0, 6):
        message = "\n".join(line[len("accelcal: "):] if line.startswith("accelcal: ") else line
                            for line in lines if not line.startswith("accelcal: warning: "))
        if message.startswith("usage: "):
            message = message[len("usage: "):]
        if data_error and status == 3:
            raise DataError(_python_message(message, command))
        _raise(status, message, command)
    for line in lines:
        if line.startswith("accelcal: warning: "):
            _warnings.warn(ToolWarning(_python_message(line[len("accelcal: warning: "):],
                                                       command)), stacklevel=stacklevel + 1)
    return lines


def _run(spec, args, options, stacklevel=3):
    command = spec["name"]
    has_json = _has_json(spec)
    argv = _arguments(spec, args, options)
    if has_json:
        argv.insert(1, "--json")
    status, out, err = _accelcal._run_command(_native(argv))
    lines = _outcome(status, err, command, stacklevel)
    failed = [line[len("accelcal: "):] for line in lines
              if status == 6 and not line.startswith("accelcal: warning: ")]
    if command == "calibrate" and has_json:
        first = args[0] if args else None
        source = (first[0] if isinstance(first, (list, tuple)) and first else first)
        result = parse_calibration_json(out.decode("utf-8"),
                                        _value(source, "input") if source is not None else "")
    elif has_json:
        result = _json.loads(out.decode("utf-8")) if out else None
        if isinstance(result, dict) and result.get("format") == "accelcal-calibration":
            # A calibration file (store get's): an accelcal.Calibration, as calibrate's.
            result = parse_calibration_json(out.decode("utf-8"), "accelcal " + " ".join(
                _value(a, "argument") for a in args if isinstance(a, (str, _os.PathLike))))
        elif isinstance(result, dict):
            result = Document(result, command)
    elif options.get("output") not in (None, "-"):
        result = None
    else:
        try:
            result = out.decode("utf-8")
        except UnicodeDecodeError:
            result = out
    if failed:
        w = CalibrationCheckFailed(_python_message("; ".join(failed), command))
        w.findings, w.result = failed, result
        _warnings.warn(w, stacklevel=stacklevel)
    return result


def _describe(option, command):
    """An option's line of a function's docstring: the tool's help, its options named as
    keywords, and its default."""
    text = _python_message(option["description"], command)
    if option["flag"]:
        return f"{text} (a flag: True gives it)"
    if option["default"] is not None:
        return f"{text} (default {option['default']})"
    return text


def _make(spec):
    positionals, options = _parameters(spec)
    names = [_keyword_name(o["name"]) for o in positionals + options]

    def command(*args, **kwargs):
        if len(args) > len(positionals):
            raise TypeError(f"{spec['name']}() takes {len(positionals)} positional arguments "
                            f"but {len(args)} were given")
        unknown = set(kwargs) - set(names)
        if unknown:
            raise TypeError(f"{spec['name']}() got an unexpected keyword argument "
                            f"'{sorted(unknown)[0]}'")
        args = list(args)
        for option in positionals[len(args):]:
            args.append(kwargs.pop(_keyword_name(option["name"]), None))
        for option, value in zip(positionals, args):
            if value is None and option["required"]:
                raise TypeError(f"{spec['name']}() missing the argument "
                                f"'{_keyword_name(option['name'])}'")
        return _run(spec, args, kwargs)

    parameters = [_inspect.Parameter(_keyword_name(o["name"]),
                                     _inspect.Parameter.POSITIONAL_OR_KEYWORD,
                                     **({} if o["required"] else {"default": None}))
                  for o in positionals]
    parameters += [_inspect.Parameter(_keyword_name(o["name"]), _inspect.Parameter.KEYWORD_ONLY,
                                      default=None) for o in options]
    command.__signature__ = _inspect.Signature(parameters)
    command.__name__ = command.__qualname__ = _keyword_name(spec["name"])
    command.__module__ = __name__
    returns = ("an accelcal.Calibration (the calibration file)" if spec["name"] == "calibrate"
               else "the --json document (a dict: an accelcal.Document, to_frame() its table)"
               if _has_json(spec) else
               "what it writes to standard output (str, or bytes when not text), or None when "
               "output names a file")
    lines = [f"accelcal {spec['name']}: {spec['description']}.", "",
             f"Runs the tool's command in this process; returns {returns}.", ""]
    for o in positionals:
        lines.append(f"{_keyword_name(o['name'])}: {_describe(o, spec['name'])}"
                     + ("" if o["required"] else " (optional)"))
    for o in options:
        lines.append(f"{_keyword_name(o['name'])}: {_describe(o, spec['name'])}")
    command.__doc__ = "\n".join(lines)
    return command


__all__ = ["ToolWarning"]
for _spec in _DESCRIPTION["commands"]:
    globals()[_keyword_name(_spec["name"])] = _make(_spec)
    __all__.append(_keyword_name(_spec["name"]))


def _stubs():
    """The type stubs of this module (cli.pyi), made from the same description."""
    # store add writes a list (an entry per calibration), get a calibration, list a document.
    returns = {"calibrate": "Calibration", "store": "Union[Calibration, Document, List[Any]]"}
    lines = ["# Made by accelcal.cli._stubs() from `accelcal --describe-options`; checked by",
             "# python/tests/test_cli.py. To remake it: PYTHONPATH=build/python python3 -c",
             "# 'import accelcal.cli as c; print(c._stubs(), end=\"\")' > python/accelcal/cli.pyi",
             "import os",
             "from typing import Any, List, Optional, Sequence, Union",
             "",
             "from . import Calibration, Document",
             "",
             "PathLike = Union[str, bytes, \"os.PathLike[str]\", \"os.PathLike[bytes]\"]",
             "Value = Union[str, int, float, PathLike]",
             "",
             "class ToolWarning(UserWarning): ...",
             ""]
    for spec in _DESCRIPTION["commands"]:
        result = returns.get(spec["name"], "Document" if _has_json(spec) else
                             "Union[str, bytes, None]")
        positionals, options = _parameters(spec)
        params = []
        for o in positionals:
            kind = "Union[PathLike, Sequence[PathLike]]" if o["many"] else "PathLike"
            params.append(f"{_keyword_name(o['name'])}: {kind}" if o["required"] else
                          f"{_keyword_name(o['name'])}: Optional[{kind}] = None")
        params.append("*")
        for o in options:
            kind = ("bool" if o["flag"] else "Union[Value, Sequence[Value]]" if o["many"]
                    else "Value")
            params.append(f"{_keyword_name(o['name'])}: Optional[{kind}] = None")
        lines.append(f"def {_keyword_name(spec['name'])}({', '.join(params)}) -> {result}: ...")
    return "\n".join(lines) + "\n"

