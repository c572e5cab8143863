"""The worked design of docs/design.md, measured: the global search, the gradient refinement with
the exact sensitivities against SciPy's Nelder-Mead from the same start on the same worst-case
function (simulations counted, each optimiser to its own convergence), and an independent
brute-force grid over the same parameters judged from fresh starts.

With ``--overhead``, instead: the documented command (``oscillator design instance-1 ...`` of
docs/design.md, figures and report) against its library call, each end to end in a fresh process
(imports and the compiled kernels loaded from numba's cache in both), alternating, the least of
``--repeats``.

Usage: python benchmarks/design.py [--grid N] [--workers W] [--overhead [--repeats N]]
"""

from __future__ import annotations

import argparse
import datetime as dt
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
from scipy.optimize import minimize

from oscillator.attractors.mapping import AttractorSettings
from oscillator.designing.judging import Judged, follow, survey_task
from oscillator.designing.optimise import design, refine
from oscillator.designing.problem import Problem
from oscillator.hybrid.counting import runs

VARY = {"d1": (2.5, 4.5), "K6": (1.0, 40.0)}
OVER = {"Omega": (1.4, 1.6)}
OBJECTIVE, CONSTRAINTS = "x_max_m1", ["impact_max_right <= 5", "rest_m2 <= 0.01"]
SETTINGS = AttractorSettings(transient=100, record=8)
#: Nelder-Mead's penalty on a broken constraint (per unit of the measure).
PENALTY = 1e3


def nelder_mead(problem: Problem, start: Judged) -> tuple[np.ndarray, float, int, int]:
    """Nelder-Mead on the same scaled box from the same start, on the worst objective plus
    :data:`PENALTY` times the violation, the attractors followed by Newton without derivatives:
    the design, its worst objective, the simulations and the function evaluations."""
    scale = problem.upper - problem.lower
    before = runs()
    calls = [0]
    base = [start]

    def worst(u: np.ndarray) -> float:
        calls[0] += 1
        judged = follow(problem, base[-1], problem.lower + np.clip(u, 0, 1) * scale, gradients=False)
        base.append(judged)
        return judged.objective + PENALTY * judged.violation

    u0 = (start.design - problem.lower) / scale
    solved = minimize(
        worst, u0, method="Nelder-Mead", bounds=[(0, 1)] * len(u0),
        options={"xatol": 1e-7, "fatol": 1e-10, "maxfev": 5000},
    )  # fmt: skip
    x = problem.lower + solved.x * scale
    return x, float(solved.fun), runs() - before, calls[0]


def grid(problem: Problem, count: int) -> tuple[np.ndarray, float, int]:
    """The best feasible design of a ``count`` x ``count`` grid, each judged by a survey."""
    best, total = (None, np.inf), 0
    axes = [np.linspace(low, high, count) for _, low, high in problem.vary]
    for a in axes[0]:
        for b in axes[1]:
            seen, cost = [], 0
            for band in problem.band_values():
                found, spent = survey_task(problem, SETTINGS, (a, b), float(band))
                seen += found
                cost += spent
            judged = Judged.of(problem, np.array([a, b]), seen, cost, "grid")
            total += cost
            if judged.feasible and judged.objective < best[1]:
                best = (judged.design, judged.objective)
    return best[0], best[1], total


COMMAND = ["design", "instance-1", "--vary", "d1=2.5,4.5", "--vary", "K6=1,40", "--over", "Omega", "1.4", "1.6",
           "--objective", OBJECTIVE, *[a for c in CONSTRAINTS for a in ("--constraint", c)], "--band", "3",
           "--starts", "2", "--candidates", "8", "--transient", "100", "--record", "8", "--quiet"]  # fmt: skip
LIBRARY = f"""
from oscillator.attractors.mapping import AttractorSettings
from oscillator.designing.optimise import design
design("instance-1", {VARY!r}, {OVER!r}, {OBJECTIVE!r}, {CONSTRAINTS!r}, band=3, starts=2, candidates=8,
       settings=AttractorSettings(transient=100, record=8), workers=1)
"""


def _fresh(arguments: list[str]) -> float:
    started = time.perf_counter()
    subprocess.run([sys.executable, *arguments], check=True, capture_output=True)
    return time.perf_counter() - started


def overhead(repeats: int) -> None:
    """The command against its library call, each in a fresh process (module docstring)."""
    print(f"benchmarks/design.py --overhead, {dt.datetime.now():%Y-%m-%d %H:%M}, load {os.getloadavg()[0]:.2f}")
    times: dict[str, list[float]] = {"library": [], "command": []}
    with tempfile.TemporaryDirectory() as scratch:
        for k in range(repeats):
            times["library"].append(_fresh(["-c", LIBRARY]))
            times["command"].append(_fresh(["-m", "oscillator", *COMMAND, "--out", f"{scratch}/design-{k}"]))
    library, command = min(times["library"]), min(times["command"])
    print(f"  library call (fresh process, one worker): {library:.2f} s")
    print(f"  oscillator design ... (figures and report): {command:.2f} s, {command / library:.2f}x the library call")
    print(f"load at the end {os.getloadavg()[0]:.2f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--grid", type=int, default=21)
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--overhead", action="store_true", help="the command against its library call")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    if args.overhead:
        overhead(args.repeats)
        return
    started = time.perf_counter()
    found = design("instance-1", VARY, OVER, OBJECTIVE, CONSTRAINTS, band=3, starts=2, candidates=8,
                   settings=SETTINGS, workers=args.workers)  # fmt: skip
    elapsed = time.perf_counter() - started
    print(f"design: {found.values} worst {OBJECTIVE} {found.best.objective:.9f}, violation {found.best.violation:g}")
    print(f"  simulations {found.runs}, {elapsed:.1f} s; {found.message}")
    problem, start = found.problem, found.start
    steps, _ = refine(problem, start)
    gradient = min(steps, key=Judged.key)
    spent = sum(j.runs for j in steps)
    x, value, nm_runs, calls = nelder_mead(problem, start)
    print(f"from {problem.design(start.design)}:")
    print(f"  SLSQP with exact gradients: {problem.design(gradient.design)} {gradient.objective:.9f}, "
          f"{len(steps)} evaluations, {spent} simulations")  # fmt: skip
    print(f"  Nelder-Mead: {problem.design(x)} {value:.9f}, {calls} evaluations, {nm_runs} simulations "
          f"({nm_runs / max(spent, 1):.1f}x the gradient's)")  # fmt: skip
    started = time.perf_counter()
    best, objective, total = grid(problem, args.grid)
    print(f"grid {args.grid}x{args.grid}: best feasible {problem.design(best)} {objective:.9f}, "
          f"{total} simulations, {time.perf_counter() - started:.1f} s")  # fmt: skip
    steps = (problem.upper - problem.lower) / (args.grid - 1)
    print(f"  grid step {dict(zip(problem.names, steps, strict=True))}; optimum - grid best: "
          f"{dict(zip(problem.names, found.best.design - best, strict=True))}")  # fmt: skip


if __name__ == "__main__":
    main()
