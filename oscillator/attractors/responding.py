"""The frequency response's tasks: each a pure top-level function that a worker process or a Dask
worker runs (:mod:`oscillator.analysis.execution`), called by
:func:`~oscillator.attractors.frequency.frequency_response`.

* :func:`seed_orbits`: the periodic attractors at one value of the parameter, as section points;
* :func:`continued`: one orbit continued towards one end of the span, and started again on both
  sides of each point where the corrector fails or stalls inside the span (:data:`RESTART`): a
  sliding, grazing or contact point it cannot step across leaves a gap of ``RESTART`` of the span
  instead of ending the family, and a family that turns back there is traced too;
* :func:`doubled`: the branch of period ``2n`` born at a period-``n`` branch's period doubling;
* :func:`measured`: the response measures of a run of one branch's points;
* :func:`sweep`: one slow sweep, up or down, each landing settled or told aperiodic
  (:func:`settled_orbit`), with its jumps (:func:`jumps`): where the attractor met is not the
  continuation of the one before (:func:`follows`), not where its cycle of switches changes.

:func:`on_branch` tells whether an orbit lies on a branch already continued, so that no branch
is traced twice.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import numpy as np
import pandas as pd

from oscillator.attractors.finding import find_attractors
from oscillator.attractors.mapping import AttractorSettings, Landing, land
from oscillator.errors import OscillatorError, Reason
from oscillator.io.cases import Case, resolve_case
from oscillator.orbits.branch import Branch
from oscillator.orbits.continuation import continue_orbit
from oscillator.orbits.response import COLUMNS, REFINE, branch_responses, response
from oscillator.orbits.shooting import STATE, fixed_point, period_map

__all__ = [
    "RESTART",
    "SAME_ORBIT",
    "continued",
    "distinct",
    "doubled",
    "follows",
    "jumps",
    "marched",
    "measured",
    "on_branch",
    "seed_orbits",
    "settled_orbit",
    "trimmed",
]

#: Two orbits at one parameter value are one where their section points agree to this (times
#: ``1 + |P|``): a seed on a branch is not continued again.
SAME_ORBIT = 1e-4
#: Where the corrector fails inside the span, orbits are sought this fraction of the span on either
#: side of the last point, by Newton from its orbit; at most :data:`MAX_RESTARTS` times a task.
RESTART = 1e-3
MAX_RESTARTS = 20
#: A branch is looked at every this many points for where it runs onto a known one.
TRIM_EVERY = 8
#: The reasons a branch ends that no restart can mend: the point budget, Ctrl-C, the span's end.
_FINAL = (Reason.MAX_POINTS, Reason.INTERRUPTED, Reason.NO_ORBIT)


def seed_orbits(
    case: Case, param: str, value: float, period: int, states: np.ndarray | None, settings: AttractorSettings
) -> list[np.ndarray]:
    """The section points of the period-``period`` attractors at ``param = value`` (from
    ``states``, the case's start by default)."""
    found = find_attractors(resolve_case(case, **{param: value}), states=states, settings=settings)
    return [a.orbit.state for a in found.attractors if a.period == period and a.orbit is not None]


def continued(
    case: Case,
    param: str,
    span: tuple[float, float],
    start: float,
    stop: float,
    period: int,
    state: np.ndarray,
    max_points: int,
    known: Sequence[Branch] = (),
) -> list[Branch]:
    """The orbit through ``state`` at ``start`` continued to ``stop``; and where a branch ends
    inside the span (the corrector failed or stalled at a sliding, grazing or contact point it
    cannot step across), the orbits on both sides of that point (:data:`RESTART` of the span away,
    Newton from its last orbit) that lie on no branch yet, each continued both ways: the family
    beyond the point, and a family that turns back there.  A branch that runs onto a ``known`` one,
    or onto one of these, ends there; at most :data:`MAX_RESTARTS` restarts."""
    low, high = span
    found: list[Branch] = []
    pending = [(start, stop, state)]
    restarts = 0
    while pending:
        start, stop, state = pending.pop(0)
        at = resolve_case(case, **{param: start})
        branch = continue_orbit(
            at, param=param, start=start, stop=stop, period=period, guess=state, max_points=max_points
        )
        whole = len(branch.points)
        branch = trimmed(case, branch, (*known, *found))
        found.append(branch)
        if len(branch.points) < whole or branch.complete or branch.reason in _FINAL or len(branch.points) < 2:
            continue
        last = float(branch.points[param].iloc[-1])
        ending = branch.points[list(STATE)].to_numpy(float)[-1]
        for side in (1.0, -1.0):
            beyond = last + side * RESTART * (high - low)
            if restarts >= MAX_RESTARTS or not low < beyond < high:
                continue
            restarts += 1
            restart = orbit_state(resolve_case(case, **{param: beyond}), period, ending)
            if restart is None or any(on_branch(case, other, beyond, restart) for other in (*known, *found)):
                continue
            pending += [(beyond, end, restart) for end in (high, low)]
    return [branch for branch in found if len(branch.points) > 1]


#: Where a period-``2n`` orbit is sought beside a period doubling: this fraction of the span
#: beyond it, either side, from the orbit moved along the eigenvector of the multiplier -1 by
#: these fractions of ``1 + |y|``.
DOUBLED_BESIDE = (1e-3, 1e-2)
DOUBLED_MOVES = (1e-2, 1e-1)


def doubled(
    case: Case,
    param: str,
    span: tuple[float, float],
    branch: Branch,
    row: int,
    max_points: int,
    known: Sequence[Branch] = (),
) -> list[Branch]:
    """The period-``2n`` branch born at the period doubling ``row`` of ``branch`` (period ``n``):
    beside it (:data:`DOUBLED_BESIDE`, first on the side of larger values), Newton for a
    period-``2n`` orbit from the doubling's orbit moved along the eigenvector of its multiplier
    -1 (:data:`DOUBLED_MOVES`), kept where its half-return point is another point (a genuine
    period ``2n``, not the period-``n`` orbit twice); then continued away from the doubling to
    the span's end on that side (:func:`continued`).  Empty where none is found."""
    low, high = span
    at = branch.bifurcations.iloc[row]
    value, y = float(at[param]), at[list(STATE)].to_numpy(float)
    base = resolve_case(case, **{param: value}, t0=branch.section)
    try:
        monodromy = period_map(base, branch.section, y, branch.period).monodromy
    except OscillatorError:
        return []
    assert monodromy is not None
    values, vectors = np.linalg.eig(monodromy)
    direction = np.real(vectors[:, int(np.argmin(np.abs(values + 1.0)))])
    direction /= float(np.max(np.abs(direction))) or 1.0
    size = 1.0 + float(np.max(np.abs(y)))
    for side in (1.0, -1.0):
        for beside in DOUBLED_BESIDE:
            start = value + side * beside * (high - low)
            if not low < start < high:
                continue
            near = resolve_case(case, **{param: start}, t0=branch.section)
            for move in DOUBLED_MOVES:
                state = orbit_state(near, 2 * branch.period, y + move * size * direction)
                if state is None:
                    continue
                half = period_map(near, branch.section, state, branch.period, derivative=False).end
                if float(np.max(np.abs(half - state))) > 1e-6 * size:
                    stop = high if side > 0 else low
                    return continued(case, param, span, start, stop, 2 * branch.period, state, max_points, known)
    return []


def trimmed(case: Case, branch: Branch, known: Sequence[Branch]) -> Branch:
    """``branch`` up to where it runs onto a ``known`` branch (after a jump at a sliding point,
    onto the orbit another seed's branch follows): every :data:`TRIM_EVERY`-th point is looked
    at, then the first on a known branch bisected for between the last two looked at.  The
    points and bifurcations before it are kept."""
    points = branch.points
    values, states = points[branch.param].to_numpy(float), points[list(STATE)].to_numpy(float)

    def merged(k: int) -> bool:
        return any(on_branch(case, other, float(values[k]), states[k]) for other in known)

    samples = [*range(TRIM_EVERY, len(points), TRIM_EVERY), len(points) - 1] if known else []
    last = next((k for k in samples if merged(k)), None)
    if last is None:
        return branch
    first = max(last - TRIM_EVERY, 0)  # not merged; the first merged point lies in (first, last]
    while last - first > 1:
        middle = (first + last) // 2
        first, last = (first, middle) if merged(middle) else (middle, last)
    kept = points.iloc[:last]
    rows = branch.bifurcations[branch.bifurcations[branch.param].isin(kept[branch.param])]
    ended = f"it runs onto another branch at {branch.param} = {values[last]:.10g}"
    return dataclasses.replace(
        branch,
        points=kept,
        bifurcations=rows.reset_index(drop=True),
        complete=False,
        message=ended,
        reason=Reason.NO_ORBIT,
    )


def distinct(case: Case, branches: Sequence[Branch], known: Sequence[Branch]) -> list[Branch]:
    """``branches`` (traced in parallel, each without the others) each up to where it runs onto a
    ``known`` one or one before it (:func:`trimmed`); those left with a point or none dropped."""
    kept: list[Branch] = []
    for branch in branches:
        branch = trimmed(case, branch, (*known, *kept))
        if len(branch.points) > 1:
            kept.append(branch)
    return kept


def measured(branch: Branch, first: int, last: int, cutoff: float = 0.0) -> pd.DataFrame:
    """The response measures of the branch's points ``first`` to ``last - 1``
    (:func:`~oscillator.orbits.response.branch_responses`, ``force_above`` and ``a_above`` above
    ``cutoff`` Hz), indexed by point."""
    part = dataclasses.replace(branch, points=branch.points.iloc[first:last])
    return branch_responses(part, cutoff).set_axis(range(first, last))


def on_branch(case: Case, branch: Branch, value: float, state: np.ndarray) -> bool:
    """Whether the orbit through ``state`` at ``value`` lies on ``branch``: from the state between
    two consecutive points of one piece that bracket ``value``, Newton at ``value`` reaches
    ``state`` (within :data:`SAME_ORBIT`)."""
    params, states, pieces = branch.columns
    low, high = np.minimum(params[:-1], params[1:]), np.maximum(params[:-1], params[1:])
    bracketing = np.flatnonzero((pieces[:-1] == pieces[1:]) & (low <= value) & (value <= high))
    at = resolve_case(case, **{branch.param: value}) if len(bracketing) else case
    for k in bracketing.tolist():
        a, b = params[k], params[k + 1]
        weight = 0.0 if a == b else (value - a) / (b - a)
        if _same(orbit_state(at, branch.period, states[k] + weight * (states[k + 1] - states[k])), state):
            return True
    return False


def orbit_state(
    case: Case, period: int, guess: np.ndarray, tolerances: tuple[float, ...] = (REFINE, 1e-9)
) -> np.ndarray | None:
    """The period-``period`` orbit Newton reaches from ``guess``: to
    :data:`~oscillator.orbits.response.REFINE`, else (where the map is not smooth enough for
    that: a sliding or grazing point near) to Newton's default 1e-9 (``tolerances``, in turn);
    None where it does not converge."""
    for tol in tolerances:
        try:
            return fixed_point(case, guess, period, tol=tol)
        except OscillatorError:
            continue
    return None


def _same(a: np.ndarray | None, b: np.ndarray | None) -> bool:
    if a is None or b is None:
        return False
    return float(np.max(np.abs(a - b))) <= SAME_ORBIT * (1.0 + float(np.max(np.abs(b))))


def sweep(case: Case, param: str, values: np.ndarray, settings: AttractorSettings) -> pd.DataFrame:
    """One slow sweep over ``values``: each landing starts where the one before ended; a landing
    that has not settled is told apart from an aperiodic one (:func:`settled_orbit`); the orbit
    met is refined by Newton and measured; the jumps are marked (:func:`jumps`)."""
    direction = "up" if values[-1] > values[0] else "down"
    start = np.array(case.initial.y, dtype=float)
    rows: list[dict[str, object]] = []
    states: list[np.ndarray | None] = []
    for value in values:
        at = resolve_case(case, **{param: float(value)})
        landing = land(at, settings, 0, (float(start[0]), float(start[1]), float(start[2]), float(start[3])))
        if landing.ok and len(landing.points):
            start = landing.points[-1]
        period, state = settled_orbit(at, landing, settings)
        if state is not None:
            start = state
        row: dict[str, object] = {"direction": direction, param: float(value), "period": period}
        row["signature"] = landing.signature
        row |= dict.fromkeys([*STATE, *COLUMNS], math.nan)  # where no orbit is met: the columns, not a number
        if state is not None:
            begin = dict(zip(STATE, (float(v) for v in state), strict=True))
            row |= begin | response(resolve_case(at, **begin), period, settings.cutoff).columns()
        rows.append(row)
        states.append(state)
    table = pd.DataFrame(rows)
    met = [(float(v), int(p), s) for v, p, s in zip(values, table["period"], states, strict=True)]
    table["jump"] = jumps(case, param, met)
    return table


#: A landing whose section points do not repeat is looked at again as one converging slowly (a
#: multiplier near 1, beside a fold): Newton from its last point for an orbit of one of these
#: periods, kept if stable and within :data:`NEAR` of it; else it runs this many times longer.
SLOW_PERIODS = (1, 2, 4)
NEAR = 1e-2
LONGER = 4


def settled_orbit(case: Case, landing: Landing, settings: AttractorSettings) -> tuple[int, np.ndarray | None]:
    """The period and the orbit's state (Newton's, refined) of the attractor ``landing`` reached:
    where its section points repeat, that orbit; where they do not, the stable orbit near its last
    point Newton finds (a landing converging slowly), else the landing run :data:`LONGER` times
    longer; ``(0, None)`` for a failed landing and a motion that does not settle (aperiodic)."""
    from oscillator.orbits.shooting import find_orbit

    if not landing.ok or not len(landing.points):
        return 0, None
    if landing.period:
        return landing.period, orbit_state(case, landing.period, landing.points[-1])
    end = landing.points[-1]
    for period in SLOW_PERIODS:
        try:
            orbit = find_orbit(case, period=period, guess=end, tol=REFINE)
        except OscillatorError:
            continue
        if orbit.stable and float(np.max(np.abs(orbit.state - end))) <= NEAR * (1.0 + float(np.max(np.abs(end)))):
            return period, orbit.state
    longer = dataclasses.replace(settings, transient=min(LONGER * settings.transient, 1_000_000))
    again = land(case, longer, 0, (float(end[0]), float(end[1]), float(end[2]), float(end[3])))
    if again.ok and again.period:
        return again.period, orbit_state(case, again.period, again.points[-1])
    return 0, None


#: Two orbits a sweep met lie on one continuous family where the orbit Newton finds halfway
#: between them lies within :data:`FOLLOW_TOL` (relative to their size) of the cubic through them
#: with their slopes (one-sided, by differences :data:`FOLLOW_DELTA` of the interval; Newton to
#: 1e-9 throughout): along a
#: smooth family its error falls as the interval's fourth power.  Where it does not, each half is
#: checked in turn: at a kink (a grazing) the misfit halves with the interval; across a jump, a
#: fold or a gap it stays, and a misfit that fell by less than :data:`FOLLOW_RATIO` at each of
#: :data:`FOLLOW_LEVELS` halvings in a row (or at :data:`FOLLOW_DEPTH` halvings) is a jump.
FOLLOW_TOL = 1e-6
FOLLOW_DELTA = 1e-3
FOLLOW_RATIO = 0.85
FOLLOW_LEVELS = 4
FOLLOW_DEPTH = 40


def follows(case: Case, param: str, a: tuple[float, np.ndarray], b: tuple[float, np.ndarray], period: int) -> bool:
    """Whether the period-``period`` orbits through ``a`` and ``b`` (each ``(value, state)``) lie on
    one continuous family (:data:`FOLLOW_TOL`): the orbit halfway lies near the chord between them
    (a fine sweep: one Newton), else near the cubic with their slopes, else each half is checked.
    A period-``period`` orbit reaches one of a period dividing it (a period doubling crossed
    continuously): both are fixed points of the ``period`` map.  False also where Newton finds no
    orbit between them (a fold, a gap)."""
    size = 1.0 + max(float(np.max(np.abs(a[1]))), float(np.max(np.abs(b[1]))))

    def slope(value: float, state: np.ndarray, side: float, width: float) -> np.ndarray | None:
        delta = side * FOLLOW_DELTA * width
        moved = orbit_state(resolve_case(case, **{param: value + delta}), period, state, (1e-9,))
        return None if moved is None else (moved - state) / delta

    def halfway(value: float, guesses: tuple[np.ndarray, ...]) -> np.ndarray | None:
        at = resolve_case(case, **{param: value})
        return next((s for s in (orbit_state(at, period, guess, (1e-9,)) for guess in guesses) if s is not None), None)

    chord = 0.5 * (a[1] + b[1])
    found = halfway(0.5 * (a[0] + b[0]), (chord, a[1], b[1]))
    if found is None:
        return False
    if float(np.max(np.abs(found - chord))) <= FOLLOW_TOL * size:
        return True
    interval = abs(b[0] - a[0])
    Slope = np.ndarray | None
    pending: list[tuple[tuple[float, np.ndarray], tuple[float, np.ndarray], Slope, Slope, float, int, int, Slope]]
    pending = [(a, b, slope(*a, 1.0, interval), slope(*b, -1.0, interval), math.inf, 0, 0, found)]
    while pending:
        (value_a, state_a), (value_b, state_b), slope_a, slope_b, misfit, slow, depth, found = pending.pop()
        if slope_a is None or slope_b is None:
            return False
        width, middle = value_b - value_a, 0.5 * (value_a + value_b)
        cubic = 0.5 * (state_a + state_b) + width / 8.0 * (slope_a - slope_b)
        found = found if found is not None else halfway(middle, (cubic, state_a, state_b))
        if found is None:
            return False
        now = float(np.max(np.abs(found - cubic)))
        if now <= FOLLOW_TOL * size:
            continue
        slow = slow + 1 if now > FOLLOW_RATIO * misfit else 0
        if slow >= FOLLOW_LEVELS or depth >= FOLLOW_DEPTH:
            return False
        left, right = slope(middle, found, -1.0, abs(width)), slope(middle, found, 1.0, abs(width))
        pending.append(((value_a, state_a), (middle, found), slope_a, left, now, slow, depth + 1, None))
        pending.append(((middle, found), (value_b, state_b), right, slope_b, now, slow, depth + 1, None))
    return True


def jumps(case: Case, param: str, met: Sequence[tuple[float, int, np.ndarray | None]]) -> np.ndarray:
    """Where a sweep jumps: at each value whose attractor (``(value, period, state)``; period 0
    where none settled) is not the continuation of the attractor met last (:func:`follows`, from
    the one of the longer period where the periods differ and one divides the other; another
    period is a jump).  A value where nothing settled is never a jump: the next attractor met is
    compared with the last one before it."""
    found = np.zeros(len(met), dtype=bool)
    last: tuple[float, int, np.ndarray] | None = None
    for k, (value, period, state) in enumerate(met):
        if not period or state is None:
            continue
        if last is not None:
            found[k] = not _continues(case, param, last, (value, period, state))
        last = (value, period, state)
    return found


def _continues(case: Case, param: str, a: tuple[float, int, np.ndarray], b: tuple[float, int, np.ndarray]) -> bool:
    (value_a, period_a, state_a), (value_b, period_b, state_b) = a, b
    if period_a == period_b:
        return follows(case, param, (value_a, state_a), (value_b, state_b), period_a)
    if max(period_a, period_b) % min(period_a, period_b):
        return False
    if period_a > period_b:
        return marched(case, param, (value_a, state_a), (value_b, state_b), period_a)
    return marched(case, param, (value_b, state_b), (value_a, state_a), period_b)


#: :func:`marched` takes steps whose orbit lies within this fraction of the size from the secant's
#: prediction, halved down to :data:`FOLLOW_DEPTH` halvings of the interval.
MARCH_TOL = 1e-2


def marched(case: Case, param: str, a: tuple[float, np.ndarray], b: tuple[float, np.ndarray], period: int) -> bool:
    """Whether the period-``period`` orbit through ``a`` reaches the orbit through ``b`` (of a
    period dividing ``period``: a period doubling between them) by Newton steps along its family,
    each predicted by the secant of the two before (:data:`MARCH_TOL`): at a period doubling
    crossed continuously the family merges with the orbit of half its period and goes on as it."""
    (value, state), (target, goal) = a, b
    size = 1.0 + max(float(np.max(np.abs(state))), float(np.max(np.abs(goal))))
    step, least = (target - value) / 16.0, abs(target - value) / 2.0**FOLLOW_DEPTH
    before: tuple[float, np.ndarray] | None = None
    while value != target:
        ahead = target if abs(target - value) <= abs(step) else value + step
        predicted = state if before is None else state + (state - before[1]) * (ahead - value) / (value - before[0])
        moved = orbit_state(resolve_case(case, **{param: ahead}), period, predicted, (1e-9,))
        if moved is not None and float(np.max(np.abs(moved - predicted))) <= MARCH_TOL * size:
            before, value, state, step = (value, state), ahead, moved, 2.0 * step
            continue
        step /= 2.0
        if abs(step) < least:
            return False
    return _same(state, goal)
