"""The guards that stop a run which would otherwise not end or would run on wrong numbers.

Each one raises :class:`~oscillator.errors.SimulationFailed` naming the option that sets it:
event storms (``storm_events`` in ``storm_window``), roots that return without a switch
(stall), a state found on the wrong side of its mode's boundary (``max_step_fraction``), too many
steps without a switch (``max_num_steps``), too many events (``max_events``); and a start that
cannot be evaluated (:func:`start_problem`).
"""

from __future__ import annotations

import collections
import math

import numpy as np

from oscillator.engines import describe
from oscillator.errors import OscillatorError, Reason, SimulationFailed
from oscillator.model.energy import mechanical_energy
from oscillator.model.events import COLUMN, decode, event_of_row
from oscillator.model.fields import coefficients
from oscillator.model.kernels import derivative
from oscillator.model.parameters import Parameters, SolverOptions
from oscillator.model.phase_space import Mode
from oscillator.model.resolving import initial_mode
from oscillator.model.roots import NUM_ROOTS, mode_violation, root_kernel

__all__ = [
    "ARITHMETIC_ERRORS",
    "EventGuard",
    "StallGuard",
    "StepGuard",
    "check_consistent",
    "start_problem",
    "strict_arithmetic",
]

#: What :func:`strict_arithmetic` and Python's own float arithmetic raise when numbers leave
#: floating point.
ARITHMETIC_ERRORS = (FloatingPointError, OverflowError, ZeroDivisionError)

#: Root returns at one instant without a switch before the supervisor declares a stall.
MAX_STALLS = 100
#: Two root returns closer than this (relative to the time) are at one instant.
SAME_INSTANT = 1e-12
#: How far (relative) the state may stand on the wrong side of a boundary of its mode at a root.
CONSISTENCY = 1e-9


def strict_arithmetic() -> np.errstate:
    """Overflow and invalid arithmetic raise instead of spreading inf and nan through the decisions."""
    return np.errstate(over="raise", invalid="raise", divide="raise")


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


def _where(mode: Mode, y: np.ndarray) -> str:
    x1, v1, x2, v2 = (float(v) for v in y[:4])
    return (
        f"domains m1: {mode.domain1}, m2: {mode.domain2} (state {mode.system_state}; "
        f"x1={x1:.6g}, v1={v1:.6g}, x2={x2:.6g}, v2={v2:.6g})"
    )


def solver_failure(engine: str, detail: str, flag: int | str, t: float, y: np.ndarray, mode: Mode) -> SimulationFailed:
    """The integrator's failure, told with the last point it reached (its output is undefined then)."""
    name = describe(engine).solver
    return SimulationFailed(
        f"{name} failed after t = {t:.10g} s with flag {flag} ({detail}) in {_where(mode, y)}; "
        f"loosen rtol/atol or raise max_num_steps",
        reason=Reason.SOLVER_FAILURE,
        field="rtol",
    )


def check_consistent(t: float, y: np.ndarray, p: Parameters, mode: Mode) -> None:
    """At a root the state must stand in its mode: else a boundary was crossed between two steps."""
    violation = mode_violation(t, y, p, mode, CONSISTENCY)
    if violation is not None:
        raise SimulationFailed(
            f"the state crossed {violation} unseen before t = {t:.10g} s in mode {mode}; "
            f"lower max_step_fraction or tighten rtol/atol",
            reason=Reason.UNSEEN_CROSSING,
            field="max_step_fraction",
        )


class StepGuard:
    """Steps taken one at a time (each one an output) without a switch: CVODE counts only between
    outputs, so ``max_num_steps`` is enforced here."""

    def __init__(self, options: SolverOptions, engine: str = "cvode") -> None:
        self.limit = options.max_num_steps
        self.steps = 0
        self.solver = describe(engine).solver

    @property
    def room(self) -> int:
        """How many steps may still be taken before the guard trips (the one that trips it included)."""
        return self.limit - self.steps + 1

    def count_many(self, n: int, at_root: bool, t: float, y: np.ndarray, mode: Mode) -> None:
        """``n`` returns at once, the last one at ``(t, y)`` (a root, or a step)."""
        self.steps += n - 1
        self.count(at_root, t, y, mode)

    def count(self, at_root: bool, t: float, y: np.ndarray, mode: Mode) -> None:
        self.steps = 0 if at_root else self.steps + 1
        if self.steps > self.limit:
            raise SimulationFailed(
                f"{self.solver} took more than max_num_steps = {self.limit} steps without a switch up to "
                f"t = {t:.10g} s in {_where(mode, y)}; loosen rtol/atol or raise max_num_steps",
                reason=Reason.STEP_LIMIT,
                field="max_num_steps",
            )


class StallGuard:
    """Root returns at one instant that switch nothing: more than :data:`MAX_STALLS` is a stall."""

    def __init__(self) -> None:
        self.stalls = 0
        self.last_root = -math.inf

    def count(self, t: float, events: int, mode: Mode) -> None:
        """A root return at ``t`` that gave ``events`` events and left the run in ``mode``."""
        same_instant = t - self.last_root <= SAME_INSTANT * (1.0 + abs(t))
        self.stalls = self.stalls + 1 if same_instant and not events else 0
        self.last_root = t
        if self.stalls > MAX_STALLS:
            raise SimulationFailed(
                f"the solver keeps stopping at roots at t = {t:.10g} s without a switch (mode {mode}); "
                f"tighten rtol/atol",
                reason=Reason.STALL,
                field="rtol",
            )


# The storm guard reads an event row's first four columns: the time, then what tells events apart.
assert [COLUMN[name] for name in ("t", "mass", "kind", "boundary")] == [0, 1, 2, 3]


class EventGuard:
    """More than ``max_events`` events in all, or more than ``storm_events`` within ``storm_window`` s."""

    def __init__(self, options: SolverOptions) -> None:
        self.options = options
        #: ``[t, mass, kind, boundary]`` of the latest events (codes, as in an event row).
        self.recent: collections.deque[list[float]] = collections.deque(maxlen=options.storm_events + 1)

    def count(self, rows: np.ndarray, total: int, t: float) -> None:
        """New events (event rows) at ``t``, ``total`` events in all so far."""
        if not len(rows):
            return
        self._storm(rows)
        if total > self.options.max_events:
            last = event_of_row(rows[-1])
            raise SimulationFailed(
                f"more than max_events = {self.options.max_events} switching events by t = {t:.10g} s (last: mass "
                f"{last.mass} {last.kind} on {last.boundary}); raise max_events or shorten t_end",
                reason=Reason.MAX_EVENTS,
                field="max_events",
            )

    def _storm(self, rows: np.ndarray) -> None:
        recent = self.recent
        recent.extend(rows[:, :4].tolist())
        if len(recent) < (recent.maxlen or 0) or recent[-1][0] - recent[0][0] > self.options.storm_window:
            return
        tally = collections.Counter((mass, kind, boundary) for _, mass, kind, boundary in recent)
        (mass, kind, boundary), count = tally.most_common(1)[0]
        what = f"{decode('kind', kind, mass)} on {decode('boundary', boundary, mass)}"
        raise SimulationFailed(
            f"event storm: {len(recent)} events within {recent[-1][0] - recent[0][0]:.3g} s up to "
            f"t = {recent[-1][0]:.10g} s, {count} of them mass {mass:.0f} {what}; the "
            f"motion chatters there. Change the case, or raise storm_events (now {self.options.storm_events}) or "
            f"lower storm_window (now {self.options.storm_window:g} s) if such a rate is meant",
            reason=Reason.STORM,
            field="storm_events",
        )
