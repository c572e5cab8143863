"""One smooth piece of a motion integrated again, compiled: the response integrals and the tangent
equations along a mode's flow between two switches (issue 53).

Three passes integrate a piece again from its start: the response measures
(:mod:`oscillator.orbits.response`: the state with ``x1^2, x2^2, a1^2, a2^2`` and the five
energies), the article's tangent system (:mod:`oscillator.orbits.sensitivity`: those and their
derivatives in the parameters, :func:`~oscillator.orbits.tangent.tangent_rates`), and a friction
chain's (:mod:`oscillator.orbits.chain_tangents`: ``Phi' = J Phi``, ``Psi' = J Psi + df/dc``,
:func:`chain_tangent_rates`).  Each ran SciPy's ``solve_ivp(..., method="DOP853")`` with a Python
right-hand side; :func:`integrate_piece` takes the same steps in compiled code: DOP853 with SciPy's
first step, error norm and step factors (the tableau and constants of
:mod:`oscillator.engines.dop853`), and SciPy's dense output where asked.  A field is named by a
``kind`` and reads its numbers from one flat vector (:func:`article_data`, :func:`chain_data`).

The interior extrema of the article's pieces are roots, as ``solve_ivp``'s events were: of each
moving mass's acceleration ``a_i`` (its speed is extreme there) and, in the contact between the
masses, of the contact force's rate ``K3 zdot1 + C3 (a1 - a2)``.  Where one changes sign over a
step (SciPy's rule: ``g <= 0 <= g_new`` or ``g >= 0 >= g_new``) the root is found by the Illinois
method to ``4 eps`` of the time (SciPy's ``brentq`` tolerance), each trial state one Runge-Kutta
step from the step's start (of the accepted step's accuracy or better: a shorter step).  The speed
and the force at an extremum are stationary in time, so the root's error enters them squared.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from oscillator.compiled import njit
from oscillator.engines.dop853 import (
    _A,
    _A_EXTRA,
    _B,
    _C,
    _C_EXTRA,
    _D,
    _E3,
    _E5,
    _EXPONENT,
    _POWER,
    MAX_FACTOR,
    MIN_FACTOR,
    SAFETY,
)
from oscillator.model.chain_fields import chain_derivative, chain_jacobian
from oscillator.model.fields import C3, K3
from oscillator.model.kernels import rates
from oscillator.model.phase_space import Mode
from oscillator.model.types import Vector
from oscillator.orbits.tangent import map_rates, tangent_rates

__all__ = [
    "ARTICLE_MAP",
    "ARTICLE_PIECE",
    "CHAIN_PIECE",
    "IntegratedPiece",
    "article_data",
    "chain_data",
    "chain_tangent_rates",
    "integrate_piece",
    "mode_flags",
]

#: The fields: the article's tangent system (the response integrals alone with no parameter), a
#: chain's tangent equations, the article's state and its derivatives in the parameters alone
#: (no integrals, no extrema: :func:`oscillator.orbits.sensitivity.map_gradient`).
ARTICLE_PIECE, CHAIN_PIECE, ARTICLE_MAP = 0, 1, 2
_STAGES = _B.shape[0]
_EPS = float(np.finfo(float).eps)
#: The extremum functions of the article's pieces: ``a1``, ``a2``, the contact force's rate.
EXTREMA = 3


def mode_flags(mode: Mode) -> tuple[int, int, bool, bool]:
    """The compiled kernels' description of a mode: each mass's velocity sign and the contacts."""
    return mode.sign(1), mode.sign(2), mode.left, mode.right


def article_data(flags: tuple[int, int, bool, bool], columns: np.ndarray, c: np.ndarray) -> np.ndarray:
    """The article's field's numbers: the mode ``(s1, s2, left, right)``, the parameters'
    positions ``columns`` in ``c`` (none for the response integrals alone), ``c``."""
    return np.concatenate([np.asarray(flags, dtype=float), [float(len(columns))], columns.astype(float), c])


def chain_data(d: np.ndarray, plus: np.ndarray, minus: np.ndarray, steps: np.ndarray) -> np.ndarray:
    """A chain's tangent field's numbers: its packed data ``d`` in the mode, and the data with
    each number stepped either way by ``steps`` (:class:`~oscillator.orbits.chain_tangents.NumberData`)."""
    return np.concatenate([[float(len(steps)), float(len(d))], steps, d, plus.ravel(), minus.ravel()])


@njit(cache=True)
def chain_tangent_rates(
    t: float, big: Vector, d: Vector, plus: np.ndarray, minus: np.ndarray, steps: Vector, out: Vector
) -> None:  # pragma: no cover - compiled
    """``out``: the rates of ``big = (y, [Phi | Psi] by rows)`` in the data's mode
    (:mod:`oscillator.orbits.chain_tangents`); ``plus``/``minus`` the data with each number stepped
    by ``+-steps``."""
    n = int(d[3])
    columns = (big.shape[0] - n) // n
    y = big[:n]
    chain_derivative(t, y, out[:n], d)
    jacobian, rate = np.empty((n, n)), np.empty(n)
    chain_jacobian(t, y, d, jacobian, rate)
    rates_ = jacobian @ big[n:].reshape((n, columns))
    ahead, back = np.empty(n), np.empty(n)
    for k in range(plus.shape[0]):
        chain_derivative(t, y, ahead, plus[k])
        chain_derivative(t, y, back, minus[k])
        for i in range(n):
            rates_[i, n + k] += (ahead[i] - back[i]) / (2.0 * steps[k])
    out[n:] = rates_.ravel()


@njit(cache=True)
def _field(kind: int, t: float, y: Vector, data: Vector, out: Vector) -> None:  # pragma: no cover - compiled
    """``out``: the field ``kind`` at ``(t, y)`` with its numbers ``data``."""
    if kind == ARTICLE_PIECE or kind == ARTICLE_MAP:
        k = int(data[4])
        columns = data[5 : 5 + k]  # the parameters' positions, as floats (read with int()): no copy a call
        s1, s2 = int(data[0]), int(data[1])
        left, right = data[2] != 0.0, data[3] != 0.0
        if kind == ARTICLE_PIECE:
            tangent_rates(t, y, data[5 + k :], columns, s1, s2, left, right, out)
        else:
            map_rates(t, y, data[5 + k :], columns, s1, s2, left, right, out)
    else:
        k, m = int(data[0]), int(data[1])
        steps = data[2 : 2 + k]
        d = data[2 + k : 2 + k + m]
        plus = data[2 + k + m : 2 + k + m + k * m].reshape((k, m))
        minus = data[2 + k + m + k * m : 2 + k + m + 2 * k * m].reshape((k, m))
        chain_tangent_rates(t, y, d, plus, minus, steps, out)


@njit(cache=True)
def _extrema(kind: int, t: float, y: Vector, data: Vector, g: Vector) -> None:  # pragma: no cover - compiled
    """``g``: ``a1``, ``a2`` (1 for a mass at rest) and the contact force's rate (1 out of contact)
    of the article's pieces; ones for a chain's."""
    g[:] = 1.0
    if kind != ARTICLE_PIECE:
        return
    s1, s2, left = int(data[0]), int(data[1]), data[2] != 0.0
    c = data[5 + int(data[4]) :]
    r = rates(t, y[0], y[1], y[2], y[3], c, s1, s2, left, data[3] != 0.0)
    g[0] = r[1] if s1 != 0 else 1.0
    g[1] = r[3] if s2 != 0 else 1.0
    g[2] = c[K3] * (y[1] - y[3]) + c[C3] * (r[1] - r[3]) if left else 1.0


@njit(cache=True)
def _stage(
    kind: int, data: Vector, a: Vector, tau: float, t: float, y: Vector, h: float, k: np.ndarray, s: int, work: Vector
) -> None:  # pragma: no cover - compiled
    """Stage ``s``: ``k[s]`` = the field at ``(t + tau h, y + h sum_j a[j] k[j])``, ``j < s`` (the
    stage's state in ``work``)."""
    size = y.shape[0]
    for i in range(size):
        total = 0.0
        for j in range(s):
            total += a[j] * k[j, i]
        work[i] = y[i] + h * total
    _field(kind, t + tau * h, work, data, k[s])


@njit(cache=True)
def _attempt(
    kind: int, data: Vector, t: float, y: Vector, h: float, k: np.ndarray, out: Vector, work: Vector
) -> None:  # pragma: no cover - compiled
    """One Runge-Kutta step from ``(t, y)`` by ``h`` (``k[0]`` the field there): the stages in
    ``k``, the new state in ``out`` (SciPy's ``rk_step`` without its last stage; ``work`` a
    scratch vector of the state's size)."""
    for s in range(1, _STAGES):
        _stage(kind, data, _A[s], _C[s], t, y, h, k, s, work)
    for i in range(y.shape[0]):
        total = 0.0
        for j in range(_STAGES):
            total += _B[j] * k[j, i]
        out[i] = y[i] + h * total


@njit(cache=True)
def _error_norm(
    k: np.ndarray, h: float, y: Vector, y_new: Vector, rtol: float, atol: float
) -> float:  # pragma: no cover - compiled
    """SciPy's DOP853 error norm of the attempt in ``k`` (its last stage the field at ``y_new``)."""
    size = y.shape[0]
    err5, err3 = 0.0, 0.0
    for i in range(size):
        scale = atol + max(abs(y[i]), abs(y_new[i])) * rtol
        e5, e3 = 0.0, 0.0
        for j in range(_STAGES + 1):
            e5 += _E5[j] * k[j, i]
            e3 += _E3[j] * k[j, i]
        err5 += (e5 / scale) ** 2
        err3 += (e3 / scale) ** 2
    if err5 == 0.0 and err3 == 0.0:
        return 0.0
    return abs(h) * err5 / math.sqrt((err5 + 0.01 * err3) * size)


@njit(cache=True)
def _first_step(
    kind: int, data: Vector, t0: float, y: Vector, f: Vector, span: float, rtol: float, atol: float
) -> float:  # pragma: no cover - compiled
    """SciPy's ``select_initial_step`` (order 7)."""
    size = y.shape[0]
    d0, d1 = 0.0, 0.0
    for i in range(size):
        scale = atol + abs(y[i]) * rtol
        d0 += (y[i] / scale) ** 2
        d1 += (f[i] / scale) ** 2
    d0, d1 = math.sqrt(d0 / size), math.sqrt(d1 / size)
    h0 = min(1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1, span)
    f1 = np.empty(size)
    _field(kind, t0 + h0, y + h0 * f, data, f1)
    d2 = 0.0
    for i in range(size):
        d2 += ((f1[i] - f[i]) / (atol + abs(y[i]) * rtol)) ** 2
    d2 = math.sqrt(d2 / size) / h0
    h1 = max(1e-6, h0 * 1e-3) if d1 <= 1e-15 and d2 <= 1e-15 else (0.01 / max(d1, d2)) ** (1.0 / 8.0)
    return min(100.0 * h0, h1, span)


@njit(cache=True)
def _root(
    kind: int, data: Vector, t: float, y: Vector, f: Vector, h: float, which: int, g_lo: float, g_hi: float
) -> tuple[float, np.ndarray]:  # pragma: no cover - compiled
    """The time and state where extremum function ``which`` vanishes inside the step ``(t, t + h)``
    (values ``g_lo``, ``g_hi`` at its ends, neither zero): the Illinois method on ``tau``, each
    state one step from ``t``."""
    size = y.shape[0]
    k, state, g, work = np.empty((_STAGES + 1, size)), np.empty(size), np.empty(EXTREMA), np.empty(size)
    k[0, :] = f
    lo, hi, side = 0.0, h, 0
    for _ in range(200):
        if hi - lo <= 4.0 * _EPS * max(abs(t + lo), abs(t + hi)):
            break
        tau = hi - g_hi * (hi - lo) / (g_hi - g_lo) if g_hi != g_lo else 0.5 * (lo + hi)
        if not lo < tau < hi:
            tau = 0.5 * (lo + hi)
        _attempt(kind, data, t, y, tau, k, state, work)
        _extrema(kind, t + tau, state, data, g)
        value = g[which]
        if value == 0.0:
            return t + tau, state
        if (value > 0.0) == (g_lo > 0.0):
            lo, g_lo = tau, value
            g_hi *= 0.5 if side == -1 else 1.0
            side = -1
        else:
            hi, g_hi = tau, value
            g_lo *= 0.5 if side == 1 else 1.0
            side = 1
    _attempt(kind, data, t, y, 0.5 * (lo + hi), k, state, work)
    return t + 0.5 * (lo + hi), state


@njit(cache=True)
def _dense(
    kind: int, data: Vector, t: float, h: float, y: Vector, y_new: Vector, k: np.ndarray, out: np.ndarray, work: Vector
) -> None:  # pragma: no cover
    """``out`` (7 x size): the step's dense output's coefficients (SciPy's ``_dense_output_impl``)."""
    size = y.shape[0]
    for e in range(_A_EXTRA.shape[0]):
        _stage(kind, data, _A_EXTRA[e], _C_EXTRA[e], t, y, h, k, _STAGES + 1 + e, work)
    for i in range(size):
        delta = y_new[i] - y[i]
        out[0, i] = delta
        out[1, i] = h * k[0, i] - delta
        out[2, i] = 2.0 * delta - h * (k[_STAGES, i] + k[0, i])
        for r in range(_POWER - 3):
            total = 0.0
            for j in range(k.shape[0]):
                total += _D[r, j] * k[j, i]
            out[3 + r, i] = h * total


@njit(cache=True)
def _grown(rows: np.ndarray, count: int) -> np.ndarray:  # pragma: no cover - compiled
    """``rows`` with room for one more at ``count`` (twice as many rows when full)."""
    if count < rows.shape[0]:
        return rows
    bigger = np.empty((2 * rows.shape[0],) + rows.shape[1:])  # noqa: RUF005 - compiled: no unpacking
    bigger[:count] = rows[:count]
    return bigger


@njit(cache=True)
def _integrate(
    kind: int, data: Vector, t0: float, t1: float, y0: Vector, rtol: float, atol: float, dense: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:  # pragma: no cover - compiled
    """:func:`integrate_piece`'s steps: the end, the extrema's rows ``(which, t, state...)``, the
    steps' start times, their start states and their dense coefficients (``dense``)."""
    size = y0.shape[0]
    y, f, y_new, work = y0.copy(), np.empty(size), np.empty(size), np.empty(size)
    k = np.empty((_STAGES + 1 + (_A_EXTRA.shape[0] if dense else 0), size))
    g, g_new = np.empty(EXTREMA), np.empty(EXTREMA)
    found, count = np.empty((4, 2 + size)), 0
    starts, states = np.empty(16), np.empty((16, size))
    coefficients, steps = np.empty((16 if dense else 1, _POWER, size)), 0
    _field(kind, t0, y, data, f)
    _extrema(kind, t0, y, data, g)
    t, h_abs = t0, _first_step(kind, data, t0, y, f, t1 - t0, rtol, atol)
    while t < t1:
        rejected = False
        while True:
            if h_abs < 10.0 * (np.nextafter(t, np.inf) - t) or not math.isfinite(h_abs):
                raise RuntimeError("the step size fell below the time's resolution")
            t_new = min(t + h_abs, t1)
            h = t_new - t
            k[0, :] = f
            _attempt(kind, data, t, y, h, k, y_new, work)
            _field(kind, t_new, y_new, data, k[_STAGES])
            error = _error_norm(k, h, y, y_new, rtol, atol)
            if error < 1.0:
                factor = MAX_FACTOR if error == 0.0 else min(MAX_FACTOR, SAFETY * error**_EXPONENT)
                h_abs = h * (min(1.0, factor) if rejected else factor)
                break
            h_abs = h * (max(MIN_FACTOR, SAFETY * error**_EXPONENT) if math.isfinite(error) else MIN_FACTOR)
            rejected = True
        if dense:
            starts, states = _grown(starts[:, None], steps)[:, 0], _grown(states, steps)
            coefficients = _grown(coefficients, steps)
            starts[steps] = t
            states[steps, :] = y
            _dense(kind, data, t, h, y, y_new, k, coefficients[steps], work)
            steps += 1
        _extrema(kind, t_new, y_new, data, g_new)
        for which in range(EXTREMA):
            if (g[which] < 0.0) == (g_new[which] < 0.0) and g[which] != 0.0 and g_new[which] != 0.0:
                continue
            found = _grown(found, count)
            if g[which] == 0.0 or g_new[which] == 0.0:  # a root at an end of the step
                at, state = (t, y) if g[which] == 0.0 else (t_new, y_new)
            else:
                at, state = _root(kind, data, t, y, f, h, which, g[which], g_new[which])
            found[count, 0], found[count, 1], found[count, 2:] = which, at, state
            count += 1
        t = t_new
        y[:] = y_new
        f[:] = k[_STAGES]
        g[:] = g_new
    return y, found[:count], starts[:steps], states[:steps], coefficients[:steps]


@dataclass(frozen=True)
class IntegratedPiece:
    """A piece integrated again (:func:`integrate_piece`): its end, its extrema (``which``: 0 for
    ``a1 = 0``, 1 for ``a2 = 0``, 2 for the contact force's; their times and full states) and,
    where asked, SciPy's dense output of every step (:meth:`__call__`)."""

    t0: float
    t1: float
    end: np.ndarray
    which: np.ndarray
    times: np.ndarray
    states: np.ndarray
    starts: np.ndarray
    origins: np.ndarray
    coefficients: np.ndarray

    def __call__(self, t: float | np.ndarray) -> np.ndarray:
        """The vector at ``t`` (a time or an array of times: one column each, as SciPy's ``sol``)."""
        if not len(self.starts):
            raise ValueError("the piece was integrated without its dense output")
        times = np.atleast_1d(np.asarray(t, dtype=float))
        ends = np.append(self.starts[1:], self.t1)
        step = np.clip(np.searchsorted(self.starts, times, side="right") - 1, 0, len(self.starts) - 1)
        x = (times - self.starts[step]) / (ends[step] - self.starts[step])
        value = np.zeros((len(times), self.end.shape[0]))
        for r, f in enumerate(reversed(range(self.coefficients.shape[1]))):
            value += self.coefficients[step, f]
            value *= (x if r % 2 == 0 else 1.0 - x)[:, None]
        value += self.origins[step]
        return value[0] if np.ndim(t) == 0 else value.T


def integrate_piece(
    kind: int,
    data: np.ndarray,
    span: tuple[float, float],
    start: np.ndarray,
    *,
    rtol: float,
    atol: float,
    dense: bool = False,
) -> IntegratedPiece:
    """The field ``kind`` (its numbers ``data``) integrated from ``start`` over ``span`` (module
    docstring); a span of no length gives its start back."""
    t0, t1 = float(span[0]), float(span[1])
    start = np.ascontiguousarray(start, dtype=float)
    if not t1 > t0:
        empty = np.empty((0, len(start)))
        return IntegratedPiece(
            t0, t1, start.copy(), np.empty(0, np.int64), np.empty(0), empty, np.empty(0), empty, np.empty(0)
        )
    end, found, starts, origins, coefficients = _integrate(kind, data, t0, t1, start, rtol, atol, dense)
    return IntegratedPiece(
        t0, t1, end, found[:, 0].astype(np.int64), found[:, 1], found[:, 2:], starts, origins, coefficients
    )
