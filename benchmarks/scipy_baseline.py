"""The same switching rules on SciPy's ``solve_ivp`` (DOP853 with events): the baseline.

What a SciPy user would write: the field and the root functions in plain Python
(:func:`python_field`, :func:`python_roots`), one ``solve_ivp`` event per root function
(memoised per ``(t, y)``, so SciPy pays one evaluation of the root vector per point it asks
about). The switching decisions are the package's own (``switching.initial_mode`` and
``resolve``): they run at events only, so the comparison is of the integration and root finding.
``compiled=True`` uses the package's compiled formulas instead of the plain-Python ones.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

from oscillator import Case
from oscillator.detection import NUM_ROOTS, Root, root_directions, root_values
from oscillator.fields import state_derivative
from oscillator.switching import initial_mode, resolve

__all__ = ["run_scipy"]

WATCH_ONLY = (Root.EXTREMUM_1, Root.EXTREMUM_2, Root.RELATIVE_VELOCITY)


def python_field(t, y, p, s1, s2, left, right):
    """``(v1, a1, v2, a2)`` in plain Python, as a SciPy user would write it."""
    x1, v1, x2, v2 = y[0], y[1], y[2], y[3]
    f1 = p.Q1 * math.sin(p.Omega * t + p.phi1) - p.K1 * x1 - p.K2 * x1**3 - p.C1 * v1 - p.C2 * v1**3
    f2 = p.Q2 * math.sin(p.Omega * t + p.phi2) - p.K4 * x2 - p.K5 * x2**3 - p.C4 * v2 - p.C5 * v2**3
    if left:
        contact = p.K3 * (x1 - x2 + p.d) + p.C3 * (v1 - v2)
        f1, f2 = f1 - contact, f2 + contact
    if right:
        f1 -= p.K6 * (x1 - p.d1)
    a1 = f1 / p.m1 - s1 * (p.mu_k * p.g + p.P1 / p.m1) if s1 else 0.0
    a2 = f2 / p.m2 - s2 * (p.mu_k * p.g + p.P2 / p.m2) if s2 else 0.0
    return [v1, a1, v2, a2]


def python_roots(t, y, p, s1, s2, left, right):
    """The root vector of ``oscillator.detection`` in plain Python (same layout)."""
    x1, v1, x2, v2 = y[0], y[1], y[2], y[3]
    _, a1, _, a2 = python_field(t, y, p, s1, s2, left, right)
    g = [1.0] * NUM_ROOTS
    for base, s, v, a, mass in ((0, s1, v1, a1, 1), (4, s2, v2, a2, 2)):
        if s:
            g[base], g[base + 1] = v, a
        else:
            force = python_field(t, y, p, 1 if mass == 1 else s1, 1 if mass == 2 else s2, left, right)[2 * mass - 1]
            force += p.mu_k * p.g + (p.P1 / p.m1 if mass == 1 else p.P2 / p.m2)
            barrier = p.mu_s * p.g + (p.P1 / p.m1 if mass == 1 else p.P2 / p.m2)
            g[base + 2], g[base + 3] = force - barrier, force + barrier
    g[Root.RIGHT_STOP] = x1 - p.d1
    g[Root.LEFT_STOP] = x1 - x2 + p.d
    g[Root.RELATIVE_VELOCITY] = v1 - v2
    return g


def run_scipy(case: Case, t_end: float, *, rtol: float, atol: float, compiled: bool = False) -> tuple[list, dict]:
    """Switching events ``(t, mass, kind, to_domain)`` and counters of a run to ``t_end``."""
    p, options = case.parameters, case.options
    start = initial_mode(case.initial.t0, case.initial.y, p)
    mode, y, t = start.mode, np.array(start.y, dtype=float), case.initial.t0
    events = [(e.t, e.mass, str(e.kind), e.to_domain) for e in start.events]
    stats = {"rhs_evaluations": 0, "segments": 0, "steps": 0}
    step = options.max_step_fraction * p.period
    near = options.grazing_displacement_tolerance
    while t < t_end:
        cache: dict = {}

        flags = (mode.sign(1), mode.sign(2), mode.left, mode.right)

        def roots(tt, yy, mode=mode, cache=cache, flags=flags):
            key = (tt, yy.tobytes())
            if key not in cache:
                cache.clear()
                if compiled:
                    cache[key] = root_values(tt, yy, p, mode, step=step, near=near)
                else:
                    cache[key] = python_roots(tt, yy, p, *flags)
            return cache[key]

        def rhs(tt, yy, mode=mode, flags=flags):
            stats["rhs_evaluations"] += 1
            return state_derivative(tt, yy, p, mode) if compiled else python_field(tt, yy, p, *flags)

        watchers = []
        for index, direction in enumerate(root_directions(mode)):

            def watcher(tt, yy, index=index):
                return roots(tt, yy)[index]

            # extrema are watched, not switched on: solve_ivp would stop at them and, restarted
            # at a zero of the same function, stop there again
            watcher.terminal = Root(index) not in WATCH_ONLY
            watcher.direction = direction
            watchers.append(watcher)
        solution = solve_ivp(rhs, (t, t_end), y, method="DOP853", rtol=rtol, atol=atol, events=watchers,
                             max_step=step)  # fmt: skip
        stats["segments"] += 1
        stats["steps"] += len(solution.t) - 1
        terminal = [k for k in range(NUM_ROOTS) if Root(k) not in WATCH_ONLY]
        t_stop = solution.t[-1]
        for k in WATCH_ONLY:  # grazing reports from the watched extrema, with the same rules
            for tk, yk in zip(solution.t_events[k], solution.y_events[k], strict=True):
                if tk < t_stop:
                    report = resolve(tk, yk, p, mode, [Root(k)], options)
                    events.extend((e.t, e.mass, str(e.kind), e.to_domain) for e in report.events)
        if solution.status != 1:
            break
        hits = [(solution.t_events[k][0], k) for k in terminal if solution.t_events[k].size]
        t = min(hit[0] for hit in hits)
        fired = [Root(k) for tk, k in hits if tk == t]
        y = solution.y_events[fired[0]][0].copy()
        resolution = resolve(t, y, p, mode, fired, options)
        events.extend((e.t, e.mass, str(e.kind), e.to_domain) for e in resolution.events)
        y[:4] = resolution.y
        mode = resolution.mode
    events.sort(key=lambda e: e[0])
    return events, stats
