"""Switching decisions: from the roots that fired to the next mode (docs/model.md, Sec. 6).

:func:`resolve_compiled` is a pure function of ``(t, y, params, mode, fired roots)``.  It
resolves one instant in a fixed order, re-checking until the domains are consistent:

1. contact changes (right stop, then left stop): Theorems 5.6-5.9;
2. moving masses reaching ``v_i = 0``: passable (Thm 5.1) or coming to rest (Thm 5.2/5.3);
3. resting masses whose flow barrier is reached: leaving rest (Thm 5.4);
4. every resting mass re-checked against its flow barrier (a contact makes the force jump),
   and every mass standing on its velocity boundary against its field, until nothing changes;
5. grazing reports (Thm 5.5 and rule 6), which switch nothing.

The rules are compiled (numba), as the fields and theorems they call are: the supervisor calls
them at every root through :func:`~oscillator.model.resolving.resolve_rows`, which writes the events as rows of numbers
(:data:`oscillator.model.events.COLUMN`) into the run's event log and builds no Python object
per event.  Inside, a mode is the tuple ``(s1, s2, left, right)`` of the velocity signs
(0 = at rest) and the contact flags (0 or 1).
"""

from __future__ import annotations

import math

import numpy as np
from numba import types

from oscillator.compiled import njit
from oscillator.model.events import (
    BARRIER,
    COLUMN,
    FIELD,
    KINDS,
    NO_NAME,
    V1_NAME,
    ZDOT1_NAME,
    EventKind,
)
from oscillator.model.fields import D1, D, scale_of
from oscillator.model.g_functions import barrier_index, displacement_values, g_values, velocity_index
from oscillator.model.numbering import LEFT_STOP_LABEL, RIGHT_STOP_LABEL
from oscillator.model.numbering_kernels import (
    displacement_boundary_code,
    domain_code,
    state_code,
    velocity_boundary_code,
)
from oscillator.model.roots import Root
from oscillator.model.theorems import (
    DECISION,
    DEFINITION_5_2,
    DEFINITION_5_4,
    NO_BRANCH,
    grazing,
    is_zero,
    left_contact,
    left_contact_in_right_contact,
    passable,
    right_contact,
    right_contact_in_left_contact,
    sliding_appears,
    sliding_exists,
    sliding_vanishes,
)
from oscillator.model.types import Vector

__all__ = ["MAX_ROWS", "initial_compiled", "resolve_compiled"]

#: Rounds of re-checking at one instant before the instant is declared an event storm.
MAX_ROUNDS = 8
#: The most events one instant can write (a storm stops at ``MAX_ROUNDS`` rounds well before).
MAX_ROWS = 64

#: Relative size, against :func:`~oscillator.model.fields.force_scale`, below which a force-like
#: G-function counts as zero: a root located by CVODE leaves about ``rtol`` of the scale.
ZERO = 1e-9

#: The time resolution of a located root, relative to the forcing period: CVODE locates a root
#: to about ``100 eps`` times the span it integrated since its last restart (a few periods at
#: most), 1e-13 periods; this is ten times that.
ZERO_TIME = 1e-12

# Bits of the fired roots (oscillator.model.roots.Root), and the event-row columns and kind codes,
# as module constants (numba freezes them into the compiled code).
(
    _VELOCITY_1,
    _EXTREMUM_1,
    _BARRIER_1_POSITIVE,
    _BARRIER_1_NEGATIVE,
    _VELOCITY_2,
    _EXTREMUM_2,
    _BARRIER_2_POSITIVE,
    _BARRIER_2_NEGATIVE,
    _RIGHT_STOP,
    _LEFT_STOP,
    _RELATIVE_VELOCITY,
) = (
    1 << int(root)
    for root in (
        Root.VELOCITY_1,
        Root.EXTREMUM_1,
        Root.BARRIER_1_POSITIVE,
        Root.BARRIER_1_NEGATIVE,
        Root.VELOCITY_2,
        Root.EXTREMUM_2,
        Root.BARRIER_2_POSITIVE,
        Root.BARRIER_2_NEGATIVE,
        Root.RIGHT_STOP,
        Root.LEFT_STOP,
        Root.RELATIVE_VELOCITY,
    )
)
(
    _T,
    _MASS,
    _KIND,
    _BOUNDARY,
    _FROM,
    _TO,
    _THEOREM,
    _EQUATION,
    _BRANCH,
    _X1,
    _G0A,
    _G1A,
    _G0B,
    _G1B,
    _NAME_A,
    _NAME_B,
    _DISTANCE,
    _STATE_FROM,
    _STATE_TO,
) = (
    COLUMN[name]
    for name in (
        "t",
        "mass",
        "kind",
        "boundary",
        "from_domain",
        "to_domain",
        "theorem",
        "equation",
        "branch",
        "x1",
        "G0_alpha",
        "G1_alpha",
        "G0_beta",
        "G1_beta",
        "G_alpha",
        "G_beta",
        "distance",
        "state_from",
        "state_to",
    )
)
(_PASSABLE, _SLIDING_ONSET, _SLIDING_VANISH, _GRAZING, _RIGHT_ONSET, _RIGHT_RELEASE, _LEFT_ONSET, _LEFT_RELEASE) = (
    KINDS.index(kind)
    for kind in (
        EventKind.PASSABLE,
        EventKind.SLIDING_ONSET,
        EventKind.SLIDING_VANISH,
        EventKind.GRAZING,
        EventKind.RIGHT_CONTACT_ONSET,
        EventKind.RIGHT_CONTACT_RELEASE,
        EventKind.LEFT_CONTACT_ONSET,
        EventKind.LEFT_CONTACT_RELEASE,
    )
)
_NAN = math.nan

# Every kernel carries its signature: one compiled version each, whatever literal constants the
# callers pass (numba would compile one per literal otherwise, and the compile time doubles).
_i, _f, _b = types.int64, types.float64, types.boolean
_MODE = types.UniTuple(_i, 4)
_VECTOR = types.Array(_f, 1, "C")
_PARAMS = types.Array(_f, 1, "C")
_ROWS = types.Array(_f, 2, "C")
_PAIR = types.UniTuple(_f, 2)
_STEP = types.Tuple((_MODE, _i))
_SETTLED = types.Tuple((_MODE, _i, _b))
_NAMES = types.UniTuple(_i, 2)


# --------------------------------------------------------------------------- modes as numbers


@njit(_i(_MODE, _i), cache=True)
def _domain_in(mode: tuple[int, int, int, int], mass: int) -> int:  # pragma: no cover - compiled
    return domain_code(mass, mode[mass - 1], mode[2], mode[3])


@njit(_MODE(_MODE, _i, _i), cache=True)
def _with_sign(mode: tuple[int, int, int, int], mass: int, sign: int) -> tuple[int, int, int, int]:  # pragma: no cover
    if mass == 1:
        return (sign, mode[1], mode[2], mode[3])
    return (mode[0], sign, mode[2], mode[3])


@njit(_i(_MODE), cache=True)
def _state_code(mode: tuple[int, int, int, int]) -> int:  # pragma: no cover - compiled
    """The system state's code (:func:`oscillator.model.numbering.state_code`)."""
    return state_code(mode[2], mode[3], int(mode[0] == 0), int(mode[1] == 0))


# --------------------------------------------------------------------------- G-functions at the instant


@njit(_VECTOR(_f, _VECTOR, _PARAMS, _MODE), cache=True)
def _g(t: float, y: Vector, c: Vector, mode: tuple[int, int, int, int]) -> Vector:  # pragma: no cover - compiled
    values = np.empty(16)
    g_values(t, y[0], y[1], y[2], y[3], mode[2] == 1, mode[3] == 1, mode[0], mode[1], c, values)
    return values


@njit(_PAIR(_f, _VECTOR, _PARAMS, _MODE, _b), cache=True)
def _displacement(
    t: float, y: Vector, c: Vector, mode: tuple[int, int, int, int], right_stop: bool
) -> tuple[float, float]:  # pragma: no cover - compiled
    return displacement_values(t, y[0], y[1], y[2], y[3], mode[2] == 1, mode[3] == 1, mode[0], mode[1], c, right_stop)


@njit(_f(_VECTOR, _PARAMS, _f, _MODE, _i, _f), cache=True)
def _zero_tolerance(
    y: Vector, c: Vector, period: float, mode: tuple[int, int, int, int], mass: int, rate: float
) -> float:  # pragma: no cover - compiled
    """How close to zero a force-like G-function of mass ``mass`` counts as zero at ``(t, y)``.

    Within the rounding of the terms that make it up (:data:`ZERO` of
    :func:`~oscillator.model.fields.force_scale`), or within what its rate ``rate`` (its
    first-order G-function) changes it in the time resolution of a located root
    (:data:`ZERO_TIME`).  The second matters where every term is small but the function moves
    fast: a resting mass struck by the other one, whose contact force starts from zero.
    """
    scale = scale_of(y[0], y[1], y[2], y[3], mode[2] == 1, mode[3] == 1, mass, c)
    return ZERO * scale + ZERO_TIME * period * abs(rate)


@njit(_i(_ROWS, _i, _f, _VECTOR, _i, _i, _i, _MODE, _MODE, DECISION, _PAIR, _PAIR, _NAMES, _f), cache=True)
def _write(
    out: np.ndarray,
    n: int,
    t: float,
    y: Vector,
    mass: int,
    kind: int,
    boundary: int,
    before: tuple[int, int, int, int],
    after: tuple[int, int, int, int],
    decision: tuple[bool, int, int, int],
    alpha: tuple[float, float],
    beta: tuple[float, float],
    names: tuple[int, int],
    distance: float,
) -> int:  # pragma: no cover - compiled
    """Write one event as row ``n`` of ``out``; the next row."""
    if n >= out.shape[0]:
        raise IndexError("more events at one instant than the event buffer holds")
    row = out[n]
    row[_T], row[_MASS], row[_KIND], row[_BOUNDARY] = t, mass, kind, boundary
    row[_FROM], row[_TO] = _domain_in(before, mass), _domain_in(after, mass)
    row[_THEOREM], row[_EQUATION], row[_BRANCH] = decision[1], decision[2], decision[3]
    for k in range(4):
        row[_X1 + k] = y[k]
    row[_G0A], row[_G1A], row[_G0B], row[_G1B] = alpha[0], alpha[1], beta[0], beta[1]
    row[_NAME_A], row[_NAME_B], row[_DISTANCE] = names[0], names[1], distance
    row[_STATE_FROM], row[_STATE_TO] = _state_code(before), _state_code(after)
    return n + 1


# --------------------------------------------------------------------------- contacts


@njit(_STEP(_f, _VECTOR, _PARAMS, _MODE, _ROWS, _i), cache=True)
def _switch_right_contact(
    t: float, y: Vector, c: Vector, mode: tuple[int, int, int, int], out: np.ndarray, n: int
) -> tuple[tuple[int, int, int, int], int]:  # pragma: no cover - compiled
    """Theorems 5.6/5.7 at ``x1 = d1``; m1 moves (a resting m1 cannot change ``x1``)."""
    after = (mode[0], mode[1], mode[2], 1 - mode[3])
    before_g = _displacement(t, y, c, mode, True)
    after_g = _displacement(t, y, c, after, True)
    from_domain, to_domain = _domain_in(mode, 1), _domain_in(after, 1)
    if mode[2]:
        decision = right_contact_in_left_contact(from_domain, to_domain, before_g[0], after_g[0])
    else:
        decision = right_contact(from_domain, to_domain, before_g[0], after_g[0])
    if not decision[0]:
        return mode, n  # touched and turned back: reported as grazing, if close, by rule 6
    kind = _RIGHT_ONSET if after[3] else _RIGHT_RELEASE
    boundary = displacement_boundary_code(1, from_domain, to_domain)
    n = _write(out, n, t, y, 1, kind, boundary, mode, after, decision, before_g, after_g, (V1_NAME, V1_NAME), _NAN)
    return after, n


@njit(_STEP(_f, _VECTOR, _PARAMS, _MODE, _ROWS, _i), cache=True)
def _switch_left_contact(
    t: float, y: Vector, c: Vector, mode: tuple[int, int, int, int], out: np.ndarray, n: int
) -> tuple[tuple[int, int, int, int], int]:  # pragma: no cover - compiled
    """Theorems 5.8/5.9 at ``z1 = -d`` (relative coordinates); both masses' domains change."""
    onset = mode[2] == 0
    after = (mode[0], mode[1], 1 - mode[2], mode[3])
    before_g = _displacement(t, y, c, mode, False)
    after_g = _displacement(t, y, c, after, False)
    if mode[3]:
        decision = left_contact_in_right_contact(onset, before_g[0], after_g[0])
    else:
        decision = left_contact(onset, before_g[0], after_g[0])
    if not decision[0]:
        return mode, n
    kind = _LEFT_ONSET if onset else _LEFT_RELEASE
    for mass in (1, 2):
        boundary = displacement_boundary_code(mass, _domain_in(mode, mass), _domain_in(after, mass))
        n = _write(
            out, n, t, y, mass, kind, boundary, mode, after, decision, before_g, after_g, (ZDOT1_NAME, ZDOT1_NAME), _NAN
        )
    return after, n


# --------------------------------------------------------------------------- velocity boundaries


@njit(_STEP(_f, _VECTOR, _PARAMS, _f, _MODE, _i, _ROWS, _i), cache=True)
def _arrive(
    t: float, y: Vector, c: Vector, period: float, mode: tuple[int, int, int, int], mass: int, out: np.ndarray, n: int
) -> tuple[tuple[int, int, int, int], int]:  # pragma: no cover - compiled
    """A moving mass on its velocity boundary: passes (Thm 5.1) or comes to rest (5.2/5.3)."""
    s = mode[mass - 1]
    alpha, beta = domain_code(mass, s, mode[2], mode[3]), domain_code(mass, -s, mode[2], mode[3])
    g = _g(t, y, c, mode)
    k_alpha, k_beta = velocity_index(mass, s), velocity_index(mass, -s)
    g_alpha, g_beta = (g[k_alpha], g[k_alpha + 1]), (g[k_beta], g[k_beta + 1])
    tol = _zero_tolerance(y, c, period, mode, mass, g_beta[1])
    names = (FIELD + alpha, FIELD + beta)
    boundary = velocity_boundary_code(mass, mode[2], mode[3])

    decision = passable(mass, alpha, beta, g_alpha[0], g_beta[0])
    if decision[0]:
        after = _with_sign(mode, mass, -s)
        n = _write(out, n, t, y, mass, _PASSABLE, boundary, mode, after, decision, g_alpha, g_beta, names, _NAN)
        return after, n

    g_odd, g_even = (g_alpha[0], g_beta[0]) if alpha % 2 else (g_beta[0], g_alpha[0])
    decision = sliding_exists(mass, min(alpha, beta), g_odd, g_even)
    if not decision[0]:
        decision = sliding_appears(mass, alpha, beta, g_alpha[0], g_beta[0], g_beta[1], tol)
    if not decision[0] and is_zero(g_beta[0], tol) and -s * g_beta[1] > 0:
        # The field across vanishes and turns outward: the flow passes (Thm 5.3 fails).
        after = _with_sign(mode, mass, -s)
        n = _write(out, n, t, y, mass, _PASSABLE, boundary, mode, after, decision, g_alpha, g_beta, names, _NAN)
        return after, n
    after = _with_sign(mode, mass, 0)
    n = _write(out, n, t, y, mass, _SLIDING_ONSET, boundary, mode, after, decision, g_alpha, g_beta, names, _NAN)
    return after, n


@njit(_STEP(_f, _VECTOR, _PARAMS, _f, _MODE, _i, _i, _ROWS, _i), cache=True)
def _leave_rest(
    t: float,
    y: Vector,
    c: Vector,
    period: float,
    mode: tuple[int, int, int, int],
    mass: int,
    s: int,
    out: np.ndarray,
    n: int,
) -> tuple[tuple[int, int, int, int], int]:  # pragma: no cover - compiled
    """A resting mass leaves into the side ``s`` if Theorem 5.4 holds."""
    delta = domain_code(mass, s, mode[2], mode[3])
    g = _g(t, y, c, mode)
    k_barrier, k_field = barrier_index(mass, s), velocity_index(mass, s)
    barrier, field = (g[k_barrier], g[k_barrier + 1]), (g[k_field], g[k_field + 1])
    tolerance = _zero_tolerance(y, c, period, mode, mass, barrier[1])
    decision = sliding_vanishes(mass, delta, barrier[0], barrier[1], field[0], tolerance)
    if not decision[0]:
        return mode, n
    after = _with_sign(mode, mass, s)
    names = (BARRIER + delta, FIELD + delta)
    boundary = velocity_boundary_code(mass, mode[2], mode[3])
    n = _write(out, n, t, y, mass, _SLIDING_VANISH, boundary, mode, after, decision, barrier, field, names, _NAN)
    return after, n


@njit(_SETTLED(_f, _VECTOR, _PARAMS, _f, _MODE, _ROWS, _i), cache=True)
def _settle(
    t: float, y: Vector, c: Vector, period: float, mode: tuple[int, int, int, int], out: np.ndarray, n: int
) -> tuple[tuple[int, int, int, int], int, bool]:  # pragma: no cover - compiled
    """Re-check every mass at one instant until the domains are consistent (docs/model.md, rule 7).

    A resting mass leaves if Theorem 5.4 holds on either side: its force is past the flow
    barrier (after a contact made it jump, or at the start), or on it and turning outward (a
    root exactly at a restart, which the integrator does not report).  A moving mass standing
    on its velocity boundary (``v_i = 0``) whose field points back at it is decided as an
    arrival (Thm 5.1-5.3).  The flag is false when the rounds run out (an event storm).
    """
    for _ in range(MAX_ROUNDS):
        changed = False
        for mass in (1, 2):
            s = mode[mass - 1]
            if s == 0:
                for side in (1, -1):
                    new, n = _leave_rest(t, y, c, period, mode, mass, side, out, n)
                    if new != mode:
                        mode, changed = new, True
                        break
            elif y[2 * mass - 1] == 0.0:
                g = _g(t, y, c, mode)
                k = velocity_index(mass, s)
                g0, g1 = g[k], g[k + 1]
                tol = _zero_tolerance(y, c, period, mode, mass, g1)
                if s * g0 < -tol or (is_zero(g0, tol) and s * g1 < 0):
                    new, n = _arrive(t, y, c, period, mode, mass, out, n)
                    changed = changed or new != mode
                    mode = new
        if not changed:
            return mode, n, True
    return mode, n, False


# --------------------------------------------------------------------------- grazing reports


@njit(_i(_f, _VECTOR, _PARAMS, _MODE, _b, _i, _ROWS, _i), cache=True)
def _stop_grazing(
    t: float,
    y: Vector,
    c: Vector,
    mode: tuple[int, int, int, int],
    right_stop: bool,
    equation: int,
    out: np.ndarray,
    n: int,
) -> int:  # pragma: no cover - compiled
    """Report grazing of a stop (docs/model.md, rule 6): ``G^(0)`` (``v1`` or ``zdot1``) is zero on
    it; decided by Definition 5.2 (right stop) or 5.4 (left stop)."""
    g = _displacement(t, y, c, mode, right_stop)
    if right_stop:
        distance, boundary, name = abs(y[0] - c[D1]), RIGHT_STOP_LABEL, V1_NAME
        decision = (True, DEFINITION_5_2, equation, NO_BRANCH)
        flipped = (mode[0], mode[1], mode[2], 1 - mode[3])
    else:
        distance, boundary, name = abs(y[0] - y[2] + c[D]), LEFT_STOP_LABEL, ZDOT1_NAME
        decision = (True, DEFINITION_5_4, equation, NO_BRANCH)
        flipped = (mode[0], mode[1], 1 - mode[2], mode[3])
    if mode[0] != 0:
        boundary = displacement_boundary_code(1, _domain_in(mode, 1), _domain_in(flipped, 1))
    return _write(out, n, t, y, 1, _GRAZING, boundary, mode, mode, decision, g, (_NAN, _NAN), (name, NO_NAME), distance)


@njit(_i(_f, _VECTOR, _PARAMS, _f, _MODE, _MODE, _i, _f, _f, _ROWS, _i), cache=True)
def _grazing_reports(
    t: float,
    y: Vector,
    c: Vector,
    period: float,
    before: tuple[int, int, int, int],
    mode: tuple[int, int, int, int],
    fired: int,
    velocity_tolerance: float,
    displacement_tolerance: float,
    out: np.ndarray,
    n: int,
) -> int:  # pragma: no cover - compiled
    """Grazing of a velocity boundary (Thm 5.5) within ``velocity_tolerance`` and of a stop
    (rule 6) within ``displacement_tolerance``."""
    for mass in (1, 2):
        s = mode[mass - 1]
        extremum = _EXTREMUM_1 if mass == 1 else _EXTREMUM_2
        if fired & extremum and s != 0 and _domain_in(before, mass) == _domain_in(mode, mass):
            alpha = _domain_in(mode, mass)
            g = _g(t, y, c, mode)
            k = velocity_index(mass, s)
            tolerance = _zero_tolerance(y, c, period, mode, mass, g[k + 1])
            decision = grazing(mass, alpha, g[k], g[k + 1], tolerance)
            speed = abs(y[2 * mass - 1])
            if decision[0] and speed <= velocity_tolerance:
                boundary = velocity_boundary_code(mass, mode[2], mode[3])
                n = _write(
                    out,
                    n,
                    t,
                    y,
                    mass,
                    _GRAZING,
                    boundary,
                    mode,
                    mode,
                    decision,
                    (g[k], g[k + 1]),
                    (_NAN, _NAN),
                    (FIELD + alpha, NO_NAME),
                    speed,
                )
    if fired & _VELOCITY_1 and abs(y[0] - c[D1]) <= displacement_tolerance:
        # v1 = 0 within tol of x1 = d1: the flow touched the right stop in m1's domain before.
        n = _stop_grazing(t, y, c, before, True, 7 if mode[2] else 6, out, n)
    if fired & _RELATIVE_VELOCITY and abs(y[0] - y[2] + c[D]) <= displacement_tolerance:
        n = _stop_grazing(t, y, c, mode, False, 11 if mode[2] else 10, out, n)
    return n


# --------------------------------------------------------------------------- the instant


@njit(_SETTLED(_f, _VECTOR, _PARAMS, _f, _MODE, _i, _f, _f, _ROWS, _i), cache=True)
def resolve_compiled(
    t: float,
    y: Vector,
    c: Vector,
    period: float,
    mode: tuple[int, int, int, int],
    fired: int,
    velocity_tolerance: float,
    displacement_tolerance: float,
    out: np.ndarray,
    n: int,
) -> tuple[tuple[int, int, int, int], int, bool]:  # pragma: no cover - compiled
    """The steps of the module's docstring at one instant; ``y`` is projected in place."""
    before = mode
    if fired & _RIGHT_STOP:
        mode, n = _switch_right_contact(t, y, c, mode, out, n)
    if fired & _LEFT_STOP:
        mode, n = _switch_left_contact(t, y, c, mode, out, n)
    for mass in (1, 2):
        if fired & (_VELOCITY_1 if mass == 1 else _VELOCITY_2) and mode[mass - 1] != 0:
            y[2 * mass - 1] = 0.0
            mode, n = _arrive(t, y, c, period, mode, mass, out, n)
    for mass in (1, 2):
        for side in (1, -1):
            if mass == 1:
                root = _BARRIER_1_POSITIVE if side == 1 else _BARRIER_1_NEGATIVE
            else:
                root = _BARRIER_2_POSITIVE if side == 1 else _BARRIER_2_NEGATIVE
            if fired & root and mode[mass - 1] == 0 and before[mass - 1] == 0:
                mode, n = _leave_rest(t, y, c, period, mode, mass, side, out, n)
    mode, n, settled = _settle(t, y, c, period, mode, out, n)
    if settled:
        n = _grazing_reports(t, y, c, period, before, mode, fired, velocity_tolerance, displacement_tolerance, out, n)
    return mode, n, settled


# --------------------------------------------------------------------------- entry points


@njit(cache=True)
def initial_compiled(
    t0: float, y: Vector, c: Vector, period: float, out: np.ndarray
) -> tuple[tuple[int, int, int, int], int, bool]:  # pragma: no cover - compiled
    """The mode at the start (:func:`oscillator.model.resolving.initial_mode` says the rules):
    the mode, the events written into ``out`` (room for ``2 MAX_ROWS``) and whether the instant
    settled.  ``y[:4]`` is projected in place."""
    x1, v1, x2, v2 = y[0], y[1], y[2], y[3]
    z1, zdot1 = x1 - x2, v1 - v2
    left = z1 < -c[D] or (z1 == -c[D] and zdot1 < 0.0)
    right = x1 > c[D1] or (x1 == c[D1] and v1 > 0.0)
    s1 = 0 if v1 == 0.0 else (1 if v1 > 0.0 else -1)
    s2 = 0 if v2 == 0.0 else (1 if v2 > 0.0 else -1)
    mode, n, ok = resolve_compiled(t0, y, c, period, (s1, s2, int(left), int(right)), 0, 0.0, 0.0, out, 0)
    if not ok:
        return mode, n, False
    on_left, on_right = z1 == -c[D] and zdot1 == 0.0, x1 == c[D1] and v1 == 0.0
    if on_left or on_right:
        flags = (mode[2] != 0, mode[3] != 0)
        relative = displacement_values(t0, x1, v1, x2, v2, flags[0], flags[1], mode[0], mode[1], c, False)[1]
        a1 = displacement_values(t0, x1, v1, x2, v2, flags[0], flags[1], mode[0], mode[1], c, True)[1]
        new_left = (relative < 0.0) if on_left else flags[0]
        new_right = (a1 > 0.0) if on_right else flags[1]
        if (new_left, new_right) != flags:
            start = (mode[0], mode[1], int(new_left), int(new_right))
            mode, n, ok = resolve_compiled(t0, y, c, period, start, 0, 0.0, 0.0, out, n)
    return mode, n, ok
