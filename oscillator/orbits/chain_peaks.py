"""The peaks of a friction chain's run (issue 52's measures): each mass's largest acceleration and
each stop's and contact's largest force, exact to the solver's tolerance.

A run's trajectory holds a row at every solver step and every event, each with its mode.  Within a
smooth piece the quantity ``f`` (a mass's acceleration, a closed stop's or contact's force) and its
rate ``f'`` are known at both rows of each step from the chain's field in the left row's mode
(:func:`~oscillator.model.chain_fields.chain_derivative`, its derivative
:func:`~oscillator.model.chain_fields.chain_jacobian`: ``y'' = J y' + df/dt``;
:func:`~oscillator.model.chain_fields.element_rate`); where ``f'`` changes sign inside a step,
the turn is the root of ``f'`` along the quintic through both rows' states, rates and second
rates (Hermite: exact to the step's sixth power), found by Brent's method, and ``f`` is valued
there from the field.  The peak is the largest ``|f|`` over the rows (the left and the right
limit of a switch both: an impact with damping, a mass that sticks, change the acceleration at
once) and over those turns.  The turn is located as well as the value (``f' = 0`` there to the
interpolant's accuracy), so that a peak's derivative in a number is the quantity's at that fixed
time (:mod:`oscillator.orbits.chain_sensitivity`).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from oscillator.hybrid.chain_run import ChainResult
from oscillator.model.chain_fields import arrays_of, chain_derivative, chain_jacobian, element_force, element_rate, pack

__all__ = ["Peak", "peak_places", "peaks", "quintic"]

#: The element types whose force is a contact's.
_CONTACTS = ("stop", "contact")


def quintic(s: float, h: float, ends: tuple[np.ndarray, ...]) -> np.ndarray:
    """The state at ``s`` (0 to 1) of a step of length ``h`` from its ends' states, rates and
    second rates ``(y0, y0', y0'', y1, y1', y1'')``: the quintic Hermite through them (exact to
    the step's sixth power)."""
    y0, r0, a0, y1, r1, a1 = ends
    h00 = 1 - 10 * s**3 + 15 * s**4 - 6 * s**5
    h10 = s - 6 * s**3 + 8 * s**4 - 3 * s**5
    h20 = (s**2 - 3 * s**3 + 3 * s**4 - s**5) / 2
    h01 = 10 * s**3 - 15 * s**4 + 6 * s**5
    h11 = -4 * s**3 + 7 * s**4 - 3 * s**5
    h21 = (s**3 - 2 * s**4 + s**5) / 2
    return h00 * y0 + h10 * h * r0 + h20 * h * h * a0 + h01 * y1 + h11 * h * r1 + h21 * h * h * a1


class _Field:
    """The field's value and second derivative at rows, in a given mode."""

    def __init__(self, run: ChainResult) -> None:
        self.chain, self.arrays = run.chain, arrays_of(run.chain)
        self.size = run.chain.system.size
        self.rate, self.jacobian, self.partial = (
            np.empty(self.arrays.size),
            np.empty((self.size,) * 2),
            np.empty(self.size),
        )

    def at(self, t: float, y: np.ndarray, data: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(y', y'')`` at ``(t, y)`` in the packed mode ``data``."""
        chain_derivative(t, y, self.rate, data)
        first = self.rate[: self.size].copy()
        chain_jacobian(t, y, data, self.jacobian, self.partial)
        return first, self.jacobian @ first + self.partial


@dataclass(frozen=True)
class Peak:
    """Where a peak is: the quantity's signed ``value`` there, the time, the state and the mode
    (one number per element) whose field gives it (at a switch: the side it is on)."""

    value: float
    t: float
    y: np.ndarray
    mode: np.ndarray


def peaks(run: ChainResult) -> dict[str, float]:
    """``a_max:<mass>`` (m/s^2: the largest ``|x''|`` of each mass) and ``force_max:<element>`` (N:
    the largest ``|force|`` of each stop and contact while closed, 0 if it never closes) over
    ``run`` (module docstring)."""
    return {name: abs(peak.value) for name, peak in peak_places(run).items()}


def peak_places(run: ChainResult) -> dict[str, Peak]:
    """:func:`peaks` with where each is (a stop or contact that never closes: value 0 at the
    run's start)."""
    chain, trajectory = run.chain, run.trajectory
    t = trajectory.t.to_numpy(float)
    states = trajectory[list(chain.system.state)].to_numpy(float)
    modes, field = run.modes(), _Field(run)
    contacts = [(k, e.name) for k, e in enumerate(chain.elements) if e.type in _CONTACTS]
    names = [f"a_max:{m.name}" for m in chain.masses] + [f"force_max:{name}" for _, name in contacts]
    best = {name: Peak(0.0, float(t[0]), states[0], modes[0]) for name in names}
    passed = {mode.tobytes(): mode for mode in modes}  # each mode the run passed, packed once
    packed = {key: pack(field.arrays, mode) for key, mode in passed.items()}  # (the calls rewrite its scratch)
    own = [packed[mode.tobytes()] for mode in modes]
    values = [field.at(t[k], states[k], own[k]) for k in range(len(t))]
    for k in range(len(t) - 1):
        left, data = values[k], own[k]
        right = values[k + 1] if np.array_equal(modes[k], modes[k + 1]) else field.at(t[k + 1], states[k + 1], data)
        step = _Step((t[k], t[k + 1]), (states[k], *left, states[k + 1], *right), modes[k], data, field)
        for i, mass in enumerate(chain.masses):
            ends = (left[0][2 * i + 1], left[1][2 * i + 1], right[0][2 * i + 1], right[1][2 * i + 1])
            _keep(best, f"a_max:{mass.name}", step.candidates(ends, functools.partial(_acceleration, i)))
        for row, name in contacts:
            if modes[k, row] != 0.0:
                ends = (
                    element_force(t[k], states[k], data, row),
                    element_rate(t[k], states[k], left[0], data, row),
                    element_force(t[k + 1], states[k + 1], data, row),
                    element_rate(t[k + 1], states[k + 1], right[0], data, row),
                )
                _keep(best, f"force_max:{name}", step.candidates(ends, functools.partial(_contact_force, row)))
    return best


def _keep(best: dict[str, Peak], name: str, candidates: list[Peak]) -> None:
    for candidate in candidates:
        if abs(candidate.value) > abs(best[name].value):
            best[name] = candidate


def _acceleration(
    i: int, t: float, y: np.ndarray, rate: np.ndarray, second: np.ndarray, data: np.ndarray
) -> tuple[float, float]:
    """Mass ``i``'s acceleration and its rate, from the field's ``rate`` and ``second`` rate at
    ``(t, y)``."""
    return float(rate[2 * i + 1]), float(second[2 * i + 1])


def _contact_force(
    row: int, t: float, y: np.ndarray, rate: np.ndarray, second: np.ndarray, data: np.ndarray
) -> tuple[float, float]:
    """Element ``row``'s force at ``(t, y)`` in the mode ``data``, and its rate along ``rate``."""
    return float(element_force(t, y, data, row)), float(element_rate(t, y, rate, data, row))


class _Step:
    """One solver step of a smooth piece: its ends' times, states, rates and second rates, and
    its mode (and the mode's data)."""

    def __init__(
        self,
        times: tuple[float, float],
        ends: tuple[np.ndarray, ...],
        mode: np.ndarray,
        data: np.ndarray,
        field: _Field,
    ) -> None:
        self.times, self.h, self.ends = times, times[1] - times[0], ends
        self.mode, self.data, self.field = mode, data, field

    def candidates(
        self, ends: tuple[float, float, float, float], quantity: Callable[..., tuple[float, float]]
    ) -> list[Peak]:
        """The quantity at both ends (values and rates ``ends``), and where its rate changes sign
        inside the step: the root of ``quantity(t, y, y', y'', data)``'s rate along the quintic's
        state, by Brent's method to the last bit (a step of length 0, at an event, has none; two
        turns in one solver step, where the rate keeps its sign, would be a wiggle the solver's
        tolerance does not resolve)."""
        f0, r0, f1, r1 = ends
        found = [Peak(f0, self.times[0], self.ends[0], self.mode), Peak(f1, self.times[1], self.ends[3], self.mode)]
        if self.h > 0.0 and r0 * r1 < 0.0:
            s = brentq(lambda s: self._at(s, quantity)[1], 0.0, 1.0, xtol=1e-15, rtol=4 * np.finfo(float).eps)
            tt, y = self.times[0] + s * self.h, quintic(s, self.h, self.ends)
            found.append(Peak(self._at(s, quantity)[0], tt, y, self.mode))
        return found

    def _at(self, s: float, quantity: Callable[..., tuple[float, float]]) -> tuple[float, float]:
        """The quantity and its rate at ``s`` (0 to 1) of the step, at the quintic's state."""
        t, y = self.times[0] + s * self.h, quintic(s, self.h, self.ends)
        return quantity(t, y, *self.field.at(t, y, self.data), self.data)
