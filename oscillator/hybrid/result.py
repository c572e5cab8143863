"""What a run returns: the event and trajectory tables, the energy audit and the solver's counts."""

from __future__ import annotations

import dataclasses
import enum
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from oscillator.errors import Reason
from oscillator.hybrid.record import RunRecord, Segment, TrajectoryRows
from oscillator.io.cases import Case
from oscillator.io.files import as_folder
from oscillator.model.energy import POWER_NAMES, mechanical_energy
from oscillator.model.types import VARIATIONAL
from oscillator.presenting import presenter

if TYPE_CHECKING:
    from pathlib import Path

    import pandas as pd
    from matplotlib.figure import Figure

__all__ = ["EnergyAudit", "Result", "SolverStats", "Status", "records_of"]


class Status(enum.StrEnum):
    """How a run ended."""

    COMPLETE = "complete"  #: it reached ``t_end``
    FAILED = "failed"  #: the solver or a guard stopped it
    INTERRUPTED = "interrupted"  #: Ctrl-C stopped it


@dataclass(frozen=True, slots=True)
class EnergyAudit:
    """The work-energy balance over the run (J).

    ``residual = E1 - E0 - (forcing + feedback - damping - friction)``: zero up to the solver's
    tolerance for a correct run (``inf`` or ``nan`` when a failed run left floating point).
    """

    E0: float  #: mechanical energy at the start
    E1: float  #: mechanical energy at the end
    forcing: float  #: work of the harmonic forces Q1, Q2
    feedback: float  #: work of the constant forces P1, P2
    damping: float  #: energy lost in the dampers C1, C2, C4, C5 and C3 in contact
    friction: float  #: energy lost to friction
    residual: float

    @classmethod
    def of(cls, record: RunRecord, case: Case) -> EnergyAudit:
        """The audit of a run: the works are the four quadratures the supervisor integrates."""
        p = case.parameters
        assert record.mode_initial is not None and record.mode_final is not None and record.y_final is not None
        start, end = record.mode_initial, record.mode_final
        work = dict(zip(POWER_NAMES, (float(w) for w in record.y_final[4:8]), strict=True))
        e0 = mechanical_energy(case.initial.y, p, start.left, start.right)
        e1 = mechanical_energy(record.y_final[:4], p, end.left, end.right)
        supplied = work["forcing"] + work["feedback"] - work["damping"] - work["friction"]
        return cls(E0=e0, E1=e1, **work, residual=e1 - e0 - supplied)

    def as_dict(self) -> dict[str, float]:
        return dataclasses.asdict(self)


@dataclass(frozen=True, slots=True)
class SolverStats:
    """What the run cost."""

    engine: str  #: the integrator that ran (:mod:`oscillator.engines`)
    returns: int  #: times the integrator handed back (every step when the trajectory is kept at its steps)
    rhs_evaluations: int  #: evaluations of the vector field
    restarts: int  #: (re-)initialisations of the integrator
    root_returns: int  #: returns at a root of the switching functions
    events: int  #: switching events, all of them (``Result.events`` may keep only the late ones)
    wall_time: float  #: seconds

    def as_dict(self) -> dict[str, float | int | str]:
        return dataclasses.asdict(self)


class _Records:
    """A run's records until its tables are asked for: each table is built then, once, and its
    records let go (a run that nobody reads a table of never imports pandas); until then the event
    rows can be read as numbers.  The tables are kept here, so every copy of the result
    (``dataclasses.replace``) reads the same tables."""

    def __init__(self, events: np.ndarray, rows: TrajectoryRows) -> None:
        self._events: np.ndarray | None = events
        self._rows: TrajectoryRows | None = rows
        self._events_frame: pd.DataFrame | None = None
        self._trajectory_frame: pd.DataFrame | None = None

    def event_rows(self) -> np.ndarray | None:
        return self._events

    def events_frame(self) -> pd.DataFrame:
        if self._events_frame is None:
            from oscillator.io.tables import events_frame

            assert self._events is not None
            self._events_frame, self._events = events_frame(self._events), None
        return self._events_frame

    def trajectory_frame(self) -> pd.DataFrame:
        if self._trajectory_frame is None:
            from oscillator.io.tables import trajectory_frame

            rows = self._rows
            assert rows is not None
            self._trajectory_frame = trajectory_frame(rows.chunks())
            self._rows = None
        return self._trajectory_frame


def _derivative(y: np.ndarray) -> np.ndarray | None:
    """The derivative of the flow a run carried in its state (entries 8 to 24), or None."""
    return y[VARIATIONAL : VARIATIONAL + 16].reshape(4, 4).copy() if len(y) > VARIATIONAL else None


def records_of(events: pd.DataFrame, trajectory: pd.DataFrame) -> _Records:
    """Records holding tables already built (a run folder read back)."""
    records = _Records(np.empty((0, 0)), TrajectoryRows())
    records._events_frame, records._trajectory_frame = events, trajectory
    records._events = records._rows = None
    return records


@dataclass(frozen=True)
class Result:
    """The outcome of :func:`oscillator.simulate`.

    Attributes
    ----------
    case : Case
        The fully resolved case that was run (overrides applied).
    events : pandas.DataFrame
        Switching events, columns ``t, mass, kind, boundary, from_domain, to_domain, theorem,
        equation, branch, x1, v1, x2, v2, G0_alpha, G1_alpha, G0_beta, G1_beta, G_alpha, G_beta,
        distance, state_from, state_to`` (see :class:`oscillator.model.events.Event`).  Built
        when first asked for.
    trajectory : pandas.DataFrame
        ``t, x1, v1, x2, v2, domain1, domain2, system_state`` at the solver's steps (an event
        time appears twice, before and after the switch) or on the requested grid.  Built when
        first asked for.
    energy : EnergyAudit
        The work-energy audit.
    stats : SolverStats
        The solver's counts and the wall time.
    final_state : tuple
        ``(t, x1, v1, x2, v2)`` at the end (for a partial result, the last point reached).
    status : Status
        ``COMPLETE``; or, for the partial result an error carries, ``FAILED`` or ``INTERRUPTED``.
    message : str
        Why a partial result stopped (the error's message); empty when complete.
    reason : Reason or None
        Why, for a program to read (:class:`~oscillator.errors.Reason`); None when complete.
    segments : tuple of Segment
        The run's smooth pieces, when asked for (``SaveAt(segments=True)``), else empty.
    derivative : ndarray or None
        ``d y(t_final) / d y(t0)`` (4 x 4) through every switch, when asked for
        (``SaveAt(derivative=True)``): over one forcing period from a point of a periodic
        orbit, its monodromy matrix.
    """

    case: Case
    energy: EnergyAudit
    stats: SolverStats
    final_state: tuple[float, ...]
    status: Status = Status.COMPLETE
    message: str = ""
    reason: Reason | None = None
    segments: tuple[Segment, ...] = field(default=(), repr=False, compare=False)
    derivative: np.ndarray | None = field(default=None, repr=False, compare=False)
    _records: _Records = field(
        default_factory=lambda: _Records(np.empty((0, 0)), TrajectoryRows()), repr=False, compare=False
    )

    @property
    def events(self) -> pd.DataFrame:
        return self._records.events_frame()

    @property
    def event_rows(self) -> np.ndarray | None:
        """The events as rows of numbers (columns :data:`~oscillator.model.events.COLUMN`, the
        kinds, boundaries and theorems as codes): ``events`` without building its table; None once
        the table is built (its rows are let go then) or for a result read back from a folder."""
        return self._records.event_rows()

    @property
    def trajectory(self) -> pd.DataFrame:
        return self._records.trajectory_frame()

    @property
    def success(self) -> bool:
        """Whether the run reached ``t_end``."""
        return self.status is Status.COMPLETE

    def plot(self, panel: str = "a", *, window: tuple[float, float] | None = None) -> Figure:
        """One of the article's panels (Figs. 9-13) of this run, as a matplotlib figure.

        Parameters
        ----------
        panel : str
            ``"a"`` or ``"displacement"``, ``"b"`` or ``"velocity"``, ``"c"`` or ``"phase"``,
            ``"d"`` or ``"forces"``.
        window : (float, float), optional
            The time window drawn; by default the whole run, or its last 10 forcing periods
            when it is longer than 20 (as ``oscillator run`` draws it).
        """
        return presenter().plot_result(self, panel, window)

    def save(self, folder: str | Path, *, formats: str = "both", figures: bool = True, report: bool = True) -> Path:
        """Write this run as a run folder, as ``oscillator run`` does: the event tables
        (``formats``: ``"csv"``, ``"parquet"`` or ``"both"``), ``trajectory.parquet``,
        ``case.toml``, ``run.json``, then the figures and the report.  ``folder`` must be new.
        :func:`oscillator.read_run` reads it back.  Returns the folder's path."""
        return presenter().save_result(self, as_folder(folder), formats=formats, figures=figures, report=report)

    def _repr_html_(self) -> str:
        """The status, the counts, the energy residual and the first events (Jupyter)."""
        return presenter().result_html(self)

    @classmethod
    def from_record(
        cls,
        case: Case,
        record: RunRecord,
        *,
        engine: str,
        status: Status = Status.COMPLETE,
        message: str = "",
        reason: Reason | None = None,
    ) -> Result:
        assert record.y_final is not None
        stats = SolverStats(
            engine=engine,
            returns=record.returns,
            rhs_evaluations=record.rhs_evaluations,
            restarts=record.restarts,
            root_returns=record.root_returns,
            events=record.event_count,
            wall_time=record.wall_time,
        )
        x1, v1, x2, v2 = (float(v) for v in np.asarray(record.y_final[:4]))
        return cls(
            case,
            EnergyAudit.of(record, case),
            stats,
            (record.t_final, x1, v1, x2, v2),
            status,
            message,
            reason,
            tuple(record.segments),
            _derivative(record.y_final),
            _Records(record.events.rows.copy(), record.rows),
        )
