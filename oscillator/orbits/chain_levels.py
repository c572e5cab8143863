"""The exact derivatives of a friction chain's spectral levels above a cut-off (docs/noise.md):
``orbit.sensitivities(names).levels(cutoff)`` for a declared system's orbit.

Over one return (``P = N 2 pi / Omega``), each stop's and contact's force on its ``on`` mass (0
while open) and each mass's acceleration (:mod:`oscillator.orbits.chain_noise`'s signals) has the
level above ``f_c`` Hz

    L = 10 log10((S - |c_0|^2 - sum_{0 < k / P <= f_c} 2 |c_k|^2) / ref^2),

``S = 1/P integral s^2 dt`` its mean square and ``c_k = 1/P integral s exp(-2 pi i k t / P) dt``:
every harmonic above the cut-off, the mean left out (as :meth:`Spectrum.level
<oscillator.orbits.spectra.Spectrum.level>`, without its tail beyond the last harmonic kept).
``S`` and the ``c_k`` below the cut-off are integrals over the run's solver steps (Gauss-Legendre,
:data:`~oscillator.orbits.chain_sensitivity.GAUSS` nodes a step, the state there the quintic
through the step's ends); each moves as the article's do (:mod:`oscillator.orbits.level_derivatives`):
inside by ``grad s . delta(t) + ds/dc`` (``delta(t)`` the orbit's variation along the tangent pass,
:func:`~oscillator.orbits.chain_sensitivity.moving_point`; ``ds/dc`` the central difference over
:class:`~oscillator.orbits.chain_tangents.NumberData`), at each stretch's ends in one mode with their
switches, and with the period (``Omega`` moves every harmonic and the return's end).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from oscillator.model.chain_fields import chain_derivative, chain_jacobian, element_force, element_gradient
from oscillator.orbits.chain_noise import smooth_stretches
from oscillator.orbits.chain_peaks import nodes_of, sides
from oscillator.orbits.chain_sensitivity import GAUSS, moving_point
from oscillator.orbits.chain_tangents import NumberData
from oscillator.orbits.spectra import ACCELERATION_REFERENCE, FORCE_REFERENCE, check_cutoff, harmonics_below

if TYPE_CHECKING:  # pragma: no cover
    from oscillator.orbits.chain_sensitivity import ChainSensitivities

__all__ = ["chain_level_derivatives"]


class _Signals:
    """The signals of a chain at a state, with their gradients in the state and their
    derivatives in the numbers: the stops' and contacts' forces (``rows``), then each mass's
    acceleration."""

    def __init__(self, found: ChainSensitivities, rows: list[int]) -> None:
        chain = found.orbit.chain
        self.rows, self.masses, self.size = rows, len(chain.masses), chain.system.size
        self.numbers = NumberData(chain, found.params)
        self.length = self.numbers.arrays.size
        self._packed: dict[bytes, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}

    def data(self, mode: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The mode's data, and stepped either way in each number (packed once a mode)."""
        key = mode.tobytes()
        if key not in self._packed:
            self._packed[key] = self.numbers.of(mode)
        return self._packed[key]

    def values(self, t: float, y: np.ndarray, d: np.ndarray, closed: np.ndarray) -> np.ndarray:
        """The signals at ``(t, y)`` in the data ``d`` (``closed``: which stops and contacts are)."""
        rate = np.empty(self.length)
        chain_derivative(t, y, rate, d)
        forces = [element_force(t, y, d, row) if shut else 0.0 for row, shut in zip(self.rows, closed, strict=True)]
        return np.concatenate([forces, rate[1 : 2 * self.masses : 2]])

    def moves(self, t: float, y: np.ndarray, mode: np.ndarray, delta: np.ndarray) -> np.ndarray:
        """How the signals move in each number at the fixed time ``t`` (``(signals, numbers)``),
        the state moving by ``delta``."""
        d, ahead, behind = self.data(mode)
        closed = mode[self.rows] != 0.0
        grads = np.zeros((len(self.rows) + self.masses, self.size))
        gradient = np.empty(self.size)
        for k, (row, shut) in enumerate(zip(self.rows, closed, strict=True)):
            if shut:
                element_gradient(t, y, d, row, gradient)
                grads[k] = gradient
        jacobian, partial = np.empty((self.size, self.size)), np.empty(self.size)
        chain_jacobian(t, y, d, jacobian, partial)
        grads[len(self.rows) :] = jacobian[1 : 2 * self.masses : 2]
        by_number = np.column_stack(
            [
                (self.values(t, y, up, closed) - self.values(t, y, down, closed)) / (2 * step)
                for up, down, step in zip(ahead, behind, self.numbers.steps, strict=True)
            ]
        )
        found: np.ndarray = grads @ delta + by_number.reshape(len(grads), -1)
        return found


def chain_level_derivatives(found: ChainSensitivities, cutoff: float = 0.0) -> pd.DataFrame:
    """The levels above ``cutoff`` Hz (dB, module docstring) of the chain orbit ``found``
    differentiates and their derivatives in its numbers: one row per signal
    (``force_level:<element>``, ``acceleration_level:<mass>``), ``value`` and ``d/d<name>``; a
    signal that is zero all the return has the level ``-inf`` and no derivative (NaN)."""
    cutoff = check_cutoff(cutoff)
    orbit, (along, moved) = found.orbit, found._motion
    run, chain = orbit.run, orbit.chain
    t, states, modes = run.times, run.states, run.modes()
    at, point = sides(run), moving_point(orbit, along, moved)
    signals = _Signals(found, at.contacts)
    span = orbit.period * chain.period
    stretch = np.array([-span / chain.Omega if name == "Omega" else 0.0 for name in found.params])
    k = np.arange(harmonics_below(cutoff, span) + 1)
    count = len(at.contacts) + len(chain.masses)
    totals = _Totals(count, len(k), len(found.params))
    nodes, weights = np.polynomial.legendre.leggauss(GAUSS)
    where = (nodes + 1.0) / 2.0
    when = {c.t: c.time_derivative(moved) for c in along.crossings}
    for first, last in smooth_stretches(t, modes):
        steps = np.arange(first, last + 1)  # the stretch's nodes, their states and moves at once
        times, states_at = nodes_of(run, at, steps, where)
        deltas = point(times.ravel())[:, : chain.system.size]
        scales = (0.5 * np.diff(t)[steps][:, None] * weights).ravel()
        data, closed = signals.data(modes[first])[0], modes[first, at.contacts] != 0.0
        nodal = zip(times.ravel().tolist(), states_at.reshape(-1, states.shape[1]), deltas, scales, strict=True)
        for time, y, delta, scale in nodal:
            change = signals.moves(time, y, modes[first], delta)
            totals.add(signals.values(time, y, data, closed), change, time, scale, (span, k, stretch))
        for time, y, step, side in ((t[first], states[first], first, -1.0), (t[last + 1], states[last + 1], last, 1.0)):
            shift = stretch if time == orbit.section + span else when.get(float(time), np.zeros(len(stretch)))
            if time == orbit.section:
                continue
            value = signals.values(float(time), y, signals.data(modes[step])[0], modes[step, at.contacts] != 0.0)
            totals.end(value, float(time), side * shift, (span, k))
    names = [f"force_level:{chain.elements[row].name}" for row in at.contacts]
    names += [f"acceleration_level:{mass.name}" for mass in chain.masses]
    references = [FORCE_REFERENCE] * len(at.contacts) + [ACCELERATION_REFERENCE] * len(chain.masses)
    return totals.levels(names, references, found.params, stretch / span)


class _Totals:
    """The integrals ``S`` and ``c_k`` of every signal over the return (each already divided by
    ``P``) and their moves, as the nodes and the stretches' ends add to them."""

    def __init__(self, signals: int, harmonics: int, numbers: int) -> None:
        self.square, self.d_square = np.zeros(signals), np.zeros((signals, numbers))
        self.coefficient = np.zeros((signals, harmonics), complex)
        self.moved = np.zeros((signals, harmonics, numbers), complex)

    def add(
        self,
        value: np.ndarray,
        change: np.ndarray,
        t: float,
        weight: float,
        sizes: tuple[float, np.ndarray, np.ndarray],
    ) -> None:
        """A node at ``t`` of quadrature ``weight``: the signals' ``value`` and their ``change``."""
        span, k, stretch = sizes
        wave = np.exp(-2j * np.pi * k * t / span) * weight / span
        self.square += value**2 * weight / span
        self.d_square += 2 * value[:, None] * change * weight / span
        self.coefficient += np.outer(value, wave)
        self.moved += change[:, None, :] * wave[None, :, None]
        self.moved += (np.outer(value, wave * 2j * np.pi * k * t / span**2))[:, :, None] * stretch[None, None, :]

    def end(self, value: np.ndarray, t: float, shift: np.ndarray, sizes: tuple[float, np.ndarray]) -> None:
        """A stretch's end at ``t`` moving by ``shift`` (its sign the end's side)."""
        span, k = sizes
        wave = np.exp(-2j * np.pi * k * t / span) / span
        self.d_square += np.outer(value**2 / span, shift)
        self.moved += np.outer(value, wave)[:, :, None] * shift[None, None, :]

    def levels(
        self, names: list[str], references: list[float], params: tuple[str, ...], relative: np.ndarray
    ) -> pd.DataFrame:
        """The levels and their derivatives (``relative``: ``dP/dc / P``)."""
        square = self.square
        d_square = self.d_square - square[:, None] * relative[None, :]
        moved = self.moved - self.coefficient[:, :, None] * relative[None, None, :]
        rows = []
        for s in range(len(names)):
            twice = np.where(np.arange(self.coefficient.shape[1]) == 0, 1.0, 2.0)
            above = square[s] - float(np.sum(twice * np.abs(self.coefficient[s]) ** 2))
            d_above = d_square[s] - 2 * np.sum(
                twice[:, None] * (self.coefficient[s, :, None].conj() * moved[s]).real, 0
            )
            if above > 0:
                rows.append([10 * math.log10(above / references[s] ** 2), *(10 / math.log(10) * d_above / above)])
            else:
                rows.append([-math.inf, *[math.nan] * len(params)])
        return pd.DataFrame(rows, index=names, columns=["value", *[f"d/d{name}" for name in params]])
