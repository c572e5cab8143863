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
from oscillator.hybrid.result import Status
from oscillator.model.chain_energy import ChainEnergy, audit
from oscillator.model.chain_fields import ChainArrays, arrays_of, state_of
from oscillator.model.chain_rules import ChainEvent, ChatterError, Names, start, switch
from oscillator.model.chains import FrictionChain
from oscillator.model.parameters import SolverOptions
from oscillator.presenting import presenter

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

__all__ = ["ChainResult", "closed_spans", "mode_spans", "simulate_chain", "stuck_spans"]

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


@dataclass(frozen=True)
class ChainResult:
    """A friction chain's run: its ``events`` (one row per event, :meth:`ChainEvent.columns`), its
    ``trajectory`` (``t``, the state columns, each switching element's mode ``mode:<element>``),
    each element's ``work`` on the masses over the run (J), and how it ended."""

    chain: FrictionChain
    events: pd.DataFrame
    trajectory: pd.DataFrame
    work: dict[str, float]
    status: Status = Status.COMPLETE
    message: str = ""
    t_end: float = math.nan
    y_end: np.ndarray = field(default_factory=lambda: np.empty(0))

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
        modes = np.zeros((len(self.trajectory), len(self.chain.elements)))
        for k, element in enumerate(self.chain.elements):
            column = f"mode:{element.name}"
            if column in self.trajectory:
                modes[:, k] = self.trajectory[column].to_numpy(float)
        return modes

    @property
    def energy(self) -> ChainEnergy:
        """The work-energy balance over the run (:func:`~oscillator.model.chain_energy.audit`)."""
        start = self.trajectory.iloc[0, 1:].to_numpy(dtype=float)
        return audit(self.chain, start, self.y_end, self.work)


class _Run:
    """What the supervisor keeps while it runs: the rows, the events, the guards' counts."""

    def __init__(self, chain: FrictionChain, arrays: ChainArrays, options: SolverOptions) -> None:
        self.chain, self.arrays, self.options = chain, arrays, options
        self.rows: list[np.ndarray] = []
        self.events: list[ChainEvent] = []
        self.recent: deque[float] = deque(maxlen=options.storm_events)
        self.switching = [k for k, e in enumerate(chain.elements) if e.type in _SWITCHING]
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
        names = ["t", *state_columns(chain)]
        modes = [f"mode:{chain.elements[k].name}" for k in self.switching]
        data = np.concatenate(self.rows) if self.rows else np.empty((0, len(names) + len(modes)))
        columns: dict[str, np.ndarray] = {name: data[:, j] for j, name in enumerate(names)}
        columns |= {name: data[:, len(names) + j].astype(np.int64) for j, name in enumerate(modes)}
        trajectory = pd.DataFrame(columns, copy=False)
        if self.events:  # column by column: each column's type told by its values
            values = zip(*(e.row() for e in self.events), strict=True)
            events = pd.DataFrame(dict(zip(ChainEvent.columns(), values, strict=True)))
        else:
            events = pd.DataFrame(columns=list(ChainEvent.columns()))
            events = events.astype({"t": "float64", "mode_before": "int64", "mode_after": "int64"})
        size = self.arrays.size
        work = {e.name: float(y[size + k]) for k, e in enumerate(chain.elements)}
        return ChainResult(chain, events, trajectory, work, status, message, t, y.copy())


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
    options = options or SolverOptions()
    end = run_end(chain, t_end)
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


def mode_spans(run: ChainResult, element: str, start: float, span: float) -> list[tuple[float, float, int]]:
    """``(from, to, mode)``: the spans of ``[start, start + span]`` between the switching element's
    events, each with its mode (a friction element's or slider's slip sign, ``0`` stuck; a stop's
    or contact's ``1`` closed)."""
    trajectory, events = run.trajectory, run.events
    mine = events[(events.element == element) & (events.mode_before != events.mode_after)]
    times = [start, *mine.t.to_numpy(float), start + span]
    modes = [int(trajectory[f"mode:{element}"].iloc[0]), *mine.mode_after.astype(int).tolist()]
    return [(a, b, m) for a, b, m in zip(times, times[1:], modes, strict=False)]


def stuck_spans(run: ChainResult, element: str, start: float, span: float) -> list[tuple[float, float]]:
    """The spans of ``[start, start + span]`` in which the friction element or Jenkins slider
    ``element`` holds, from its events."""
    return [(a, b) for a, b, mode in mode_spans(run, element, start, span) if mode == 0]


def closed_spans(run: ChainResult, element: str, start: float, span: float) -> list[tuple[float, float]]:
    """The spans of ``[start, start + span]`` in which the stop or contact ``element`` is closed."""
    return [(a, b) for a, b, mode in mode_spans(run, element, start, span) if mode != 0]
