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

The field, its second rate and the contacts' forces at every row are computed in one compiled
pass over the rows (each mode the run passed packed once); only the turns, a few a period, are
sought one by one.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from oscillator.compiled import njit
from oscillator.hybrid.chain_run import ChainResult
from oscillator.model.chain_fields import arrays_of, chain_derivative, chain_jacobian, element_force, element_rate, pack

__all__ = [
    "Peak",
    "Sides",
    "impulses",
    "nodes_of",
    "peak_places",
    "peaks",
    "quintic",
    "rates_at",
    "sides",
    "slip_steps",
    "within",
]

#: The element types whose force is a contact's.
_CONTACTS = ("stop", "contact")


def quintic(s: float | np.ndarray, h: float | np.ndarray, ends: tuple[np.ndarray, ...]) -> np.ndarray:
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


@dataclass(frozen=True)
class Sides:
    """The field at both ends of every step of a run, each in the step's mode, with the stops' and
    contacts' forces (:func:`sides`): computed once, read by :func:`peak_places`,
    :func:`impulses` and :func:`slip_steps`."""

    field: _Field
    contacts: list[int]
    left: _Rows
    right: _Rows
    data: list[np.ndarray]


def sides(run: ChainResult) -> Sides:
    """The run's :class:`Sides`: one compiled pass over its rows."""
    field = _Field(run)
    contacts = [k for k, e in enumerate(run.chain.elements) if e.type in _CONTACTS]
    left, right, data = _ends(field, run.times, run.states, run.modes(), contacts)
    return Sides(field, contacts, left, right, data)


def within(run: ChainResult, at: Sides, steps: tuple[int, int], times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The field ``y'`` and the stops' and contacts' forces (in ``at.contacts``' order) at
    ``times`` inside the run's steps ``first`` to ``last`` (``steps``; from ``t[first]`` to
    ``t[last + 1]``, all in one mode), each at the quintic's state through its step's ends, in the
    mode: arrays ``(len(times), state)`` and ``(len(times), contacts)``."""
    t, states = run.times, run.states
    first, last = steps
    times = np.asarray(times, dtype=float)
    k = np.clip(np.searchsorted(t, times, side="right") - 1, first, last)
    h = (t[k + 1] - t[k])[:, None]
    y = quintic((times[:, None] - t[k][:, None]) / h, h, _step_ends(states, at, k))
    which = np.zeros(len(y), dtype=np.int64)
    found = _rows_at(at.field, times, y, at.data[first][None, :], which, np.asarray(at.contacts, np.int64))
    return found.rates, found.forces


def nodes_of(run: ChainResult, at: Sides, steps: np.ndarray, where: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The times at the fractions ``where`` (0 to 1) of each of the run's ``steps`` (the step
    from ``t[k]`` to ``t[k + 1]`` for each ``k``) and the quintic's states there through each
    step's ends: arrays ``(steps, where)`` and ``(steps, where, state)``."""
    t = run.times
    h = t[steps + 1] - t[steps]
    times = t[steps][:, None] + where[None, :] * h[:, None]
    ends = tuple(end[:, None, :] for end in _step_ends(run.states, at, steps))
    return times, quintic(where[None, :, None], h[:, None, None], ends)


def _step_ends(states: np.ndarray, at: Sides, k: np.ndarray) -> tuple[np.ndarray, ...]:
    """The ends of the steps ``k`` (from row ``k`` to ``k + 1``) as :func:`quintic` takes them."""
    return (states[k], at.left.rates[k], at.left.seconds[k], states[k + 1], at.right.rates[k], at.right.seconds[k])


def peaks(run: ChainResult, at: Sides | None = None) -> dict[str, float]:
    """``a_max:<mass>`` (m/s^2: the largest ``|x''|`` of each mass) and ``force_max:<element>`` (N:
    the largest ``|force|`` of each stop and contact while closed, 0 if it never closes) over
    ``run`` (module docstring); ``at`` its :func:`sides` if computed already."""
    return {name: abs(peak.value) for name, peak in peak_places(run, at).items()}


def peak_places(run: ChainResult, at: Sides | None = None) -> dict[str, Peak]:
    """:func:`peaks` with where each is (a stop or contact that never closes: value 0 at the
    run's start).  Each quantity's candidates, in the run's order (each step's left end, its
    right end, its turn), are valued at once; the first of the largest is the peak."""
    chain, t, states, modes = run.chain, run.times, run.states, run.modes()
    at = at or sides(run)
    field, rows, left, right, data = at.field, at.contacts, at.left, at.right, at.data
    best: dict[str, Peak] = {}
    for i, mass in enumerate(chain.masses):
        ends = (
            left.rates[:, 2 * i + 1],
            left.seconds[:, 2 * i + 1],
            right.rates[:, 2 * i + 1],
            right.seconds[:, 2 * i + 1],
        )
        quantity = functools.partial(_acceleration, i)
        best[f"a_max:{mass.name}"] = _largest(
            (t, states, modes, data), field, (left, right), ends, quantity, np.ones(len(t) - 1, bool)
        )
    for c, row in enumerate(rows):
        ends = (left.forces[:, c], left.force_rates[:, c], right.forces[:, c], right.force_rates[:, c])
        closed = modes[:-1, row] != 0.0
        quantity = functools.partial(_contact_force, row)
        best[f"force_max:{chain.elements[row].name}"] = _largest(
            (t, states, modes, data), field, (left, right), ends, quantity, closed
        )
    return best


def impulses(run: ChainResult, at: Sides | None = None) -> dict[str, float]:
    """Each stop's and contact's force integrated over ``run`` while closed (N s; the force on its
    ``on`` mass, :func:`~oscillator.model.chain_fields.element_force`).  A closed element's force
    is affine in the state, so each step's integral is the step's length times the force at the
    step's mean state, and the mean state is the integral of the quintic through both rows' states,
    rates and second rates, ``(y0 + y1) / 2 + h (y0' - y1') / 10 + h^2 (y0'' + y1'') / 120``
    (exact to the step's seventh power, as the quintic is to its sixth); ``at`` the run's
    :func:`sides` if computed already."""
    chain, t, states, modes = run.chain, run.times, run.states, run.modes()
    rows = [k for k, e in enumerate(chain.elements) if e.type in _CONTACTS]
    if not rows or len(t) < 2:
        return {chain.elements[row].name: 0.0 for row in rows}
    at = at or sides(run)
    left, right, data = at.left, at.right, at.data
    h = np.diff(t)[:, None]
    mean = (
        (states[:-1] + states[1:]) / 2
        + h * (left.rates[:-1] - right.rates) / 10
        + h * h * (left.seconds[:-1] + right.seconds) / 120
    )
    found = {}
    for row in rows:
        closed = np.flatnonzero((modes[:-1, row] != 0.0) & (h[:, 0] > 0.0))
        middle = (t[:-1] + t[1:]) / 2
        total = sum(float(h[k, 0] * element_force(middle[k], mean[k], data[k], row)) for k in closed.tolist())
        found[chain.elements[row].name] = total
    return found


def slip_steps(run: ChainResult, at: Sides | None = None) -> dict[str, list[float]]:
    """Each friction element's steps of its mass's acceleration (m/s^2) where the mass sticks to
    its floor or belt or slips off it, in the run's order: ``|a(t+) - a(t-)|``, the field at the
    switch's row in its own mode against the step before's (the jerk there is an impulse of this
    size).  Slipping off, the force that held the mass passes from the static threshold to the
    kinetic one: the step is ``(mu_s - mu_k) N / m``; ``at`` the run's :func:`sides` if computed
    already."""
    chain, t, modes = run.chain, run.times, run.modes()
    found: dict[str, list[float]] = {}
    sliding = [(row, e) for row, e in enumerate(chain.elements) if e.type == "friction"]
    if not sliding or len(t) < 2:
        return {e.name: [] for _, e in sliding}
    at = at or sides(run)
    own, right = at.left, at.right
    masses = [mass.name for mass in chain.masses]
    for row, element in sliding:
        i = masses.index(element.on)
        turned = np.flatnonzero((modes[:-1, row] == 0.0) != (modes[1:, row] == 0.0)).tolist()
        found[element.name] = [abs(float(own.rates[k + 1, 2 * i + 1] - right.rates[k, 2 * i + 1])) for k in turned]
    return found


@dataclass(frozen=True)
class _Rows:
    """The field at rows, each in a given mode: the rates and second rates ``(rows, state)``, the
    contacts' forces and their rates ``(rows, contacts)``."""

    rates: np.ndarray
    seconds: np.ndarray
    forces: np.ndarray
    force_rates: np.ndarray


def _ends(
    field: _Field, t: np.ndarray, states: np.ndarray, modes: np.ndarray, rows: list[int]
) -> tuple[_Rows, _Rows, list[np.ndarray]]:
    """The field at every step's left end in the step's mode (each row in its own) and at its
    right end in the same mode (the next row's own but where a switch changed it); each step's
    mode's data."""
    datas, which = _packed(field, modes)
    contacts = np.asarray(rows, dtype=np.int64)
    own = _rows_at(field, t, states, datas, which, contacts)
    switched = np.flatnonzero(which[:-1] != which[1:])
    after = _rows_at(field, t[switched + 1], states[switched + 1], datas, which[switched], contacts)

    def joined(name: str) -> np.ndarray:
        values: np.ndarray = getattr(own, name)[1:].copy()
        values[switched] = getattr(after, name)
        return values

    right = _Rows(joined("rates"), joined("seconds"), joined("forces"), joined("force_rates"))
    return own, right, [datas[j] for j in which[:-1].tolist()]


def _packed(field: _Field, modes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The data of each mode the run passed, packed once (one row each), and the one each
    trajectory row is in."""
    starts = np.concatenate([[0], np.flatnonzero((modes[1:] != modes[:-1]).any(axis=1)) + 1])
    index: dict[bytes, int] = {}
    passed: list[np.ndarray] = []
    for k in starts.tolist():
        if index.setdefault(modes[k].tobytes(), len(passed)) == len(passed):
            passed.append(modes[k])
    spans = np.array([index[modes[k].tobytes()] for k in starts.tolist()], dtype=np.int64)
    datas = np.stack([pack(field.arrays, mode) for mode in passed])
    return datas, np.repeat(spans, np.diff(np.append(starts, len(modes))))


def _rows_at(
    field: _Field, t: np.ndarray, states: np.ndarray, datas: np.ndarray, which: np.ndarray, contacts: np.ndarray
) -> _Rows:
    """:class:`_Rows` at ``(t, states)``, row ``k`` in the mode of ``datas[which[k]]``."""
    n, size = len(t), field.size
    rates, seconds = np.empty((n, size)), np.empty((n, size))
    forces, force_rates = np.empty((n, len(contacts))), np.empty((n, len(contacts)))
    _field_at_rows(  # contiguous arrays: one compiled version (a strided time column compiled a second one)
        np.ascontiguousarray(t),
        np.ascontiguousarray(states),
        datas,
        which,
        contacts,
        field.arrays.size,
        rates,
        seconds,
        forces,
        force_rates,
    )
    return _Rows(rates, seconds, forces, force_rates)


@njit(cache=True)
def _field_at_rows(
    t: np.ndarray,
    states: np.ndarray,
    datas: np.ndarray,
    which: np.ndarray,
    contacts: np.ndarray,
    length: int,
    rates: np.ndarray,
    seconds: np.ndarray,
    forces: np.ndarray,
    force_rates: np.ndarray,
) -> None:  # pragma: no cover - compiled
    """Fill :class:`_Rows`' arrays (``length``: the field's vector's)."""
    size = states.shape[1]
    rate, jacobian, partial = np.empty(length), np.empty((size, size)), np.empty(size)
    for k in range(len(t)):
        d, y = datas[which[k]], states[k]
        chain_derivative(t[k], y, rate, d)
        chain_jacobian(t[k], y, d, jacobian, partial)
        rates[k] = rate[:size]
        seconds[k] = jacobian @ rates[k] + partial
        for c in range(len(contacts)):
            forces[k, c] = element_force(t[k], y, d, contacts[c])
            force_rates[k, c] = element_rate(t[k], y, rates[k], d, contacts[c])


def _largest(
    run: tuple[np.ndarray, np.ndarray, np.ndarray, list[np.ndarray]],
    field: _Field,
    sides: tuple[_Rows, _Rows],
    ends: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    quantity: Callable[..., tuple[float, float]],
    counted: np.ndarray,
) -> Peak:
    """The first of the largest ``|value|`` over the counted steps' candidates (their ends'
    values and rates ``ends``: left value, left rate, right value, right rate), or 0 at the run's
    start if none is larger; ``run``: its times, states, modes and each step's mode's data."""
    t, states, modes, data = run
    f0, r0, f1, r1 = (np.where(counted, part[:-1] if k < 2 else part, 0.0) for k, part in enumerate(ends))
    h = np.diff(t)
    turning = np.flatnonzero(counted & (h > 0.0) & (r0 * r1 < 0.0))
    turns: dict[int, Peak] = {}
    for k in turning.tolist():
        step_ends = (
            states[k],
            sides[0].rates[k],
            sides[0].seconds[k],
            states[k + 1],
            sides[1].rates[k],
            sides[1].seconds[k],
        )
        turns[k] = _Step((t[k], t[k + 1]), step_ends, modes[k], data[k], field).turn(quantity)
    inner = np.zeros(len(h))
    inner[turning] = [turns[k].value for k in turning.tolist()]
    candidates = np.abs(np.column_stack([f0, f1, inner]))
    if len(h) == 0 or candidates.max() == 0.0:
        return Peak(0.0, float(t[0]), states[0].copy(), modes[0])
    k, side = divmod(int(np.argmax(candidates)), 3)
    if side == 2:
        return turns[k]
    return Peak(float((f0, f1)[side][k]), float(t[k + side]), states[k + side].copy(), modes[k])


def rates_at(run: ChainResult, rows: np.ndarray) -> np.ndarray:
    """The field's value ``y'`` at the run's trajectory ``rows``, each in its own mode:
    ``(len(rows), state)``."""
    field, modes = _Field(run), run.modes()
    datas, which = _packed(field, modes)
    contacts = np.zeros(0, dtype=np.int64)
    return _rows_at(field, run.times[rows], run.states[rows], datas, which[rows], contacts).rates


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

    def turn(self, quantity: Callable[..., tuple[float, float]]) -> Peak:
        """Where the quantity's rate changes sign inside the step: the root of
        ``quantity(t, y, y', y'', data)``'s rate along the quintic's state, by Brent's method to
        the last bit (two turns in one solver step, where the rate keeps its sign, would be a
        wiggle the solver's tolerance does not resolve)."""
        s = brentq(lambda s: self._at(s, quantity)[1], 0.0, 1.0, xtol=1e-15, rtol=4 * np.finfo(float).eps)
        return Peak(self._at(s, quantity)[0], self.times[0] + s * self.h, quintic(s, self.h, self.ends), self.mode)

    def _at(self, s: float, quantity: Callable[..., tuple[float, float]]) -> tuple[float, float]:
        """The quantity and its rate at ``s`` (0 to 1) of the step, at the quintic's state."""
        t, y = self.times[0] + s * self.h, quintic(s, self.h, self.ends)
        return quantity(t, y, *self.field.at(t, y, self.data), self.data)
