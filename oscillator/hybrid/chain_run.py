"""The supervisor of a friction chain: CVODE on the chain's mode until a root, the element's rule
(:mod:`oscillator.model.chain_rules`), a restart; the events, the trajectory and the energy audit
gathered in a :class:`ChainResult`.  The supervisor is the only stateful part; the rules and the
fields are pure.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from oscillator.engines import EngineFailure, StepKind
from oscillator.engines.chain_cvode import ChainEngine
from oscillator.errors import InputError, Reason, SimulationFailed
from oscillator.hybrid.counting import counted
from oscillator.hybrid.result import Status
from oscillator.model.chain_energy import ChainEnergy, audit
from oscillator.model.chain_fields import ChainArrays, arrays_of, state_of
from oscillator.model.chain_rules import ChainEvent, ChatterError, Names, start, switch
from oscillator.model.chains import FrictionChain
from oscillator.model.parameters import SolverOptions
from oscillator.presenting import presenter
from oscillator.text import shown

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

__all__ = ["ChainResult", "closed_spans", "mode_spans", "rows_at", "simulate_chain", "stuck_spans"]

#: The forcing periods a run lasts when no end is given.
DEFAULT_PERIODS = 10
#: The most solver steps the compiled loop takes before it returns to the supervisor.
STEPS_AT_ONCE = 4096
#: Element types whose mode the trajectory records.
_SWITCHING = ("friction", "stop", "contact", "jenkins")


def names_of(chain: FrictionChain) -> Names:
    """The names the events and tables carry."""
    return Names(
        tuple(m.name for m in chain.masses),
        tuple(e.name for e in chain.elements),
        tuple(e.type for e in chain.elements),
    )


def state_columns(chain: FrictionChain) -> tuple[str, ...]:
    """The trajectory's state columns: ``x:<mass>``, ``v:<mass>`` for each mass, ``z:<element>``
    for each Jenkins slider."""
    return chain.system.state


class _ChainRecords:
    """A chain run's rows and events until its tables are asked for: each table is built then,
    once (a period map whose tables nobody reads builds none), and kept here, so every copy of the
    result (``dataclasses.replace``) reads the same tables.  The times, the states and the modes
    are read from the rows without a table (:meth:`ChainResult.times` and its neighbours)."""

    def __init__(self, chain: FrictionChain, data: np.ndarray, events: list[ChainEvent]) -> None:
        self.chain, self.data, self.events = chain, data, events
        self.switching = _switching(chain)
        self._events_frame: pd.DataFrame | None = None
        self._trajectory_frame: pd.DataFrame | None = None

    def events_frame(self) -> pd.DataFrame:
        if self._events_frame is None:
            if self.events:  # column by column: each column's type told by its values
                values = zip(*(e.row() for e in self.events), strict=True)
                self._events_frame = pd.DataFrame(dict(zip(ChainEvent.columns(), values, strict=True)))
            else:
                empty = pd.DataFrame(columns=list(ChainEvent.columns()))
                self._events_frame = empty.astype({"t": "float64", "mode_before": "int64", "mode_after": "int64"})
        return self._events_frame

    def switches(self) -> tuple[np.ndarray, list[str], list[str], list[int]]:
        if self._events_frame is None or self.events:  # the run's own events: no table needed
            found = [e for e in self.events if e.mode_before != e.mode_after]
            return (
                np.array([e.t for e in found], dtype=float),
                [e.element for e in found],
                [str(e.kind) for e in found],
                [int(e.mode_after) for e in found],
            )
        events = self._events_frame[self._events_frame.mode_before != self._events_frame.mode_after]
        return (
            events.t.to_numpy(float),
            [str(name) for name in events.element],
            [str(kind) for kind in events.kind],
            [int(m) for m in events.mode_after],
        )

    def trajectory_frame(self) -> pd.DataFrame:
        if self._trajectory_frame is None:
            chain, data = self.chain, self.data
            names = ["t", *state_columns(chain)]
            columns: dict[str, np.ndarray] = {name: data[:, j] for j, name in enumerate(names)}
            for j, k in enumerate(self.switching):
                columns[f"mode:{chain.elements[k].name}"] = data[:, len(names) + j].astype(np.int64)
            self._trajectory_frame = pd.DataFrame(columns, copy=False)
        return self._trajectory_frame


def chain_records_of(chain: FrictionChain, events: pd.DataFrame, trajectory: pd.DataFrame) -> _ChainRecords:
    """Records holding tables already built (a run folder read back)."""
    names = [*("t", *state_columns(chain)), *(f"mode:{chain.elements[k].name}" for k in _switching(chain))]
    records = _ChainRecords(chain, trajectory.reindex(columns=names).to_numpy(float), [])
    records._events_frame, records._trajectory_frame = events, trajectory
    return records


def _switching(chain: FrictionChain) -> list[int]:
    """The rows of the elements whose mode the trajectory records."""
    return [k for k, e in enumerate(chain.elements) if e.type in _SWITCHING]


@dataclass(frozen=True)
class ChainResult:
    """A friction chain's run: its ``events`` (one row per event, :meth:`ChainEvent.columns`), its
    ``trajectory`` (``t``, the state columns, each switching element's mode ``mode:<element>``),
    each element's ``work`` on the masses over the run (J), and how it ended.  The two tables are
    built when first asked for."""

    chain: FrictionChain
    work: dict[str, float]
    status: Status = Status.COMPLETE
    message: str = ""
    t_end: float = math.nan
    y_end: np.ndarray = field(default_factory=lambda: np.empty(0))
    _records: _ChainRecords = field(default=None, repr=False, compare=False)  # type: ignore[assignment]

    @property
    def events(self) -> pd.DataFrame:
        return self._records.events_frame()

    @property
    def trajectory(self) -> pd.DataFrame:
        return self._records.trajectory_frame()

    @property
    def times(self) -> np.ndarray:
        """The trajectory's times (its ``t`` column), read without building the table."""
        return self._records.data[:, 0]

    @property
    def states(self) -> np.ndarray:
        """The trajectory's states, ``(rows, state)`` (its state columns, in the system's order)."""
        return self._records.data[:, 1 : 1 + self.chain.system.size]

    def switches(self) -> tuple[np.ndarray, list[str], list[str], list[int]]:
        """The events that changed a mode: their times, elements, kinds and modes after."""
        return self._records.switches()

    def plot(self) -> Figure:
        """Each mass's motion and each slider's force against time (a matplotlib figure)."""
        return presenter().plot_chain_result(self)

    def save(self, folder: str | Path, *, figures: bool = True, report: bool = True) -> Path:
        """Write the run as ``oscillator run FILE`` does into ``folder`` (a new one)."""
        return presenter().save_chain_result(self, folder, figures=figures, report=report)

    def modes(self) -> np.ndarray:
        """Each trajectory row's mode of every element, ``(rows, elements)`` (0 for an element
        that does not switch): what the field takes at that row with
        :func:`~oscillator.model.chain_fields.pack`."""
        records, size = self._records, self.chain.system.size
        modes = np.zeros((len(records.data), len(self.chain.elements)))
        for j, k in enumerate(records.switching):
            modes[:, k] = records.data[:, 1 + size + j]
        return modes

    def mode_of(self, element: str) -> np.ndarray:
        """The mode of the switching element ``element`` at each trajectory row."""
        records = self._records
        k = [e.name for e in self.chain.elements].index(element)
        return records.data[:, 1 + self.chain.system.size + records.switching.index(k)].astype(np.int64)

    @property
    def energy(self) -> ChainEnergy:
        """The work-energy balance over the run (:func:`~oscillator.model.chain_energy.audit`)."""
        return audit(self.chain, self.states[0], self.y_end, self.work)


class _Run:
    """What the supervisor keeps while it runs: the rows, the events, the guards' counts."""

    def __init__(self, chain: FrictionChain, arrays: ChainArrays, options: SolverOptions) -> None:
        self.chain, self.arrays, self.options = chain, arrays, options
        self.rows: list[np.ndarray] = []
        self.events: list[ChainEvent] = []
        self.recent: deque[float] = deque(maxlen=options.storm_events)
        self.switching = _switching(chain)
        self.count = 0  # rows kept

    def keep(self, t: float, y: np.ndarray, mode: np.ndarray) -> None:
        """One row: the time, the state, the mode."""
        row = np.empty((1, 1 + self.arrays.size + len(self.switching)))
        row[0, 0], row[0, 1 : 1 + self.arrays.size] = t, y[: self.arrays.size]
        row[0, 1 + self.arrays.size :] = mode[self.switching]
        self.rows.append(row)

    def keep_steps(self, steps: np.ndarray, mode: np.ndarray) -> None:
        """Rows of the stepping loop (time and state) in one mode."""
        block = np.empty((len(steps), steps.shape[1] + len(self.switching)))
        block[:, : steps.shape[1]] = steps
        block[:, steps.shape[1] :] = mode[self.switching]
        self.rows.append(block)
        self.count += len(block)
        if self.count > self.options.max_trajectory_rows:
            raise SimulationFailed(
                f"the trajectory passed max_trajectory_rows = {self.options.max_trajectory_rows} rows at t = "
                f"{steps[-1, 0]!r} s; shorten the run (--t-end) or raise max_trajectory_rows",
                reason=Reason.MAX_ROWS,
            )

    def happened(self, events: list[ChainEvent]) -> None:
        """Record the events of an instant; refuse a storm, or more than ``max_events`` in all."""
        self.events.extend(events)
        if len(self.events) > self.options.max_events:
            raise SimulationFailed(
                f"more than max_events = {self.options.max_events} events by t = {self.events[-1].t!r} s; shorten the "
                "run or raise max_events",
                reason=Reason.MAX_EVENTS,
            )
        window = self.options.storm_window
        for event in events:
            self.recent.append(event.t)
        if len(self.recent) == self.recent.maxlen and self.recent[-1] - self.recent[0] <= window:
            last = self.events[-1]
            raise SimulationFailed(
                f"an event storm: {len(self.recent)} events within {window:g} s up to t = {last.t!r} s (last: "
                f"element {last.element!r}, {last.kind}); the motion chatters: refine the model or raise "
                "storm_events",
                reason=Reason.STORM,
            )

    def result(self, status: Status, message: str, t: float, y: np.ndarray) -> ChainResult:
        chain = self.chain
        width = 1 + self.arrays.size + len(self.switching)
        data = np.concatenate(self.rows) if self.rows else np.empty((0, width))
        size = self.arrays.size
        work = {e.name: float(y[size + k]) for k, e in enumerate(chain.elements)}
        return ChainResult(chain, work, status, message, t, y.copy(), _ChainRecords(chain, data, self.events))


def run_end(chain: FrictionChain, t_end: float | None) -> float:
    """The time a run of ``chain`` ends: ``t_end``, the chain's, or 10 forcing periods; refused when
    not after ``t0`` or too long."""
    t_end = chain.t_end if t_end is None else t_end
    end = chain.t0 + DEFAULT_PERIODS * chain.period if t_end is None else float(t_end)
    if not math.isfinite(end) or end <= chain.t0:
        raise InputError(f"t_end must be a time after t0 = {chain.t0!r} s, got {t_end!r}", field="t_end")
    if (end - chain.t0) / chain.period > 1e8:
        raise InputError("t_end: a run of more than 10^8 forcing periods is refused; shorten it", field="t_end")
    return end


def simulate_chain(
    chain: FrictionChain,
    t_end: float | None = None,
    *,
    options: SolverOptions | None = None,
    at: np.ndarray | None = None,
    start_state: np.ndarray | None = None,
) -> ChainResult:
    """Simulate a friction chain from its start to ``t_end`` (s; by default the chain's, else 10
    forcing periods), the trajectory recorded at every solver step and at every event, and at
    each time of ``at`` exactly (the solver stops there: the stroboscopic section
    ``t0 + kT``, say).  ``start_state`` starts it from another state than the chain's (its
    :attr:`~oscillator.model.chains.FrictionChain.system`'s ``state``: each mass's ``x, v``, then
    each slider's ``z``), as a period map does.

    Raises :class:`~oscillator.errors.SimulationFailed` (its ``result`` the run so far) when the
    solver fails or the events storm."""
    chain = chain.checked()
    if options is not None and not isinstance(options, SolverOptions):
        raise InputError(
            f"options must be a SolverOptions (e.g. SolverOptions(rtol=1e-12)) or None, got {shown(options)}",
            field="options",
        )
    options = options or SolverOptions()
    end = run_end(chain, t_end)
    counted()
    arrays, names = arrays_of(chain), names_of(chain)
    y = np.concatenate(
        [state_of(chain) if start_state is None else _given(chain, start_state), np.zeros(len(arrays.kind))]
    )
    run = _Run(chain, arrays, options)
    engine = ChainEngine(arrays, options, max_step=options.max_step_fraction * chain.period)
    t = chain.t0
    try:
        mode, y, events = start(arrays, names, t, y)
        run.keep(t, y, mode)
        run.happened(events)
        engine.reset(mode, t, y)
        marks = np.sort(np.asarray(at if at is not None else (), dtype=float).ravel())
        t, y = _supervise(run, engine, names, mode, t, y, end, marks[(marks > t) & (marks < end)])
    except ChatterError as error:
        failure = SimulationFailed(str(error), reason=Reason.STORM)
        failure.result = run.result(Status.FAILED, str(error), t, y)  # type: ignore[assignment]
        raise failure from None
    except EngineFailure as error:
        message = f"CVODE failed at t = {t!r} s: {error}"
        failure = SimulationFailed(message, reason=Reason.SOLVER_FAILURE)
        failure.result = run.result(Status.FAILED, message, t, y)  # type: ignore[assignment]
        raise failure from None
    except SimulationFailed as failure:
        failure.result = run.result(Status.FAILED, str(failure), t, y)  # type: ignore[assignment]
        raise
    finally:
        engine.close()
    return run.result(Status.COMPLETE, "", t, y)


def _given(chain: FrictionChain, state: np.ndarray) -> np.ndarray:
    """``state`` as a start of ``chain``: one finite number per name of its system's state."""
    names = chain.system.state
    given = np.asarray(state, dtype=float).ravel()
    if len(given) != len(names) or not np.isfinite(given).all():
        raise InputError(
            f"start_state must hold {len(names)} finite numbers ({', '.join(names)}), got {len(given)}",
            field="start_state",
        )
    return given.copy()


def _supervise(
    run: _Run,
    engine: ChainEngine,
    names: Names,
    mode: np.ndarray,
    t: float,
    y: np.ndarray,
    end: float,
    marks: np.ndarray,
) -> tuple[float, np.ndarray]:
    near = run.options.grazing_velocity_tolerance
    rows = np.empty((STEPS_AT_ONCE, 1 + run.arrays.size))
    stops, k = [*marks.tolist(), end], 0
    while t < end:
        step, n = engine.advance_steps(stops[k], rows)
        t, y = step.t, step.y
        if t >= stops[k]:
            k += 1
        if not np.isfinite(rows[:n]).all() or not np.isfinite(y).all():
            raise SimulationFailed(f"the state left floating point before t = {t!r} s", reason=Reason.ARITHMETIC)
        run.keep_steps(rows[:n].copy(), mode)
        if step.kind is not StepKind.ROOT:
            continue
        new_mode, new_y, events = switch(run.arrays, names, t, y, mode, step.roots, near)
        run.happened(events)
        if not np.array_equal(new_mode, mode) or not np.array_equal(new_y, y):
            mode, y = new_mode, new_y
            run.keep(t, y, mode)
            engine.reset(mode, t, y)
    return t, y


# -- the spans of a run in which an element is in a mode (its events between) ----------------------


def rows_at(times: np.ndarray, marks: np.ndarray, period: float) -> np.ndarray:
    """The row of ``times`` (increasing; the first of several equal ones) at each of ``marks``,
    times a run was told to stop at (``simulate_chain(..., at=marks)``).  The solver lands on a
    mark to within its rounding, on either side: a row within ``1e-9`` of a ``period`` counts.

    Raises
    ------
    SimulationFailed
        A mark the run did not stop at.
    """
    rows = np.clip(np.searchsorted(times, marks - 1e-9 * period), 0, len(times) - 1)
    if len(rows) and np.max(np.abs(times[rows] - marks)) > 1e-9 * period:
        raise SimulationFailed("the run did not stop at every marked time", reason=Reason.SOLVER_FAILURE)
    return rows


def mode_spans(run: ChainResult, element: str, start: float, span: float) -> list[tuple[float, float, int]]:
    """``(from, to, mode)``: the spans of ``[start, start + span]`` between the switching element's
    events, each with its mode (a friction element's or slider's slip sign, ``0`` stuck; a stop's
    or contact's ``1`` closed)."""
    t, elements, _, after = run.switches()
    mine = [k for k, name in enumerate(elements) if name == element]
    times = [start, *(float(t[k]) for k in mine), start + span]
    modes = [int(run.mode_of(element)[0]), *(after[k] for k in mine)]
    return [(a, b, m) for a, b, m in zip(times, times[1:], modes, strict=False)]


def stuck_spans(run: ChainResult, element: str, start: float, span: float) -> list[tuple[float, float]]:
    """The spans of ``[start, start + span]`` in which the friction element or Jenkins slider
    ``element`` holds, from its events."""
    return [(a, b) for a, b, mode in mode_spans(run, element, start, span) if mode == 0]


def closed_spans(run: ChainResult, element: str, start: float, span: float) -> list[tuple[float, float]]:
    """The spans of ``[start, start + span]`` in which the stop or contact ``element`` is closed."""
    return [(a, b) for a, b, mode in mode_spans(run, element, start, span) if mode != 0]
