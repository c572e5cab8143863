"""An independent event-driven implementation on SciPy, written from docs/model.md (Sec. 1-6) alone.

It shares no code with the package: its own forces, its own mode bookkeeping, SciPy's DOP853 with
``solve_ivp`` events instead of CVODE.  Tests compare the package's switching events with it on
cases that reach every domain.  It returns ``(t, mass, kind, to_sign)`` tuples for the switches
(grazing is not reported here).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp


def _watched(function, direction):
    """A terminal ``solve_ivp`` event watching one crossing direction."""
    function.direction = direction
    function.terminal = True
    return function


def run(p: dict, t0: float, y0, t_end: float, *, rtol: float = 1e-12, atol: float = 1e-12, max_step: float = 0.002):
    """Switching events ``(t, mass, kind, to_sign)``; steps capped at ``max_step`` forcing periods.

    The cap is small so that a contact or rest lasting a few hundredths of a second is not
    stepped over (this implementation watches no extrema).
    """
    g = p["g"]
    mass = {1: p["m1"], 2: p["m2"]}
    fb = {1: p["P1"] / p["m1"], 2: p["P2"] / p["m2"]}
    kin = {i: p["mu_k"] * g + fb[i] for i in (1, 2)}
    sta = {i: p["mu_s"] * g + fb[i] for i in (1, 2)}

    def forces(t, y, left, right):
        x1, v1, x2, v2 = y[:4]
        f1 = p["Q1"] * math.sin(p["Omega"] * t + p["phi1"]) - p["K1"] * x1 - p["K2"] * x1**3 - p["C1"] * v1
        f1 -= p["C2"] * v1**3
        f2 = p["Q2"] * math.sin(p["Omega"] * t + p["phi2"]) - p["K4"] * x2 - p["K5"] * x2**3 - p["C4"] * v2
        f2 -= p["C5"] * v2**3
        if left:
            c = p["K3"] * (x1 - x2 + p["d"]) + p["C3"] * (v1 - v2)
            f1, f2 = f1 - c, f2 + c
        if right:
            f1 -= p["K6"] * (x1 - p["d1"])
        return {1: f1 / mass[1], 2: f2 / mass[2]}

    y = np.array(y0, dtype=float)
    t = t0
    sign = {i: (0 if y[2 * i - 1] == 0 else int(math.copysign(1, y[2 * i - 1]))) for i in (1, 2)}
    z1 = y[0] - y[2]
    left = z1 < -p["d"] or (z1 == -p["d"] and y[1] - y[3] <= 0)
    right = y[0] > p["d1"] or (y[0] == p["d1"] and y[1] >= 0)
    log = []

    def settle():
        for _ in range(8):
            changed = False
            a = forces(t, y, left, right)
            for i in (1, 2):
                if sign[i] == 0 and abs(a[i]) > sta[i] + 1e-9 * (1 + sta[i]):
                    sign[i] = 1 if a[i] > 0 else -1
                    log.append((t, i, "sliding_vanish", sign[i]))
                    changed = True
            if not changed:
                return

    settle()
    while t < t_end:
        s, L, R = dict(sign), left, right

        def rhs(tt, yy, s=s, L=L, R=R):
            a = forces(tt, yy, L, R)
            acc = {i: (a[i] - s[i] * kin[i]) if s[i] else 0.0 for i in (1, 2)}
            return [yy[1], acc[1], yy[3], acc[2]]

        events, meaning = [], []

        for i in (1, 2):
            if s[i]:
                events.append(_watched(lambda tt, yy, i=i: yy[2 * i - 1], -s[i]))
                meaning.append(("velocity", i))
            else:
                for side in (1, -1):
                    barrier = _watched(
                        lambda tt, yy, i=i, side=side, L=L, R=R: forces(tt, yy, L, R)[i] - side * sta[i], side
                    )
                    events.append(barrier)
                    meaning.append(("barrier", i, side))
        events.append(_watched(lambda tt, yy: yy[0] - p["d1"], -1 if R else 1))
        meaning.append(("right",))
        events.append(_watched(lambda tt, yy: yy[0] - yy[2] + p["d"], 1 if L else -1))
        meaning.append(("left",))

        sol = solve_ivp(rhs, (t, t_end), y, method="DOP853", rtol=rtol, atol=atol, events=events,
                        max_step=max_step * 2 * math.pi / p["Omega"])  # fmt: skip
        if sol.status != 1:
            break
        hits = [(sol.t_events[k][0], k) for k in range(len(events)) if sol.t_events[k].size]
        t_hit = min(h[0] for h in hits)
        fired = [meaning[k] for tk, k in hits if tk - t_hit < 1e-12]
        t = t_hit
        y = sol.y_events[min(hits)[1]][0].copy()
        for m in fired:
            if m == ("right",):
                right = not right
                log.append((t, 1, "right_contact_onset" if right else "right_contact_release", sign[1]))
            elif m == ("left",):
                left = not left
                log.append((t, 1, "left_contact_onset" if left else "left_contact_release", sign[1]))
        for m in fired:
            if m[0] == "velocity":
                i = m[1]
                y[2 * i - 1] = 0.0
                a = forces(t, y, left, right)[i]
                if s[i] * (a + s[i] * kin[i]) < 0:
                    sign[i] = -s[i]
                    log.append((t, i, "passable", sign[i]))
                else:
                    sign[i] = 0
                    log.append((t, i, "sliding_onset", 0))
            elif m[0] == "barrier":
                i, side = m[1], m[2]
                if sign[i] == 0:
                    sign[i] = side
                    log.append((t, i, "sliding_vanish", side))
        settle()
    return log
