"""A friction chain's hot path against an earlier checkout: the same calls on this code and on the
code of ``--against DIR`` (:mod:`checkouts`: a checkout of an earlier commit, each in a fresh
process, numba's cache filled by a first call there, alternating, the minimum of ``--repeats``
each); the answers must be the same.

1. docs/systems.md's design of the friction damper (``oscillator design
   docs/systems/blade-damper.toml --vary platform.F=0.05,3 --over Omega 0.6 1.6 --objective
   x_max:blade --band 5``, the library call: ``chain_design(..., sweep=5)``);
2. its frequency sweep over the band at F = 0.5 N, 11 values (each orbit by Newton with the exact
   monodromy, its measures);
3. 200 period maps of its orbit at Omega = 1.1 with their tangent pass (what a Newton step takes);
4. the calibration of docs/calibration.md's command (``oscillator calibrate
   docs/systems/rattler.toml docs/measured/rattler-response.csv ...``, the library call
   ``calibrate(...)``): every residual's orbit with its measures' exact derivatives.

Paths: period maps and their tangents only, no table read unless a measure needs it (trajectory
off for a user: nothing is written).

Usage: python benchmarks/chain_paths.py --against DIR [--repeats N]
"""

from __future__ import annotations

import argparse
import datetime as dt
import os
from pathlib import Path

from checkouts import ROOT, alternating, fastest, script

_BODY = """
import sys
import numpy as np
from oscillator.designing.chain_design import chain_design
from oscillator.io.chains import load_system
from oscillator.orbits.chain_orbits import chain_period_map, find_chain_orbit
from oscillator.orbits.chain_response import frequency_sweep
from oscillator.orbits.chain_tangents import tangent_pass

machine = load_system(sys.argv[2])
loaded = machine.with_values({"platform.F": 0.5, "Omega": 1.1})
orbit = find_chain_orbit(loaded, transient=60)


def design():
    found = chain_design(machine, {"platform.F": (0.05, 3.0)}, {"Omega": (0.6, 1.6)}, "x_max:blade", sweep=5)
    return [found.value, found.worst.value]


def sweep():
    table = frequency_sweep(machine.with_values({"platform.F": 0.5}), np.linspace(0.6, 1.6, 11), transient=60)
    return table["x_max:blade"].tolist()


def calibration():
    from pathlib import Path

    from oscillator import calibrate
    from oscillator.io.measurements import read_measurements

    rattler = load_system(sys.argv[3]).with_values({"floor.mu_k": 0.08, "floor.mu_s": 0.2, "stop.K": 30.0})
    vary = {"floor.mu_k": (0.02, 0.14), "floor.mu_s": (0.14, 0.4), "stop.K": (10.0, 200.0)}
    found = calibrate(rattler, read_measurements(Path(sys.argv[4])), vary)
    return found.estimate.tolist()


def maps():
    for _ in range(200):
        image = chain_period_map(loaded, loaded.t0, orbit.state)
        last = tangent_pass(image).monodromy
    return last.ravel().tolist()


import oscillator
assert oscillator.__file__.startswith(sys.argv[1]), oscillator.__file__
"""
_CALLS = script(_BODY, ("design", "sweep", "maps", "calibration"))

LABELS = {
    "design": "docs/systems.md's damper design (chain_design, sweep=5)",
    "sweep": "its frequency sweep at F = 0.5 N, 11 values",
    "maps": "200 period maps with their tangent pass",
    "calibration": "docs/calibration.md's calibration of the rattler (calibrate)",
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--against", type=Path, required=True, help="a checkout of the earlier code")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    print(f"benchmarks/chain_paths.py, {dt.datetime.now():%Y-%m-%d %H:%M}, load {os.getloadavg()[0]:.2f}")
    files = [ROOT / "docs" / "systems" / "blade-damper.toml", ROOT / "docs" / "systems" / "rattler.toml"]
    files.append(ROOT / "docs" / "measured" / "rattler-response.csv")
    runs = alternating(args.against, _CALLS, *map(str, files), repeats=args.repeats)
    for name, label in LABELS.items():
        before, now = fastest(runs["before"], name), fastest(runs["now"], name)
        same = runs["before"][0][name][1] == runs["now"][0][name][1]
        print(f"{label}: {before:.2f} s -> {now:.2f} s ({before / now:.2f}x), same answers: {same}")
    print(f"load at the end {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
