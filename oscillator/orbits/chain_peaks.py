"""The peaks of a friction chain's run (issue 52's measures): each mass's largest acceleration and
each stop's and contact's largest force, exact to the solver's tolerance.

A run's trajectory holds a row at every solver step and every event, each with its mode.  Within a
smooth piece the quantity ``f`` (a mass's acceleration, a closed stop's or contact's force) and its
rate ``f'`` are known at both rows of each step from the chain's field in the left row's mode
(:func:`~oscillator.model.chain_fields.chain_derivative`, its derivative
:func:`~oscillator.model.chain_fields.chain_jacobian`: ``y'' = J y' + df/dt``;
:func:`~oscillator.model.chain_fields.element_rate`); where ``f'`` changes sign inside a step,
the cubic through both rows' values and rates has its turn there (Hermite: exact to the step's
fourth power).  The peak is the largest ``|f|`` over the rows (the left and the right limit of a
switch both: an impact with damping, a mass that sticks, change the acceleration at once) and
over those turns.
"""

from __future__ import annotations

import functools
from collections.abc import Callable

import numpy as np

from oscillator.hybrid.chain_run import ChainResult
from oscillator.model.chain_fields import arrays_of, chain_derivative, chain_jacobian, element_force, element_rate, pack

__all__ = ["hermite_turns", "peaks", "quintic"]

#: The element types whose force is a contact's.
_CONTACTS = ("stop", "contact")


def hermite_turns(f0: float, d0: float, f1: float, d1: float) -> list[float]:
    """Where inside ``(0, 1)`` the cubic with values ``f0``, ``f1`` and rates ``d0``, ``d1`` (per
    unit of ``s``) at ``s = 0, 1`` turns."""
    step = f1 - f0
    a, b, c = 3.0 * (d0 + d1 - 2.0 * step), 2.0 * (3.0 * step - 2.0 * d0 - d1), d0  # p'(s) = a s^2 + b s + c
    roots = np.roots([a, b, c]) if abs(a) > 1e-300 or abs(b) > 1e-300 else np.empty(0)
    return [float(r.real) for r in np.atleast_1d(roots) if abs(r.imag) < 1e-12 and 0.0 < r.real < 1.0]


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


def peaks(run: ChainResult) -> dict[str, float]:
    """``a_max:<mass>`` (m/s^2: the largest ``|x''|`` of each mass) and ``force_max:<element>`` (N:
    the largest ``|force|`` of each stop and contact while closed, 0 if it never closes) over
    ``run`` (module docstring)."""
    chain, trajectory = run.chain, run.trajectory
    t = trajectory.t.to_numpy(float)
    states = trajectory[list(chain.system.state)].to_numpy(float)
    modes, field = run.modes(), _Field(run)
    contacts = [(k, e.name) for k, e in enumerate(chain.elements) if e.type in _CONTACTS]
    best = {f"a_max:{m.name}": 0.0 for m in chain.masses} | {f"force_max:{name}": 0.0 for _, name in contacts}
    own = [pack(field.arrays, modes[k]) for k in range(len(t))]
    values = [field.at(t[k], states[k], own[k]) for k in range(len(t))]
    for k in range(len(t) - 1):
        left, data = values[k], own[k]
        right = values[k + 1] if np.array_equal(modes[k], modes[k + 1]) else field.at(t[k + 1], states[k + 1], data)
        step = _Step(t[k], t[k + 1] - t[k], (states[k], *left, states[k + 1], *right), data, field)
        for i, mass in enumerate(chain.masses):
            ends = (left[0][2 * i + 1], left[1][2 * i + 1], right[0][2 * i + 1], right[1][2 * i + 1])
            key = f"a_max:{mass.name}"
            best[key] = max(best[key], *step.magnitudes(ends, functools.partial(_acceleration, i)))
        for row, name in contacts:
            if modes[k, row] != 0.0:
                ends = (
                    element_force(t[k], states[k], data, row),
                    element_rate(t[k], states[k], left[0], data, row),
                    element_force(t[k + 1], states[k + 1], data, row),
                    element_rate(t[k + 1], states[k + 1], right[0], data, row),
                )
                key = f"force_max:{name}"
                best[key] = max(best[key], *step.magnitudes(ends, functools.partial(_contact_force, row)))
    return best


def _acceleration(i: int, t: float, y: np.ndarray, rate: np.ndarray, data: np.ndarray) -> float:
    """Mass ``i``'s acceleration, from the field's ``rate`` at ``(t, y)``."""
    return float(rate[2 * i + 1])


def _contact_force(row: int, t: float, y: np.ndarray, rate: np.ndarray, data: np.ndarray) -> float:
    """Element ``row``'s force at ``(t, y)`` in the mode ``data``."""
    return float(element_force(t, y, data, row))


class _Step:
    """One solver step of a smooth piece: its start ``t0``, length ``h``, its ends' states, rates
    and second rates, and its mode's data."""

    def __init__(self, t0: float, h: float, ends: tuple[np.ndarray, ...], data: np.ndarray, field: _Field) -> None:
        self.t0, self.h, self.ends, self.data, self.field = t0, h, ends, data, field

    def magnitudes(self, ends: tuple[float, float, float, float], value: Callable[..., float]) -> list[float]:
        """``|f|`` at both ends (values and rates ``ends``), and at the turn where the rate changes
        sign inside the step: found on the cubic through both ends, its value
        ``value(t, y, y', data)`` at the quintic's state there (a step of length 0, at an event,
        has no turn; two turns in one solver step, where the rate keeps its sign, would be a
        wiggle the solver's tolerance does not resolve)."""
        f0, r0, f1, r1 = ends
        found = [abs(f0), abs(f1)]
        if self.h > 0.0 and r0 * r1 < 0.0:
            for s in hermite_turns(f0, r0 * self.h, f1, r1 * self.h):
                tt = self.t0 + s * self.h
                y = quintic(s, self.h, self.ends)
                found.append(abs(value(tt, y, self.field.at(tt, y, self.data)[0], self.data)))
        return found
