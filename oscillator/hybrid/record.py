"""What a run produced, as plain records; the tables are built at the user-facing edge."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from oscillator.model.events import Event
from oscillator.model.phase_space import Mode

__all__ = ["RunRecord"]


@dataclass
class RunRecord:
    """The supervisor's record of a run: events, trajectory rows, the last point and the counts."""

    events: list[Event] = field(default_factory=list)
    #: Trajectory rows ``(t, (x1, v1, x2, v2), mode)``, each appended whole (a Ctrl-C between two
    #: appends of separate columns would leave them of different lengths).
    rows: list[tuple[float, np.ndarray, Mode]] = field(default_factory=list)
    #: ``(t, y, mode)`` of the last point reached, replaced whole (so a Ctrl-C cannot split it).
    last: tuple[float, np.ndarray | None, Mode | None] = (float("nan"), None, None)
    mode_initial: Mode | None = None
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
