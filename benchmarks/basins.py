"""The documented basins command on each engine and transient: wall time on this machine's cores,
and whether every start's attractor and every share is the same; with ``--memory``, the peak memory
of the command for growing grids.

Usage: python benchmarks/basins.py [--cells N] [--workers W] [--memory 50 100 200]
  (docs/attractors.md's command: --cells 30, Q2 = 71.165, x2 2..7, v2 -5..5, 100 + 16 periods)
"""

from __future__ import annotations

import argparse
import dataclasses
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import oscillator as osc
from oscillator.attractors.basins import basin_store


def run(case, x, y, settings, workers):
    with tempfile.TemporaryDirectory() as scratch:
        store = basin_store(Path(scratch) / "b", case, x, y, settings)
        store.check()
        started = time.perf_counter()
        basins = osc.find_basins(case, x, y, store, settings=settings, workers=workers)
        return basins, time.perf_counter() - started


def timings(cells: int, workers: int) -> None:
    case = osc.resolve_case("instance-1", Q2=71.165)
    x, y = osc.Axis("x2", 2.0, 7.0, cells), osc.Axis("v2", -5.0, 5.0, cells)
    settled = osc.AttractorSettings(transient=100, record=16)
    variants = {
        "cvode, whole transient": dataclasses.replace(settled, engine="cvode", settle=False),
        "cvode, settled transient": dataclasses.replace(settled, engine="cvode"),
        "dop853, whole transient": dataclasses.replace(settled, settle=False),
        "dop853, settled transient (the default)": settled,
    }
    print(f"basins {cells} x {cells} at Q2 = 71.165, 100 + 16 periods, {workers} workers")
    found = {name: run(case, x, y, settings, workers) for name, settings in variants.items()}
    reference, t_reference = found["cvode, whole transient"]
    for name, (basins, seconds) in found.items():
        same = np.array_equal(basins.grid, reference.grid)
        shares = basins.found.fractions()[["name", "starts"]].equals(reference.found.fractions()[["name", "starts"]])
        print(
            f"  {name:40s} {seconds:7.1f} s  ({t_reference / seconds:5.1f}x)  "
            f"same attractor at every start: {same}; same shares: {shares}"
        )
    for row in reference.found.fractions().itertuples(index=False):
        print(f"    {row.name}: {row.starts} starts")


def peak_memory(cells: int, workers: int) -> tuple[float, float, float]:
    """The command's wall time, and the peak over its run of the process tree's summed resident
    memory and of its largest process (MB), sampled every 50 ms."""
    import psutil

    with tempfile.TemporaryDirectory() as scratch:
        command = [sys.executable, "-m", "oscillator", "basins", "instance-1", "--set", "Q2=71.165"]
        command += ["--x", "x2", "2", "7", str(cells), "--y", "v2", "-5", "5", str(cells), "--transient", "100"]
        command += ["--record", "16", "--workers", str(workers), "--no-plots", "-q", "--out", f"{scratch}/b"]
        started = time.perf_counter()
        process = subprocess.Popen(command, stdout=subprocess.DEVNULL)
        root, total, largest = psutil.Process(process.pid), 0.0, 0.0
        while process.poll() is None:
            try:
                tree = [root, *root.children(recursive=True)]
                sizes = [p.memory_info().rss / 2**20 for p in tree]
            except psutil.Error:
                continue
            total, largest = max(total, sum(sizes)), max(largest, max(sizes))
            time.sleep(0.05)
        assert process.returncode == 0
        return time.perf_counter() - started, total, largest


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", type=int, default=30)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--memory", type=int, nargs="*", metavar="CELLS", help="grids of CELLS x CELLS starts")
    options = parser.parse_args()
    if options.memory:
        print(f"oscillator basins, CELLS x CELLS starts, 100 + 16 periods, {options.workers} workers")
        for cells in options.memory:
            seconds, total, largest = peak_memory(cells, options.workers)
            print(
                f"  {cells:4d} x {cells:<4d} = {cells * cells:6d} starts: {seconds:7.1f} s, peak {total:6.0f} MB "
                f"summed over the processes, {largest:5.0f} MB the largest"
            )
        return
    timings(options.cells, options.workers)


if __name__ == "__main__":
    main()
