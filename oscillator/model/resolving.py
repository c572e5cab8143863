"""The switching rules' entry points: the roots that fired at an instant resolved into the next
mode and its events (:func:`resolve_rows`, called by the supervisor at every root, writing rows
into the run's event log; :func:`resolve`, the same as records), and the mode at the start
(:func:`initial_mode`).  The rules themselves are compiled, in :mod:`oscillator.model.switching`
(:func:`~oscillator.model.switching.resolve_compiled`)."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from oscillator.errors import Reason, SimulationFailed
from oscillator.model.events import WIDTH, Event, event_of_row
from oscillator.model.fields import coefficients
from oscillator.model.parameters import Parameters, SolverOptions
from oscillator.model.phase_space import Mode
from oscillator.model.switching import MAX_ROWS, initial_compiled, resolve_compiled
from oscillator.model.types import StateLike

__all__ = ["MAX_ROWS", "Resolution", "initial_mode", "resolve", "resolve_rows"]


def _numbers(mode: Mode) -> tuple[int, int, int, int]:
    return (mode.sign(1), mode.sign(2), int(mode.left), int(mode.right))


def _storm(t: float, mode: Mode) -> SimulationFailed:
    return SimulationFailed(
        f"event storm at t = {t:.10g} s: the masses keep switching at one instant "
        f"(mode {mode}); the flow barrier and the fields contradict each other here — check "
        f"mu_s >= mu_k and the contact parameters",
        reason=Reason.STORM,
        field="mu_s",
    )


def resolve_rows(
    t: float,
    y: np.ndarray,
    p: Parameters,
    mode: Mode,
    fired: int,
    options: SolverOptions,
    out: np.ndarray,
    start: int,
) -> tuple[Mode, int]:
    """Resolve the roots that fired at ``t`` (the bits ``1 << root``) into the next mode.

    The events are written as rows ``out[start:]`` (:data:`oscillator.model.events.COLUMN`;
    ``out`` must have :data:`MAX_ROWS` rows free); returns the next mode and how many events.
    ``y[:4]`` is projected in place: the velocity of a mass that reached its velocity boundary
    is set to exactly zero (it is zero to the solver's accuracy), so that a resting mass has
    ``v_i = 0`` identically.

    Raises
    ------
    SimulationFailed
        The masses keep switching at the instant (an event storm).
    """
    (s1, s2, left, right), end, settled = resolve_compiled(
        float(t),
        y,
        coefficients(p),
        p.period,
        _numbers(mode),
        fired,
        options.grazing_velocity_tolerance,
        options.grazing_displacement_tolerance,
        out,
        start,
    )
    after = Mode.from_signs(s1, s2, left=bool(left), right=bool(right))
    if not settled:
        raise _storm(t, after)
    return after, end - start


@dataclass(frozen=True, slots=True)
class Resolution:
    """What one instant resolved to: the next mode, the events (as rows), and the (projected) state."""

    mode: Mode
    rows: np.ndarray
    y: tuple[float, float, float, float]

    @property
    def events(self) -> tuple[Event, ...]:
        """The events as :class:`~oscillator.model.events.Event` records."""
        return tuple(event_of_row(row) for row in self.rows)


def resolve(
    t: float,
    y: StateLike,
    p: Parameters,
    mode: Mode,
    fired: Iterable[int],
    options: SolverOptions,
) -> Resolution:
    """Resolve the roots that fired at ``t`` into the next mode and the event records
    (:func:`resolve_rows` on a copy of the state)."""
    state = np.array([float(v) for v in y[:4]])
    out = np.empty((MAX_ROWS, WIDTH))
    bits = sum(1 << int(root) for root in set(fired))
    after, count = resolve_rows(t, state, p, mode, bits, options, out, 0)
    return Resolution(after, out[:count].copy(), (float(state[0]), float(state[1]), float(state[2]), float(state[3])))


def initial_mode(t0: float, y: StateLike, p: Parameters) -> Resolution:
    """The mode at the start, and the masses that leave rest at once (docs/model.md, rule 8).

    A mass given ``v_i = 0`` is at rest; it leaves at ``t0`` only if Theorem 5.4 holds.
    Contacts follow ``z1 <= -d`` and ``x1 >= d1``.  Exactly on a stop, the contact counts if the
    velocity points into it; with zero velocity there the contact force vanishes, so both
    choices give the same field at ``t0`` and the acceleration decides (the integrator never
    reports a crossing that starts exactly at its initial time).  The rules are compiled
    (:func:`~oscillator.model.switching.initial_compiled`, which the compiled landings call too).
    """
    x1, v1, x2, v2 = (float(v) for v in y[:4])
    out = np.empty((2 * MAX_ROWS, WIDTH))
    (s1, s2, left, right), count, settled = initial_compiled(
        float(t0), np.array([x1, v1, x2, v2]), coefficients(p), p.period, out
    )
    mode = Mode.from_signs(s1, s2, left=bool(left), right=bool(right))
    if not settled:
        raise _storm(t0, mode)
    return Resolution(mode, out[:count].copy(), (x1, v1, x2, v2))
