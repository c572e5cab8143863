"""The stroboscopic map ``P: y(t0) -> y(t0 + N T)`` and its derivative, one run each
(:func:`period_map`), and the Newton system of a fixed point (:func:`fixed_point_system`):
what :mod:`oscillator.orbits.shooting` and the continuation's corrector iterate on.

The map is one run that keeps its segments (``SaveAt(segments=True)``); its derivative, the
monodromy matrix, is carried by the same run (``SaveAt(derivative=True)``): the engine integrates
each mode's variational equations with the state, and the supervisor applies the saltation matrix
of each switch it resolves (:func:`oscillator.model.saltation.carried_through`).  On the
``"dop853"`` engine (:data:`ORBIT_ENGINE`) the run is one compiled call (:func:`compiled_run`,
recorded as the supervisor records it); on ``"cvode"``, the reference, it is
:func:`oscillator.simulate`'s.
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from oscillator.compiled import CACHE, holds
from oscillator.engines.dop853 import EVALS, new_work
from oscillator.errors import Reason, SimulationFailed
from oscillator.hybrid.batch import OK, SWITCH_COLUMNS, WINDOW_FULL, map_compiled, options_vector
from oscillator.hybrid.counting import counted
from oscillator.hybrid.record import RunRecord, Segment
from oscillator.hybrid.recording import SaveAt
from oscillator.hybrid.result import Result
from oscillator.hybrid.simulate import simulate
from oscillator.io.cases import Case, resolve_case
from oscillator.model.events import COLUMN, KINDS, WIDTH, EventKind
from oscillator.model.fields import coefficients
from oscillator.model.phase_space import Mode
from oscillator.model.system import ARTICLE
from oscillator.model.types import VARIATIONAL

__all__ = [
    "ORBIT_ENGINE",
    "ORBIT_ENGINES",
    "PeriodMap",
    "compile_period_map",
    "compiled_run",
    "fixed_point_system",
    "period_map",
    "pinned_rows",
    "solve_step",
]

#: The period maps' engine: the compiled DOP853 (:mod:`oscillator.engines.dop853`), whose
#: derivative of the flow is that of its own steps; ``"cvode"`` is the reference it is held to
#: (the same orbits to 1e-9, their monodromy matrices to 1e-9: tests/test_orbit_engines.py).
ORBIT_ENGINE = "dop853"
#: The engines a period map can run on (those that carry the derivative of the flow).
ORBIT_ENGINES = ("dop853", "cvode")


@dataclass(frozen=True)
class PeriodMap:
    """``P(y)`` and what it passed: one evaluation of the stroboscopic map.

    Attributes
    ----------
    t0, t1 : float
        Start and end of the map (``t1 = t0 + N T``).
    start, end : ndarray
        ``y(t0)`` and ``y(t1)`` = ``P(y(t0))``.
    segments : tuple of Segment
        The run's smooth pieces, in order (:class:`oscillator.hybrid.record.Segment`).
    result : Result
        The run itself (its event table is built when :attr:`events` is first read).
    monodromy : ndarray or None
        ``dP/dy`` (4 x 4), when asked for: the derivative of the flow the run carried through
        every switch (``SaveAt(derivative=True)``).
    """

    t0: float
    t1: float
    start: np.ndarray
    end: np.ndarray
    segments: tuple[Segment, ...]
    result: Result = field(repr=False)
    monodromy: np.ndarray | None = None

    @property
    def switches(self) -> list[tuple[float, np.ndarray, Mode]]:
        """The start and every switch: the time, the state after it, the mode after it."""
        return [(segment.t0, segment.y0, segment.mode) for segment in self.segments]

    @property
    def events(self) -> pd.DataFrame:
        """The event table over ``[t0, t1]`` (as ``Result.events``)."""
        return self.result.events

    @property
    def kinds(self) -> list[tuple[float, int, EventKind]]:
        """``(t, mass, kind)`` of every event, in order, read from the segments' event rows
        (no table is built)."""
        rows = [segment.rows for segment in self.segments if len(segment.rows)]
        if not rows:
            return []
        table = np.concatenate(rows)
        columns = table[:, [COLUMN["t"], COLUMN["mass"], COLUMN["kind"]]]
        return [(float(t), int(mass), KINDS[int(kind)]) for t, mass, kind in columns]

    @property
    def resting(self) -> tuple[int, ...]:
        """The masses at rest over the whole map (in every mode it passed)."""
        return tuple(mass for mass in (1, 2) if all(segment.mode.sign(mass) == 0 for segment in self.segments))

    @property
    def settled(self) -> tuple[int, ...]:
        """The masses at rest at the end of the map that never left rest during it: at rest all
        along, or moving at first and then stuck for good."""
        modes = [segment.mode for segment in self.segments]
        return tuple(
            mass
            for mass in (1, 2)
            if modes[-1].sign(mass) == 0
            and not any(a.sign(mass) == 0 and b.sign(mass) != 0 for a, b in itertools.pairwise(modes))
        )


def pinned_rows(masses: tuple[int, ...]) -> list[int]:
    """The state rows of these masses' displacements (:func:`fixed_point_system`)."""
    return [2 * mass - 2 for mass in masses]


def fixed_point_system(image: PeriodMap) -> tuple[np.ndarray, np.ndarray]:
    """``(J, F)`` for a Newton step ``J dy = -F`` towards a fixed point from ``y = image.start``:
    ``J = M - I`` and ``F = P(y) - y``, but for the masses that settle (:attr:`PeriodMap.settled`).

    A mass at rest over the whole period stays where it is put: ``P`` leaves its ``x_i``
    unchanged (row ``x_i`` of ``M`` is ``e_(x_i)``), so ``M - I`` has a zero row and every nearby
    ``x_i`` is an orbit too, a continuum; a mass that moves at first and then sticks for good
    makes that row nearly zero.  Its row becomes ``(e_(x_i), y_i - P_i(y))``: the step puts
    the mass where it stuck (nowhere else for one at rest all period) and the system is regular.
    """
    assert image.monodromy is not None
    matrix, residual = image.monodromy - np.eye(4), image.end - image.start
    for row in pinned_rows(image.settled):
        matrix[row] = 0.0
        matrix[row, row] = 1.0
        residual[row] = -residual[row]
    return matrix, residual


def solve_step(matrix: np.ndarray, rhs: np.ndarray, what: str) -> np.ndarray:
    """``matrix^-1 rhs``; a singular system is the library's error, with the reason."""
    try:
        step = np.linalg.solve(matrix, rhs)
    except np.linalg.LinAlgError:
        step = np.full(len(rhs), np.nan)
    if not np.isfinite(step).all():
        raise SimulationFailed(
            f"{what}: the Newton system is singular (a Floquet multiplier of the map at this guess is 1: "
            "an orbit at a fold, or a family of orbits); give another guess or a longer transient",
            reason=Reason.SINGULAR,
            field="guess",
        )
    return step


def period_map(
    case: Case, t0: float, y: np.ndarray, periods: int = 1, *, derivative: bool = True, engine: str = ORBIT_ENGINE
) -> PeriodMap:
    """``P(y)`` over ``periods`` forcing periods from ``t0``, and its derivative if asked.

    One :func:`~oscillator.simulate` run on ``engine`` (:data:`ORBIT_ENGINES`) that keeps no
    trajectory, only its segments, and with ``derivative`` carries the derivative of the flow
    through every switch (the monodromy).

    Raises
    ------
    SimulationFailed
        The simulation failed, or the orbit grazes a boundary (the map has no derivative there).
    """
    t1 = t0 + periods * case.parameters.period
    start = np.array(y[:4], dtype=float)
    initial = dataclasses.replace(case.initial, t0=t0, **dict(zip(ARTICLE.state, start, strict=True)))
    run_case = dataclasses.replace(case, initial=initial, t_end=t1, expected=(), keep_events_from=None)
    result = compiled_run(run_case, start, derivative, periods) if engine == "dop853" else None
    if result is None:  # another engine, or the compiled run failed: the supervisor's, with its words
        result = simulate(run_case, save=SaveAt(steps=False, segments=True, derivative=derivative), engine=engine)
    end = np.asarray(result.final_state[1:], dtype=float)
    return PeriodMap(t0, t1, start, end, result.segments, result, result.derivative)


#: Rows of the compiled run's buffers per forcing period (grown where a map needs more).
_ROWS_PER_PERIOD = 64


def compiled_run(case: Case, start: np.ndarray, derivative: bool, periods: int) -> Result | None:
    """The run of ``case`` (a period map: segments, events, the derivative of the flow if asked)
    in one compiled call (:func:`~oscillator.hybrid.batch.map_compiled`), recorded as the
    supervisor records it with the ``"dop853"`` engine; None where it failed (an engine's failure,
    a guard, a grazing), for the supervisor to run it again and say why."""
    p, options = case.parameters, case.options
    c, vector = coefficients(p), options_vector(options)
    rows = _ROWS_PER_PERIOD * periods
    while True:
        w = new_work(p, options, tangent=derivative)
        events, switches = np.empty((rows, WIDTH)), np.empty((rows, SWITCH_COLUMNS))
        end = np.empty(VARIATIONAL + 16 if derivative else VARIATIONAL)
        status, kept, count, returns = map_compiled(
            c, case.initial.t0, case.t_end, p.period, start, w, vector, (events, switches, end)
        )
        if status != WINDOW_FULL or rows >= options.max_events:
            break
        rows *= 8
    if status != OK:
        return None
    counted()
    record = RunRecord()
    record.events.stage(events[:kept])
    record.events.keep(kept)
    modes = [_mode(row) for row in switches[:count]]
    opens = [*(int(k) for k in switches[1:count, 13]), kept]
    ends = [*((switches[k + 1, 0], switches[k + 1, 5:9]) for k in range(count - 1)), (case.t_end, end[:4])]
    for k in range(count):
        row, (t_end, y_end) = switches[k], ends[k]
        pieces = events[int(row[13]) : opens[k]]
        record.segments.append(Segment(modes[k], float(row[0]), row[9:13].copy(), float(t_end), y_end.copy(), pieces))
    record.mode_initial = modes[0]
    record.reached(case.t_end, end, modes[-1])
    record.returns, record.root_returns, record.restarts = returns, returns - 1, count
    record.event_count, record.rhs_evaluations = kept, int(w[EVALS])
    return Result.from_record(case, record, engine="dop853")


def compile_period_map() -> None:
    """The compiled period map's kernels (:func:`~oscillator.hybrid.batch.map_compiled` carrying
    the derivative of the flow, the saltation) compiled into numba's cache in this process, where
    the cache does not hold them yet (one period map of Instance 2): run before local workers
    start (:func:`oscillator.analysis.execution.before_workers`, registered by the attractors'
    mapper), since the workers of a fresh install would each compile them at once."""
    if not CACHE or holds(map_compiled):
        return
    case = resolve_case("instance-2")
    compiled_run(case, np.array(case.initial.y[:4]), True, 1)


@functools.cache
def _mode_of(s1: int, s2: int, left: bool, right: bool) -> Mode:
    return Mode.from_signs(s1, s2, left=left, right=right)


def _mode(row: np.ndarray) -> Mode:
    """The mode in a row of :func:`~oscillator.hybrid.batch.map_compiled`'s switches."""
    return _mode_of(int(row[1]), int(row[2]), bool(row[3]), bool(row[4]))
