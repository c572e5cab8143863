"""Results as pandas tables: switching events, trajectory and the energy audit."""

from __future__ import annotations

from dataclasses import dataclass

import pandas as pd

from oscillator.cases import Case
from oscillator.energy import POWER_NAMES, mechanical_energy
from oscillator.supervisor import RunRecord
from oscillator.tables import events_frame, trajectory_frame

__all__ = ["Result"]


@dataclass(frozen=True)
class Result:
    """The outcome of :func:`oscillator.simulate`.

    Attributes
    ----------
    case : Case
        The fully resolved case that was run (overrides applied).
    events : pandas.DataFrame
        Switching events, columns ``t, mass, kind, boundary, from_domain, to_domain, theorem,
        equation, x1, v1, x2, v2, G0_alpha, G1_alpha, G0_beta, G1_beta, G_alpha, G_beta,
        distance, state_from, state_to`` (see :class:`oscillator.events.Event`).
    trajectory : pandas.DataFrame
        ``t, x1, v1, x2, v2, domain1, domain2, system_state`` at CVODE's steps (an event time
        appears twice, before and after the switch) or on the requested grid.
    energy : dict
        The work-energy audit: ``E0, E1``, the works ``forcing, feedback, damping, friction``
        and ``residual = E1 - E0 - (forcing + feedback - damping - friction)``.
    stats : dict
        ``returns`` (times CVODE handed back: every internal step when the trajectory is recorded
        at its steps, else roots, grid times and chunk ends), ``rhs_evaluations, restarts,
        root_returns, events, wall_time``.
    final_state : tuple
        ``(t, x1, v1, x2, v2)`` at the end (for a partial result, the last point reached).
    status : str
        ``"complete"``; or, for the partial result attached to an error as ``error.result``,
        ``"failed"`` (the solver or a guard stopped the run) or ``"interrupted"`` (Ctrl-C).
    failure : str or None
        Why a partial result stopped: the error's message.
    """

    case: Case
    events: pd.DataFrame
    trajectory: pd.DataFrame
    energy: dict
    stats: dict
    final_state: tuple
    status: str = "complete"
    failure: str | None = None

    @property
    def complete(self) -> bool:
        """Whether the run reached ``t_end``."""
        return self.status == "complete"

    @classmethod
    def from_record(
        cls, case: Case, record: RunRecord, *, status: str = "complete", failure: str | None = None
    ) -> Result:
        p = case.parameters
        y0 = case.initial.y
        start, end = record.mode_initial, record.mode_final
        work = dict(zip(POWER_NAMES, (float(w) for w in record.y_final[4:8]), strict=True))
        e0 = mechanical_energy(y0, p, start.left, start.right)
        e1 = mechanical_energy(record.y_final[:4], p, end.left, end.right)
        supplied = work["forcing"] + work["feedback"] - work["damping"] - work["friction"]
        energy = {"E0": e0, "E1": e1, **work, "residual": e1 - e0 - supplied}  # inf or nan past floating point
        stats = {
            "returns": record.returns,
            "rhs_evaluations": record.rhs_evaluations,
            "restarts": record.restarts,
            "root_returns": record.root_returns,
            "events": record.event_count,
            "wall_time": record.wall_time,
        }
        final = (record.t_final, *(float(v) for v in record.y_final[:4]))
        trajectory = trajectory_frame(record.t, record.y, record.modes)
        return cls(case, events_frame(record.events), trajectory, energy, stats, final, status, failure)
