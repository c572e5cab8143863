"""The same switching rules on SciPy's ``solve_ivp`` (DOP853 with events): the baseline.

What a SciPy user would write: the field and the root functions in plain Python
(:func:`python_field`, :func:`python_roots`), handed to the package's SciPy engine
(:class:`oscillator.engines.scipy.ScipyEngine`: one ``solve_ivp`` call per mode, one event per root
function). The supervisor and the switching decisions are the package's own, so the comparison is
of the integration and the root finding. ``compiled=True`` uses the package's compiled formulas
instead of the plain-Python ones.
"""

from __future__ import annotations

import math

from oscillator import Case, simulate
from oscillator.engines.scipy import ScipyEngine
from oscillator.model.roots import NUM_ROOTS, Root

__all__ = ["run_scipy"]


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
    """The root vector of ``oscillator.model.roots`` in plain Python (same layout)."""
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


def plain_python_engine(p, options):
    """The SciPy engine on the plain-Python field of the state (no work quadratures, as a script has)."""

    def flags(mode):
        return mode.sign(1), mode.sign(2), mode.left, mode.right

    def field(t, y, mode):
        return python_field(t, y, p, *flags(mode))

    def roots(t, y, mode):
        return python_roots(t, y, p, *flags(mode))

    return ScipyEngine(p, options, field=field, roots=roots, quadratures=False)


def run_scipy(case: Case, t_end: float, *, rtol: float, atol: float, compiled: bool = False) -> tuple[list, dict]:
    """Switching events ``(t, mass, kind, to_domain)`` and counters of a run to ``t_end``."""
    result = simulate(case, t_end=t_end, rtol=rtol, atol=atol, record_trajectory=False,
                      engine=ScipyEngine if compiled else plain_python_engine)  # fmt: skip
    events = [(e.t, e.mass, str(e.kind), e.to_domain) for e in result.events.itertuples(index=False)]
    stats = {"rhs_evaluations": result.stats.rhs_evaluations, "segments": result.stats.restarts,
             "steps": result.stats.returns}  # fmt: skip
    return events, stats
