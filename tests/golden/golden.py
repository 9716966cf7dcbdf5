#!/usr/bin/python3
"""Golden outputs: every command of the CLI on the bundled recordings and the test inputs.

Each case of cases.txt runs in one shared working directory (where `data`, `hostile`, `inputs` and
`v1`, the version-1 calibration files, name the project's folders, so that paths in outputs are the
same on every machine), in order, so a case may read what an earlier one wrote. Its exit status, stdout, stderr and every file it created
or changed are compared byte for byte with expected/NAME.txt: a refactoring that changes an output
fails here. Outputs larger than 64 KiB (the HTML reports, corrected streams) are compared by
SHA-256 and size. Wall-clock times in the text outputs (the solver's microseconds, `-v`'s
milliseconds, compare's time row) are masked: they are the only outputs allowed to vary.

  golden.py ACCELCAL          compare; on a difference print it and keep the run's directory
  golden.py ACCELCAL --update rewrite expected/ (review the diff before committing it)
  golden.py --in-process      the same cases through the Python package's in-process runner
                              (accelcal._accelcal._run_command, which accelcal.cli calls; the
                              package on PYTHONPATH): the same bytes as the tool's
"""
import hashlib
import re
import os
import shlex
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
INLINE_LIMIT = 64 * 1024
TIMINGS = [
    (re.compile(r"; [0-9.]+ us\b"), "; <time> us"),
    (re.compile(r"\bin [0-9.]+ ms\b"), "in <time> ms"),
    (re.compile(r"^(time \[us\]) .*$", re.M), r"\1 <times>"),
]


def mask_timings(text):
    for pattern, replacement in TIMINGS:
        text = pattern.sub(replacement, text)
    return text


def read_cases():
    cases = []
    with open(os.path.join(HERE, "cases.txt"), encoding="utf-8") as f:
        for number, line in enumerate(f, 1):
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            name, sep, args = line.partition(":")
            if not sep or not name.strip() or any(c in name for c in "/ \t"):
                sys.exit(f"cases.txt:{number}: expected 'name: arguments'")
            cases.append((name.strip(), shlex.split(args)))
    names = [n for n, _ in cases]
    if len(set(names)) != len(names):
        sys.exit("cases.txt: a case name is used twice")
    return cases


def snapshot(directory):
    state = {}
    for name in sorted(os.listdir(directory)):
        path = os.path.join(directory, name)
        if os.path.isfile(path) and not os.path.islink(path):
            with open(path, "rb") as f:
                state[name] = f.read()
    return state


def describe(content):
    """A file's content as text for the record: itself when small UTF-8, else its digest."""
    if len(content) <= INLINE_LIMIT:
        try:
            text = content.decode("utf-8")
            if "\0" not in text:
                return text if text.endswith("\n") or not text else text + "\n[no final newline]\n"
        except UnicodeDecodeError:
            pass
    return f"[{len(content)} bytes, sha256 {hashlib.sha256(content).hexdigest()}]\n"


def run_in_process(args, work):
    """The case through the Python package's runner, in this process (cwd: work; stdin: empty,
    as the tool's run has it)."""
    import accelcal
    previous = os.getcwd()
    saved_stdin = os.dup(0)
    empty = os.open(os.devnull, os.O_RDONLY)
    try:
        os.chdir(work)
        os.dup2(empty, 0)
        status, out, err = accelcal._accelcal._run_command(args)
    finally:
        os.dup2(saved_stdin, 0)
        os.close(saved_stdin)
        os.close(empty)
        os.chdir(previous)
    return subprocess.CompletedProcess(args, status, out, err)


def run_case(accelcal, work, args):
    before = snapshot(work)
    env = dict(os.environ, LC_ALL="C", LANG="C")
    env.pop("ACCELCAL_THREADS", None)
    if accelcal is None:
        r = run_in_process(args, work)
    else:
        # argv[0] is "accelcal", as on a PATH: help texts print it, and the build directory
        # differs from one clone to the next.
        r = subprocess.run(["accelcal"] + args, executable=accelcal, cwd=work,
                           stdin=subprocess.DEVNULL, capture_output=True, env=env, timeout=600)
    after = snapshot(work)
    record = [f"$ accelcal {shlex.join(args)}\n", f"status {r.returncode}\n",
              "--- stdout\n", describe(r.stdout), "--- stderr\n", describe(r.stderr)]
    for name, content in after.items():
        if before.get(name) != content:
            record += [f"--- file {name}\n", describe(content)]
    return mask_timings("".join(record))


def main():
    if sys.argv[1:] == ["--in-process"]:
        accelcal = None
        update = False
        os.environ.pop("ACCELCAL_THREADS", None)
    elif len(sys.argv) < 2 or not os.access(sys.argv[1], os.X_OK):
        sys.exit(__doc__)
    else:
        accelcal = os.path.abspath(sys.argv[1])
        update = "--update" in sys.argv[2:]
    expected_dir = os.path.join(HERE, "expected")
    work = tempfile.mkdtemp(prefix="accelcal-golden-")
    for link, target in (("data", os.path.join(ROOT, "data")),
                         ("hostile", os.path.join(ROOT, "tests", "hostile")),
                         ("inputs", os.path.join(HERE, "inputs")),
                         ("v1", os.path.join(ROOT, "tests", "data", "calibration-v1"))):
        os.symlink(target, os.path.join(work, link))
    cases = read_cases()
    failures = []
    for name, args in cases:
        got = run_case(accelcal, work, args)
        path = os.path.join(expected_dir, name + ".txt")
        if update:
            os.makedirs(expected_dir, exist_ok=True)
            with open(path, "w", encoding="utf-8") as f:
                f.write(got)
            continue
        try:
            with open(path, encoding="utf-8") as f:
                want = f.read()
        except FileNotFoundError:
            want = None
        if got != want:
            failures.append(name)
            with open(os.path.join(work, name + ".actual.txt"), "w", encoding="utf-8") as f:
                f.write(got)
            if want is None:
                print(f"{name}: no expected/{name}.txt")
            else:
                import difflib
                diff = difflib.unified_diff(want.splitlines(True), got.splitlines(True),
                                            f"expected/{name}.txt", "actual", n=2)
                print(f"{name}: differs\n" + "".join(list(diff)[:60]))
    if update:
        known = {n + ".txt" for n, _ in cases}
        for stale in sorted(set(os.listdir(expected_dir)) - known):
            os.remove(os.path.join(expected_dir, stale))
        shutil.rmtree(work)
        print(f"wrote {len(cases)} cases to {expected_dir}")
        return
    if failures:
        print(f"{len(failures)} of {len(cases)} cases differ; outputs kept in {work}")
        sys.exit(1)
    shutil.rmtree(work)
    print(f"{len(cases)} cases, every output as expected")


if __name__ == "__main__":
    main()
