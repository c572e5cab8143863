"""What a run keeps, said once (:class:`SaveAt`): the trajectory at the solver's steps, on a grid,
or not at all; the events from some time on; the smooth segments; the derivative of the flow.

A :class:`Recording` tells the supervisor where to ask the engine to go next and keeps the rows;
the supervisor itself knows nothing of the three ways.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from oscillator.engines import Step, StepKind
from oscillator.errors import Reason, SimulationFailed
from oscillator.hybrid.record import RunRecord
from oscillator.model.phase_space import Mode

__all__ = ["AtSteps", "NoTrajectory", "OnGrid", "Recording", "SaveAt", "recording"]

#: Without a trajectory to record, the engine runs this many forcing periods between returns.
CHUNK_PERIODS = 4


@dataclass(frozen=True, eq=False)
class SaveAt:
    """What a run keeps (diffrax's ``SaveAt`` is the model).

    Attributes
    ----------
    steps : bool
        The trajectory at every step of the solver (and on both sides of every switch).
    ts : ndarray or None
        The trajectory on this grid instead (times within the run); ``steps`` is then ignored.
        With neither, no trajectory.
    events_from : float
        Keep the events at or after this time (all are counted): memory stays flat in a long run.
    segments : bool
        Keep each smooth piece of the run: its mode, its start and end (time and state) and the
        event rows that ended it (``Result.segments``).
    derivative : bool
        Integrate the derivative of the flow with the state, through every switch (variational
        equations and saltation matrices): ``Result.derivative`` is ``d y(t_end) / d y(t0)``, the
        monodromy matrix of a stroboscopic map.  Needs the compiled CVODE engine.
    """

    steps: bool = True
    ts: np.ndarray | None = None
    events_from: float = -math.inf
    segments: bool = False
    derivative: bool = False


@dataclass
class Recording:
    """The base policy: no trajectory rows; the engine returns every ``chunk`` seconds.

    Attributes
    ----------
    max_rows : int
        The most trajectory rows kept (``SolverOptions.max_trajectory_rows``).
    chunk : float
        Longest stretch (s) between the engine's returns when there is nothing to record.
    keep_events_from : float
        Keep only the events at or after this time (all are counted).
    """

    max_rows: int
    chunk: float
    keep_events_from: float = -math.inf

    #: Whether the engine is asked for one internal step at a time.
    one_step = False

    def start(self, record: RunRecord, t0: float, y: np.ndarray, mode: Mode, t_end: float) -> None:
        """The run starts at ``(t0, y)`` in ``mode``."""

    def target(self, t: float, t_end: float) -> float:
        """Where the engine goes next from ``t``."""
        return min(t_end, t + self.chunk)

    def returned(self, record: RunRecord, step: Step, mode: Mode, target: float) -> None:
        """The engine returned ``step`` (``target`` was asked for)."""

    def switched(self, record: RunRecord, t: float, y: np.ndarray, mode: Mode) -> None:
        """The mode switched at ``t`` to ``mode``, with the state ``y`` after the switch."""

    def stopped(self, record: RunRecord) -> None:
        """The run stopped early (a failure or Ctrl-C) at ``record``'s last point."""

    def events(self, record: RunRecord, t: float, count: int) -> None:
        """Count the ``count`` events at ``t`` written past the end of the log, and keep them if
        they are late enough."""
        record.event_count += count
        if t >= self.keep_events_from:
            record.events.keep(count)

    def row(self, record: RunRecord, t: float, y: np.ndarray, mode: Mode) -> None:
        """Keep one trajectory row; refuse past ``max_rows``."""
        if len(record.rows) >= self.max_rows:
            raise SimulationFailed(
                f"the trajectory passed max_trajectory_rows = {self.max_rows} rows at t = {t:.10g} s; record it on "
                f"a grid (t_eval; --sample DT on the command line) or not at all, shorten t_end, or raise "
                f"max_trajectory_rows",
                reason=Reason.MAX_ROWS,
                field="max_trajectory_rows",
            )
        record.rows.append(t, y, mode)

    def ahead(self) -> np.ndarray | None:
        """The grid times still to be reached, for an engine that goes to them in compiled code
        (:class:`OnGrid`); None for the other policies."""
        return None

    def batch(self, record: RunRecord, rows: np.ndarray, mode: Mode) -> None:
        """Returns taken together in ``mode`` (rows ``t, x1, v1, x2, v2``): each step's
        (:class:`AtSteps`) or each grid time's (:class:`OnGrid`)."""

    def keep(self, record: RunRecord, rows: np.ndarray, mode: Mode) -> None:
        """Keep a batch of rows (``n x 5``: time and state, all in ``mode``); refuse past ``max_rows``."""
        room = self.max_rows - len(record.rows)
        if len(rows) > room:
            record.rows.extend(rows[:room], mode)
            self.row(record, float(rows[room, 0]), rows[room, 1:], mode)  # refused, naming the time
        record.rows.extend(rows, mode)


class NoTrajectory(Recording):
    """Events and the energy audit only."""


class AtSteps(Recording):
    """A row at every step of the engine, and one on each side of every switch."""

    one_step = True

    def start(self, record: RunRecord, t0: float, y: np.ndarray, mode: Mode, t_end: float) -> None:
        self.row(record, t0, y, mode)

    def target(self, t: float, t_end: float) -> float:
        return t_end

    def returned(self, record: RunRecord, step: Step, mode: Mode, target: float) -> None:
        self.row(record, step.t, step.y, mode)

    def batch(self, record: RunRecord, rows: np.ndarray, mode: Mode) -> None:
        self.keep(record, rows, mode)

    def switched(self, record: RunRecord, t: float, y: np.ndarray, mode: Mode) -> None:
        self.row(record, t, y, mode)

    def stopped(self, record: RunRecord) -> None:
        """End the rows at the last point reached: a Ctrl-C can land between the supervisor's
        note of a point and its row (in the progress callback, say).  Not past ``max_rows``
        (a run stopped for that keeps its rows as they are)."""
        t, y, mode = record.last
        if y is not None and mode is not None and record.rows.last_t < t and len(record.rows) < self.max_rows:
            record.rows.append(t, y, mode)


@dataclass
class OnGrid(Recording):
    """A row at each time of a grid (which the engine reaches exactly)."""

    grid: np.ndarray = field(default_factory=lambda: np.empty(0))
    _next: int = 0

    def start(self, record: RunRecord, t0: float, y: np.ndarray, mode: Mode, t_end: float) -> None:
        self.grid = self.grid[(self.grid >= t0) & (self.grid <= t_end)]
        self._next = 0
        if self.grid.size and self.grid[0] == t0:
            self.row(record, t0, y, mode)
            self._next = 1

    def target(self, t: float, t_end: float) -> float:
        if self._next < self.grid.size:
            return float(self.grid[self._next])
        return super().target(t, t_end)

    def ahead(self) -> np.ndarray | None:
        return self.grid[self._next :] if self._next < self.grid.size else None

    def batch(self, record: RunRecord, rows: np.ndarray, mode: Mode) -> None:
        self.keep(record, rows, mode)
        self._next += len(rows)

    def returned(self, record: RunRecord, step: Step, mode: Mode, target: float) -> None:
        on_grid = self._next < self.grid.size
        if on_grid and step.kind is not StepKind.ROOT and step.t == target:
            self.row(record, step.t, step.y, mode)
            self._next += 1


def recording(save: SaveAt, *, max_rows: int, period: float) -> Recording:
    """The trajectory's policy for a run: on ``save.ts`` if given, else at the steps if
    ``save.steps``, else none."""
    chunk = CHUNK_PERIODS * period
    if save.ts is not None:
        return OnGrid(max_rows, chunk, save.events_from, grid=np.asarray(save.ts, dtype=float))
    if save.steps:
        return AtSteps(max_rows, chunk, save.events_from)
    return NoTrajectory(max_rows, chunk, save.events_from)
