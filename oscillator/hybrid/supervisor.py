"""The supervisor: drives an engine through each mode and restarts it at every switch.

This is the only stateful part of the package.  The engine (:mod:`oscillator.engines`)
integrates the current mode's field and returns at the roots of its switching functions
(:mod:`oscillator.model.roots`); at each root the supervisor hands the instant to
:func:`oscillator.model.resolving.resolve`, records the events it returns, and restarts the
engine with the next mode's field.  What is kept of the trajectory is the recording policy's
business (:mod:`oscillator.hybrid.recording`); what stops a run that would not end is the
guards' (:mod:`oscillator.hybrid.guards`).

The state carries four quadratures besides ``(x1, v1, x2, v2)``: the work of the forcing and of
the feedback and the losses in the dampers and to friction (:mod:`oscillator.model.energy`).
Asked for the derivative of the flow, the supervisor carries ``Phi = d y(t) / d y(t0)`` too: the
engine integrates its variational equations with the state (:mod:`oscillator.model.kernels`),
and at every switch the supervisor resolves, ``Phi`` passes the switch's saltation matrix
(:func:`oscillator.model.saltation.carried_through`).  Asked for the segments, it keeps each
smooth piece of the run (:class:`oscillator.hybrid.record.Segment`).
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from oscillator.engines import Engine, EngineFailure, Step, StepKind
from oscillator.errors import Reason, SimulationFailed
from oscillator.hybrid.guards import (
    ARITHMETIC_ERRORS,
    EventGuard,
    StallGuard,
    StepGuard,
    check_consistent,
    solver_failure,
    strict_arithmetic,
)
from oscillator.hybrid.record import RunRecord, Segment
from oscillator.hybrid.recording import Recording
from oscillator.model.events import WIDTH
from oscillator.model.parameters import Parameters, SolverOptions
from oscillator.model.phase_space import Mode
from oscillator.model.resolving import initial_mode, resolve_rows
from oscillator.model.saltation import carried_through, rest_projection
from oscillator.model.switching import MAX_ROWS
from oscillator.model.types import VARIATIONAL

__all__ = ["STEPS_PER_RETURN", "CallbackRaised", "Supervisor"]

#: The most solver steps the compiled stepping loop takes before it comes back (the progress
#: callback and Ctrl-C are then served; 0.1-1 ms of work).
STEPS_PER_RETURN = 256


class CallbackRaised(Exception):
    """Carries an exception of the user's progress callback through the supervisor's handlers."""

    def __init__(self, error: Exception) -> None:
        super().__init__(str(error))
        self.error = error


class Supervisor:
    """Event-driven hybrid integration of the oscillator.

    Parameters
    ----------
    params : Parameters
    options : SolverOptions
    engine : Engine
        The integrator (:func:`oscillator.engines.build_engine`).
    recording : Recording
        What to keep of the trajectory and of the events.
    progress : callable, keyword-only
        Called with the time after every return of the engine.
    segments : bool, keyword-only
        Keep each smooth piece of the run in ``record.segments``.
    derivative : bool, keyword-only
        Carry the derivative of the flow (the engine must integrate 24 equations); the run's
        last point then holds it (``y[8:24]``, row by row).
    """

    def __init__(
        self,
        params: Parameters,
        options: SolverOptions,
        engine: Engine,
        recording: Recording,
        *,
        progress: Callable[[float], None] | None = None,
        segments: bool = False,
        derivative: bool = False,
        interrupted: Callable[[], bool] | None = None,
    ) -> None:
        #: The state's length: 8, or 24 with the derivative (an engine of the user's without a
        #: ``size`` integrates the 8 of the state and the works).
        self.size: int = getattr(engine, "size", VARIATIONAL)
        if derivative and self.size < VARIATIONAL + 16:
            raise ValueError(f"the derivative of the flow needs an engine of 24 equations, not {self.size}")
        self.params = params
        self.options = options
        self.engine = engine
        self.recording = recording
        self.progress = progress
        #: Whether a Ctrl-C came (:func:`~oscillator.io.signals.interrupts_heard`), asked at each
        #: return of the engine: one Python dropped where it was raised is raised again here.
        self.interrupted = interrupted
        self.segments = segments
        self.derivative = derivative
        #: The segment under way: its start and the event rows written since (when segments are kept).
        self._opened: tuple[float, np.ndarray, Mode] | None = None
        self._segment_rows: list[np.ndarray] = []
        #: With the trajectory at every step, the engine's compiled stepping loop where it has one
        #: (:meth:`oscillator.engines.cvode_c.CCvodeEngine.advance_steps`) and the rows it writes.
        self._stepper: Callable[..., tuple[Step, int]] | None = (
            getattr(engine, "advance_steps", None) if recording.one_step else None
        )
        #: On a grid, the engine's compiled loop over the grid's times where it has one.
        self._grid: Callable[..., tuple[Step, int]] | None = getattr(engine, "advance_grid", None)
        #: Whether the grid loop's last call reached no grid time (a root came first): returns are
        #: then taken one at a time until one reaches a grid time, so that a sparse grid (the
        #: sweeps' once a period, among ten roots) does not pay the loop's call at every root.
        self._grid_idle = False
        self._rows_buffer = np.empty((STEPS_PER_RETURN, 5))
        self._events = EventGuard(options)
        self._caller_errstate = np.geterr()

    def run(self, t0: float, y0: tuple[float, float, float, float], t_end: float, record: RunRecord) -> None:
        """Integrate from ``t0`` to ``t_end`` into ``record``.

        Raises :class:`SimulationFailed` (a solver failure or a guard) or ``KeyboardInterrupt``;
        ``record`` then holds the run up to the last point reached.  An exception raised by the
        progress callback comes wrapped in :class:`CallbackRaised`.
        """
        started = time.perf_counter()
        try:
            with strict_arithmetic():
                self._run(record, t0, y0, t_end)
        except ARITHMETIC_ERRORS as exc:
            raise SimulationFailed(
                f"arithmetic failed after t = {record.t_final:.10g} s ({exc}): the forces leave floating point; "
                f"give parameters and a start of physical size",
                reason=Reason.ARITHMETIC,
                field="parameters",
            ) from exc
        finally:
            record.wall_time = time.perf_counter() - started
            record.rhs_evaluations = self.engine.rhs_evaluations
            record.restarts = self.engine.restarts

    def _run(self, record: RunRecord, t0: float, y0: tuple[float, float, float, float], t_end: float) -> None:
        start = initial_mode(t0, y0, self.params)
        mode = record.mode_initial = start.mode
        self.recording.events(record, t0, record.events.stage(start.rows))
        self._events.count(start.rows, record.event_count, t0)
        self._segment_rows = [start.rows.copy()]
        y = np.zeros(self.size)
        y[:4] = start.y
        if self.derivative:
            y[VARIATIONAL:] = rest_projection(mode).ravel()
        t = t0
        self.recording.start(record, t0, y, mode, t_end)
        record.reached(t, y.copy(), mode)
        while t < t_end:
            self.engine.reset(mode, t, y)
            self._opened = (t, y[:4].copy(), mode)
            t, y, mode = self._through_mode(record, mode, t, t_end)
        if self.segments:  # the last piece ends with the run (of length zero after a switch at the end)
            if self._opened is None:
                self._opened = (t, y[:4].copy(), mode)
            self._close(record, t, y)

    def _through_mode(self, record: RunRecord, mode: Mode, t: float, t_end: float) -> tuple[float, np.ndarray, Mode]:
        """Advance in ``mode`` until it switches or the run ends; the point and mode reached."""
        stalls, steps = StallGuard(), StepGuard(self.options, self.engine.name)
        while True:
            step = self._returned(record, mode, t, t_end, steps)
            t, y = step.t, step.y
            if step.kind is StepKind.ROOT:
                record.root_returns += 1
                after, state, events = self._resolve_root(record, step, mode)
                if after != mode:
                    self._switching(record, t, y, state, mode, after)
                    y[:4] = state
                    mode = after
                    record.reached(t, y, mode)
                    self.recording.switched(record, t, y, mode)
                    return t, y, mode
                stalls.count(t, events, mode)
            if t >= t_end:
                return t, y, mode

    def _returned(self, record: RunRecord, mode: Mode, t: float, t_end: float, steps: StepGuard) -> Step:
        """The engine's next return, recorded: or its next returns, taken at once in compiled code
        when the trajectory is kept at every step or on a grid (the last one)."""
        target = self.recording.target(t, t_end)
        grid = self.recording.ahead() if self._grid is not None and not self._grid_idle else None
        if self._stepper is not None:
            rows = self._rows_buffer[: min(len(self._rows_buffer), steps.room)]
            step, n = self._batch(self._stepper, (target,), t_end, rows, record, mode)
            self.recording.batch(record, rows[:n], mode)
            steps.count_many(n, step.kind is StepKind.ROOT, step.t, step.y, mode)
            record.returns += n
        elif grid is not None and self._grid is not None:
            step, n = self._batch(self._grid, (grid,), t_end, self._rows_buffer, record, mode)
            rows = self._rows_buffer[:n]
            self.recording.batch(record, rows, mode)
            wrote_last = n > 0 and step.kind is not StepKind.ROOT and rows[-1, 0] == step.t
            record.returns += n + (not wrote_last)  # a root, or the stop time off the grid, writes no row
            self._grid_idle = n == 0
        else:
            step = self._advance(target, t_end, self.recording.one_step, record, mode)
            record.returns += 1
            self.recording.returned(record, step, mode, target)
            if self.recording.one_step:
                steps.count(step.kind is StepKind.ROOT, step.t, step.y, mode)
            self._grid_idle = self._grid_idle and step.kind is StepKind.ROOT
        record.reached(step.t, step.y, mode)
        if self.interrupted is not None and self.interrupted():
            raise KeyboardInterrupt
        if self.progress is not None:
            self._report_progress(step.t)
        return step

    def _batch(
        self,
        method: Callable[..., tuple[Step, int]],
        first: tuple[object, ...],
        t_end: float,
        rows: np.ndarray,
        record: RunRecord,
        mode: Mode,
    ) -> tuple[Step, int]:
        """Returns of the engine taken in compiled code: ``method(*first, t_stop, rows)``."""
        try:
            return method(*first, t_stop=t_end, rows=rows)
        except EngineFailure as failure:
            assert record.y_final is not None
            raise solver_failure(
                self.engine.name, str(failure), failure.flag, record.t_final, record.y_final, mode
            ) from None

    def _switching(
        self, record: RunRecord, t: float, y: np.ndarray, state: np.ndarray, mode: Mode, after: Mode
    ) -> None:
        """At a switch, before the state is projected: the derivative of the flow through it
        (in ``y``), and the segment that ends."""
        if self.derivative:
            phi = y[VARIATIONAL:].reshape(4, 4)
            try:
                y[VARIATIONAL:] = carried_through(phi, t, y[:4], state, self.params, mode, after).ravel()
            except ZeroDivisionError as exc:
                raise SimulationFailed(
                    f"no derivative of the flow through the switch at t = {t:.10g} s: {exc} (a grazing contact)",
                    reason=Reason.NO_MONODROMY,
                    field="orbit",
                ) from exc
        if self.segments:
            self._close(record, t, y)

    def _close(self, record: RunRecord, t: float, y: np.ndarray) -> None:
        """The segment under way ends at ``(t, y)`` (the flow's state, before any projection)."""
        assert self._opened is not None
        t0, y0, mode = self._opened
        rows = np.concatenate(self._segment_rows) if self._segment_rows else np.empty((0, WIDTH))
        record.segments.append(Segment(mode, t0, y0, t, y[:4].copy(), rows))
        self._opened, self._segment_rows = None, []

    def _advance(self, target: float, t_end: float, one_step: bool, record: RunRecord, mode: Mode) -> Step:
        try:
            return self.engine.advance(target, t_stop=t_end, one_step=one_step)
        except EngineFailure as failure:
            assert record.y_final is not None
            raise solver_failure(
                self.engine.name, str(failure), failure.flag, record.t_final, record.y_final, mode
            ) from None

    def _report_progress(self, t: float) -> None:
        """Call the progress callback with the caller's floating-point settings; let what it
        raises through untouched (Ctrl-C, which lands there often, stays an interrupt)."""
        assert self.progress is not None
        with np.errstate(**self._caller_errstate):
            try:
                self.progress(t)
            except Exception as exc:
                raise CallbackRaised(exc) from exc

    def _resolve_root(self, record: RunRecord, step: Step, mode: Mode) -> tuple[Mode, np.ndarray, int]:
        """Hand the roots that fired to :func:`~oscillator.model.resolving.resolve_rows`, which
        writes the events into the run's log; keep them.  The next mode, the projected state and the
        number of events."""
        t, y = step.t, step.y
        check_consistent(t, y, self.params, mode)
        state = y[:4].copy()
        log = record.events
        after, count = resolve_rows(t, state, self.params, mode, step.fired, self.options, log.free(MAX_ROWS), len(log))
        new = log.staged(count)
        if self.segments and count:
            self._segment_rows.append(new.copy())
        self.recording.events(record, t, count)
        self._events.count(new, record.event_count, t)
        return after, state, count
