"""What a fresh install compiles, measured: each set of numba kernels compiled from an empty cache,
in order, in one fresh process (the command's kernels, the compiled landing's, the period map's,
the friction chains'), as the test suite compiles them before its workers start
(``tests/conftest.py``).  With ``--against DIR`` (a checkout of an earlier commit, ``git worktree
add DIR REV``) the same in a fresh process on that code, alternating, each with an empty cache of
its own; the date, the cores and the load average before each printed beside.

Usage: python benchmarks/compile.py [--against DIR] [--repeats N]
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: The compiles, in order, each timed; the last line printed is their seconds as JSON.
_SCRIPT = """
import json, sys, time
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
    seconds[name] = time.perf_counter() - started
print(json.dumps(seconds))
"""


def cold(root: Path, scratch: Path) -> dict[str, float]:
    """The seconds of each compile on the code at ``root``, numba's cache empty."""
    cache = Path(tempfile.mkdtemp(dir=scratch))
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache), "OSCILLATOR_COMPILE_NOTICE": "0"}
    print(f"    {root}: load average before {os.getloadavg()[0]:.2f}", flush=True)
    done = subprocess.run(
        [sys.executable, "-c", _SCRIPT, str(root)], env=env, cwd=scratch, capture_output=True, text=True
    )
    if done.returncode != 0:
        sys.exit(f"the compile on {root} failed:\n{done.stderr[-3000:]}")
    seconds: dict[str, float] = json.loads(done.stdout.strip().splitlines()[-1])
    return seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--against", type=Path, help="a checkout of an earlier commit to compare with")
    parser.add_argument("--repeats", type=int, default=1, help="runs of each code, alternating (default 1)")
    options = parser.parse_args()
    trees = [ROOT] if options.against is None else [options.against.resolve(), ROOT]
    started = datetime.datetime.now().strftime("%Y-%m-%d %H:%M")
    print(f"{started}, {len(os.sched_getaffinity(0))} cores, numba's cache empty for each run")
    runs: dict[Path, list[dict[str, float]]] = {tree: [] for tree in trees}
    with tempfile.TemporaryDirectory() as scratch:
        for _ in range(options.repeats):
            for tree in trees:
                runs[tree].append(cold(tree, Path(scratch)))
    print(f"load average at the end {os.getloadavg()[0]:.2f}; the least of {options.repeats} run(s) each, seconds:")
    names = list(runs[ROOT][0])
    print(f"{'compiled':<24}" + "".join(f"{str(tree)[-28:]:>30}" for tree in trees))
    for name in [*names, "in all"]:
        cells = []
        for tree in trees:
            values = [sum(run.values()) if name == "in all" else run[name] for run in runs[tree]]
            cells.append(f"{min(values):>30.1f}")
        print(f"{name:<24}" + "".join(cells))


if __name__ == "__main__":
    main()
