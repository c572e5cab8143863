"""The documented basins command, with the transient ended where each start settled and with the
whole transient: wall time on this machine's cores, the periods run, and whether every start's
attractor and every share is the same.

Usage: python benchmarks/basins.py [--cells N] [--workers W]
  (docs/attractors.md's command: --cells 30, Q2 = 71.165, x2 2..7, v2 -5..5, 100 + 16 periods)
"""

from __future__ import annotations

import argparse
import dataclasses
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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", type=int, default=30)
    parser.add_argument("--workers", type=int, default=2)
    options = parser.parse_args()
    case = osc.resolve_case("instance-1", Q2=71.165)
    x, y = osc.Axis("x2", 2.0, 7.0, options.cells), osc.Axis("v2", -5.0, 5.0, options.cells)
    settled = osc.AttractorSettings(transient=100, record=16)
    whole = dataclasses.replace(settled, settle=False)
    print(f"basins {options.cells} x {options.cells} at Q2 = 71.165, 100 + 16 periods, {options.workers} workers")
    quick, t_quick = run(case, x, y, settled, options.workers)
    full, t_full = run(case, x, y, whole, options.workers)
    same = np.array_equal(quick.grid, full.grid)
    shares = quick.found.fractions()[["name", "starts"]].equals(full.found.fractions()[["name", "starts"]])
    print(f"  whole transient:    {t_full:7.1f} s")
    print(f"  settled transient:  {t_quick:7.1f} s   ({t_full / t_quick:.1f}x)")
    print(f"  every start's attractor the same: {same}; every share the same: {shares}")
    for row in quick.found.fractions().itertuples(index=False):
        print(f"    {row.name}: {row.starts} starts")


if __name__ == "__main__":
    main()
