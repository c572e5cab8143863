"""The frequency response: every branch of periodic orbits over a parameter's span, with the
response measures at each point, and what slow sweeps up and down meet (issue 38).

:func:`frequency_response` finds the periodic attractors at a few values of the parameter (seeds:
:func:`~oscillator.attractors.finding.find_attractors` from the given starts), continues each orbit
both ways to the span's ends through folds and unstable stretches
(:func:`~oscillator.orbits.continuation.continue_orbit`; a seed already on a branch is not
continued again), and measures every point of every branch (:meth:`~oscillator.orbits.branch.Branch.responses`:
peaks, RMS values, rests, contacts, impact velocities, contact forces, energies, each orbit
refined by Newton first).  The sweeps are what an experiment turning the knob slowly sees: at
each of ``sweep`` values, up the span and then down, the motion lands from where it was at the
value before (:func:`~oscillator.attractors.mapping.land`), and its attractor is measured; a
``jump`` marks a value where the motion left the attractor it followed (another period, or a
move of the section point out of scale with the moves around it: :func:`_jumps`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from oscillator.attractors.finding import find_attractors
from oscillator.attractors.mapping import AttractorSettings, check_settings, land
from oscillator.errors import InputError, OscillatorError
from oscillator.io.cases import Case, resolve_case
from oscillator.model.parameters import Parameters, check_count
from oscillator.orbits.branch import Bifurcation, Branch
from oscillator.orbits.continuation import continue_orbit
from oscillator.orbits.response import REFINE, response
from oscillator.orbits.shooting import find_orbit
from oscillator.presenting import presenter

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

__all__ = ["JUMP", "JUMP_RATIO", "FrequencyResponse", "frequency_response"]

#: A sweep jumps where its orbit's section point moves by more than this fraction of its size and
#: by more than :data:`JUMP_RATIO` times the moves before and after it (or the period changes).
JUMP = 0.05
JUMP_RATIO = 3.0
#: Two orbits at one parameter value are one where their section points agree to this (times
#: ``1 + |P|``): a seed on a branch is not continued again.
SAME_ORBIT = 1e-4


@dataclass(frozen=True)
class FrequencyResponse:
    """What :func:`frequency_response` found.

    Attributes
    ----------
    param : str
        The parameter swept (``"Omega"`` for a frequency response).
    branches : tuple of Branch
        Every branch continued, each from a seed to one end of the span.
    points : DataFrame
        One row per branch point: ``branch`` (its index in ``branches``), the parameter,
        ``stable``, ``piece`` and every response measure (:meth:`oscillator.Response.columns`).
    sweeps : DataFrame
        One row per sweep value: ``direction`` (``"up"``, ``"down"``), the parameter, ``period``
        (0: aperiodic or failed), ``signature``, ``jump`` and the response measures of the
        attractor met (NaN where it is not periodic).
    """

    param: str
    branches: tuple[Branch, ...]
    points: pd.DataFrame
    sweeps: pd.DataFrame
    case: Case = field(repr=False, compare=False)  #: the case, as given

    def plot(self, measure: str = "x_pp") -> Figure:
        """``measure`` of each mass against the parameter, in the engineers' style
        (:func:`oscillator.report.frequency.frequency_figure`): branches stable solid and unstable
        dashed, bifurcations marked, the sweeps with their jumps, sticking and contact shaded."""
        return presenter().plot_global(self, measure=measure)

    @property
    def folds(self) -> pd.DataFrame:
        """The branches' folds: the parameter and the branch."""
        rows = [
            {"branch": k, self.param: float(row[self.param])}
            for k, branch in enumerate(self.branches)
            for _, row in branch.bifurcations.iterrows()
            if row["kind"] == Bifurcation.FOLD
        ]
        return pd.DataFrame(rows, columns=["branch", self.param])

    def jumps(self, direction: str) -> list[float]:
        """The values at which the sweep ``direction`` (``"up"`` or ``"down"``) jumped."""
        rows = self.sweeps[(self.sweeps.direction == direction) & self.sweeps.jump]
        return [float(value) for value in rows[self.param]]


def frequency_response(
    case: Case | str,
    param: str = "Omega",
    span: tuple[float, float] = (1.3, 1.85),
    *,
    period: int = 1,
    seeds: int = 5,
    states: Sequence[Sequence[float]] | np.ndarray | None = None,
    sweep: int = 41,
    settings: AttractorSettings | None = None,
    max_points: int = 3000,
    progress: Callable[[str], None] | None = None,
) -> FrequencyResponse:
    """The branches of period-``period`` orbits over ``span`` of ``param`` with their response
    measures, and the sweeps up and down (module docstring).

    ``seeds`` values (2 to 1000, evenly over the span) look for attractors from ``states`` (the
    case's start by default); ``sweep`` values (2 to 100000) make each sweep; ``settings`` are the
    landings' (:class:`~oscillator.attractors.mapping.AttractorSettings`); ``max_points`` bounds
    each branch.  ``progress`` is told each stage in words."""
    base = resolve_case(case) if isinstance(case, str) else case
    low, high = _check(base, param, span, period, seeds, sweep)
    settings = check_settings(settings)
    say = progress or (lambda _: None)
    branches: list[Branch] = []
    for value in np.linspace(low, high, seeds):
        say(f"attractors at {param} = {value:.6g}")
        found = find_attractors(resolve_case(base, **{param: float(value)}), states=states, settings=settings)
        for attractor in found.attractors:
            if attractor.period != period or attractor.orbit is None:
                continue
            state = attractor.orbit.state
            if any(_on(base, branch, float(value), state) for branch in branches):
                continue
            for stop in (high, low):
                if stop != value:
                    say(f"continuing the orbit of {param} = {value:.6g} to {stop:.6g}")
                    branches.append(_continued(base, param, float(value), stop, period, state, max_points))
    say("measuring the branches")
    points = pd.concat(
        [branch.responses().assign(branch=k) for k, branch in enumerate(branches)] or [pd.DataFrame()],
        ignore_index=True,
    )
    say("sweeping up and down")
    sweeps = pd.concat([_sweep(base, param, values, settings) for values in _sweep_values(low, high, sweep)])
    return FrequencyResponse(param, tuple(branches), points, sweeps.reset_index(drop=True), base)


def _check(case: Case, param: str, span: object, period: int, seeds: int, sweep: int) -> tuple[float, float]:
    Parameters.check_name(param, "param")
    check_count(period, "period", 1, 1000)
    check_count(seeds, "seeds", 2, 1000)
    check_count(sweep, "sweep", 2, 100_000)
    try:
        low, high = (float(value) for value in span)  # type: ignore[attr-defined]
    except (TypeError, ValueError):
        raise InputError(f"span must be two numbers (low, high), got {span!r}", field="span") from None
    if not (np.isfinite(low) and np.isfinite(high) and low < high):
        raise InputError(
            f"span must be two finite numbers, low < high, got {span!r}; give e.g. (1.3, 1.85)", field="span"
        )
    for value in (low, high):
        resolve_case(case, **{param: value})  # each end must be a valid value, or it is refused by name
    return low, high


def _continued(
    case: Case, param: str, start: float, stop: float, period: int, state: np.ndarray, max_points: int
) -> Branch:
    at = resolve_case(case, **{param: start})
    return continue_orbit(at, param=param, start=start, stop=stop, period=period, guess=state, max_points=max_points)


def _on(case: Case, branch: Branch, value: float, state: np.ndarray) -> bool:
    """Whether the orbit through ``state`` at ``value`` lies on ``branch``: from the state between
    two consecutive points of one piece that bracket ``value``, Newton at ``value`` reaches
    ``state`` (within :data:`SAME_ORBIT`)."""
    points = branch.points
    params = points[branch.param].to_numpy(float)
    states = points[["x1", "v1", "x2", "v2"]].to_numpy(float)
    pieces = points["piece"].to_numpy()
    at = resolve_case(case, **{branch.param: value})
    for k in range(len(points) - 1):
        a, b = params[k], params[k + 1]
        if pieces[k] != pieces[k + 1] or not min(a, b) <= value <= max(a, b):
            continue
        weight = 0.0 if a == b else (value - a) / (b - a)
        if _same(_orbit_state(at, branch.period, states[k] + weight * (states[k + 1] - states[k])), state):
            return True
    return False


def _orbit_state(case: Case, period: int, guess: np.ndarray) -> np.ndarray | None:
    """The period-``period`` orbit Newton reaches from ``guess``: to :data:`REFINE`, else (where
    the map is not smooth enough for that: a sliding or grazing point near) to Newton's default
    1e-9; None where it does not converge."""
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


def _sweep_values(low: float, high: float, count: int) -> tuple[np.ndarray, np.ndarray]:
    up = np.linspace(low, high, count)
    return up, up[::-1]


def _sweep(case: Case, param: str, values: np.ndarray, settings: AttractorSettings) -> pd.DataFrame:
    """One slow sweep over ``values``: each landing starts where the one before ended, and the
    orbit met is refined by Newton and measured; the jumps are marked (:func:`_jumps`)."""
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
        state = _orbit_state(at, period, start) if period else None
        row: dict[str, object] = {"direction": direction, param: float(value), "period": period}
        row["signature"] = landing.signature
        if state is not None:
            begin = dict(zip(("x1", "v1", "x2", "v2"), (float(v) for v in state), strict=True))
            row |= response(resolve_case(at, **begin), period).columns()
        rows.append(row)
        states.append(state)
    table = pd.DataFrame(rows)
    table["jump"] = _jumps(table["period"].to_numpy(), states)
    return table


def _jumps(periods: np.ndarray, states: list[np.ndarray | None]) -> np.ndarray:
    """Where a sweep jumps: the period changes, or the orbit's section point moves by more than
    :data:`JUMP_RATIO` times the moves on either side (and by more than :data:`JUMP` of its size).
    An orbit followed towards a fold moves ever faster, but its moves grow step by step; a jump
    is one move out of scale with its neighbours."""
    count = len(states)
    moves = np.zeros(count)
    for k in range(1, count):
        a, b = states[k - 1], states[k]
        moves[k] = np.inf if a is None or b is None else float(np.max(np.abs(b - a)))
    jumps = np.zeros(count, dtype=bool)
    for k in range(1, count):
        if periods[k] != periods[k - 1]:
            jumps[k] = True
            continue
        state = states[k]
        if state is None or not np.isfinite(moves[k]):
            continue
        neighbours = max(moves[k - 1] if k > 1 else 0.0, moves[k + 1] if k + 1 < count else 0.0)
        size = JUMP * (1.0 + float(np.max(np.abs(state))))
        jumps[k] = moves[k] > size and (not np.isfinite(neighbours) or moves[k] > JUMP_RATIO * neighbours)
    return jumps
