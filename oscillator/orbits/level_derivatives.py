"""The exact derivatives of a periodic orbit's spectral levels above a cut-off (docs/noise.md):
``orbit.sensitivities(params).levels(cutoff)``.

Over one return of ``n`` forcing periods (``P = nT``), a signal ``s`` (each contact's force,
compressive, and each mass's acceleration: :mod:`oscillator.orbits.noise`'s) has the level above
the cut-off ``f_c`` Hz

    L = 10 log10((R^2 - |c_0|^2 - sum_{0 < k / P <= f_c} 2 |c_k|^2) / ref^2),

``R^2`` its mean square (``force_rms^2 + c_0^2``, ``a_rms^2``: the response integrals, every
harmonic by Parseval) and ``c_k = 1/P integral s(t) exp(-2 pi i k t / P) dt``: every harmonic above
the cut-off, not the first ``harmonics`` of a :class:`~oscillator.orbits.spectra.Spectrum` (their
levels differ by the tail).  Its derivative in a parameter ``c``: ``R``'s is the response
measures' (:mod:`oscillator.orbits.response_derivatives`), and each ``c_k`` below the cut-off
moves by

    dc_k = -c_k dP/P + 1/P sum_pieces [s(b-) e_k(b) db - s(a+) e_k(a) da]
           + 1/P integral (grad s . delta(t) + ds/dc + s(t) 2 pi i k t dP / P^2) e_k(t) dt,

``e_k(t) = exp(-2 pi i k t / P)``, ``delta(t)`` the orbit's variation at fixed time (the tangent
pass's ``sigma`` from ``dy*/dc``, :func:`~oscillator.orbits.sensitivity.tangent_pass`), each
smooth piece's ends ``a, b`` moving with their switches (``tau``; the return's end with
``Omega``), the integral by Gauss-Legendre on each piece (16 nodes on every stretch no longer
than ``P`` over the larger of 16 and the harmonics below the cut-off), where ``sigma`` and the
state are read from the pass's dense output.  ``grad s`` and ``ds/dc`` are the contact forces'
(affine) and the field's (:func:`~oscillator.model.kernels.jacobian`,
:func:`~oscillator.orbits.tangent.field_gradient`).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from oscillator.model.fields import C3, D1, K3, K6, D, coefficients
from oscillator.model.kernels import jacobian, rates
from oscillator.model.phase_space import Mode
from oscillator.orbits.pieces import mode_flags
from oscillator.orbits.sensitivity import selector_of, tangent_pass
from oscillator.orbits.spectra import (
    ACCELERATION_REFERENCE,
    FORCE_REFERENCE,
    STRETCHES,
    check_cutoff,
    harmonics_below,
    quadrature_nodes,
)
from oscillator.orbits.tangent import field_gradient

if TYPE_CHECKING:  # pragma: no cover
    from oscillator.orbits.sensitivity import Sensitivities

__all__ = ["ABOVE", "LEVELS", "above_derivatives", "level_derivatives"]

#: The levels, in the rows' order: each signal's name, the response measure of its RMS, whether
#: that RMS is about the mean (the forces') and its decibel reference.
LEVELS = (
    ("force_level_right", "force_rms_right", True, FORCE_REFERENCE),
    ("force_level_left", "force_rms_left", True, FORCE_REFERENCE),
    ("acceleration_level_m1", "a_rms_m1", False, ACCELERATION_REFERENCE),
    ("acceleration_level_m2", "a_rms_m2", False, ACCELERATION_REFERENCE),
)


#: Each level's response measure above a cut-off (:func:`above_derivatives`), by its RMS's.
ABOVE = {
    "force_rms_right": "force_above_right",
    "force_rms_left": "force_above_left",
    "a_rms_m1": "a_above_m1",
    "a_rms_m2": "a_above_m2",
}


def _signals(t: float, y: np.ndarray, mode: Mode, c: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The four signals of :data:`LEVELS` at ``(t, y)`` in ``mode``, their gradients in the state
    ``(4, 4)`` and in the parameter vector ``(4, 25)`` at fixed ``(t, y)``."""
    s1, s2, left, right = mode_flags(mode)
    x1, v1, x2, v2 = (float(v) for v in y)
    values, by_state, by_number = np.zeros(4), np.zeros((4, 4)), np.zeros((4, len(c)))
    if right:  # K6 (x1 - d1)
        values[0], by_state[0, 0] = c[K6] * (x1 - c[D1]), c[K6]
        by_number[0, K6], by_number[0, D1] = x1 - c[D1], -c[K6]
    if left:  # -(K3 (x1 - x2 + d) + C3 (v1 - v2))
        values[1] = -(c[K3] * (x1 - x2 + c[D]) + c[C3] * (v1 - v2))
        by_state[1] = [-c[K3], -c[C3], c[K3], c[C3]]
        by_number[1, K3], by_number[1, C3], by_number[1, D] = -(x1 - x2 + c[D]), -(v1 - v2), -c[K3]
    field = rates(t, x1, v1, x2, v2, c, s1, s2, left, right)
    values[2], values[3] = field[1], field[3]
    matrix, gradient = np.empty(16), np.empty((4, len(c)))
    jacobian(x1, v1, x2, v2, c, s1, s2, left, right, matrix)
    field_gradient(t, np.asarray(y, dtype=float), c, s1, s2, left, right, gradient)
    by_state[2:] = matrix.reshape(4, 4)[[1, 3]]
    by_number[2:] = gradient[[1, 3]]
    return values, by_state, by_number


def _nodes(pieces: list[tuple[float, float]], longest: float) -> tuple[np.ndarray, np.ndarray]:
    """:func:`~oscillator.orbits.spectra.quadrature_nodes` of every piece, joined."""
    found = [quadrature_nodes(t0, t1, longest) for t0, t1 in pieces]
    return np.concatenate([times for times, _ in found]), np.concatenate([scales for _, scales in found])


def level_derivatives(found: Sensitivities, cutoff: float = 0.0) -> pd.DataFrame:
    """The levels above ``cutoff`` Hz (dB, module docstring) of the orbit ``found`` differentiates,
    and their derivatives in its parameters: one row per level of :data:`LEVELS`, ``value`` and
    ``d/d<param>``; a signal that is zero all the return (a contact that never closes) has the
    level ``-inf`` and no derivative (NaN)."""
    rows = []
    for (square, d_square), (_, _, _, reference) in zip(_squares(found, cutoff), LEVELS, strict=True):
        if square > 0:
            rows.append([10 * math.log10(square / reference**2), *(10 / math.log(10) * d_square / square)])
        else:
            rows.append([-math.inf, *[math.nan] * len(found.params)])
    return _table(found, [level for level, *_ in LEVELS], rows)


def above_derivatives(found: Sensitivities, cutoff: float = 0.0) -> pd.DataFrame:
    """The response measures ``force_above_right``, ``force_above_left``, ``a_above_m1`` and
    ``a_above_m2`` above ``cutoff`` Hz (the RMS of every harmonic above it: ``sqrt`` of the mean
    square the levels take, module docstring) and their derivatives, as rows of
    :attr:`~oscillator.orbits.sensitivity.Sensitivities.measures`; a signal that is zero all the
    return has the RMS 0 and the derivative 0 (a contact that does not close, nor nearby)."""
    rows = []
    for square, d_square in _squares(found, cutoff):
        rms = math.sqrt(max(square, 0.0))
        rows.append([rms, *(d_square / (2 * rms) if rms > 0 else np.zeros(len(found.params)))])
    return _table(found, [ABOVE[rms] for _, rms, _, _ in LEVELS], rows)


def _table(found: Sensitivities, index: list[str], rows: list[list[float]]) -> pd.DataFrame:
    return pd.DataFrame(rows, index=index, columns=["value", *(f"d/d{name}" for name in found.params)])


def _squares(found: Sensitivities, cutoff: float) -> list[tuple[float, np.ndarray]]:
    """Each signal's (of :data:`LEVELS`) mean square above ``cutoff`` Hz and its derivative."""
    coefficient, moved = _low_harmonics(found, check_cutoff(cutoff))
    columns = [f"d/d{name}" for name in found.params]
    squares = []
    for s, (_, rms, about_mean, _) in enumerate(LEVELS):
        r, dr = float(found.measures.loc[rms, "value"]), found.measures.loc[rms, columns].to_numpy(float)
        low = range(1, coefficient.shape[1]) if about_mean else range(coefficient.shape[1])
        weights = {j: 1.0 if j == 0 else 2.0 for j in low}  # the mean once, each harmonic twice
        square = r * r - sum(w * abs(coefficient[s, j]) ** 2 for j, w in weights.items())
        d_square = 2 * r * dr
        d_square -= sum(2 * w * (coefficient[s, j].conjugate() * moved[s, j]).real for j, w in weights.items())
        squares.append((square, d_square))
    return squares


def _low_harmonics(found: Sensitivities, cutoff: float) -> tuple[np.ndarray, np.ndarray]:
    """The four signals' Fourier coefficients ``c_k`` at or below ``cutoff`` Hz, ``(4, K + 1)``,
    and their derivatives in the parameters, ``(4, K + 1, params)`` (module docstring)."""
    segments, dy, dt_end = found._along
    orbit, names = found.orbit, found.params
    p = orbit.case.parameters
    c, selector = coefficients(p), selector_of(names)
    span = orbit.period * p.period
    below = harmonics_below(cutoff, span)
    smooth = [(s.t0, s.t1) for s in segments if s.t1 > s.t0]
    times, scales = _nodes(smooth, span / max(STRETCHES, below))
    along = tangent_pass(segments, p, names, dy, segments[-1].t1, dt_end, times.tolist())
    k = np.arange(below + 1)
    coefficient = np.zeros((4, below + 1), complex)
    moved = np.zeros((4, below + 1, len(names)), complex)
    pieces = iter(along.pieces)
    piece = next(pieces)
    for t, scale, mark in zip(times.tolist(), scales.tolist(), along.marks, strict=True):
        while not piece.t0 <= t < piece.t1:
            piece = next(pieces)
        y, sigma = mark[:4], mark[4:].reshape(4, len(names))
        values, by_state, by_number = _signals(t, y, piece.mode, c)
        wave = np.exp(-2j * np.pi * k * t / span) * scale / span
        change = by_state @ sigma + by_number @ selector  # (4, params): at fixed time
        coefficient += np.outer(values, wave)
        moved += change[:, None, :] * wave[None, :, None]
        moved += (values[:, None] * wave[None, :] * 2j * np.pi * k * t / span**2)[:, :, None] * dt_end[None, None, :]
    for piece in along.pieces:  # each piece's ends ride their switches
        if piece.t1 > piece.t0:
            for t, y, tau, sign in ((piece.t0, piece.y0, piece.tau0, -1.0), (piece.t1, piece.y1, piece.tau1, 1.0)):
                wave = np.exp(-2j * np.pi * k * t / span) / span
                value = _signals(t, y, piece.mode, c)[0]
                moved += sign * (value[:, None] * wave[None, :])[:, :, None] * tau[None, None, :]
    moved -= coefficient[:, :, None] * (dt_end / span)[None, None, :]
    return coefficient, moved
