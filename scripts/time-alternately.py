#!/usr/bin/env python3
"""Whole-process times of several commands run alternately, so that the VM's changing load falls on
all of them alike (hyperfine runs one command's runs, then the next's). Prints each one's median
and quartiles in ms.

  scripts/time-alternately.py RUNS 'CMD A ...' 'ENV=1 CMD B ...'

A command may start with VAR=value words, set in its environment."""
import os
import statistics
import subprocess
import sys
import time


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    runs = int(sys.argv[1])
    commands = []
    for spec in sys.argv[2:]:
        words, env = spec.split(), dict(os.environ)
        while words and "=" in words[0]:
            key, value = words.pop(0).split("=", 1)
            env[key] = value
        commands.append((words, env))
    times = [[] for _ in commands]
    with open(os.devnull, "w") as null:
        for _ in range(runs):
            for (words, env), spent in zip(commands, times):
                start = time.perf_counter()
                subprocess.run(words, stdout=null, stderr=null, env=env, check=False)
                spent.append(time.perf_counter() - start)
    for spec, spent in zip(sys.argv[2:], times):
        spent.sort()
        print(f"median {1e3 * statistics.median(spent):6.2f} ms, quartiles "
              f"{1e3 * spent[len(spent) // 4]:6.2f} {1e3 * spent[3 * len(spent) // 4]:6.2f}  {spec}")


if __name__ == "__main__":
    main()
