"""The local pool's cost against what it gains (issue 56), each pair in one run, alternating:

* the documented basins command (Instance 1, Q2 = 71.165, x2 2..7, v2 -5..5, 100 + 16 periods,
  landings without a trajectory) at N x N starts on one worker and on two: where one worker is as
  fast (``SERIAL_BELOW`` in oscillator/analysis/execution.py);
* the default atlas (80 x 60, ``--starts 3``, 2 workers) with one task a submit (``MAX_CHUNK = 1``,
  as before issue 56) and with the chunks of ``chunk_size``: the same table both ways;
* smaller atlases (12 x 8 and 30 x 20, one start a point) and the documented frequency response
  (``frc instance-1 --param Omega 1.3 1.85``: 2 x 41 sweep values and 5 seeds) on one worker and
  on two: the commands that, without ``--workers``, run fewer than 1,000 landings in their own
  process.

Each is the command itself (``--no-plots``), in a fresh process, warm (the kernels compiled first).

With ``--against DIR`` (a checkout of earlier code), instead, on that code and on this,
alternating, the least of 2 each: the pools' start (the basins command at 10 x 10 on two workers,
one pool in a fresh process; and three ``find_basins`` calls at 8 x 8 on two workers in one Python
session, each its own pool, as a notebook makes them), then (unless ``--no-atlas``) the default
atlas with ``--starts 3`` and whether the tables are the same (the attractors' states and
exponents to within what they moved).

Usage: python benchmarks/pool.py [--cells 10 30 45] [--no-atlas] [--against DIR]
"""

from __future__ import annotations

import argparse
import datetime
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pandas as pd

CHILD = r"""
import os, sys
import oscillator.analysis.execution as execution
code = os.environ.get("POOL_BENCHMARK_CODE")
assert code is None or execution.__file__.startswith(code), (execution.__file__, code)  # the checkout's
execution.MAX_CHUNK = int(sys.argv[1])
from oscillator.cli.app import main
sys.argv = ["oscillator", *sys.argv[2:]]
main()
"""


def timed(arguments: list[str], chunk: int = 8, code: Path | None = None) -> float:
    """The command in a fresh process, on this code or on the package at ``code`` (run in ``code``:
    ``-c`` puts the working folder first on the path, before the editable install's)."""
    env = {**os.environ, "PYTHONPATH": str(code), "POOL_BENCHMARK_CODE": str(code)} if code is not None else None
    started = time.perf_counter()
    subprocess.run([sys.executable, "-c", CHILD, str(chunk), *arguments], check=True, capture_output=True, env=env,
                   cwd=code)  # fmt: skip
    return time.perf_counter() - started


def basins(cells: int, workers: int, folder: Path, code: Path | None = None) -> float:
    axes = ["--x", "x2", "2", "7", str(cells), "--y", "v2", "-5", "5", str(cells)]
    return timed(["basins", "instance-1", "--set", "Q2=71.165", *axes, "--transient", "100", "--record", "16",
                  "--workers", str(workers), "--no-plots", "--quiet", "--out", str(folder)], code=code)  # fmt: skip


def atlas(chunk: int, folder: Path, code: Path | None = None) -> float:
    arguments = ["atlas", "instance-1", "--x", "Omega", "1.3", "1.85", "80", "--y", "Q2", "68.5", "72", "60",
                 "--starts", "3", "--workers", "2", "--no-plots", "--quiet", "--out", str(folder)]  # fmt: skip
    return timed(arguments, chunk, code)


#: Three pools in one session: ``find_basins`` at 8 x 8 on two workers, three times; the seconds of each.
SESSION = r"""
import os, sys, time
import oscillator
from oscillator.analysis.axes import Axis
code = os.environ.get("POOL_BENCHMARK_CODE")
assert code is None or oscillator.__file__.startswith(code), (oscillator.__file__, code)
case = oscillator.resolve_case("instance-1", Q2=71.165)
for _ in range(3):
    started = time.perf_counter()
    oscillator.find_basins(case, Axis("x2", 2, 7, 8), Axis("v2", -5, 5, 8), workers=2)
    print(time.perf_counter() - started)
"""


def session(code: Path | None = None) -> list[float]:
    env = {**os.environ, "PYTHONPATH": str(code), "POOL_BENCHMARK_CODE": str(code)} if code is not None else None
    done = subprocess.run([sys.executable, "-c", SESSION], check=True, capture_output=True, text=True, env=env,
                          cwd=code)  # fmt: skip
    return [float(line) for line in done.stdout.split()]


def pools(code: Path, root: Path, repeats: int = 2) -> None:
    """The pools' start on the code at ``code`` and on this code, alternating, the least of
    ``repeats`` each."""
    fresh: dict[str, list[float]] = {"before": [], "now": []}
    calls: dict[str, list[list[float]]] = {"before": [], "now": []}
    for k in range(repeats):
        fresh["before"].append(basins(10, 2, root / f"pool-before-{k}", code))
        fresh["now"].append(basins(10, 2, root / f"pool-now-{k}"))
        calls["before"].append(session(code))
        calls["now"].append(session())
    before, now = min(fresh["before"]), min(fresh["now"])
    print(f"basins 10 x 10, 2 workers, a fresh process: {before:.2f} s -> {now:.2f} s ({before / now:.2f}x)")
    for label in ("before", "now"):
        best = [min(times[k] for times in calls[label]) for k in range(3)]
        print(
            f"  find_basins 8 x 8 on 2 workers, three in one session, {label}: " + ", ".join(f"{t:.2f} s" for t in best)
        )


def against(code: Path, root: Path, repeats: int = 2, atlas_too: bool = True) -> None:
    """The pools' start (:func:`pools`), then the default atlas with ``--starts 3`` on the code at
    ``code`` and on this code, alternating, the least of ``repeats`` each, and whether the two
    tables are the same."""
    basins(5, 1, root / "warm-before", code), basins(5, 1, root / "warm-now")  # the kernels compiled first
    pools(code, root, repeats)
    if not atlas_too:
        return
    times: dict[str, list[float]] = {"before": [], "now": []}
    for k in range(repeats):
        times["before"].append(atlas(8, root / f"before-{k}", code))
        times["now"].append(atlas(8, root / f"now-{k}"))
    tables = [pd.read_parquet(root / f"{label}-0" / "atlas.parquet") for label in ("before", "now")]
    numbers = ["x1", "v1", "x2", "v2", "lyapunov"]  # a landing's section points move within its tolerance
    same = tables[0].drop(columns=numbers).equals(tables[1].drop(columns=numbers))
    moved = (tables[0][numbers] - tables[1][numbers]).abs().max().max()
    before, now = min(times["before"]), min(times["now"])
    print(f"default atlas, --starts 3, 2 workers, against {code}: {before:.2f} s -> {now:.2f} s "
          f"({before / now:.2f}x); every other column the same: {same}, "
          f"states and exponents within {moved:.1e}")  # fmt: skip


def atlas_of(columns: int, rows: int, workers: int, folder: Path) -> float:
    return timed(["atlas", "instance-1", "--x", "Omega", "1.3", "1.85", str(columns), "--y", "Q2", "68.5", "72",
                  str(rows), "--workers", str(workers), "--no-plots", "--quiet", "--out", str(folder)])  # fmt: skip


def frc(workers: int, folder: Path) -> float:
    return timed(["frc", "instance-1", "--param", "Omega", "1.3", "1.85", "--workers", str(workers), "--no-plots",
                  "--quiet", "--out", str(folder)])  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--cells", type=int, nargs="+", default=[10, 30, 45])
    parser.add_argument("--no-atlas", action="store_true")
    parser.add_argument("--against", type=Path, help="a checkout of earlier code: the default atlas on both, alone")
    options = parser.parse_args()
    print(f"{datetime.datetime.now():%Y-%m-%d %H:%M}, {os.cpu_count()} cores, load {os.getloadavg()[0]:.2f}")
    with tempfile.TemporaryDirectory() as scratch:
        root = Path(scratch)
        if options.against is not None:
            against(options.against.resolve(), root, atlas_too=not options.no_atlas)
            print(f"load at the end {os.getloadavg()[0]:.2f}")
            return
        basins(5, 1, root / "warm")  # the kernels compiled (or loaded) before anything is timed
        print("basins (landings, no trajectory): starts, one worker, two workers")
        for cells in options.cells:
            one, two = basins(cells, 1, root / f"b{cells}-1"), basins(cells, 2, root / f"b{cells}-2")
            print(f"  {cells * cells:>6} {one:8.2f} s {two:8.2f} s")
        print("below 1,000 landings: one worker, two workers")
        for columns, rows in ((12, 8), (30, 20)):
            one, two = atlas_of(columns, rows, 1, root / f"s{rows}-1"), atlas_of(columns, rows, 2, root / f"s{rows}-2")
            print(f"  atlas {columns} x {rows:<3} {one:8.2f} s {two:8.2f} s")
        one, two = frc(1, root / "f1"), frc(2, root / "f2")
        print(f"  frc (82 sweep values, 5 seeds) {one:8.2f} s {two:8.2f} s")
        if options.no_atlas:
            return
        before, after = atlas(1, root / "a1"), atlas(8, root / "a8")
        same = pd.read_parquet(root / "a1" / "atlas.parquet").equals(pd.read_parquet(root / "a8" / "atlas.parquet"))
        print("default atlas, --starts 3, 2 workers (landings, no trajectory):")
        print(f"  one task a submit {before:8.2f} s")
        print(f"  chunks            {after:8.2f} s   ratio {before / after:.2f}x, the same table: {same}")
    print(f"load at the end {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
