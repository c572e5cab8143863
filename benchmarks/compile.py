"""What a fresh install compiles, measured: each set of numba kernels compiled from an empty cache,
in order, in one fresh process (the command's kernels, the compiled landing's, the period map's,
the friction chains'), as the test suite compiles them before its workers start
(``tests/conftest.py``).  With ``--against DIR`` (a checkout of an earlier commit, ``git worktree
add DIR REV``) the same on that code (:mod:`checkouts`: fresh processes, alternating, the least of
the repeats), each process with an empty cache of its own.

Usage: python benchmarks/compile.py [--against DIR] [--repeats N]
"""

from __future__ import annotations

import argparse
import datetime
import os
from pathlib import Path

from checkouts import ROOT, alternating, fastest, timed

#: The compiles, in order, each timed, in a process whose numba cache is a new empty folder (set
#: before numba is imported); its last line is ``{name: [seconds, None]}``.
_CALLS = """
import json, os, sys, tempfile, time
empty = tempfile.TemporaryDirectory()
os.environ["NUMBA_CACHE_DIR"] = empty.name
os.environ["OSCILLATOR_COMPILE_NOTICE"] = "0"
root = sys.argv[1]
sys.path[:0] = [root, root + "/tests"]
import oscillator
assert oscillator.__file__.startswith(root), oscillator.__file__

def kernels():  # the modules compile their kernels as they are imported
    from oscillator.cli.console import compile_kernels
    compile_kernels(beside=False, show=False)

def landing():
    from oscillator.attractors.mapping import _compile_landing
    _compile_landing()

def period_map():
    from oscillator.orbits.stroboscopic import compile_period_map
    compile_period_map()

def chains():
    from conftest import _compile_chains
    _compile_chains()

steps = {"the command's kernels": kernels, "the compiled landing": landing, "the period map": period_map,
         "the friction chains": chains}
seconds = {}
for name, step in steps.items():
    started = time.perf_counter()
    step()
    seconds[name] = (time.perf_counter() - started, None)
empty.cleanup()
print(json.dumps(seconds))
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--against", type=Path, help="a checkout of an earlier commit to compare with")
    parser.add_argument("--repeats", type=int, default=1, help="runs of each code, alternating (default 1)")
    options = parser.parse_args()
    started = datetime.datetime.now().strftime("%Y-%m-%d %H:%M")
    print(f"{started}, {len(os.sched_getaffinity(0))} cores, load {os.getloadavg()[0]:.2f}, numba's cache empty")
    if options.against is None:
        runs = {"now": [timed(ROOT, _CALLS) for _ in range(options.repeats)]}
    else:
        runs = alternating(options.against, _CALLS, repeats=options.repeats)
    print(f"load at the end {os.getloadavg()[0]:.2f}; the least of {options.repeats} run(s) each, seconds:")
    print(f"{'compiled':<24}" + "".join(f"{label:>10}" for label in runs))
    names = list(runs["now"][0])
    for name in names:
        print(f"{name:<24}" + "".join(f"{fastest(each, name):>10.1f}" for each in runs.values()))
    totals = [min(sum(seconds for seconds, _ in run.values()) for run in each) for each in runs.values()]
    print(f"{'in all':<24}" + "".join(f"{total:>10.1f}" for total in totals))


if __name__ == "__main__":
    main()
