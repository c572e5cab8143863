"""What the explorer shows of one motion: computed here, drawn by :mod:`oscillator.exploring.app`.

A :class:`Scene` is the motion of a case over a number of forcing periods from its start: the
trajectory on a grid of the period, every switching event (time, mass, kind, theorem, equation),
the stroboscopic (Poincaré) points ``y(t0 + kT)``, and the intervals in which each mass rests
and each stop is in contact, exact from the run's smooth pieces (a rest shorter than the grid's
step is kept).  Nothing here draws or serves: the page is a view of these values, and the tests
compare them with :func:`~oscillator.simulate` directly.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import partial

import numpy as np
import pandas as pd

from oscillator.analysis.intervals import spans
from oscillator.errors import InputError
from oscillator.hybrid.record import Segment
from oscillator.hybrid.recording import SaveAt
from oscillator.hybrid.simulate import simulate
from oscillator.io.cases import Case, resolve_case, section_times
from oscillator.model.parameters import Parameters
from oscillator.model.phase_space import Mode

__all__ = ["EVENT_COLUMNS", "GRID", "PERIODS", "TIME_AGREEMENT", "Scene", "differences", "scene_of"]

#: The forcing periods a scene spans unless asked otherwise.
PERIODS = 50
#: Trajectory points per forcing period (the events are exact whatever the grid).
GRID = 64
#: How far two engines' event times may lie apart and still show the same table (s): its precision.
TIME_AGREEMENT = 1e-6
#: The event table's columns, in the page's order.
EVENT_COLUMNS = ("t", "mass", "kind", "from_domain", "to_domain", "theorem", "equation", "boundary")


@dataclass(frozen=True, eq=False)
class Scene:
    """One motion as the explorer shows it.

    Attributes
    ----------
    case : Case
        The case simulated (its ``t_end`` set by the periods).
    periods : int
        Forcing periods from the start.
    trajectory : DataFrame
        ``t, x1, v1, x2, v2`` on :data:`GRID` points a period, with the state on both sides of
        every switch.
    events : DataFrame
        Every switching event, :data:`EVENT_COLUMNS` and the state.
    strobe : DataFrame
        ``k, t, x1, v1, x2, v2`` at ``t0 + kT``, ``k = 0 .. periods``.
    rests : dict
        Mass (1, 2) -> the ``(from, to)`` intervals in which it rests.
    contacts : dict
        ``"left"`` (between the masses), ``"right"`` (the right stop) -> its contact intervals.
    seconds : float
        The simulation's wall time.
    status : str
        How the run ended (``"complete"``; a failure's message otherwise).
    engine : str
        The integrator that ran it (:mod:`oscillator.engines`).
    """

    case: Case
    periods: int
    trajectory: pd.DataFrame
    events: pd.DataFrame
    strobe: pd.DataFrame
    rests: dict[int, list[tuple[float, float]]]
    contacts: dict[str, list[tuple[float, float]]]
    seconds: float
    status: str
    engine: str

    @property
    def t0(self) -> float:
        return float(self.case.initial.t0)

    @property
    def t_end(self) -> float:
        return float(self.case.t_end)


def check_periods(periods: object) -> int:
    """``periods`` as a whole number from 1 to 10000, or refused naming the field."""
    if isinstance(periods, bool) or not isinstance(periods, int | np.integer) or not 1 <= periods <= 10_000:
        raise InputError(f"periods must be a whole number from 1 to 10000, got {periods!r}", field="periods")
    return int(periods)


def scene_of(case: Case | str, periods: int = PERIODS, *, engine: str = "cvode", **overrides: float) -> Scene:
    """The motion of ``case`` (with ``overrides`` of its parameters and start) over ``periods``
    forcing periods from its start: one :func:`~oscillator.simulate` run with ``engine`` (CVODE,
    the reference, unless another is named).

    Raises
    ------
    InputError
        An unknown name or an impossible value (the field named).
    """
    periods = check_periods(periods)
    base = resolve_case(case, **overrides)
    marks = section_times(base, 0, periods)
    run_case = resolve_case(base, t_end=float(marks[-1]))
    grid = np.linspace(marks[0], marks[-1], periods * GRID + 1)
    started = time.perf_counter()
    result = simulate(run_case, engine=engine, save=SaveAt(ts=grid, segments=True))
    seconds = time.perf_counter() - started
    trajectory = result.trajectory[["t", "x1", "v1", "x2", "v2"]]
    return Scene(
        case=run_case,
        periods=periods,
        trajectory=_with_switches(trajectory, result.events),
        events=result.events[[*EVENT_COLUMNS, "x1", "v1", "x2", "v2"]].reset_index(drop=True),
        strobe=_strobe(trajectory, marks),
        rests={mass: _intervals(result.segments, partial(_rests, mass=mass)) for mass in (1, 2)},
        contacts={side: _intervals(result.segments, partial(_touches, side=side)) for side in ("left", "right")},
        seconds=seconds,
        status=result.status.value if not result.message else result.message,
        engine=engine,
    )


def differences(scene: Scene, reference: Scene) -> tuple[str | None, float]:
    """How ``scene``'s switching events differ from ``reference``'s, as the event table shows
    them: None when both hold the same events (mass, kind, domains, theorem, equation, boundary)
    at times within :data:`TIME_AGREEMENT`, a sentence otherwise; and the largest time difference
    of the events both hold (nan when there are none)."""
    shown, ruled = scene.events, reference.events
    both = min(len(shown), len(ruled))
    gaps = np.abs(shown.t.to_numpy(float)[:both] - ruled.t.to_numpy(float)[:both])
    largest = float(gaps.max()) if both else float("nan")
    columns = list(EVENT_COLUMNS[1:])
    same = shown[columns].iloc[:both].astype(str).to_numpy() == ruled[columns].iloc[:both].astype(str).to_numpy()
    unlike = np.flatnonzero(~same.all(axis=1) | (gaps > TIME_AGREEMENT))
    if len(unlike):
        k = int(unlike[0])
        said = f"event {k + 1} differs (t = {float(shown.t.iloc[k]):.9g} s against {float(ruled.t.iloc[k]):.9g} s)"
        return said, largest
    if len(shown) != len(ruled):
        return f"{len(shown)} events against {len(ruled)}", largest
    if scene.status != reference.status:
        return f"the run ended {scene.status!r} against {reference.status!r}", largest
    return None, largest


def _with_switches(trajectory: pd.DataFrame, events: pd.DataFrame) -> pd.DataFrame:
    """The grid's rows and each event's state, in time order: the corners of a contact or a
    stop show where they are, not cut by the grid."""
    switches = events[["t", "x1", "v1", "x2", "v2"]]
    merged = pd.concat([trajectory, switches], ignore_index=True)
    return merged.sort_values("t", kind="stable").reset_index(drop=True)


def _strobe(trajectory: pd.DataFrame, marks: np.ndarray) -> pd.DataFrame:
    """The grid's rows at the section times (the grid holds them, one every :data:`GRID` rows)."""
    t = trajectory.t.to_numpy(float)
    rows = trajectory.iloc[np.clip(np.searchsorted(t, marks - 1e-9 * (1.0 + np.abs(marks))), 0, len(t) - 1)]
    strobe = rows.reset_index(drop=True).assign(t=marks)
    strobe.insert(0, "k", np.arange(len(marks)))
    return strobe


def _rests(mode: Mode, mass: int) -> bool:
    return mode.sign(mass) == 0


def _touches(mode: Mode, side: str) -> bool:
    return bool(getattr(mode, side))


def _intervals(segments: Sequence[Segment], holds: Callable[[Mode], bool]) -> list[tuple[float, float]]:
    """The maximal intervals over which ``holds(mode)`` is true, from the run's smooth pieces."""
    if not segments:
        return []
    times = [segment.t0 for segment in segments]
    states = [bool(holds(segment.mode)) for segment in segments]
    return [(a, b) for state, a, b in spans(times, states, segments[-1].t1) if state and b > a]


def with_changes(case: Case, values: dict[str, float]) -> Case:
    """``case`` with the changed ``values`` (parameters and start), checked."""
    changed = {name: value for name, value in values.items() if _current(case, name) != value}
    return resolve_case(case, **changed) if changed else case


def _current(case: Case, name: str) -> float:
    holder = case.parameters if name in Parameters.names() else case.initial
    return float(getattr(holder, name))
