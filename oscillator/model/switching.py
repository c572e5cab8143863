"""Switching decisions: from the roots that fired to the next mode (docs/model.md, Sec. 6).

:func:`resolve` is a pure function of ``(t, y, params, mode, fired roots)``.  It resolves one
instant in a fixed order, re-checking until the domains are consistent:

1. contact changes (right stop, then left stop): Theorems 5.6-5.9;
2. moving masses reaching ``v_i = 0``: passable (Thm 5.1) or coming to rest (Thm 5.2/5.3);
3. resting masses whose flow barrier is reached: leaving rest (Thm 5.4);
4. every resting mass re-checked against its flow barrier (a contact makes the force jump),
   and every mass standing on its velocity boundary against its field, until nothing changes;
5. grazing reports (Thm 5.5 and rule 6), which switch nothing.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

from oscillator.errors import SimulationFailed
from oscillator.model.events import Event, EventKind
from oscillator.model.g_functions import displacement_g, flow_barrier_g, scale, velocity_g
from oscillator.model.parameters import Parameters, SolverOptions
from oscillator.model.phase_space import Mode, displacement_boundary_label, domain_of
from oscillator.model.roots import Root
from oscillator.model.theorems import (
    Decision,
    is_zero,
    theorem_5_1_passable,
    theorem_5_2_sliding_exists,
    theorem_5_3_sliding_appears,
    theorem_5_4_sliding_vanishes,
    theorem_5_5_grazing,
    theorem_5_6_right_contact,
    theorem_5_7_right_contact_in_left_contact,
    theorem_5_8_left_contact,
    theorem_5_9_left_contact_in_right_contact,
)
from oscillator.model.types import StateLike

__all__ = ["Resolution", "initial_mode", "resolve", "settle"]

_NAN = math.nan
#: Rounds of re-checking at one instant before the instant is declared an event storm.
MAX_ROUNDS = 8
_VELOCITY = {1: Root.VELOCITY_1, 2: Root.VELOCITY_2}
_EXTREMUM = {1: Root.EXTREMUM_1, 2: Root.EXTREMUM_2}
_BARRIERS = {
    1: ((Root.BARRIER_1_POSITIVE, 1), (Root.BARRIER_1_NEGATIVE, -1)),
    2: ((Root.BARRIER_2_POSITIVE, 1), (Root.BARRIER_2_NEGATIVE, -1)),
}


@dataclass(frozen=True, slots=True)
class Resolution:
    """What one instant resolved to: the next mode, the events, and the (projected) state."""

    mode: Mode
    events: tuple[Event, ...]
    y: tuple[float, float, float, float]


#: Relative size, against :func:`~oscillator.model.fields.force_scale`, below which a force-like
#: G-function counts as zero: a root located by CVODE leaves about ``rtol`` of the scale.
ZERO = 1e-9


#: The time resolution of a located root, relative to the forcing period: CVODE locates a root
#: to about ``100 eps`` times the span it integrated since its last restart (a few periods at
#: most), 1e-13 periods; this is ten times that.
ZERO_TIME = 1e-12


def zero_tolerance(t: float, y: StateLike, p: Parameters, mode: Mode, mass: int, rate: float) -> float:
    """How close to zero a force-like G-function of mass ``mass`` counts as zero at ``(t, y)``.

    Within the rounding of the terms that make it up (:data:`ZERO` of
    :func:`~oscillator.model.fields.force_scale`), or within what its rate ``rate`` (its
    first-order G-function) changes it in the time resolution of a located root
    (:data:`ZERO_TIME`).  The second matters where every term is small but the function moves
    fast: a resting mass struck by the other one, whose contact force starts from zero.
    """
    return ZERO * scale(t, y, p, mode, mass) + ZERO_TIME * p.period * abs(rate)


def _field_name(mass: int, domain: int, *, barrier: bool = False) -> str:
    """``F2^(1)``, or ``F2^(0>0_1)`` for the flow barrier on the side of domain 1."""
    return f"F{mass}^(0>0_{domain})" if barrier else f"F{mass}^({domain})"


def _event(
    t: float,
    y: StateLike,
    mass: int,
    kind: EventKind,
    boundary: str,
    before: Mode,
    after: Mode,
    decision: Decision,
    alpha: tuple[float, float] = (_NAN, _NAN),
    beta: tuple[float, float] = (_NAN, _NAN),
    names: tuple[str, str] = ("", ""),
    distance: float = _NAN,
) -> Event:
    return Event(
        t=t,
        mass=mass,
        kind=kind,
        boundary=boundary,
        from_domain=before.domain(mass),
        to_domain=after.domain(mass),
        theorem=decision.theorem,
        equation=decision.equation,
        branch=decision.branch,
        x1=y[0],
        v1=y[1],
        x2=y[2],
        v2=y[3],
        G0_alpha=alpha[0],
        G1_alpha=alpha[1],
        G0_beta=beta[0],
        G1_beta=beta[1],
        G_alpha=names[0],
        G_beta=names[1],
        distance=distance,
        state_from=before.system_state,
        state_to=after.system_state,
    )


# --------------------------------------------------------------------------- contacts


def _switch_right_contact(t: float, y: StateLike, p: Parameters, mode: Mode, events: list[Event]) -> Mode:
    """Theorems 5.6/5.7 at ``x1 = d1``; m1 moves (a resting m1 cannot change ``x1``)."""
    after = mode.with_contacts(left=mode.left, right=not mode.right)
    before_g = displacement_g(t, y, p, mode, "right")
    after_g = displacement_g(t, y, p, after, "right")
    theorem = theorem_5_7_right_contact_in_left_contact if mode.left else theorem_5_6_right_contact
    decision = theorem(mode.domain1, after.domain1, before_g[0], after_g[0])
    if not decision:
        return mode  # touched and turned back: reported as grazing, if close, by rule 6
    kind = EventKind.RIGHT_CONTACT_ONSET if after.right else EventKind.RIGHT_CONTACT_RELEASE
    boundary = displacement_boundary_label(1, mode.domain1, after.domain1)
    names = ("v1", "v1")
    events.append(_event(t, y, 1, kind, boundary, mode, after, decision, before_g, after_g, names))
    return after


def _switch_left_contact(t: float, y: StateLike, p: Parameters, mode: Mode, events: list[Event]) -> Mode:
    """Theorems 5.8/5.9 at ``z1 = -d`` (relative coordinates); both masses' domains change."""
    onset = not mode.left
    after = mode.with_contacts(left=onset, right=mode.right)
    before_g = displacement_g(t, y, p, mode, "left")
    after_g = displacement_g(t, y, p, after, "left")
    theorem = theorem_5_9_left_contact_in_right_contact if mode.right else theorem_5_8_left_contact
    decision = theorem(onset, before_g[0], after_g[0])
    if not decision:
        return mode
    kind = EventKind.LEFT_CONTACT_ONSET if onset else EventKind.LEFT_CONTACT_RELEASE
    names = ("zdot1", "zdot1")
    for mass in (1, 2):
        boundary = displacement_boundary_label(mass, mode.domain(mass), after.domain(mass))
        events.append(_event(t, y, mass, kind, boundary, mode, after, decision, before_g, after_g, names))
    return after


# --------------------------------------------------------------------------- velocity boundaries


def _arrive(t: float, y: StateLike, p: Parameters, mode: Mode, mass: int, events: list[Event]) -> Mode:
    """A moving mass on its velocity boundary: passes (Thm 5.1) or comes to rest (5.2/5.3)."""
    s = mode.sign(mass)
    alpha = mode.domain(mass)
    beta = domain_of(mass, -s, left=mode.left, right=mode.right)
    g_alpha = velocity_g(t, y, p, mode, mass, s)
    g_beta = velocity_g(t, y, p, mode, mass, -s)
    tol = zero_tolerance(t, y, p, mode, mass, g_beta[1])
    names = (_field_name(mass, alpha), _field_name(mass, beta))
    boundary = mode.boundary_label(mass)

    passable = theorem_5_1_passable(mass, alpha, beta, g_alpha[0], g_beta[0])
    if passable:
        after = mode.with_sign(mass, -s)
        events.append(_event(t, y, mass, EventKind.PASSABLE, boundary, mode, after, passable, g_alpha, g_beta, names))
        return after

    pair = (min(alpha, beta), max(alpha, beta))
    g_odd, g_even = (g_alpha[0], g_beta[0]) if alpha % 2 else (g_beta[0], g_alpha[0])
    decision = theorem_5_2_sliding_exists(mass, pair, g_odd, g_even)
    if not decision:
        decision = theorem_5_3_sliding_appears(mass, alpha, beta, g_alpha[0], g_beta[0], g_beta[1], tolerance=tol)
    if not decision and is_zero(g_beta[0], tol) and -s * g_beta[1] > 0:
        # The field across vanishes and turns outward: the flow passes (Thm 5.3 fails).
        after = mode.with_sign(mass, -s)
        events.append(_event(t, y, mass, EventKind.PASSABLE, boundary, mode, after, decision, g_alpha, g_beta, names))
        return after
    after = mode.with_sign(mass, 0)
    events.append(_event(t, y, mass, EventKind.SLIDING_ONSET, boundary, mode, after, decision, g_alpha, g_beta, names))
    return after


def _leave_rest(t: float, y: StateLike, p: Parameters, mode: Mode, mass: int, s: int, events: list[Event]) -> Mode:
    """A resting mass leaves into the side ``s`` if Theorem 5.4 holds."""
    delta = domain_of(mass, s, left=mode.left, right=mode.right)
    barrier = flow_barrier_g(t, y, p, mode, mass, s)
    field = velocity_g(t, y, p, mode, mass, s)
    decision = theorem_5_4_sliding_vanishes(
        mass, delta, barrier[0], barrier[1], field[0], tolerance=zero_tolerance(t, y, p, mode, mass, barrier[1])
    )
    if not decision:
        return mode
    after = mode.with_sign(mass, s)
    names = (_field_name(mass, delta, barrier=True), _field_name(mass, delta))
    events.append(
        _event(
            t,
            y,
            mass,
            EventKind.SLIDING_VANISH,
            mode.boundary_label(mass),
            mode,
            after,
            decision,
            barrier,
            field,
            names,
        )
    )
    return after


def settle(t: float, y: StateLike, p: Parameters, mode: Mode, events: list[Event]) -> Mode:
    """Re-check every mass at one instant until the domains are consistent (docs/model.md, rule 7).

    A resting mass leaves if Theorem 5.4 holds on either side: its force is past the flow
    barrier (after a contact made it jump, or at the start), or on it and turning outward (a
    root exactly at a restart, which the integrator does not report).  A moving mass standing
    on its velocity boundary (``v_i = 0``) whose field points back at it is decided as an
    arrival (Thm 5.1-5.3).
    """
    for _ in range(MAX_ROUNDS):
        changed = False
        for mass in (1, 2):
            if mode.resting(mass):
                for side in (1, -1):
                    new = _leave_rest(t, y, p, mode, mass, side, events)
                    if new != mode:
                        mode, changed = new, True
                        break
            elif y[2 * mass - 1] == 0.0:
                s = mode.sign(mass)
                g0, g1 = velocity_g(t, y, p, mode, mass, s)
                tol = zero_tolerance(t, y, p, mode, mass, g1)
                if s * g0 < -tol or (is_zero(g0, tol) and s * g1 < 0):
                    new = _arrive(t, y, p, mode, mass, events)
                    changed |= new != mode
                    mode = new
        if not changed:
            return mode
    raise SimulationFailed(
        f"event storm at t = {t:.10g} s: the masses keep switching at one instant "
        f"(mode {mode}); the flow barrier and the fields contradict each other here — check "
        f"mu_s >= mu_k and the contact parameters",
        field="mu_s",
    )


# --------------------------------------------------------------------------- grazing reports


def _grazing_reports(
    t: float,
    y: StateLike,
    p: Parameters,
    before: Mode,
    mode: Mode,
    fired: set[Root],
    options: SolverOptions,
    events: list[Event],
) -> None:
    for mass in (1, 2):
        s = mode.sign(mass)
        if _EXTREMUM[mass] in fired and s and before.domain(mass) == mode.domain(mass):
            alpha = mode.domain(mass)
            g = velocity_g(t, y, p, mode, mass, s)
            tolerance = zero_tolerance(t, y, p, mode, mass, g[1])
            decision = theorem_5_5_grazing(mass, alpha, g[0], g[1], tolerance=tolerance)
            speed = abs(y[2 * mass - 1])
            if decision and speed <= options.grazing_velocity_tolerance:
                events.append(
                    _event(
                        t,
                        y,
                        mass,
                        EventKind.GRAZING,
                        mode.boundary_label(mass),
                        mode,
                        mode,
                        decision,
                        g,
                        names=(_field_name(mass, alpha), ""),
                        distance=speed,
                    )
                )
    tol = options.grazing_displacement_tolerance
    if _VELOCITY[1] in fired and abs(y[0] - p.d1) <= tol:
        # v1 = 0 within tol of x1 = d1: the flow touched the right stop in m1's domain before.
        _stop_grazing(t, y, p, before, "right", Decision(True, "Def. 5.2", "(5.7)" if mode.left else "(5.6)"), events)
    if Root.RELATIVE_VELOCITY in fired and abs(y[0] - y[2] + p.d) <= tol:
        _stop_grazing(t, y, p, mode, "left", Decision(True, "Def. 5.4", "(5.11)" if mode.left else "(5.10)"), events)


def _stop_grazing(
    t: float, y: StateLike, p: Parameters, mode: Mode, stop: str, decision: Decision, events: list[Event]
) -> None:
    """Report grazing of a stop (docs/model.md, rule 6): ``G^(0)`` (``v1`` or ``zdot1``) is zero on it."""
    g = displacement_g(t, y, p, mode, stop)
    distance = abs(y[0] - p.d1) if stop == "right" else abs(y[0] - y[2] + p.d)
    boundary = "x1 = d1" if stop == "right" else "z1 = -d"
    if mode.sign(1):
        flags = {"left": mode.left, "right": mode.right}
        flags[stop] = not flags[stop]
        boundary = displacement_boundary_label(1, mode.domain1, domain_of(1, mode.sign(1), **flags))
    names = ("v1" if stop == "right" else "zdot1", "")
    events.append(_event(t, y, 1, EventKind.GRAZING, boundary, mode, mode, decision, g, names=names, distance=distance))


# --------------------------------------------------------------------------- entry points


def resolve(
    t: float,
    y: StateLike,
    p: Parameters,
    mode: Mode,
    fired: Iterable[Root],
    options: SolverOptions,
) -> Resolution:
    """Resolve the roots that fired at ``t`` into the next mode and the event records.

    The velocity of a mass that reached its velocity boundary is set to exactly zero (it is
    zero to the solver's accuracy), so that a resting mass has ``v_i = 0`` identically.
    """
    fired = set(fired)
    state = [float(v) for v in y[:4]]
    events: list[Event] = []
    before = mode
    if Root.RIGHT_STOP in fired:
        mode = _switch_right_contact(t, state, p, mode, events)
    if Root.LEFT_STOP in fired:
        mode = _switch_left_contact(t, state, p, mode, events)
    for mass in (1, 2):
        if _VELOCITY[mass] in fired and not mode.resting(mass):
            state[2 * mass - 1] = 0.0
            mode = _arrive(t, state, p, mode, mass, events)
    for mass in (1, 2):
        for root, side in _BARRIERS[mass]:
            if root in fired and mode.resting(mass) and before.resting(mass):
                mode = _leave_rest(t, state, p, mode, mass, side, events)
    mode = settle(t, state, p, mode, events)
    _grazing_reports(t, state, p, before, mode, fired, options, events)
    return Resolution(mode, tuple(events), (state[0], state[1], state[2], state[3]))


def initial_mode(t0: float, y: StateLike, p: Parameters) -> Resolution:
    """The mode at the start, and the masses that leave rest at once (docs/model.md, rule 8).

    A mass given ``v_i = 0`` is at rest; it leaves at ``t0`` only if Theorem 5.4 holds.
    Contacts follow ``z1 <= -d`` and ``x1 >= d1``.  Exactly on a stop, the contact counts if the
    velocity points into it; with zero velocity there the contact force vanishes, so both
    choices give the same field at ``t0`` and the acceleration decides (the integrator never
    reports a crossing that starts exactly at its initial time).
    """
    x1, v1, x2, v2 = (float(v) for v in y[:4])
    state = (x1, v1, x2, v2)
    z1, zdot1 = x1 - x2, v1 - v2
    left = z1 < -p.d or (z1 == -p.d and zdot1 < 0)
    right = x1 > p.d1 or (x1 == p.d1 and v1 > 0)
    signs = [int(math.copysign(1, v)) if v != 0 else 0 for v in (v1, v2)]
    mode = Mode.from_signs(signs[0], signs[1], left=left, right=right)
    events: list[Event] = []
    mode = settle(t0, state, p, mode, events)
    on_left, on_right = z1 == -p.d and zdot1 == 0, x1 == p.d1 and v1 == 0
    if on_left or on_right:
        rel, a1 = displacement_g(t0, state, p, mode, "left")[1], displacement_g(t0, state, p, mode, "right")[1]
        contacts = {"left": (rel < 0) if on_left else mode.left, "right": (a1 > 0) if on_right else mode.right}
        if (contacts["left"], contacts["right"]) != (mode.left, mode.right):
            mode = settle(t0, state, p, mode.with_contacts(**contacts), events)
    return Resolution(mode, tuple(events), state)
