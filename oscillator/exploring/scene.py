"""What the explorer shows of one motion: computed here, drawn by :mod:`oscillator.exploring.app`.

A :class:`Scene` is the motion of a system over a number of forcing periods from its start: the
trajectory on a grid of the period (a friction chain's: at every solver step), every switching
event (time, mass, kind, theorem, equation), the stroboscopic (Poincaré) points ``y(t0 + kT)``,
and the intervals in which each mass rests and each stop is in contact, exact from the run's
smooth pieces (a rest shorter than the grid's step is kept).  Its :class:`Outline` says what of
it the page draws, read from the system: the masses' names and columns, the contacts, the event
table's columns.  Nothing here draws or serves: the page is a view of these values, and the tests
compare them with :func:`~oscillator.simulate` and
:func:`~oscillator.hybrid.chain_run.simulate_chain` directly.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Hashable
from dataclasses import dataclass
from typing import Any, TypeAlias

import numpy as np
import pandas as pd

from oscillator.analysis.intervals import spans
from oscillator.errors import InputError, Reason, SimulationFailed
from oscillator.hybrid.recording import SaveAt
from oscillator.hybrid.simulate import simulate
from oscillator.io.cases import Case, resolve_case, section_times
from oscillator.model.chains import FrictionChain
from oscillator.model.parameters import Parameters, SolverOptions
from oscillator.model.system import ARTICLE as ARTICLE_SYSTEM
from oscillator.model.system import System

__all__ = [
    "ARTICLE",
    "EVENT_COLUMNS",
    "GRID",
    "MAX_EVENTS",
    "MAX_POINTS",
    "PERIODS",
    "TIME_AGREEMENT",
    "Explored",
    "Outline",
    "Scene",
    "Superseded",
    "chain_scene_of",
    "differences",
    "outline_of",
    "scene_of",
]

#: The forcing periods a scene spans unless asked otherwise.
PERIODS = 50
#: Trajectory points per forcing period (the events are exact whatever the grid), fewer where the
#: periods asked would make more than :data:`MAX_POINTS` (at least 4).
GRID = 64
#: What one change may cost: at most this many events (the run stops there, and the page says so:
#: ``C1 = 1e6`` made 108,304 grazings in 50 periods, a 5.9 GB message) and trajectory points.
MAX_EVENTS = 10_000
MAX_POINTS = 50_000
#: How far two engines' event times may lie apart and still show the same table (s): its precision.
TIME_AGREEMENT = 1e-6
#: Event rows a forcing period the compiled run has room for, beyond which the run goes through
#: :func:`~oscillator.simulate` (a chattering motion).
EVENT_ROWS = 64
#: The event table's columns, in the page's order.
EVENT_COLUMNS = ("t", "mass", "kind", "from_domain", "to_domain", "theorem", "equation", "boundary")
#: A friction chain's event table's columns, in the page's order.
CHAIN_EVENT_COLUMNS = ("t", "element", "mass", "kind", "mode_before", "mode_after", "theorem", "equations")
#: The system a scene shows: the article's (a case) or a friction chain.
Explored: TypeAlias = Case | FrictionChain


@dataclass(frozen=True)
class Outline:
    """What the page draws of a system's motion, read from the system.

    Attributes
    ----------
    masses : tuple
        Each mass as ``(key, label, position column, velocity column)``: its key in the events'
        ``mass`` column and in :attr:`Scene.rests`, its name, its trajectory's columns.
    contacts : tuple
        The keys of :attr:`Scene.contacts`, each a stop or contact shaded while closed.
    event_columns : tuple
        The event table's columns, time first.
    rest, closed : str
        What a mass's shaded interval is called (``at rest``; a chain's mass ``stuck`` on its
        belt or the floor), and a contact's (``contact``; a chain's stop ``closed``).
    resting : tuple or None
        The keys of the masses that may rest (a chain's with a friction element); None: all.
    """

    masses: tuple[tuple[Hashable, str, str, str], ...]
    contacts: tuple[str, ...]
    event_columns: tuple[str, ...]
    rest: str = "at rest"
    closed: str = "contact"
    resting: tuple[Hashable, ...] | None = None

    @property
    def state(self) -> tuple[str, ...]:
        """The positions and velocities the page draws, mass after mass."""
        return tuple(column for _, _, x, v in self.masses for column in (x, v))

    @classmethod
    def of(cls, system: System, event_columns: tuple[str, ...], contacts: tuple[str, ...], **words: Any) -> Outline:
        """The outline of ``system`` (:mod:`oscillator.model.system`): each of its masses with its
        label, position and velocity; ``contacts`` in the order shaded."""
        masses = tuple((m, system.label(m), system.position(m), system.velocity(m)) for m in system.masses)
        return cls(masses, contacts, event_columns, **words)


#: The article's system as the page draws it (the contact between the masses, then the right stop).
ARTICLE = Outline.of(ARTICLE_SYSTEM, EVENT_COLUMNS, ("left", "right"))


def outline_of(chain: FrictionChain) -> Outline:
    """A friction chain as the page draws it: each mass by its name (``x:<mass>``, ``v:<mass>``),
    each stop and contact by its element's name, a mass with a friction element stuck."""
    system = chain.system
    resting = tuple(e.on for e in chain.elements if e.type == "friction")
    return Outline.of(system, CHAIN_EVENT_COLUMNS, system.contacts, rest="stuck", closed="closed", resting=resting)


@dataclass(frozen=True, eq=False)
class Scene:
    """One motion as the explorer shows it.

    Attributes
    ----------
    case : Case or FrictionChain
        The system simulated (a case's ``t_end`` set by the periods).
    periods : int
        Forcing periods from the start.
    trajectory : DataFrame
        ``t`` and the state (``x1, v1, x2, v2``; a chain's ``x:<mass>``, ``v:<mass>``,
        ``z:<slider>``) on :data:`GRID` points a period (a chain's: at every solver step, at most
        :data:`MAX_POINTS`), with the state on both sides of every switch.
    events : DataFrame
        Every switching event, :attr:`Outline.event_columns` and (the article's) the state.
    strobe : DataFrame
        ``k, t`` and the state at ``t0 + kT``, ``k = 0 .. periods``.
    rests : dict
        Mass (1, 2; a chain's by name) -> the ``(from, to)`` intervals in which it rests (a
        chain's mass: stuck on its belt or the floor).
    contacts : dict
        ``"left"`` (between the masses), ``"right"`` (the right stop); a chain's stops and
        contacts by name -> its contact intervals.
    seconds : float
        The simulation's wall time.
    status : str
        How the run ended (``"complete"``; a failure's message otherwise).
    engine : str
        The integrator that ran it (:mod:`oscillator.engines`).
    bounded : bool
        Whether the run stopped at :data:`MAX_EVENTS`, the explorer's bound (``status`` says so);
        a run another guard or the solver stopped shows its motion up to there too.
    outline : Outline
        What the page draws of it.
    t0, t_end, period : float
        The run's start and end, the forcing period (s).
    """

    case: Explored
    periods: int
    trajectory: pd.DataFrame
    events: pd.DataFrame
    strobe: pd.DataFrame
    rests: dict[Hashable, list[tuple[float, float]]]
    contacts: dict[str, list[tuple[float, float]]]
    seconds: float
    status: str
    engine: str
    bounded: bool
    outline: Outline
    t0: float
    t_end: float
    period: float


def check_periods(periods: object) -> int:
    """``periods`` as a whole number from 1 to 10000, or refused naming the field."""
    if isinstance(periods, bool) or not isinstance(periods, int | np.integer) or not 1 <= periods <= 10_000:
        raise InputError(f"periods must be a whole number from 1 to 10000, got {periods!r}", field="periods")
    return int(periods)


class Superseded(Exception):
    """A run stopped because another change came (``scene_of``'s ``stop`` said so)."""


def grid_of(periods: int) -> int:
    """Trajectory points per period for ``periods`` periods (:data:`GRID`, :data:`MAX_POINTS`)."""
    return max(4, min(GRID, MAX_POINTS // periods))


def scene_of(
    case: Case | str,
    periods: int = PERIODS,
    *,
    engine: str = "cvode",
    stop: Callable[[], bool] | None = None,
    **overrides: float,
) -> Scene:
    """The motion of ``case`` (with ``overrides`` of its parameters and start) over ``periods``
    forcing periods from its start: one run with ``engine`` (CVODE, the reference, unless another
    is named), through :func:`~oscillator.simulate`; with ``"dop853"``, the same run with the
    supervisor compiled (:func:`~oscillator.hybrid.batch.run_compiled`), and through ``simulate``
    where that one cannot finish.  At most :data:`MAX_EVENTS` events (the run stops there, and the
    scene says so) and :data:`MAX_POINTS` trajectory points; a run a guard or the solver stops is
    shown up to there, its ``status`` the reason.  ``stop()``, asked as a run through ``simulate``
    goes, ends it with :class:`Superseded` where it says so.

    Raises
    ------
    InputError
        An unknown name or an impossible value (the field named).
    """
    periods = check_periods(periods)
    base = resolve_case(case, **overrides)
    marks = section_times(base, 0, periods)
    bound = min(base.options.max_events, MAX_EVENTS)
    run_case = resolve_case(base, t_end=float(marks[-1]), max_events=bound)
    grid = np.linspace(marks[0], marks[-1], periods * grid_of(periods) + 1)
    started = time.perf_counter()
    run = _compiled_run(run_case, grid) if engine == "dop853" else None
    if run is None:  # another engine, or a run the compiled supervisor could not finish: in words
        run = _simulated_run(run_case, grid, engine, stop)
    seconds = time.perf_counter() - started
    trajectory, events, modes, status, bounded = run
    times, end = modes[:, 0], float(run_case.t_end)
    system = run_case.system
    state = list(system.state)
    return Scene(
        case=run_case,
        periods=periods,
        trajectory=_with_switches(trajectory, events, state),
        events=events[[*EVENT_COLUMNS, *state]].reset_index(drop=True),
        strobe=_strobe(trajectory, marks[marks <= float(trajectory.t.iloc[-1]) + 1e-9]),
        rests={mass: _intervals(times, modes[:, k] == 0, end) for k, mass in enumerate(system.masses, start=1)},
        contacts={side: _intervals(times, modes[:, k] != 0, end) for k, side in ((3, "left"), (4, "right"))},
        seconds=seconds,
        status=status,
        engine=engine,
        bounded=bounded,
        outline=ARTICLE,
        t0=float(run_case.initial.t0),
        t_end=float(run_case.t_end),
        period=float(run_case.parameters.period),
    )


def chain_scene_of(
    chain: FrictionChain, periods: int = PERIODS, *, stop: Callable[[], bool] | None = None, **changes: float
) -> Scene:
    """The motion of a friction chain (with ``changes`` of its numbers by name:
    :meth:`~oscillator.model.chains.FrictionChain.with_values`) over ``periods`` forcing periods
    from its start: one run of :func:`~oscillator.hybrid.chain_run.simulate_chain` (CVODE, the
    trajectory at every step and at each ``t0 + kT``), at most :data:`MAX_EVENTS` events (the
    run stops there, and the scene says so); the trajectory thinned to :data:`MAX_POINTS` rows
    (the strobe points, rests and contacts from the whole run).  A run a guard or the solver stops
    is shown up to there, its ``status`` the reason.  ``stop()`` is asked before the run (a
    chain's run is not cut short: it is bounded instead).
    """
    from oscillator.hybrid.chain_run import simulate_chain, state_columns

    periods = check_periods(periods)
    chain = (chain.with_values(changes) if changes else chain).checked()
    if stop is not None and stop():
        raise Superseded
    marks = chain.t0 + chain.period * np.arange(periods + 1)
    options = SolverOptions(max_events=MAX_EVENTS, max_trajectory_rows=100 * MAX_POINTS)
    started = time.perf_counter()
    bounded = False
    try:
        result = simulate_chain(chain, float(marks[-1]), options=options, at=marks)
        status = result.status.value
    except SimulationFailed as failed:
        if failed.result is None:
            raise
        result = failed.result  # type: ignore[assignment]  # simulate_chain's run so far
        bounded = failed.reason == Reason.MAX_EVENTS
        status = str(failed)
        if bounded:
            status = (
                f"stopped after {MAX_EVENTS} events at t = {float(result.trajectory.t.iloc[-1]):.6g} s, the explorer's "
                "bound for one change: fewer periods, or `oscillator run` for the whole motion"
            )
    seconds = time.perf_counter() - started
    outline, full = outline_of(chain), result.trajectory
    times, end = full.t.to_numpy(float), float(marks[-1])
    stuck = {e.on: f"mode:{e.name}" for e in chain.elements if e.type == "friction"}
    trajectory = full[["t", *state_columns(chain)]]
    every = max(1, -(-len(trajectory) // MAX_POINTS))
    return Scene(
        case=chain,
        periods=periods,
        trajectory=trajectory.iloc[::every].reset_index(drop=True),
        events=result.events.reset_index(drop=True),
        strobe=_strobe(trajectory, marks[marks <= times[-1] + 1e-9]),
        rests={
            m.name: _intervals(times, full[stuck[m.name]].to_numpy() == 0, end) if m.name in stuck else []
            for m in chain.masses
        },
        contacts={name: _intervals(times, full[f"mode:{name}"].to_numpy() != 0, end) for name in outline.contacts},
        seconds=seconds,
        status=status,
        engine="cvode",
        bounded=bounded,
        outline=outline,
        t0=chain.t0,
        t_end=end,
        period=chain.period,
    )


#: A run as a scene needs it: the trajectory on the grid, the events, each mode from the time it
#: holds (rows ``t, s1, s2, left, right``), how the run ended, and whether the event bound did.
_Run = tuple[pd.DataFrame, pd.DataFrame, np.ndarray, str, bool]


def _simulated_run(case: Case, grid: np.ndarray, engine: str, stop: Callable[[], bool] | None = None) -> _Run:
    """The run through :func:`~oscillator.simulate` (its supervisor in Python, any engine); a run
    the solver or a guard stops, up to there (the bound of :data:`MAX_EVENTS` said as such)."""

    def asked(t: float) -> None:
        if stop is not None and stop():
            raise Superseded

    try:
        result = simulate(case, engine=engine, save=SaveAt(ts=grid, segments=True), progress=asked)
    except SimulationFailed as failed:
        if failed.result is None:
            raise
        result = failed.result
    modes = np.array(
        [(s.t0, s.mode.sign(1), s.mode.sign(2), s.mode.left, s.mode.right) for s in result.segments], dtype=float
    ).reshape(-1, 5)
    bounded = result.reason == Reason.MAX_EVENTS and case.options.max_events == MAX_EVENTS
    status = result.status.value if not result.message else result.message
    if bounded:
        status = (
            f"stopped after {MAX_EVENTS} events at t = {float(result.trajectory.t.iloc[-1]):.6g} s, the explorer's "
            "bound for one change: fewer periods, or `oscillator run` for the whole motion"
        )
    return result.trajectory[["t", *case.system.state]], result.events, modes, status, bounded


def _compiled_run(case: Case, grid: np.ndarray) -> _Run | None:
    """The same run with the supervisor compiled (:func:`~oscillator.hybrid.batch.run_compiled`,
    the DOP853 engine: nothing in Python per event), or None where it failed or outgrew its
    buffers (:func:`_simulated_run` then runs it, and says why)."""
    from oscillator.engines.dop853 import new_work
    from oscillator.hybrid.batch import OK, options_vector, run_compiled
    from oscillator.hybrid.guards import ARITHMETIC_ERRORS
    from oscillator.hybrid.result import Status
    from oscillator.io.tables import events_frame
    from oscillator.model.events import WIDTH
    from oscillator.model.fields import coefficients

    p, o = case.parameters, case.options
    periods = round((grid[-1] - grid[0]) / p.period)
    rows = min(EVENT_ROWS * periods, MAX_EVENTS) + 2 * EVENT_ROWS
    buffers = (np.empty((len(grid), 5)), np.empty((rows, WIDTH)), np.empty((rows + 1, 5)))
    start = np.array(case.initial.y, dtype=float)
    try:
        status, done, kept, changes = run_compiled(
            coefficients(p), case.initial.t0, p.period, start, new_work(p, o), options_vector(o), grid, buffers
        )
    except ARITHMETIC_ERRORS:
        return None
    if status != OK or done != len(grid):
        return None
    trajectory = pd.DataFrame(buffers[0], columns=["t", *case.system.state])
    return trajectory, events_frame(buffers[1][:kept]), buffers[2][:changes], Status.COMPLETE.value, False


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


def _with_switches(trajectory: pd.DataFrame, events: pd.DataFrame, state: list[str]) -> pd.DataFrame:
    """The grid's rows and each event's ``state``, in time order: the corners of a contact or a
    stop show where they are, not cut by the grid."""
    switches = events[["t", *state]]
    merged = pd.concat([trajectory, switches], ignore_index=True)
    return merged.sort_values("t", kind="stable").reset_index(drop=True)


def _strobe(trajectory: pd.DataFrame, marks: np.ndarray) -> pd.DataFrame:
    """The trajectory's rows at the section times (it holds them: the grid one every :data:`GRID`
    rows, a chain's run stopped there)."""
    t = trajectory.t.to_numpy(float)
    rows = trajectory.iloc[np.clip(np.searchsorted(t, marks - 1e-9 * (1.0 + np.abs(marks))), 0, len(t) - 1)]
    strobe = rows.reset_index(drop=True).assign(t=marks)
    strobe.insert(0, "k", np.arange(len(marks)))
    return strobe


def _intervals(times: np.ndarray, holds: np.ndarray, end: float) -> list[tuple[float, float]]:
    """The maximal intervals over which ``holds`` is true: ``holds[i]`` from ``times[i]`` on."""
    return [(a, b) for state, a, b in spans(times.tolist(), holds.tolist(), end) if state and b > a]


def with_changes(case: Case, values: dict[str, float]) -> Case:
    """``case`` with the changed ``values`` (parameters and start), checked."""
    changed = {name: value for name, value in values.items() if _current(case, name) != value}
    return resolve_case(case, **changed) if changed else case


def _current(case: Case, name: str) -> float:
    holder = case.parameters if name in Parameters.names() else case.initial
    return float(getattr(holder, name))
