"""The worked calibration of docs/calibration.md, measured: the least-squares fit with the exact
sensitivities against SciPy's Nelder-Mead on the same weighted sum of squares from the same
start (each point's orbit followed by Newton in both, the measures without derivatives for
Nelder-Mead), the simulations counted, each to its own convergence.

From the page's start Nelder-Mead does not reach the optimum; from :data:`NEAR` (three starts
between the page's and the truth) it does, and there both are counted to the same optimum:
Nelder-Mead's simulations until its cost is first within :data:`SAME` of the least squares'
optimum, and until its own convergence.

Usage: python benchmarks/calibration.py
"""

from __future__ import annotations

import datetime as dt
import os
import time
from typing import Any

import numpy as np
import pandas as pd
from scipy.optimize import minimize

import oscillator as osc
from oscillator.hybrid.counting import runs
from oscillator.orbits.chain_response import orbit_measures

SYSTEM = "docs/systems/rattler.toml"
VARY = {"floor.mu_k": (0.02, 0.14), "floor.mu_s": (0.14, 0.4), "stop.K": (10.0, 200.0)}
START = {"floor.mu_k": 0.08, "floor.mu_s": 0.2, "stop.K": 30.0}
MEASURES = (("x_pp:part", 0.01), ("stuck:floor", 0.01), ("force_max:stop", 0.1))
#: Starts from which Nelder-Mead reaches the optimum too.
NEAR = (
    {"floor.mu_k": 0.09, "floor.mu_s": 0.17, "stop.K": 40.0},
    {"floor.mu_k": 0.11, "floor.mu_s": 0.14, "stop.K": 70.0},
    {"floor.mu_k": 0.12, "floor.mu_s": 0.2, "stop.K": 60.0},
)
#: "The same optimum": a cost within this share of the least squares' optimum.
SAME = 1e-6


def measured(truth: Any) -> pd.DataFrame:
    """docs/calibration.md's data: six frequencies, three measures each, seeded noise."""
    rng = np.random.default_rng(1)
    rows = []
    for omega in (0.6, 0.7, 0.8, 0.9, 1.0, 1.1):
        measures = orbit_measures(osc.find_orbit(truth, Omega=omega))
        rows += [(omega, name, measures[name] + rng.normal(0, sigma), sigma) for name, sigma in MEASURES]
    return pd.DataFrame(rows, columns=["Omega", "measure", "value", "sigma"])


def nelder_mead(guess: Any, data: pd.DataFrame, target: float) -> tuple[np.ndarray, float, int, int, int | None]:
    """Nelder-Mead on the scaled box from ``guess``'s values: the estimate, its cost (half the sum
    of squares), the simulations and the function evaluations, and the simulations until the cost
    was first within :data:`SAME` of ``target`` (None: never)."""
    names = list(VARY)
    low, high = (np.array([VARY[n][k] for n in names]) for k in (0, 1))
    guesses: dict[float, np.ndarray] = {}
    calls, before, reached = [0], runs(), [None]

    def cost(u: np.ndarray) -> float:
        calls[0] += 1
        values = dict(zip(names, low + np.clip(u, 0, 1) * (high - low), strict=True))
        total = 0.0
        for omega, rows in data.groupby("Omega"):
            try:
                orbit = osc.find_orbit(guess, guess=guesses.get(omega), **values, Omega=omega)
            except osc.SimulationFailed:  # lost by a long step: settled afresh, as calibrate does
                try:
                    orbit = osc.find_orbit(guess, **values, Omega=omega)
                except osc.SimulationFailed:  # no period-1 orbit there: a step refused, as calibrate does
                    return np.inf
            guesses[omega] = orbit.state
            measures = orbit_measures(orbit)
            total += float((((rows.measure.map(measures) - rows.value) / rows.sigma) ** 2).sum())
        if reached[0] is None and 0.5 * total <= target * (1 + SAME):
            reached[0] = runs() - before
        return 0.5 * total

    u0 = np.array([(guess.value(n) - lo) / (hi - lo) for n, lo, hi in zip(names, low, high, strict=True)])
    solved = minimize(cost, u0, method="Nelder-Mead", bounds=[(0, 1)] * len(names),
                      options={"xatol": 1e-7, "fatol": 1e-9, "maxfev": 3000})  # fmt: skip
    return low + solved.x * (high - low), float(solved.fun), runs() - before, calls[0], reached[0]


def _text(values: np.ndarray) -> str:
    return ", ".join(f"{name} = {value:.8g}" for name, value in zip(VARY, values, strict=True))


def compare(guess: Any, data: pd.DataFrame) -> None:
    """Both fits from ``guess``'s values, counted."""
    started = time.perf_counter()
    found = osc.calibrate(guess, data, VARY)
    exact = time.perf_counter() - started
    print(f"  least squares, exact sensitivities: {_text(found.estimate.to_numpy())}, cost {found.cost:.8f}")
    print(f"    {found.evaluations} evaluations, {found.runs} simulations, {exact:.1f} s")
    started = time.perf_counter()
    x, cost, spent, calls, reached = nelder_mead(guess, data, found.cost)
    elapsed = time.perf_counter() - started
    print(f"  Nelder-Mead: {_text(x)}, cost {cost:.8f}")
    print(f"    {calls} evaluations, {spent} simulations ({spent / found.runs:.1f}x), {elapsed:.1f} s")
    if reached is None:
        print(f"    never within {SAME:g} of the least squares' cost")
    else:
        ratio = reached / found.runs
        print(f"    within {SAME:g} of the least squares' cost after {reached} simulations ({ratio:.1f}x)")
    gap = (x - found.estimate.to_numpy()) / found.table.stderr.to_numpy()
    print(f"    Nelder-Mead's estimate minus the least squares', in standard errors: {gap.round(4).tolist()}")


def main() -> None:
    print(f"benchmarks/calibration.py, {dt.datetime.now():%Y-%m-%d %H:%M}, load {os.getloadavg()[0]:.2f}")
    truth = osc.load_system(SYSTEM)
    data = measured(truth)
    for start in (START, *NEAR):
        print(f"from {_text(np.array([start[n] for n in VARY]))}:")
        compare(truth.with_values(start), data)


if __name__ == "__main__":
    main()
