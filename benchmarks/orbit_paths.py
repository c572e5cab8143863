"""The article's periodic orbits against an earlier checkout (issue 53): the same calls on this code
and on the code of ``--against DIR`` (:mod:`checkouts`: fresh processes, alternating, the minimum of
``--repeats`` each, numba's cache filled by a first call there).

1. 200 period maps of Instance 1's orbit at Omega = 1.6, each with its monodromy (what a Newton
   step of the shooting and of the continuation's corrector takes);
2. ``find_orbit("instance-1", Omega=1.6)`` (a transient of 100 periods, then Newton);
3. the branch of Instance 1 over Omega from 1.3652471 to 1.85 (``continue_orbit``, one process:
   sliding onset, a grazing, two sliding-vanish points 1e-5 apart);
4. ``frequency_response("instance-1", "Omega", (1.3, 1.85), workers=2)``: the library call of
   ``oscillator frc instance-1 --param Omega 1.3 1.85``;
5. the hardening Duffing oscillator of docs/frequency.md (``frequency_response`` over Omega 0.8 to
   1.6, 3 seeds, 81 sweep values, transient 400; one worker);
6. ``oscillator frc instance-1 --param Omega 1.3 1.85`` end to end in a fresh process (``python -m
   oscillator``, figures and report written to a scratch folder).

Paths: period maps with their monodromy, no trajectory kept; the frequency response's measures
read from their own pieces.  The answers are compared, not required equal: the orbits' engine
changed from CVODE to the compiled DOP853 (same orbits to 1e-9, tests/test_orbit_engines.py), and
the corrector's column in the parameter from a central difference to the exact one.

Usage: python benchmarks/orbit_paths.py --against DIR [--repeats N]
"""

from __future__ import annotations

import argparse
import datetime as dt
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from checkouts import ROOT, alternating, fastest, script

_BODY = """
import sys
import numpy as np
import oscillator
from oscillator.orbits.shooting import orbit_case, period_map
from oscillator.orbits.continuation import continue_orbit

assert oscillator.__file__.startswith(sys.argv[1]), oscillator.__file__
case = orbit_case("instance-1", {"Omega": 1.6})
orbit = oscillator.find_orbit(case)


def maps():
    for _ in range(200):
        last = period_map(case, orbit.section, orbit.state).monodromy
    return last.ravel().tolist()


def find():
    return oscillator.find_orbit("instance-1", Omega=1.6).state.tolist()


def branch():
    found = continue_orbit("instance-1", param="Omega", start=1.3652471244941282, stop=1.85,
                           guess=[2.94047837, 6.3078346, 4.69895901, 0.06390857], max_points=3000)
    return [len(found.points), *found.bifurcations["Omega"].tolist()]


def frc():
    found = oscillator.frequency_response("instance-1", "Omega", (1.3, 1.85), workers=2)
    return [len(found.points), *sorted(found.bifurcations["Omega"].tolist())]


def duffing():
    case = oscillator.resolve_case("instance-1", **DUFFING)
    found = oscillator.frequency_response(case, "Omega", (0.8, 1.6), seeds=3, sweep=81,
                                          settings=oscillator.AttractorSettings(transient=400, record=8))
    return [len(found.points), *sorted(found.bifurcations["Omega"].tolist())]


"""
#: docs/frequency.md's hardening Duffing oscillator (mass 1 cubic, no friction, no stops).
DUFFING = dict(m1=1.0, K1=1.0, K2=0.05, C1=0.05, C2=0.0, K3=0.0, C3=0.0, m2=1.5, K4=1.0, K5=0.0, C4=0.2, C5=0.0,
               mu_k=0.0, mu_s=0.0, P1=0.0, P2=0.0, d=1000.0, d1=1000.0, Q1=0.2, Q2=0.1, Omega=0.8, x1=0.0, v1=0.0,
               x2=0.0, v2=0.1)  # fmt: skip
_CALLS = script(f"DUFFING = {DUFFING!r}\n" + _BODY, ("maps", "find", "branch", "frc", "duffing"))

LABELS = {
    "maps": "200 period maps with their monodromy (Instance 1, Omega 1.6)",
    "find": "find_orbit(instance-1, Omega=1.6)",
    "branch": "continue_orbit over Omega 1.3652471..1.85 (one branch)",
    "frc": "frequency_response(instance-1, Omega 1.3..1.85), 2 workers",
    "duffing": "frequency_response of docs/frequency.md's Duffing oscillator, one worker",
}
COMMAND = ["frc", "instance-1", "--param", "Omega", "1.3", "1.85", "--quiet"]


def command(code: Path) -> float:
    """``oscillator frc ...`` end to end in a fresh process on the package at ``code``."""
    env = {**os.environ, "PYTHONPATH": str(code)}
    with tempfile.TemporaryDirectory() as scratch:
        started = time.perf_counter()
        subprocess.run(
            [sys.executable, "-m", "oscillator", *COMMAND, "--out", f"{scratch}/frc"], cwd=code, env=env, check=True
        )
        return time.perf_counter() - started


def _difference(before: list[float], now: list[float]) -> str:
    if len(before) != len(now):
        return f"answers of {len(before)} and {len(now)} numbers"
    return f"answers within {float(np.max(np.abs(np.subtract(before, now)))):.1e}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--against", type=Path, required=True, help="a checkout of the earlier code")
    parser.add_argument("--repeats", type=int, default=2)
    args = parser.parse_args()
    print(f"benchmarks/orbit_paths.py, {dt.datetime.now():%Y-%m-%d %H:%M}, load {os.getloadavg()[0]:.2f}")
    runs = alternating(args.against, _CALLS, repeats=args.repeats)
    for name, label in LABELS.items():
        before, now = fastest(runs["before"], name), fastest(runs["now"], name)
        compared = _difference(runs["before"][0][name][1], runs["now"][0][name][1])
        print(f"{label}: {before:.2f} s -> {now:.2f} s ({before / now:.2f}x), {compared}")
    for name in ("branch", "frc"):
        print(f"  {name}: before {runs['before'][0][name][1]}")
        print(f"  {name}: now    {runs['now'][0][name][1]}")
    commands = {"before": [], "now": []}
    for _ in range(args.repeats):
        commands["before"].append(command(args.against.resolve()))
        commands["now"].append(command(ROOT))
    before, now = min(commands["before"]), min(commands["now"])
    print(f"oscillator {' '.join(COMMAND)} end to end: {before:.1f} s -> {now:.1f} s ({before / now:.2f}x)")
    print(f"load at the end {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
