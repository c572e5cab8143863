"""The exact derivatives of a friction chain's period map through every switch (issue 52): its
monodromy ``M = dP/dy`` and its derivative ``dP/dc`` in any of the chain's numbers ``c``.

Along each smooth piece of a run (one mode) the tangent equations ``Phi' = J Phi`` and
``Psi' = J Psi + df/dc`` are integrated with the state (DOP853, compiled:
:func:`~oscillator.orbits.pieces.chain_tangent_rates`, from the run's own state at the piece's
start): ``J`` is the field's Jacobian in the mode
(:func:`~oscillator.model.chain_fields.chain_jacobian`, exact), ``df/dc`` its derivative in the
number at fixed state and time (central differences of the compiled field in the number's
direction of the chain's arrays: the arrays are affine in every number, the field affine in all
but ``Omega``, ``phi`` and the masses, so the differences are exact or second order at a step of
1e-6). Where the field is affine in the state (no cubic spring or damper) and no number is asked,
``Phi`` over a piece is the exponential ``expm(J tau)`` of the mode's constant Jacobian, exact and
without integrating. At a switch the root function ``g`` that CVODE found (the first event of the
instant that changed a mode, :func:`root_slot`) sets the switch time; with ``f-`` the field before
(the old mode) and ``f+`` after (the mode the rules settled on, cascades included), the saltation
rule

    dt_s = -(grad g . delta + dg/dc) / (grad g . f- + dg/dt),     delta+ = delta- - (f+ - f-) dt_s

carries both ``Phi`` and ``Psi`` across (the article's rule, :mod:`oscillator.orbits.sensitivity`).
It covers every switch of a chain: a mass sticking to its belt (``g = v - w``: the velocity's row
of ``Phi`` becomes ``dw/dc``), slipping off it (the flow barrier), passing its belt's speed, a
stop or contact closing and opening, and a Jenkins slider slipping (``g = kt (u - z) -+ F``: ``z``
then follows, ``delta z = delta u -+ delta F / kt``) and sticking (``g = u'``).  A run of ``N``
periods ends at ``t1 = s + N 2 pi / Omega``: ``dP/dOmega`` takes ``f(t1) dt1/dOmega`` too.

Where a switch is a grazing (``grad g . f- + dg/dt`` near zero against its terms) the map is not
differentiable there; :attr:`ChainPass.margin` says how near the run comes.
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from oscillator.errors import InputError
from oscillator.hybrid.chain_run import ChainResult
from oscillator.model.chain_fields import (
    DAMPER,
    LAYOUT,
    SPRING,
    ChainArrays,
    arrays_of,
    chain_derivative,
    chain_jacobian,
    pack,
    root_gradient,
    root_values,
)
from oscillator.model.chain_rules import ChainEventKind
from oscillator.model.chains import FrictionChain
from oscillator.orbits.pieces import CHAIN_PIECE, chain_data, integrate_piece
from oscillator.text import printable

__all__ = [
    "ATOL",
    "RTOL",
    "STEP",
    "ChainPass",
    "Crossing",
    "NumberData",
    "check_names",
    "root_slot",
    "tangent_pass",
]

#: The step of the field's differences in a number, relative to the number (at least 1).
STEP = 1e-6
#: A piece's tangents ``[Phi | Psi]`` at a time, or at an array of times (one block a time).
Tangent = Callable[[float | np.ndarray], np.ndarray]
#: The tangent equations' tolerances (DOP853).
RTOL, ATOL = 1e-11, 1e-12
#: The event kinds whose time the element's second root function sets when it leaves to the left
#: (a slip to ``s = -1`` past ``-(mu_s N + P)`` or ``-F``); every other switch's is its first.
_SECOND_WHEN_LEFT = (ChainEventKind.SLIPS, ChainEventKind.SLIDER_SLIPS)


def root_slot(kind: ChainEventKind, after: int) -> int:
    """Which of an element's two root functions (:func:`~oscillator.model.chain_fields.
    root_values`) set the time of an event of ``kind`` that left the element in mode ``after``:
    ``v - w`` for a mass reaching its belt's speed, the flow barrier's side for a slip, the gap for
    a stop or contact, ``kt (u - z) -+ F`` for a slider's slip, ``u'`` for its stick."""
    return 1 if kind in _SECOND_WHEN_LEFT and after < 0 else 0


@dataclass(frozen=True)
class Crossing:
    """One switch of a run: its time, the element whose root set it, that root's gradient
    ``normal`` and ``moved`` (its derivative in each number), the ``speed`` ``grad g . f- + dg/dt``
    at which the flow crossed it, the field ``rates`` ``f-`` before it and its ``jump``
    ``f+ - f-``, the tangent block ``[Phi | Psi]`` just before, and ``margin``: the speed relative
    to its terms (0 at a grazing)."""

    t: float
    element: str
    kind: str
    normal: np.ndarray
    moved: np.ndarray
    speed: float
    rates: np.ndarray
    jump: np.ndarray
    before: np.ndarray
    margin: float

    def state_derivative(self, start: np.ndarray) -> np.ndarray:
        """How the state just before the switch moves at its own (moving) time, for a start
        moving by ``start``: ``delta- + f- dt_s``."""
        n = len(self.normal)
        delta = self.before[:, :n] @ start + self.before[:, n:]
        moved: np.ndarray = delta + np.outer(self.rates, self.time_derivative(start))
        return moved

    def time_derivative(self, start: np.ndarray) -> np.ndarray:
        """``dt_s/dc`` for a start moving by ``start`` (``dy0/dc``, one column a number)."""
        n = len(self.normal)
        delta = self.before[:, :n] @ start + self.before[:, n:]
        moved: np.ndarray = -(self.normal @ delta + self.moved) / self.speed
        return moved


@dataclass(frozen=True)
class ChainPass:
    """The tangent pass along one run: ``end`` is ``[M | dP/dc]`` at its end (the chain's state
    by rows: ``M = dP/dy``, then one column a number of ``params``), ``crossings`` its switches,
    and the dense tangents along each piece (:meth:`at`)."""

    run: ChainResult
    params: tuple[str, ...]
    end: np.ndarray
    crossings: tuple[Crossing, ...]
    pieces: tuple[tuple[float, float, Tangent], ...]

    @property
    def monodromy(self) -> np.ndarray:
        """``M = dP/dy`` over the whole state."""
        return self.end[:, : self.end.shape[0]]

    @property
    def derivatives(self) -> np.ndarray:
        """``dP/dc``: one column a number of :attr:`params`."""
        return self.end[:, self.end.shape[0] :]

    @property
    def margin(self) -> float:
        """The smallest :attr:`Crossing.margin` (``inf`` without a switch)."""
        return min((c.margin for c in self.crossings), default=float("inf"))

    def at(self, t: float | np.ndarray) -> np.ndarray:
        """``[Phi | Psi]`` at ``t`` (the piece that ends at a switch time: before it); at an array
        of times, one block a time (the first axis)."""
        if np.ndim(t) != 0:
            return self._at_times(np.asarray(t, dtype=float))
        for start, stop, tangent in self.pieces:
            if start <= t <= stop:
                return tangent(t)
        raise ValueError(f"t = {t!r} s is outside the run")

    def _at_times(self, times: np.ndarray) -> np.ndarray:
        found, left = np.empty((len(times), *self.end.shape)), np.ones(len(times), dtype=bool)
        for start, stop, tangent in self.pieces:
            inside = left & (times >= start) & (times <= stop)
            if inside.any():
                found[inside] = tangent(times[inside])
                left &= ~inside
        if left.any():
            raise ValueError(f"t = {times[left][0]!r} s is outside the run")
        return found


def _direction(chain: FrictionChain, arrays: ChainArrays, name: str) -> ChainArrays:
    """The chain's arrays with the number ``name`` one unit larger (the arrays are affine in it)."""
    mass, value, omega = arrays.mass.copy(), arrays.value.copy(), arrays.Omega
    owner, _, key = name.rpartition(".")
    masses = [m.name for m in chain.masses]
    for row, element in enumerate(chain.elements):
        weight = element.type == "friction" and element.values.get("N") is None
        if element.name == owner and key in LAYOUT[element.type]:
            value[row, LAYOUT[element.type].index(key)] += 1.0
        elif weight and name == "g":
            value[row, 2] += arrays.mass[masses.index(element.on)]
        elif weight and key == "m" and owner == element.on:
            value[row, 2] += chain.g
    if name == "Omega":
        omega += 1.0
    elif key == "m" and owner in masses:
        mass[masses.index(owner)] += 1.0
    return dataclasses.replace(arrays, mass=mass, value=value, Omega=omega)


def check_names(chain: FrictionChain, params: str | Sequence[str]) -> tuple[str, ...]:
    """``params`` as a tuple of the chain's numbers (:meth:`FrictionChain.parameter_names`);
    an unknown one refused naming the closest."""
    names = (params,) if isinstance(params, str) else tuple(params)
    known = chain.parameter_names()
    for name in names:
        if name not in known:
            chain.with_values({name: 0.0})  # raises, with the closest name
            raise InputError(f"{printable(str(name))} is no number of the system", field="params")
    return names


def _steps(chain: FrictionChain, params: tuple[str, ...]) -> np.ndarray:
    values = [chain.value(name) or 0.0 for name in params]
    return STEP * np.maximum(1.0, np.abs(values))


class NumberData:
    """The chain's packed data in a mode, and with each of the numbers ``params`` stepped either
    way (by :data:`STEP` of its size): a central difference of the field over them is its
    derivative in each number (exact where the field is affine in it, to ``STEP^2`` else)."""

    def __init__(self, chain: FrictionChain, params: tuple[str, ...]) -> None:
        self.arrays = arrays_of(chain)
        zero = np.zeros(len(self.arrays.kind))
        base = pack(self.arrays, zero)
        self.directions = np.array([pack(_direction(chain, self.arrays, p), zero) - base for p in params])
        self.directions = self.directions.reshape(len(params), len(base))
        self.steps = _steps(chain, params)

    def of(self, mode: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        d = pack(self.arrays, mode)
        shift = self.directions * self.steps[:, None]
        return d, d + shift, d - shift


def _rates(t: float, y: np.ndarray, d: np.ndarray) -> np.ndarray:
    out = np.empty(len(y))
    chain_derivative(t, y, out, d)
    return out


@dataclass(frozen=True)
class _Switches:
    """A run's switching events as arrays: for each, its time, its element's row, its kind and
    the element's mode after (only the events that changed a mode)."""

    t: np.ndarray
    rows: list[int]
    kinds: list[str]
    after: list[int]

    @classmethod
    def of(cls, run: ChainResult) -> _Switches:
        t, elements, kinds, after = run.switches()
        rows = {e.name: k for k, e in enumerate(run.chain.elements)}
        return cls(t, [rows[name] for name in elements], kinds, after)

    def first_at(self, t: float) -> int:
        """The first event at ``t``: the one whose root CVODE found (the others follow from it)."""
        return int(np.flatnonzero(self.t == t)[0])


def _crossing(
    data: NumberData,
    t: float,
    states: tuple[np.ndarray, np.ndarray],
    modes: tuple[np.ndarray, np.ndarray],
    switch: tuple[int, str, int],
    block: np.ndarray,
    element: str,
) -> Crossing:
    """The saltation at a switch at ``t`` from ``states[0]`` in ``modes[0]`` to ``states[1]`` in
    ``modes[1]``, its time set by ``switch = (row, kind, mode after)``'s root function."""
    (before, after), (row, kind, left_in) = states, switch
    index = 2 * row + root_slot(ChainEventKind(kind), left_in)
    (old, ahead, back), (new, _, _) = data.of(modes[0]), data.of(modes[1])
    rates = _rates(t, before, old)
    jump = _rates(t, after, new) - rates
    normal = np.empty(len(before))
    dt = root_gradient(t, before, old, index, normal)
    speed = float(normal @ rates + dt)
    moved = np.empty(len(data.steps))
    g = np.empty(2 * len(data.arrays.kind))
    for k in range(len(moved)):
        root_values(t, before, ahead[k], g)
        high = g[index]
        root_values(t, before, back[k], g)
        moved[k] = (high - g[index]) / (2.0 * data.steps[k])
    scale = float(np.abs(normal) @ np.abs(rates) + abs(dt))
    margin = abs(speed) / scale if scale > 0 else 0.0
    return Crossing(t, element, kind, normal, moved, speed, rates, jump, block.copy(), margin)


def tangent_pass(run: ChainResult, params: Sequence[str] = (), *, rtol: float = RTOL) -> ChainPass:
    """The tangents along ``run`` (a period map's: :func:`~oscillator.orbits.chain_orbits.
    chain_period_map`), from ``Phi = I``, ``Psi = 0`` at its start, in the numbers ``params``
    (module docstring); ``rtol`` the tangent equations' tolerance (a Newton step's Jacobian needs
    less than the orbit's multipliers)."""
    chain = run.chain
    params = check_names(chain, params)
    data = NumberData(chain, params)
    n, k = data.arrays.size, len(params)
    t, states = run.times, run.states
    modes, switches = run.modes(), _Switches.of(run)
    block = np.hstack([np.eye(n), np.zeros((n, k))])
    changes = [0, *(np.flatnonzero((modes[1:] != modes[:-1]).any(axis=1)) + 1).tolist(), len(t)]
    pieces: list[tuple[float, float, Tangent]] = []
    crossings = []
    affine = not params and _affine(data.arrays)
    for a, b in itertools.pairwise(changes):
        span = (float(t[a]), float(t[b - 1]))
        if span[1] <= span[0]:
            tangent: Tangent = functools.partial(_held, block.copy())
        elif affine:  # a constant Jacobian in the mode: the exponential, exact
            jacobian, rate = np.empty((n, n)), np.empty(n)
            chain_jacobian(span[0], states[a], data.of(modes[a])[0], jacobian, rate)
            tangent = functools.partial(_exponential, span[0], jacobian, block.copy())
        else:
            tangent = _along_piece(data, modes[a], span, states[a], block, rtol)
        block = tangent(span[1])
        pieces.append((*span, tangent))
        if b < len(t):
            first = switches.first_at(t[b])
            switch = (switches.rows[first], switches.kinds[first], switches.after[first])
            name = chain.elements[switch[0]].name
            pair = (states[b - 1], states[b])
            crossing = _crossing(data, float(t[b]), pair, (modes[b - 1], modes[b]), switch, block, name)
            row = crossing.normal @ block
            row[n:] += crossing.moved
            block = block + np.outer(crossing.jump, row) / crossing.speed
            crossings.append(crossing)
    return _ended(run, data, params, block, tuple(crossings), tuple(pieces), modes[-1])


def _affine(arrays: ChainArrays) -> bool:
    """Whether the chain's field is affine in the state in every mode (no cubic spring or damper):
    its Jacobian is then constant in a mode."""
    cubic = np.isin(arrays.kind, (SPRING, DAMPER)) & (arrays.value[:, 1] != 0.0)
    return not bool(cubic.any())


def _held(block: np.ndarray, t: float | np.ndarray) -> np.ndarray:
    return block if np.ndim(t) == 0 else np.repeat(block[None], np.size(t), axis=0)


def _exponential(start: float, jacobian: np.ndarray, block: np.ndarray, t: float | np.ndarray) -> np.ndarray:
    if np.ndim(t) != 0:
        return np.stack([_exponential(start, jacobian, block, float(s)) for s in np.asarray(t)])
    moved: np.ndarray = scipy.linalg.expm(jacobian * (t - start)) @ block
    return moved


def _along_piece(
    data: NumberData, mode: np.ndarray, span: tuple[float, float], start: np.ndarray, block: np.ndarray, rtol: float
) -> Tangent:
    """The tangent equations over one piece in ``mode``: the block at any time of it (the dense
    solution's)."""
    numbers = chain_data(*data.of(mode), data.steps)
    n, shape = len(start), block.shape
    big = np.concatenate([start, block.ravel()])
    solution = integrate_piece(CHAIN_PIECE, numbers, span, big, rtol=rtol, atol=rtol * ATOL / RTOL, dense=True)

    def tangent(t: float | np.ndarray) -> np.ndarray:
        moved: np.ndarray = solution(t)[n:]
        return moved.reshape(shape) if np.ndim(t) == 0 else np.moveaxis(moved.reshape(*shape, -1), -1, 0)

    return tangent


def _ended(
    run: ChainResult,
    data: NumberData,
    params: tuple[str, ...],
    block: np.ndarray,
    crossings: tuple[Crossing, ...],
    pieces: tuple[tuple[float, float, Tangent], ...],
    mode: np.ndarray,
) -> ChainPass:
    """The pass's end: ``dP/dOmega`` takes ``f(t1) dt1/dOmega`` (``t1 = s + N 2 pi/Omega``)."""
    n = data.arrays.size
    end = block.copy()
    if "Omega" in params:
        trajectory = run.trajectory
        span = float(trajectory.t.iloc[-1] - trajectory.t.iloc[0])
        last = trajectory[list(run.chain.system.state)].iloc[-1].to_numpy(float)
        rates = _rates(float(trajectory.t.iloc[-1]), last, data.of(mode)[0])
        end[:, n + params.index("Omega")] += rates * (-span / run.chain.Omega)
    return ChainPass(run, params, end, crossings, pieces)
