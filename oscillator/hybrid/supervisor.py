"""The supervisor: drives an engine through each mode and restarts it at every switch.

This is the only stateful part of the package.  The engine (:mod:`oscillator.engines`)
integrates the current mode's field and returns at the roots of its switching functions
(:mod:`oscillator.model.roots`); at each root the supervisor hands the instant to
:func:`oscillator.model.switching.resolve`, records the events it returns, and restarts the
engine with the next mode's field.  What is kept of the trajectory is the recording policy's
business (:mod:`oscillator.hybrid.recording`); what stops a run that would not end is the
guards' (:mod:`oscillator.hybrid.guards`).

The state carries four quadratures besides ``(x1, v1, x2, v2)``: the work of the forcing and of
the feedback and the losses in the dampers and to friction (:mod:`oscillator.model.energy`).
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
from oscillator.hybrid.record import RunRecord
from oscillator.hybrid.recording import Recording
from oscillator.model.parameters import Parameters, SolverOptions
from oscillator.model.phase_space import Mode
from oscillator.model.switching import MAX_ROWS, initial_mode, resolve_rows

__all__ = ["CallbackRaised", "Supervisor"]


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
    """

    def __init__(
        self,
        params: Parameters,
        options: SolverOptions,
        engine: Engine,
        recording: Recording,
        *,
        progress: Callable[[float], None] | None = None,
    ) -> None:
        self.params = params
        self.options = options
        self.engine = engine
        self.recording = recording
        self.progress = progress
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
        y = np.zeros(8)
        y[:4] = start.y
        t = t0
        self.recording.start(record, t0, y, mode, t_end)
        record.reached(t, y.copy(), mode)
        while t < t_end:
            self.engine.reset(mode, t, y)
            t, y, mode = self._through_mode(record, mode, t, t_end)

    def _through_mode(self, record: RunRecord, mode: Mode, t: float, t_end: float) -> tuple[float, np.ndarray, Mode]:
        """Advance in ``mode`` until it switches or the run ends; the point and mode reached."""
        stalls, steps = StallGuard(), StepGuard(self.options)
        one_step = self.recording.one_step
        while True:
            target = self.recording.target(t, t_end)
            step = self._advance(target, t_end, one_step, record, mode)
            record.returns += 1
            t, y = step.t, step.y
            record.reached(t, y, mode)
            if self.progress is not None:
                self._report_progress(t)
            self.recording.returned(record, step, mode, target)
            if one_step:
                steps.count(step.kind is StepKind.ROOT, t, y, mode)
            if step.kind is StepKind.ROOT:
                record.root_returns += 1
                after, state, events = self._resolve_root(record, step, mode)
                if after != mode:
                    y[:4] = state
                    mode = after
                    record.reached(t, y, mode)
                    self.recording.switched(record, t, y, mode)
                    return t, y, mode
                stalls.count(t, events, mode)
            if t >= t_end:
                return t, y, mode

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
        """Hand the roots that fired to :func:`~oscillator.model.switching.resolve_rows`, which
        writes the events into the run's log; keep them.  The next mode, the projected state and the
        number of events."""
        t, y = step.t, step.y
        check_consistent(t, y, self.params, mode)
        state = y[:4].copy()
        log = record.events
        after, count = resolve_rows(t, state, self.params, mode, step.fired, self.options, log.free(MAX_ROWS), len(log))
        new = log.staged(count)
        self.recording.events(record, t, count)
        self._events.count(new, record.event_count, t)
        return after, state, count
