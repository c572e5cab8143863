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
    t: list[float] = field(default_factory=list)
    y: list[np.ndarray] = field(default_factory=list)
    modes: list[Mode] = field(default_factory=list)
    t_final: float = float("nan")
    y_final: np.ndarray | None = None
    mode_final: Mode | None = None
    mode_initial: Mode | None = None
    returns: int = 0
    rhs_evaluations: int = 0
    restarts: int = 0
    root_returns: int = 0
    event_count: int = 0
    wall_time: float = 0.0

    @property
    def started(self) -> bool:
        """Whether the run got as far as its first mode (a partial result can be told)."""
        return self.mode_initial is not None and self.y_final is not None

    def reached(self, t: float, y: np.ndarray, mode: Mode) -> None:
        """The last point reached so far."""
        self.t_final, self.y_final, self.mode_final = t, y, mode
