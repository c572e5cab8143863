"""The frequency response's tasks: each a pure top-level function that a worker process or a Dask
worker runs (:mod:`oscillator.analysis.execution`), called by
:func:`~oscillator.attractors.frequency.frequency_response`.

* :func:`seed_orbits`: the periodic attractors at one value of the parameter, as section points;
* :func:`continued`: one orbit continued towards one end of the span, started again just beyond
  each point where the corrector fails inside the span (:data:`RESTART`): a sliding or grazing
  point it cannot step across, or a cluster of them, leaves a gap of ``RESTART`` of the span
  instead of ending the branch;
* :func:`doubled`: the branch of period ``2n`` born at a period-``n`` branch's period doubling;
* :func:`measured`: the response measures of a run of one branch's points;
* :func:`sweep`: one slow sweep, up or down, with its jumps (:func:`jumps`).

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
from oscillator.attractors.mapping import AttractorSettings, land
from oscillator.errors import OscillatorError, Reason
from oscillator.io.cases import Case, resolve_case
from oscillator.orbits.branch import Branch
from oscillator.orbits.continuation import continue_orbit
from oscillator.orbits.response import COLUMNS, REFINE, branch_responses, response
from oscillator.orbits.shooting import STATE, find_orbit, period_map

__all__ = [
    "JUMP",
    "JUMP_RATIO",
    "RESTART",
    "SAME_ORBIT",
    "continued",
    "doubled",
    "jumps",
    "measured",
    "on_branch",
    "seed_orbits",
    "trimmed",
]

#: A sweep jumps where its orbit's section point moves by more than this fraction of its size and
#: by more than :data:`JUMP_RATIO` times the moves before and after it (or the period changes).
JUMP = 0.05
JUMP_RATIO = 3.0
#: Two orbits at one parameter value are one where their section points agree to this (times
#: ``1 + |P|``): a seed on a branch is not continued again.
SAME_ORBIT = 1e-4
#: Where the corrector fails inside the span, the branch starts again this fraction of the span
#: beyond the last point, from Newton's orbit there; at most :data:`MAX_RESTARTS` times a branch.
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
    """The orbit through ``state`` at ``start`` continued to ``stop``: one branch, or several
    where the corrector failed inside the span and the branch was started again beyond
    (module docstring); a restart that lands on a ``known`` branch, or on one of these, ends it."""
    low, high = span
    found: list[Branch] = []
    while True:
        at = resolve_case(case, **{param: start})
        branch = continue_orbit(
            at, param=param, start=start, stop=stop, period=period, guess=state, max_points=max_points
        )
        whole = len(branch.points)
        branch = trimmed(case, branch, known)
        found.append(branch)
        if (
            len(branch.points) < whole
            or branch.complete
            or branch.reason in _FINAL
            or len(found) > MAX_RESTARTS
            or len(branch.points) < 2
        ):
            return found
        values = branch.points[param].to_numpy(float)
        heading = 1.0 if values[-1] >= values[-2] else -1.0
        beyond = float(values[-1] + heading * RESTART * (high - low))
        if not low < beyond < high:
            return found
        restart = orbit_state(
            resolve_case(case, **{param: beyond}), period, branch.points[list(STATE)].to_numpy(float)[-1]
        )
        if restart is None or any(on_branch(case, other, beyond, restart) for other in (*known, *found)):
            return found
        start, stop, state = beyond, (high if heading > 0 else low), restart


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


def measured(branch: Branch, first: int, last: int) -> pd.DataFrame:
    """The response measures of the branch's points ``first`` to ``last - 1``
    (:func:`~oscillator.orbits.response.branch_responses`), indexed by point."""
    part = dataclasses.replace(branch, points=branch.points.iloc[first:last])
    return branch_responses(part).set_axis(range(first, last))


def on_branch(case: Case, branch: Branch, value: float, state: np.ndarray) -> bool:
    """Whether the orbit through ``state`` at ``value`` lies on ``branch``: from the state between
    two consecutive points of one piece that bracket ``value``, Newton at ``value`` reaches
    ``state`` (within :data:`SAME_ORBIT`)."""
    points = branch.points
    params = points[branch.param].to_numpy(float)
    states = points[list(STATE)].to_numpy(float)
    pieces = points["piece"].to_numpy()
    at = resolve_case(case, **{branch.param: value})
    for k in range(len(points) - 1):
        a, b = params[k], params[k + 1]
        if pieces[k] != pieces[k + 1] or not min(a, b) <= value <= max(a, b):
            continue
        weight = 0.0 if a == b else (value - a) / (b - a)
        if _same(orbit_state(at, branch.period, states[k] + weight * (states[k + 1] - states[k])), state):
            return True
    return False


def orbit_state(case: Case, period: int, guess: np.ndarray) -> np.ndarray | None:
    """The period-``period`` orbit Newton reaches from ``guess``: to
    :data:`~oscillator.orbits.response.REFINE`, else (where the map is not smooth enough for
    that: a sliding or grazing point near) to Newton's default 1e-9; None where it does not
    converge."""
    for tol in (REFINE, 1e-9):
        try:
            return find_orbit(case, period=period, guess=guess, tol=tol).state
        except OscillatorError:
            continue
    return None


def _same(a: np.ndarray | None, b: np.ndarray | None) -> bool:
    if a is None or b is None:
        return False
    return float(np.max(np.abs(a - b))) <= SAME_ORBIT * (1.0 + float(np.max(np.abs(b))))


def sweep(case: Case, param: str, values: np.ndarray, settings: AttractorSettings) -> pd.DataFrame:
    """One slow sweep over ``values``: each landing starts where the one before ended, and the
    orbit met is refined by Newton and measured; the jumps are marked (:func:`jumps`)."""
    direction = "up" if values[-1] > values[0] else "down"
    start = np.array(case.initial.y, dtype=float)
    rows: list[dict[str, object]] = []
    states: list[np.ndarray | None] = []
    for value in values:
        at = resolve_case(case, **{param: float(value)})
        landing = land(at, settings, 0, (float(start[0]), float(start[1]), float(start[2]), float(start[3])))
        if landing.ok and len(landing.points):
            start = landing.points[-1]
        period = landing.period if landing.ok else 0
        state = orbit_state(at, period, start) if period else None
        row: dict[str, object] = {"direction": direction, param: float(value), "period": period}
        row["signature"] = landing.signature
        row |= dict.fromkeys(COLUMNS, math.nan)  # where no orbit is met: the columns, not a number
        if state is not None:
            begin = dict(zip(STATE, (float(v) for v in state), strict=True))
            row |= response(resolve_case(at, **begin), period).columns()
        rows.append(row)
        states.append(state)
    table = pd.DataFrame(rows)
    table["jump"] = jumps(table["period"].to_numpy(), states, table["signature"].tolist())
    return table


def jumps(periods: np.ndarray, states: list[np.ndarray | None], signatures: Sequence[str] | None = None) -> np.ndarray:
    """Where a sweep jumps: the period changes, or the orbit's section point moves by more than
    :data:`JUMP_RATIO` times the moves on either side, and by more than :data:`JUMP` of its size
    or with its cycle of switches changed (a rest interval that appears with a finite length).
    An orbit followed towards a fold moves ever faster, but its moves grow step by step; a jump
    is one move out of scale with its neighbours."""
    count = len(states)
    changed = [False] + [signatures[k] != signatures[k - 1] for k in range(1, count)] if signatures else [False] * count
    moves = np.zeros(count)
    for k in range(1, count):
        a, b = states[k - 1], states[k]
        moves[k] = np.inf if a is None or b is None else float(np.max(np.abs(b - a)))
    found = np.zeros(count, dtype=bool)
    for k in range(1, count):
        if periods[k] != periods[k - 1]:
            found[k] = True
            continue
        state = states[k]
        if state is None or not np.isfinite(moves[k]):
            continue
        neighbours = max(moves[k - 1] if k > 1 else 0.0, moves[k + 1] if k + 1 < count else 0.0)
        large = moves[k] > JUMP * (1.0 + float(np.max(np.abs(state)))) or changed[k]
        found[k] = large and (not np.isfinite(neighbours) or moves[k] > JUMP_RATIO * neighbours)
    return found
