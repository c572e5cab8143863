"""The supervisor: integrates each mode with CVODE and restarts it at every switch.

This is the only stateful part of the package.  Each mode (both masses' domains plus the contact
flags) maps to one CVODE problem (scikit-sundae), created once and re-initialised at every
restart; its root functions and their directions are those of :mod:`oscillator.detection`.  At
each root the supervisor hands the instant to :func:`oscillator.switching.resolve`, records the
events it returns, and restarts CVODE with the next mode's fields.

The state carries four quadratures besides ``(x1, v1, x2, v2)``: the work of the forcing and of
the feedback and the losses in the dampers and to friction (:mod:`oscillator.energy`).

CVODE integrates in a local time ``tau = t - t_ref`` with ``t_ref`` moved to the current time at
every restart.  CVODE locates a root to about ``100 eps max(|tau|, |h|)``; in absolute time that
would grow with ``t``, and with it the G-functions' values at their roots (1e-9 m/s in a velocity
after 940 s of Instance 1).  The fields themselves are evaluated at ``t_ref + tau``.
"""

from __future__ import annotations

import collections
import contextlib
import io
import math
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

import numpy as np
from sksundae.cvode import CVODE

from oscillator._errors import OscillatorError
from oscillator.detection import NUM_ROOTS, Root, mode_violation, root_directions, root_kernel
from oscillator.energy import mechanical_energy
from oscillator.events import Event
from oscillator.fields import coefficients
from oscillator.kernels import derivative
from oscillator.parameters import Parameters, SolverOptions
from oscillator.phase_space import Mode
from oscillator.switching import Resolution, initial_mode, resolve

__all__ = ["ARITHMETIC_ERRORS", "RunRecord", "Supervisor", "start_problem", "strict_arithmetic"]

#: What :func:`strict_arithmetic` and Python's own float arithmetic raise when numbers leave
#: floating point.
ARITHMETIC_ERRORS = (FloatingPointError, OverflowError, ZeroDivisionError)


def strict_arithmetic() -> np.errstate:
    """Overflow and invalid arithmetic raise instead of spreading inf and nan through the decisions."""
    return np.errstate(over="raise", invalid="raise", divide="raise")


#: CVODE's return flags (scikit-sundae ``status``) for a root and for reaching ``tstop``.
_ROOT_RETURN = 2
_TSTOP_RETURN = 1
#: CVODE's CV_ILL_INPUT, returned as "root found at and very near t" when a root function is
#: exactly 0.0 at the root it just returned and still 0.0 a rounding step later (a difference of
#: two O(1) velocities that change by less than an ulp); a restart at the root clears it.
_CLOSE_ROOTS = -22
#: Root returns at one instant without a switch before the supervisor declares a stall.
_MAX_STALLS = 100
#: Two root returns closer than this (relative to the time) are at one instant.
_SAME_INSTANT = 1e-12
#: Without a trajectory to record, CVODE runs this many forcing periods between returns.
_CHUNK_PERIODS = 4
#: How far (relative) the state may stand on the wrong side of a boundary of its mode at a root.
_CONSISTENCY = 1e-9


class _CallbackRaised(Exception):
    """Carries an exception of the user's progress callback through the supervisor's handlers."""

    def __init__(self, error: Exception) -> None:
        super().__init__(str(error))
        self.error = error


def start_problem(t0: float, y0: tuple[float, float, float, float], p: Parameters) -> str | None:
    """What cannot be evaluated at the start, or ``None``: the initial mode is decided and its
    field, powers, root functions and energy are computed; each must be a finite number."""
    try:
        with strict_arithmetic():
            start = initial_mode(t0, y0, p)
            mode = start.mode
            y = np.zeros(8)
            y[:4] = start.y
            rates, roots = np.zeros(8), np.zeros(NUM_ROOTS)
            c = coefficients(p)
            derivative(t0, y, rates, c, mode.sign(1), mode.sign(2), mode.left, mode.right)
            root_kernel(t0, y, roots, c, mode.sign(1), mode.sign(2), mode.left, mode.right, 0.0, 0.0)
            energy = mechanical_energy(start.y, p, mode.left, mode.right)
    except ARITHMETIC_ERRORS:
        return "the forces overflow"
    except OscillatorError as error:
        return f"the switching rules fail ({error})"
    if not np.isfinite(rates[:4]).all():
        return "the forces overflow"
    if not np.isfinite(rates[4:]).all():
        return "the powers of the energy audit overflow"
    if not np.isfinite(roots).all():
        return "the switching functions overflow"
    if not math.isfinite(energy):
        return "the mechanical energy overflows"
    return None


@dataclass
class RunRecord:
    """What a run produced, as plain records (tables are built at the user-facing edge)."""

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


class Supervisor:
    """Event-driven hybrid integration of the oscillator.

    Parameters
    ----------
    params : Parameters
    options : SolverOptions
    t_eval : array_like or None, keyword-only
        Record the trajectory on this grid instead of at CVODE's steps.
    record_trajectory : bool, keyword-only
        Keep trajectory rows at all (events are always kept).
    progress : callable, keyword-only
        Called with the time after every solver step.
    keep_events_from : float, keyword-only
        Keep only the events at or after this time (all are counted); memory then stays flat in
        the length of a run.
    """

    def __init__(
        self,
        params: Parameters,
        options: SolverOptions,
        *,
        t_eval: np.ndarray | None = None,
        record_trajectory: bool = True,
        progress: Callable[[float], None] | None = None,
        keep_events_from: float = -math.inf,
    ) -> None:
        self.params = params
        self.options = options
        self.t_eval = None if t_eval is None else np.asarray(t_eval, dtype=float)
        self.record_trajectory = record_trajectory
        self.progress = progress
        self.keep_events_from = keep_events_from
        self._solvers: dict[Mode, tuple[CVODE, object]] = {}
        self._t_ref = 0.0  # CVODE's time is tau = t - _t_ref
        self._recent: collections.deque[Event] = collections.deque(maxlen=options.storm_events + 1)
        # scikit-sundae prints CVODE's error messages to stdout; they are caught here and told
        # in the library's own error when the solver fails.
        self._solver_output = io.StringIO()
        self._caller_errstate = np.geterr()

    # ----------------------------------------------------------------- CVODE problems per mode

    def _problem(self, mode: Mode) -> tuple[CVODE, object]:
        """The CVODE problem of a mode, created on first use."""
        if mode in self._solvers:
            return self._solvers[mode]
        p = self.params

        c = coefficients(p)
        s1, s2, left, right = mode.sign(1), mode.sign(2), mode.left, mode.right
        step = self.options.max_step_fraction * p.period
        near = self.options.grazing_displacement_tolerance

        def rhs(tau: float, y: np.ndarray, yp: np.ndarray) -> None:
            derivative(self._t_ref + tau, y, yp, c, s1, s2, left, right)

        def roots(tau: float, y: np.ndarray, g: np.ndarray) -> None:
            root_kernel(self._t_ref + tau, y, g, c, s1, s2, left, right, step, near)

        roots.direction = root_directions(mode)
        roots.terminal = [True] * NUM_ROOTS
        solver = CVODE(
            rhs,
            method="Adams",
            rtol=self.options.rtol,
            atol=self.options.atol,
            max_step=step,
            max_num_steps=self.options.max_num_steps,
            eventsfn=roots,
            num_events=NUM_ROOTS,
        )
        self._solvers[mode] = (solver, roots)
        return solver, roots

    # ----------------------------------------------------------------- the run

    def run(self, t0: float, y0: tuple[float, float, float, float], t_end: float) -> RunRecord:
        """Integrate from ``t0`` to ``t_end``; raise :class:`OscillatorError` on failure.

        The partial record is attached to the error as ``error.partial``.  An exception raised
        by the progress callback reaches the caller unchanged.
        """
        record = RunRecord()
        self._recent.clear()
        started = time.perf_counter()
        try:
            with strict_arithmetic():
                self._run(record, t0, y0, t_end)
        except _CallbackRaised as raised:
            raise raised.error from None
        except ARITHMETIC_ERRORS as exc:
            error = OscillatorError(
                f"arithmetic failed after t = {record.t_final:.10g} s ({exc}): the forces leave floating point; "
                f"give parameters and a start of physical size",
                field="parameters",
            )
            error.partial = record  # type: ignore[attr-defined]
            raise error from exc
        except (OscillatorError, KeyboardInterrupt) as error:
            error.partial = record  # type: ignore[attr-defined]
            raise
        finally:
            record.wall_time = time.perf_counter() - started
        return record

    def _report_progress(self, t: float) -> None:
        """Call the progress callback with the caller's floating-point settings; let what it
        raises through untouched (Ctrl-C, which lands there often, stays an interrupt)."""
        with np.errstate(**self._caller_errstate):
            try:
                self.progress(t)  # type: ignore[misc]
            except Exception as exc:
                raise _CallbackRaised(exc) from exc

    def _record(self, record: RunRecord, t: float, y: np.ndarray, mode: Mode) -> None:
        if self.record_trajectory:
            if len(record.t) >= self.options.max_trajectory_rows:
                raise OscillatorError(
                    f"the trajectory passed max_trajectory_rows = {self.options.max_trajectory_rows} rows at "
                    f"t = {t:.10g} s; record it on a grid (t_eval; --sample DT on the command line) or not at "
                    f"all, shorten t_end, or raise max_trajectory_rows",
                    field="max_trajectory_rows",
                )
            record.t.append(t)
            record.y.append(y[:4].copy())
            record.modes.append(mode)

    def _run(self, record: RunRecord, t0: float, y0, t_end: float) -> None:
        p = self.params
        start = initial_mode(t0, y0, p)
        mode = start.mode
        record.mode_initial = mode
        record.event_count += len(start.events)
        if t0 >= self.keep_events_from:
            record.events.extend(start.events)
        y = np.zeros(8)
        y[:4] = start.y
        t = t0

        grid = self.t_eval
        grid_index = 0
        every_step = grid is None and self.record_trajectory
        chunk = _CHUNK_PERIODS * p.period
        if grid is not None:
            grid = grid[(grid >= t0) & (grid <= t_end)]
            if grid.size and grid[0] == t0:
                self._record(record, t0, y, mode)
                grid_index = 1
        else:
            self._record(record, t0, y, mode)

        record.t_final, record.y_final, record.mode_final = t, y.copy(), mode
        while t < t_end:
            solver, roots = self._problem(mode)
            self._t_ref = t
            self._solver_output.seek(0)
            self._solver_output.truncate()
            solver.init_step(0.0, y)
            record.restarts += 1
            after_root, stalls, last_root, steps = False, 0, -math.inf, 0
            while True:
                on_grid = grid is not None and grid_index < grid.size
                if on_grid:
                    target, method = grid[grid_index], "normal"
                elif every_step:
                    target, method = t_end, "onestep"
                else:  # nothing to record between roots: let CVODE run, returning now and then
                    target, method = min(t_end, t + chunk), "normal"
                with contextlib.redirect_stdout(self._solver_output):
                    out = solver.step(target - self._t_ref, method=method, tstop=t_end - self._t_ref)
                if out.status == _CLOSE_ROOTS and after_root:
                    self._solver_output.seek(0)
                    self._solver_output.truncate()
                    self._t_ref = t
                    solver.init_step(0.0, y)
                    record.restarts += 1
                    after_root = False
                    continue
                if out.status < 0:
                    record.rhs_evaluations += out.nfev
                    raise self._failure(out, t, y, mode)
                record.returns += 1
                reached = out.status == _TSTOP_RETURN or (out.status == 0 and method == "normal")
                t = (t_end if out.status == _TSTOP_RETURN else target) if reached else self._t_ref + float(out.t)
                y = np.array(out.y, dtype=float)
                record.t_final, record.y_final, record.mode_final = t, y, mode
                if self.progress is not None:
                    self._report_progress(t)
                if every_step:
                    self._record(record, t, y, mode)
                    steps = 0 if out.status == _ROOT_RETURN else steps + 1
                    if steps > self.options.max_num_steps:  # CVODE counts only between outputs
                        raise self._too_many_steps(t, y, mode)
                elif on_grid and out.status != _ROOT_RETURN and t == target:
                    self._record(record, t, y, mode)
                    grid_index += 1

                after_root = out.status == _ROOT_RETURN
                if after_root:
                    record.root_returns += 1
                    resolution = self._resolve_root(record, t, y, mode, out, roots)
                    if resolution.mode != mode:
                        y[:4] = resolution.y
                        mode = record.mode_final = resolution.mode
                        if every_step:
                            self._record(record, t, y, mode)
                        record.rhs_evaluations += out.nfev
                        break
                    same_instant = t - last_root <= _SAME_INSTANT * (1.0 + abs(t))
                    stalls = stalls + 1 if same_instant and not resolution.events else 0
                    last_root = t
                    if stalls > _MAX_STALLS:
                        raise OscillatorError(
                            f"the solver keeps stopping at roots at t = {t:.10g} s without a "
                            f"switch (mode {mode}); tighten rtol/atol",
                            field="rtol",
                        )
                if t >= t_end:
                    record.rhs_evaluations += out.nfev
                    break

    def _resolve_root(self, record: RunRecord, t: float, y: np.ndarray, mode: Mode, out, roots) -> Resolution:
        """Hand the roots that fired at ``t`` to :func:`switching.resolve` and record the events."""
        violation = mode_violation(t, y, self.params, mode, _CONSISTENCY)
        if violation is not None:
            raise OscillatorError(
                f"the state crossed {violation} unseen before t = {t:.10g} s in mode {mode}; "
                f"lower max_step_fraction or tighten rtol/atol",
                field="max_step_fraction",
            )
        fired = [Root(i) for i in np.flatnonzero(out.i_events[-1])]
        # scikit-sundae keeps every root in Python lists for the solver's lifetime; empty them
        # so that memory stays flat in the length of the run.
        roots._i.clear()
        roots._t.clear()
        roots._y.clear()
        resolution = resolve(t, y, self.params, mode, fired, self.options)
        record.event_count += len(resolution.events)
        if t >= self.keep_events_from:
            record.events.extend(resolution.events)
        self._guard_storm(resolution.events)
        if record.event_count > self.options.max_events:
            last = resolution.events[-1]
            raise OscillatorError(
                f"more than max_events = {self.options.max_events} switching events by "
                f"t = {t:.10g} s (last: mass {last.mass} {last.kind} on {last.boundary}); "
                f"raise max_events or shorten t_end",
                field="max_events",
            )
        return resolution

    def _guard_storm(self, events: Iterable[Event]) -> None:
        """Stop when more than ``storm_events`` events fall within ``storm_window`` seconds."""
        recent = self._recent
        recent.extend(events)
        if len(recent) < recent.maxlen or recent[-1].t - recent[0].t > self.options.storm_window:
            return
        tally = collections.Counter((e.mass, e.kind, e.boundary) for e in recent)
        (mass, kind, boundary), count = tally.most_common(1)[0]
        raise OscillatorError(
            f"event storm: {len(recent)} events within {recent[-1].t - recent[0].t:.3g} s up to "
            f"t = {recent[-1].t:.10g} s, {count} of them mass {mass} {kind} on {boundary}; the motion chatters "
            f"there. Change the case, or raise storm_events (now {self.options.storm_events}) or lower "
            f"storm_window (now {self.options.storm_window:g} s) if such a rate is meant",
            field="storm_events",
        )

    def _too_many_steps(self, t: float, y: np.ndarray, mode: Mode) -> OscillatorError:
        """CVODE's ``max_num_steps`` failure, for steps taken one at a time (each one an output)."""
        x1, v1, x2, v2 = (float(v) for v in y[:4])
        return OscillatorError(
            f"CVODE took more than max_num_steps = {self.options.max_num_steps} steps without a switch up to "
            f"t = {t:.10g} s in domains m1: {mode.domain1}, m2: {mode.domain2} (state {mode.system_state}; "
            f"x1={x1:.6g}, v1={v1:.6g}, x2={x2:.6g}, v2={v2:.6g}); loosen rtol/atol or raise max_num_steps",
            field="max_num_steps",
        )

    def _failure(self, out, t: float, y: np.ndarray, mode: Mode) -> OscillatorError:
        """CVODE's failure, told with the last point it reached (its output is undefined then)."""
        x1, v1, x2, v2 = (float(v) for v in y[:4])
        said = " ".join(self._solver_output.getvalue().split())
        detail = f"{out.message}; CVODE: {said}" if said else out.message
        return OscillatorError(
            f"CVODE failed after t = {t:.10g} s with flag {out.status} "
            f"({detail}) in domains m1: {mode.domain1}, m2: {mode.domain2} "
            f"(state {mode.system_state}; x1={x1:.6g}, v1={v1:.6g}, x2={x2:.6g}, v2={v2:.6g}); "
            f"loosen rtol/atol or raise max_num_steps",
            field="rtol",
        )
