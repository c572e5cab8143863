"""What a run produced, as plain records; the tables are built at the user-facing edge."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from oscillator.model.events import WIDTH
from oscillator.model.phase_space import Mode

__all__ = ["EventLog", "RunRecord", "Segment", "TrajectoryRows"]


class EventLog:
    """A run's events as rows of numbers (:data:`oscillator.model.events.COLUMN`) in one array
    that grows by doubling: the switching rules write new events straight into its free rows,
    and :meth:`keep` makes them part of the log (a Ctrl-C before that leaves the log as it was).
    """

    def __init__(self, capacity: int = 256) -> None:
        self._rows = np.empty((capacity, WIDTH))
        self._size = 0

    def __len__(self) -> int:
        return self._size

    @property
    def rows(self) -> np.ndarray:
        """The events so far, one row each (a view)."""
        return self._rows[: self._size]

    def free(self, count: int) -> np.ndarray:
        """The array to write up to ``count`` new rows into, from row ``len(self)`` on."""
        needed = self._size + count
        if needed > len(self._rows):
            grown = np.empty((max(needed, 2 * len(self._rows)), WIDTH))
            grown[: self._size] = self._rows[: self._size]
            self._rows = grown
        return self._rows

    def stage(self, rows: np.ndarray) -> int:
        """Write ``rows`` into the free rows (not yet kept); how many."""
        self.free(len(rows))[self._size : self._size + len(rows)] = rows
        return len(rows)

    def staged(self, count: int) -> np.ndarray:
        """The ``count`` rows written past the log's end."""
        return self._rows[self._size : self._size + count]

    def keep(self, count: int) -> None:
        """Make the ``count`` rows written past the end part of the log."""
        self._size += count


class TrajectoryRows:
    """A run's trajectory rows ``(t, x1, v1, x2, v2)`` in arrays, each array's rows in one mode:
    no Python object per row (memory stays flat in the length of the run).

    Rows are appended one at a time (:meth:`append`) or a batch at a time (:meth:`extend`,
    what the compiled stepping loop writes); the open chunk grows by doubling and is sealed
    when the mode changes.
    """

    def __init__(self) -> None:
        self._chunks: list[tuple[np.ndarray, Mode]] = []
        self._open = np.empty((0, 5))
        self._size = 0
        self._mode: Mode | None = None
        self._count = 0
        #: The time of the last row (``-inf`` before the first).
        self.last_t = -math.inf

    def __len__(self) -> int:
        return self._count

    def append(self, t: float, y: np.ndarray, mode: Mode) -> None:
        """One row: the time, the state (its first four entries) and its mode."""
        free = self._free(mode, 1)
        free[0, 0] = t
        free[0, 1:] = y[:4]
        self._kept(1, t)

    def extend(self, rows: np.ndarray, mode: Mode) -> None:
        """``rows`` (``n x 5``: time and state), all in ``mode``."""
        n = len(rows)
        if n:
            self._free(mode, n)[:] = rows
            self._kept(n, float(rows[-1, 0]))

    def chunks(self) -> list[tuple[np.ndarray, Mode]]:
        """The rows as ``(array, mode)`` pieces, in order."""
        self._seal()
        return list(self._chunks)

    def _free(self, mode: Mode, n: int) -> np.ndarray:
        if mode != self._mode:
            self._seal()
            self._mode = mode
        if self._size + n > len(self._open):
            grown = np.empty((max(self._size + n, 2 * len(self._open), 64), 5))
            grown[: self._size] = self._open[: self._size]
            self._open = grown
        return self._open[self._size : self._size + n]

    def _kept(self, n: int, t: float) -> None:
        self._size += n
        self._count += n
        self.last_t = t

    def _seal(self) -> None:
        if self._size and self._mode is not None:
            self._chunks.append((self._open[: self._size].copy(), self._mode))
        self._open, self._size = np.empty((0, 5)), 0


@dataclass(frozen=True)
class Segment:
    """One smooth piece of a run: ``mode``'s flow from ``(t0, y0)`` to ``(t1, y1)``.

    ``y1`` is the state the flow reached, before the switch that ended the piece projected it
    (the next segment's ``y0``); ``rows`` are the event rows written in ``(t0, t1]``, the
    switch's last (the first segment's also those written at the start; the last segment's
    ``t1`` is the run's end, with no switch).  States are ``(x1, v1, x2, v2)``.
    """

    mode: Mode
    t0: float
    y0: np.ndarray
    t1: float
    y1: np.ndarray
    rows: np.ndarray


@dataclass
class RunRecord:
    """The supervisor's record of a run: events, trajectory rows, the last point and the counts."""

    events: EventLog = field(default_factory=EventLog)
    #: Trajectory rows (a row is written whole before it counts: a Ctrl-C leaves none half written).
    rows: TrajectoryRows = field(default_factory=TrajectoryRows)
    #: ``(t, y, mode)`` of the last point reached, replaced whole (so a Ctrl-C cannot split it).
    last: tuple[float, np.ndarray | None, Mode | None] = (float("nan"), None, None)
    mode_initial: Mode | None = None
    #: The run's smooth pieces, when they are kept (``SaveAt(segments=True)``).
    segments: list[Segment] = field(default_factory=list)
    returns: int = 0
    rhs_evaluations: int = 0
    restarts: int = 0
    root_returns: int = 0
    event_count: int = 0
    wall_time: float = 0.0

    @property
    def t_final(self) -> float:
        return self.last[0]

    @property
    def y_final(self) -> np.ndarray | None:
        return self.last[1]

    @property
    def mode_final(self) -> Mode | None:
        return self.last[2]

    @property
    def started(self) -> bool:
        """Whether the run got as far as its first mode (a partial result can be told)."""
        return self.mode_initial is not None and self.y_final is not None

    def reached(self, t: float, y: np.ndarray, mode: Mode) -> None:
        """The last point reached so far."""
        self.last = (t, y, mode)
