"""An independent event-driven simulator of friction chains on SciPy, written from issue 51's text
and docs/model.md's rules alone.

It shares no code with the package: its own element forces (per element, in plain Python), its own
modes, SciPy's DOP853 with ``solve_ivp`` events instead of CVODE.  It takes a system file's data
as plain dictionaries and returns the switches as ``(t, element, to_mode)`` tuples (no grazing).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp


def _event(function, direction):
    function.direction = direction
    function.terminal = True
    return function


class Machine:
    def __init__(self, masses, elements, omega, g):
        self.names = [m["name"] for m in masses]
        self.m = np.array([m["m"] for m in masses])
        self.y0 = [v for m in masses for v in (m.get("x", 0.0), m.get("v", 0.0))]
        self.elements, self.omega = elements, omega
        self.index = {name: i for i, name in enumerate(self.names)}
        self.slider = {}
        for e in elements:
            if e["type"] == "jenkins":
                self.slider[e["name"]] = len(self.y0)
                self.y0.append(self.u(e, self.y0)[0])
            if e["type"] == "friction":
                e.setdefault("N", self.m[self.index[e["on"]]] * g)

    def u(self, e, y):
        i = self.index[e["on"]]
        if e.get("with") is None:
            return y[2 * i], y[2 * i + 1]
        j = self.index[e["with"]]
        return y[2 * i] - y[2 * j], y[2 * i + 1] - y[2 * j + 1]

    def force(self, e, t, y, mode):
        """The force of a non-friction element on its ``on`` mass."""
        kind, (u, w) = e["type"], self.u(e, y)
        if kind == "spring":
            return -e.get("k", 0.0) * u - e.get("k3", 0.0) * u**3
        if kind == "damper":
            return -e.get("c", 0.0) * w - e.get("c3", 0.0) * w**3
        if kind == "force":
            return e["Q"] * math.sin(self.omega * t + e.get("phi", 0.0))
        if kind == "stop":
            return -(e["K"] * (u - e["at"]) + e.get("C", 0.0) * w) if mode[e["name"]] else 0.0
        if kind == "contact":
            edge = -e["gap"] if e["side"] == "left" else e["gap"]
            return -(e["K"] * (u - edge) + e.get("C", 0.0) * w) if mode[e["name"]] else 0.0
        if kind == "jenkins":
            s = mode[e["name"]]
            return -e["kt"] * (u - y[self.slider[e["name"]]]) if s == 0 else -s * e["F"]
        return 0.0

    def net(self, t, y, mode):
        total = np.zeros(len(self.m))
        for e in self.elements:
            f = self.force(e, t, y, mode)
            total[self.index[e["on"]]] += f
            if e.get("with") is not None:
                total[self.index[e["with"]]] -= f
        return total

    def rhs(self, t, y, mode):
        forces, dy = self.net(t, y, mode), np.zeros(len(y))
        stuck = {}
        for e in self.elements:
            if e["type"] == "friction":
                stuck[self.index[e["on"]]] = e
        for i in range(len(self.m)):
            e = stuck.get(i)
            if e is not None and mode[e["name"]] == 0:
                dy[2 * i] = e.get("w", 0.0)
                continue
            dy[2 * i] = y[2 * i + 1]
            kinetic = 0.0 if e is None else mode[e["name"]] * (e["mu_k"] * e["N"] + e.get("P", 0.0))
            dy[2 * i + 1] = (forces[i] - kinetic) / self.m[i]
        for e in self.elements:
            if e["type"] == "jenkins":
                dy[self.slider[e["name"]]] = 0.0 if mode[e["name"]] == 0 else self.u(e, y)[1]
        return dy

    def watched(self, mode):
        """(event function, element, what) for every boundary of the mode."""
        found = []
        for e in self.elements:
            name, kind, s = e["name"], e["type"], mode.get(e["name"], 0)
            i = self.index[e["on"]]
            if kind == "friction" and s != 0:
                found.append((_event(lambda t, y, i=i, e=e: y[2 * i + 1] - e.get("w", 0.0), -s), name, "arrive"))
            elif kind == "friction":
                limit = e["mu_s"] * e["N"] + e.get("P", 0.0)
                for side in (1, -1):
                    found.append(
                        (_event(lambda t, y, i=i, L=limit, d=side: self.net(t, y, mode)[i] - d * L, side), name, side)
                    )
            elif kind == "stop":
                side = 1 if e["side"] == "right" else -1
                found.append(
                    (_event(lambda t, y, e=e: self.u(e, y)[0] - e["at"], side if s == 0 else -side), name, "toggle")
                )
            elif kind == "contact":
                side = 1 if e["side"] == "right" else -1
                edge = side * e["gap"]
                found.append(
                    (_event(lambda t, y, e=e, c=edge: self.u(e, y)[0] - c, side if s == 0 else -side), name, "toggle")
                )
            elif kind == "jenkins" and e["F"] > 0 and s == 0:
                for side in (1, -1):

                    def pull(t, y, e=e, d=side):
                        return e["kt"] * (self.u(e, y)[0] - y[self.slider[e["name"]]]) - d * e["F"]

                    found.append((_event(pull, side), name, side))
            elif kind == "jenkins" and e["F"] > 0:
                found.append((_event(lambda t, y, e=e: self.u(e, y)[1], -s), name, "turn"))
        return found

    def settle(self, t, y, mode, arrived, log):
        for _ in range(20):
            changed, forces = False, self.net(t, y, mode)
            for e in self.elements:
                name = e["name"]
                if e["type"] == "friction":
                    i = self.index[e["on"]]
                    static = e["mu_s"] * e["N"] + e.get("P", 0.0)
                    kinetic = e["mu_k"] * e["N"] + e.get("P", 0.0)
                    if name in arrived:
                        s = arrived.pop(name)
                        mode[name] = -s if s * (forces[i] + s * kinetic) < 0 else 0
                        log.append((t, name, mode[name]))
                        changed = True
                    elif mode[name] == 0 and abs(forces[i]) > static:
                        mode[name] = 1 if forces[i] > 0 else -1
                        log.append((t, name, mode[name]))
                        changed = True
                elif e["type"] == "jenkins" and e["F"] > 0 and mode[name] != 0:  # a turn at this instant too
                    s, (u, rate) = mode[name], self.u(e, y)
                    if abs(rate) < 1e-9:
                        rate = self.u(e, np.repeat(self.rhs(t, y, mode)[1 : 2 * len(self.m) : 2], 2))[0]
                    if rate * s < 0:
                        y[self.slider[name]] = u - s * e["F"] * (1 - 1e-12) / e["kt"]
                        mode[name] = 0
                        log.append((t, name, 0))
                        changed = True
                elif e["type"] == "jenkins" and e["F"] > 0 and mode[name] == 0:
                    u, rate = self.u(e, y)
                    pull = e["kt"] * (u - y[self.slider[name]])
                    if abs(rate) < 1e-9:  # at a turn, or at rest: where it goes next
                        dy = self.rhs(t, y, mode)
                        rate = self.u(e, np.repeat(dy[1 : 2 * len(self.m) : 2], 2))[0]  # u
                    if abs(pull) > e["F"] * (1 + 1e-9) or (abs(pull) > e["F"] * (1 - 1e-9) and rate * pull > 0):
                        s = 1 if pull > 0 else -1
                        y[self.slider[name]] = u - s * e["F"] / e["kt"]
                        mode[name] = s
                        log.append((t, name, s))
                        changed = True
            if not changed:
                return

    def start(self, t):
        y, mode = np.array(self.y0, dtype=float), {}
        for e in self.elements:
            name, kind = e["name"], e["type"]
            if kind == "friction":
                mode[name] = int(np.sign(y[2 * self.index[e["on"]] + 1] - e.get("w", 0.0)))
            elif kind == "jenkins":
                mode[name] = 1 if e["F"] == 0 else 0
            elif kind in ("stop", "contact"):
                side = 1 if e["side"] == "right" else -1
                edge = e["at"] if kind == "stop" else side * e["gap"]
                mode[name] = int(side * (self.u(e, y)[0] - edge) > 0)
        return y, mode


def _apply(machine, watched, y, mode, arrived, log, t):
    """One located event's switch (a friction element reaching its belt is decided in settle)."""
    _, name, what = watched
    element = next(e for e in machine.elements if e["name"] == name)
    if what == "arrive":
        i = machine.index[element["on"]]
        y[2 * i + 1] = element.get("w", 0.0)
        arrived[name] = mode[name]
        return
    if what == "toggle":
        mode[name] = 1 - mode[name]
    elif what == "turn":
        u = machine.u(element, y)[0]
        y[machine.slider[name]] = u - mode[name] * element["F"] * (1 - 1e-12) / element["kt"]
        mode[name] = 0
    elif element["type"] == "jenkins":
        y[machine.slider[name]] = machine.u(element, y)[0] - what * element["F"] / element["kt"]
        mode[name] = what
    else:  # a stuck mass leaves
        mode[name] = what
    log.append((t, name, mode[name]))


def run(masses, elements, omega, g, t0, t_end, *, rtol=1e-12, atol=1e-12, max_step=0.01, pieces=None):
    """The switches ``(t, element, to_mode)`` of a chain from ``t0`` to ``t_end``; with a list
    ``pieces``, each smooth piece appended to it as ``(t_from, t_to, dense solution, mode)`` and
    the machine as its first item."""
    machine = Machine(masses, [dict(e) for e in elements], omega, g)
    if pieces is not None:
        pieces.append(machine)
    y, mode = machine.start(t0)
    log: list[tuple[float, str, int]] = []
    machine.settle(t0, y, mode, {}, log)
    t = t0
    while t < t_end:
        watched = machine.watched(mode)
        frozen = dict(mode)

        def field(tt, yy, frozen=frozen):
            return machine.rhs(tt, yy, frozen)

        settings = {"rtol": rtol, "atol": atol, "max_step": max_step, "dense_output": True}
        solution = solve_ivp(field, (t, t_end), y, method="DOP853", events=[w[0] for w in watched], **settings)
        if solution.status != 1:
            if pieces is not None and solution.status == 0:  # the last piece, to t_end
                pieces.append((t, t_end, solution.sol, frozen))
            break
        hits = [(float(te[0]), k) for k, te in enumerate(solution.t_events) if len(te)]
        if pieces is not None:
            pieces.append((t, min(h[0] for h in hits), solution.sol, frozen))
        t = min(h[0] for h in hits)
        t += 1e-12  # just past the crossings (brentq may stop on either side of a root)
        y = solution.sol(t).copy()
        arrived, before = {}, dict(mode)
        for tt, k in hits:  # the events of this instant, together
            if tt - t <= 1e-9 - 1e-12:
                _apply(machine, watched[k], y, mode, arrived, log, t)
        for e in machine.elements:  # a mass that reached its belt's speed at this instant too
            i = machine.index[e["on"]]
            if e["type"] == "friction" and mode[e["name"]] and before[e["name"]] and e["name"] not in arrived:
                if (y[2 * i + 1] - e.get("w", 0.0)) * mode[e["name"]] < 1e-9:
                    y[2 * i + 1] = e.get("w", 0.0)
                    arrived[e["name"]] = mode[e["name"]]
        machine.settle(t, y, mode, arrived, log)
    return log
