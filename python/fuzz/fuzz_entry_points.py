#!/usr/bin/python3
"""Random calls of every public entry point of the accelcal Python package with hostile
arguments (issue 16: a negative rate or a decreasing time array segfaulted the binding).

Arrays of every shape, dtype and memory layout (empty, 1-d, (n, 2), (n, 4), 3-d, float32, int,
bool, complex, object, Fortran order, strided, read-only) holding NaN, infinities, zeros,
constants, 1e±300 and real readings; numbers an option must check (negative, zero, NaN, inf,
beyond int64); wrong words; files that are no logs (a directory, /dev/null, /dev/zero, a missing
path). Each call must return or raise ValueError (InputError and DataError are ValueErrors),
TypeError (pybind11's refusal of an argument's type) or OverflowError; any other exception is a
finding (exit status 1, the call printed), and a crash ends the process with its signal
(faulthandler prints where). Deterministic in --seed: a finding is reproduced by the same seed
and --verbose lists the calls.

Usage: fuzz_entry_points.py [--seconds S] [--seed N] [--verbose]   (PYTHONPATH: build/python)
"""
import argparse
import faulthandler
import os
import random
import sys
import time
import warnings

import numpy as np

import accelcal

DATA = os.environ.get("ACCELCAL_DATA_DIR",
                      os.path.join(os.path.dirname(__file__), "..", "..", "data"))
XSENS_LOG = os.path.join(DATA, "imutk-xsens-mti", "xsens_acc.mat")
XSENS_POSITIONS = os.path.join(DATA, "imutk-xsens-mti", "derived_static_means.csv")
ACCEPTED = (ValueError, TypeError, OverflowError)
# accelcal.cli's exit status 5 (an output that cannot be written) is an OSError.
CLI_ACCEPTED = ACCEPTED + (OSError,)

NUMBERS = [float("nan"), float("inf"), float("-inf"), -1.0, -2.0, 0.0, -0.0, 1e-300, 1e308,
           -1e308, 0.5, 3.0, 100.0, 2 ** 31, 2 ** 63, -(2 ** 63) - 1, 10 ** 30, 1, 0, -1, True]
WORDS = ["", "bogus", "\x00", "x" * 10000, "linear", "quadratic", "auto", "joint", "two-step",
         "newton-lagrange", "modulus", "ellipsoid", "x-first", "z-first", "platform", "ml",
         "bias-corrected", "exclude", "flag", "off", "m/s2", "g", "s", "ms", "us", "ns", "raw",
         "positions", "yaml", "px4", "ardupilot", "kalibr", "c-header", "imutk", "json"]
PATHS = [XSENS_LOG, XSENS_POSITIONS, "/", "/dev/null", "/dev/zero", "/nonexistent/file.csv", "",
         os.path.join(DATA, "README.md"), os.path.join(DATA, "imucal-ferraris", "example_cal.json")]


class Fuzzer:
    def __init__(self, seed):
        self.r = random.Random(seed)
        np_seed = self.r.randrange(2 ** 32)
        self.np = np.random.default_rng(np_seed)
        self.positions = np.loadtxt(XSENS_POSITIONS, delimiter=",", skiprows=1)[:, 3:6]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            self.result = accelcal.calibrate(self.positions, gravity=9.81744)
        self.json_text = self.result.to_json()
        self.log = accelcal.read_input(XSENS_LOG)
        import tempfile
        self.scratch = tempfile.mkdtemp(prefix="accelcal-fuzz-")
        self.json_path = os.path.join(self.scratch, "calibration.json")
        with open(self.json_path, "w") as f:
            f.write(self.json_text)

    def choice(self, items):
        return items[self.r.randrange(len(items))]

    def scalar(self, good):
        """A good value most of the time, else a hostile one of any type."""
        roll = self.r.random()
        if roll < 0.6:
            return good
        if roll < 0.85:
            return self.choice(NUMBERS)
        if roll < 0.95:
            return self.choice(WORDS)
        return self.choice([None, [], [1, 2], {}, object(), b"bytes"])

    def word(self, good):
        return good if self.r.random() < 0.6 else self.choice(WORDS + [None, 3, 1.5])

    def array(self, good=None, rows=None):
        """An array: a mutated copy of `good`, or one made of anything."""
        r = self.r
        if good is not None and r.random() < 0.5:
            a = np.array(good, dtype=float, copy=True)
        else:
            shape = self.choice([(0, 3), (1, 3), (2, 3), (9, 3), (30, 3), (500, 3), (30, 2), (30, 4),
                                 (3,), (0,), (), (30, 3, 1), (rows or 30, 3)])
            scale = self.choice([1e-300, 1e-3, 1.0, 9.8, 3e4, 1e300])
            # (a 0-d draw is a Python float: asarray keeps it an array)
            a = np.asarray(self.np.normal(0.0, 1.0, size=shape) * scale +
                           self.choice([0.0, 1.0, -5e4]))
        if a.size and r.random() < 0.3:  # special values
            flat = a.reshape(-1)
            for _ in range(r.randrange(1, 4)):
                flat[r.randrange(flat.size)] = self.choice(
                    [np.nan, np.inf, -np.inf, 0.0, 1e308, -1e308, 5e-324])
        if r.random() < 0.1:  # (arithmetic on a 0-d array gives a scalar: asarray again)
            a = np.asarray(np.zeros_like(a) + self.choice([0.0, 1.0, np.nan]))
        roll = r.random()
        if roll < 0.05:
            a = a.astype(np.float32)
        elif roll < 0.1:
            a = a.astype(np.int64) if np.isfinite(a).all() and np.abs(a).max(initial=0) < 1e18 \
                else a
        elif roll < 0.12:
            a = a.astype(bool)
        elif roll < 0.14:
            a = a.astype(complex)
        elif roll < 0.16:
            a = a.astype(object)
        elif roll < 0.18:
            return a.tolist()  # a list, or a Python number from a 0-d array: hostile too
        a = np.asarray(a)
        roll = r.random()
        if roll < 0.1 and a.ndim == 2:
            a = np.asfortranarray(a)
        elif roll < 0.2 and a.ndim >= 1 and a.shape[0] > 1:
            a = a[::2]
        elif roll < 0.25:
            a.setflags(write=False)
        return a

    def times(self, n):
        """A time array for n samples: good, decreasing, constant, NaN, wrong length, in µs."""
        good = np.arange(n) * 0.01
        return self.choice([good, good[::-1].copy(), np.zeros(n), np.full(n, np.nan), good[:-1],
                            good * 1e6, np.arange(n + 5) * 1.0, good.reshape(-1, 1), None,
                            self.array(good)])

    # One call of each entry point ------------------------------------------------------------
    def calibrate(self):
        kwargs = dict(model=self.word("linear"), method=self.word("joint"),
                      frame=self.word("x-first"), gravity=self.scalar(9.81744),
                      estimator=self.word("ml"), cross_validate=self.scalar(True),
                      outliers=self.word("exclude"), outlier_probability=self.scalar(1e-3),
                      max_outliers=self.scalar(3), units=self.word(None),
                      max_iterations=self.scalar(0))
        if self.r.random() < 0.3:
            kwargs["reading_sigmas"] = self.array(np.full(self.positions.shape, 0.5))
        return accelcal.calibrate(self.array(self.positions), **self.subset(kwargs))

    def calibrate_log(self):
        kwargs = dict(model=self.word("linear"), gravity=self.scalar(9.81744),
                      columns=self.choice([(), ("1", "2", "3", "4"), ("x",), ("0", "1", "2"),
                                           ("t", "x", "y", "z"), ("99", "1", "2")]),
                      rate=self.scalar(None), window=self.scalar(0.5),
                      min_static=self.scalar(1.0), threshold_factor=self.scalar(10.0),
                      init_rest=self.scalar(0.0), no_crossval=self.scalar(True),
                      bias_model=self.word("constant"), method=self.word("joint"),
                      gyro_columns=self.choice([None, ("1", "2", "3"), ("x",)]),
                      max_outliers=self.scalar(3), units=self.word(None),
                      time_unit=self.word("auto"), instance=self.scalar(None),
                      input_kind=self.word("raw"), max_iterations=self.scalar(0),
                      frame_id=self.word(None))
        return accelcal.calibrate_log(self.choice(PATHS), **self.subset(kwargs))

    def diagnose(self):
        n = self.r.randrange(0, 300)
        samples = self.log["samples"][:n] if isinstance(self.log, dict) and "samples" in self.log \
            else self.array(rows=n)
        kwargs = dict(positions=self.array(self.positions), units=self.word(None),
                      samples=self.array(samples), time=self.times(n), rate_hz=self.scalar(None),
                      time_unit=self.word("s"), max_outliers=self.scalar(None),
                      detection=self.choice([None, {}, {"intervals": []}, {"rejected": 3}]))
        return accelcal.diagnose(self.result, **self.subset(kwargs))

    def read_input(self):
        kwargs = dict(kind=self.word("auto"), columns=self.choice([(), ("1", "2", "3"), ("q",)]),
                      rate_hz=self.scalar(None), time_unit=self.word("auto"),
                      instance=self.scalar(None), frame_id=self.word(None))
        return accelcal.read_input(self.choice(PATHS), **self.subset(kwargs))

    def detect(self):
        n = self.r.choice([0, 1, 2, 10, 1000, 3000])
        kwargs = dict(time=self.times(n), rate_hz=self.scalar(100.0), window_s=self.scalar(0.5),
                      min_static_s=self.scalar(1.0), threshold_factor=self.scalar(10.0),
                      init_rest_s=self.scalar(0.0), time_unit=self.word("s"))
        return accelcal.detect_static_intervals(self.array(rows=n), **self.subset(kwargs))

    def export(self):
        text = self.json_text if self.r.random() < 0.7 else self.mutated_json()
        kwargs = dict(raw_unit=self.word(""), instance=self.scalar(0),
                      c_prefix=self.word("accelcal"))
        return accelcal.export_calibration(text, self.word("yaml"), **self.subset(kwargs))

    def report(self):
        text = self.json_text if self.r.random() < 0.7 else self.mutated_json()
        n = self.r.choice([0, 5, 500])
        kwargs = dict(samples=self.array(rows=n), time=self.times(n), rate_hz=self.scalar(None),
                      time_unit=self.word("s"))
        return accelcal.render_report(text, **self.subset(kwargs))

    def parse(self):
        calibration = accelcal.parse_calibration_json(self.mutated_json(), self.word("<string>"))
        return calibration.provenance, calibration.version, calibration.verdict

    def to_json(self):
        kwargs = dict(positions=self.array(self.positions), units=self.word(None),
                      raw_units=self.word("raw"), source=self.word(None),
                      date=self.choice([None, "2026-11-23", "2026-02-29", "2026-11-23T10:00Z", "",
                                        "yesterday", "2026-11-23T25:00", 20261123, "\u00e9"]))
        return self.result.to_json(**self.subset(kwargs))

    def load(self):
        return accelcal.load_calibration(self.choice(PATHS))

    def apply(self):
        return self.result.apply(self.array(self.positions))

    def cli(self):
        """A command of accelcal.cli with a random subset of its options, hostile values
        included (the keyword layer: its conversions of numbers, lists, flags and paths). Its
        outputs go to a scratch directory; montecarlo and simulate are left to the C++ option
        fuzzer (fuzz_cli_options), where a huge count or duration is cheap to refuse."""
        import inspect
        name = self.choice([n for n in accelcal.cli.__all__
                            if n not in ("ToolWarning", "montecarlo", "simulate")])
        function = getattr(accelcal.cli, name)
        args, kwargs = [], {}
        for parameter in inspect.signature(function).parameters.values():
            if parameter.kind is parameter.POSITIONAL_OR_KEYWORD:
                args.append(self.choice(PATHS + [self.json_path]) if self.r.random() < 0.9
                            else self.choice([None, 3, [XSENS_LOG, XSENS_LOG], b"x"]))
            elif self.r.random() < 0.15:
                if parameter.name in ("output", "report"):
                    kwargs[parameter.name] = os.path.join(self.scratch, self.word("out.txt"))
                else:
                    kwargs[parameter.name] = self.choice([
                        self.scalar(1.0), self.word("auto"), self.choice(PATHS), True, False,
                        [self.scalar(1.0), self.scalar(2.0)], ["x", "y", "z"], []])
        return function(*args, **kwargs)

    def mutated_json(self):
        text = self.json_text
        for _ in range(self.r.randrange(1, 4)):
            i = self.r.randrange(len(text))
            text = text[:i] + self.choice(["", "-", "0.7069", "null", "\"", "}", "]", ",", "1e999",
                                           "\"format\":1,", "\\u0000"]) + text[i + 1:]
        return text

    def subset(self, kwargs):
        """Each keyword given with probability 0.7 (else its default)."""
        return {k: v for k, v in kwargs.items() if self.r.random() < 0.7}


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--seconds", type=float, default=60)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--verbose", action="store_true")
    args = parser.parse_args()
    faulthandler.enable()
    warnings.simplefilter("ignore")
    fuzzer = Fuzzer(args.seed)
    import atexit
    import shutil
    atexit.register(shutil.rmtree, fuzzer.scratch, True)
    calls = [fuzzer.calibrate, fuzzer.calibrate_log, fuzzer.diagnose, fuzzer.read_input,
             fuzzer.detect, fuzzer.export, fuzzer.report, fuzzer.parse, fuzzer.load, fuzzer.apply,
             fuzzer.to_json, fuzzer.cli]
    counts = {c.__name__: 0 for c in calls}
    accepted = 0
    end = time.monotonic() + args.seconds
    executions = 0
    while time.monotonic() < end:
        call = fuzzer.choice(calls)
        if args.verbose:
            print(f"{executions}: {call.__name__}", flush=True)
        try:
            call()
        except CLI_ACCEPTED if call == fuzzer.cli else ACCEPTED:
            accepted += 1
        except Exception as e:  # noqa: BLE001 - anything else is what this harness looks for
            print(f"finding (seed {args.seed}, call {executions}, {call.__name__}): "
                  f"{type(e).__name__}: {e}", file=sys.stderr)
            return 1
        counts[call.__name__] += 1
        executions += 1
    print(f"fuzz_entry_points: {executions} executions in {args.seconds:g} s (seed {args.seed}), "
          f"{accepted} refused as they should be, no finding; "
          + ", ".join(f"{k} {v}" for k, v in counts.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
