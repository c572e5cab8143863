"""The tangent system: how the state and the response integrals move with the parameters.

In a mode the state obeys ``y' = f(t, y, c)`` (``c`` the parameter vector, :func:`~oscillator.model.
fields.coefficients`), and the response integrals ``I' = g(t, y, c)`` (:mod:`oscillator.orbits.response`:
``x1^2, x2^2, a1^2, a2^2``, the five powers, the two contact forces and their squares).  Their derivatives along a
parameter ``c_j`` at fixed time, ``sigma_j = dy/dc_j`` and ``dI/dc_j``, obey the tangent equations

    sigma_j' = J sigma_j + df/dc_j,        (dI/dc_j)' = dg/dy sigma_j + dg/dc_j,

with ``J = df/dy`` (:func:`~oscillator.model.kernels.jacobian`).  This module holds the derivatives of
the formulas in ``c`` and in ``y`` that the equations need (:func:`force_gradient`,
:func:`threshold_gradient`) and their right-hand side (:func:`tangent_rates`), compiled like the
fields they differentiate.  Column ``k`` of ``df/dc`` is zero in the displacement rows, and in the
velocity row of a resting mass (its field is zero whatever the parameters, (4.12)).
"""

from __future__ import annotations

import math

import numpy as np

from oscillator.compiled import njit
from oscillator.model.fields import (
    C1,
    C2,
    C3,
    C4,
    C5,
    D1,
    K1,
    K2,
    K3,
    K4,
    K5,
    K6,
    M1,
    M2,
    MU_K,
    MU_S,
    OMEGA,
    P1,
    P2,
    PHI1,
    PHI2,
    Q1,
    Q2,
    D,
    G,
    drives,
    mass_forces,
)
from oscillator.model.kernels import jacobian, rates
from oscillator.model.types import Vector

__all__ = [
    "INTEGRALS",
    "force_gradient",
    "jacobian_gradient",
    "map_rates",
    "monodromy_rates",
    "tangent_rates",
    "threshold_gradient",
]

#: The response integrals carried with the state, in :mod:`oscillator.orbits.response`'s order:
#: ``x1^2, x2^2, a1^2, a2^2``, the five powers, the right stop's and the left contact's force,
#: and the squares of the two forces.
INTEGRALS = 13
#: The parameter vector's length.
_SIZE = 25


@njit(cache=True)
def force_gradient(
    t: float, x1: float, v1: float, x2: float, v2: float, left: bool, right: bool, c: Vector, out: Vector
) -> None:  # pragma: no cover - compiled
    """Fill ``out`` (2 x 25) with ``dA_i/dc`` at fixed ``(t, y)``: the non-friction force per unit mass
    (:func:`~oscillator.model.fields.non_friction_force`) differentiated in each parameter."""
    out[:, :] = 0.0
    drive1, drive2 = drives(t, c)
    f1, f2 = mass_forces(x1, v1, x2, v2, left, right, c, drive1, drive2)
    m1, m2 = c[M1], c[M2]
    wave1, wave2 = math.cos(c[OMEGA] * t + c[PHI1]), math.cos(c[OMEGA] * t + c[PHI2])
    out[0, Q1] = math.sin(c[OMEGA] * t + c[PHI1]) / m1
    out[0, PHI1] = c[Q1] * wave1 / m1
    out[0, OMEGA] = c[Q1] * t * wave1 / m1
    out[0, K1], out[0, K2] = -x1 / m1, -(x1 * x1 * x1) / m1
    out[0, C1], out[0, C2] = -v1 / m1, -(v1 * v1 * v1) / m1
    out[0, M1] = -f1 / (m1 * m1)
    out[1, Q2] = math.sin(c[OMEGA] * t + c[PHI2]) / m2
    out[1, PHI2] = c[Q2] * wave2 / m2
    out[1, OMEGA] = c[Q2] * t * wave2 / m2
    out[1, K4], out[1, K5] = -x2 / m2, -(x2 * x2 * x2) / m2
    out[1, C4], out[1, C5] = -v2 / m2, -(v2 * v2 * v2) / m2
    out[1, M2] = -f2 / (m2 * m2)
    if left:
        gap, closing = x1 - x2 + c[D], v1 - v2
        out[0, K3], out[0, C3], out[0, D] = -gap / m1, -closing / m1, -c[K3] / m1
        out[1, K3], out[1, C3], out[1, D] = gap / m2, closing / m2, c[K3] / m2
    if right:
        out[0, K6], out[0, D1] = -(x1 - c[D1]) / m1, c[K6] / m1


@njit(cache=True)
def threshold_gradient(c: Vector, mass: int, static: bool, out: Vector) -> None:  # pragma: no cover - compiled
    """Fill ``out`` (25) with the derivative of ``mu g + p_i`` (``p_i = P_i / m_i``;
    :func:`~oscillator.model.fields.threshold`) in each parameter."""
    out[:] = 0.0
    mu = MU_S if static else MU_K
    out[mu] = c[G]
    out[G] = c[mu]
    if mass == 1:
        out[P1], out[M1] = 1.0 / c[M1], -c[P1] / (c[M1] * c[M1])
    else:
        out[P2], out[M2] = 1.0 / c[M2], -c[P2] / (c[M2] * c[M2])


@njit(cache=True)
def field_gradient(
    t: float, y: Vector, c: Vector, s1: int, s2: int, left: bool, right: bool, out: Vector
) -> None:  # pragma: no cover - compiled
    """Fill ``out`` (4 x 25) with ``df/dc`` of the mode's field at fixed ``(t, y)``."""
    out[:, :] = 0.0
    forces = np.empty((2, _SIZE))
    force_gradient(t, y[0], y[1], y[2], y[3], left, right, c, forces)
    friction = np.empty(_SIZE)
    for mass in (1, 2):
        sign = s1 if mass == 1 else s2
        if sign != 0:
            threshold_gradient(c, mass, False, friction)
            for k in range(_SIZE):
                out[2 * mass - 1, k] = forces[mass - 1, k] - sign * friction[k]


@njit(cache=True)
def _integrand_gradients(
    t: float,
    y: Vector,
    c: Vector,
    s1: int,
    s2: int,
    left: bool,
    right: bool,
    grad: Vector,
    partial: Vector,
) -> None:  # pragma: no cover - compiled
    """Fill ``grad`` (13 x 4) with ``dg/dy`` and ``partial`` (13 x 25) with ``dg/dc`` for the response
    integrands but the two accelerations' squares (their derivatives need the field's own)."""
    x1, v1, x2, v2 = y[0], y[1], y[2], y[3]
    grad[:, :] = 0.0
    partial[:, :] = 0.0
    grad[0, 0], grad[1, 2] = 2.0 * x1, 2.0 * x2
    drive1, drive2 = drives(t, c)
    grad[4, 1], grad[4, 3] = drive1, drive2
    sine1, sine2 = math.sin(c[OMEGA] * t + c[PHI1]), math.sin(c[OMEGA] * t + c[PHI2])
    wave1, wave2 = math.cos(c[OMEGA] * t + c[PHI1]), math.cos(c[OMEGA] * t + c[PHI2])
    partial[4, Q1], partial[4, Q2] = sine1 * v1, sine2 * v2
    partial[4, PHI1], partial[4, PHI2] = c[Q1] * wave1 * v1, c[Q2] * wave2 * v2
    partial[4, OMEGA] = t * (c[Q1] * wave1 * v1 + c[Q2] * wave2 * v2)
    grad[5, 1], grad[5, 3] = -c[P1] * s1, -c[P2] * s2
    partial[5, P1], partial[5, P2] = -s1 * v1, -s2 * v2
    grad[6, 1] = 2.0 * c[C1] * v1 + 4.0 * c[C2] * v1 * v1 * v1
    grad[6, 3] = 2.0 * c[C4] * v2 + 4.0 * c[C5] * v2 * v2 * v2
    partial[6, C1], partial[6, C2] = v1 * v1, v1 * v1 * v1 * v1
    partial[6, C4], partial[6, C5] = v2 * v2, v2 * v2 * v2 * v2
    if left:
        closing = v1 - v2
        grad[7, 1], grad[7, 3] = 2.0 * c[C3] * closing, -2.0 * c[C3] * closing
        partial[7, C3] = closing * closing
    friction = c[MU_K] * c[G]
    grad[8, 1], grad[8, 3] = friction * c[M1] * s1, friction * c[M2] * s2
    moving = c[M1] * s1 * v1 + c[M2] * s2 * v2
    partial[8, MU_K], partial[8, G] = c[G] * moving, c[MU_K] * moving
    partial[8, M1], partial[8, M2] = friction * s1 * v1, friction * s2 * v2
    if right:  # the stop's force K6 (x1 - d1)
        grad[9, 0] = c[K6]
        partial[9, K6], partial[9, D1] = x1 - c[D1], -c[K6]
    if left:  # the compressive force -(K3 (x1 - x2 + d) + C3 (v1 - v2))
        grad[10, 0], grad[10, 1], grad[10, 2], grad[10, 3] = -c[K3], -c[C3], c[K3], c[C3]
        partial[10, K3], partial[10, C3], partial[10, D] = -(x1 - x2 + c[D]), -(v1 - v2), -c[K3]
    forces = (c[K6] * (x1 - c[D1]) if right else 0.0, -(c[K3] * (x1 - x2 + c[D]) + c[C3] * (v1 - v2)) if left else 0.0)
    for q in range(2):  # d(F^2) = 2 F dF
        for m in range(4):
            grad[11 + q, m] = 2.0 * forces[q] * grad[9 + q, m]
        for m in range(_SIZE):
            partial[11 + q, m] = 2.0 * forces[q] * partial[9 + q, m]


@njit(cache=True)
def tangent_rates(
    t: float, state: Vector, c: Vector, columns: np.ndarray, s1: int, s2: int, left: bool, right: bool, out: Vector
) -> None:  # pragma: no cover - compiled
    """The right-hand side of the tangent system (module docstring) for the parameters ``columns``
    (their positions in ``c``, ``k`` of them).  Layout of ``state`` and ``out``: ``y`` (4), the
    integrals (13), ``sigma`` (4 x k, row by row), ``dI/dc`` (13 x k, row by row)."""
    k = len(columns)
    y = state[:4]
    r = rates(t, y[0], y[1], y[2], y[3], c, s1, s2, left, right)
    out[0], out[1], out[2], out[3] = r[0], r[1], r[2], r[3]
    a1, a2 = r[1], r[3]
    contact = c[C3] * (y[1] - y[3]) ** 2 if left else 0.0
    out[4], out[5], out[6], out[7] = y[0] * y[0], y[2] * y[2], a1 * a1, a2 * a2
    out[8], out[9], out[10], out[11], out[12] = r[4], r[5], r[6] - contact, contact, r[7]
    out[13] = c[K6] * (y[0] - c[D1]) if right else 0.0
    out[14] = -(c[K3] * (y[0] - y[2] + c[D]) + c[C3] * (y[1] - y[3])) if left else 0.0
    out[15], out[16] = out[13] * out[13], out[14] * out[14]
    if k == 0:  # the response integrals alone (oscillator.orbits.response): no gradient to build
        return
    sigma = state[4 + INTEGRALS : 4 + INTEGRALS + 4 * k]
    tangent = out[4 + INTEGRALS : 4 + INTEGRALS + 4 * k]
    _sigma_rates(t, y, c, columns, s1, s2, left, right, sigma, tangent)
    grad = np.empty((INTEGRALS, 4))
    partial = np.empty((INTEGRALS, _SIZE))
    _integrand_gradients(t, y, c, s1, s2, left, right, grad, partial)
    integral = out[4 + INTEGRALS + 4 * k :]
    for j in range(k):
        p = int(columns[j])
        for q in range(INTEGRALS):
            total = partial[q, p]
            for m in range(4):
                total += grad[q, m] * sigma[m * k + j]
            integral[q * k + j] = total
        # d(a_i^2) = 2 a_i da_i, da_i the velocity row of the tangent just computed
        integral[2 * k + j] = 2.0 * a1 * tangent[1 * k + j]
        integral[3 * k + j] = 2.0 * a2 * tangent[3 * k + j]


@njit(cache=True)
def _sigma_rates(
    t: float,
    y: Vector,
    c: Vector,
    columns: np.ndarray,
    s1: int,
    s2: int,
    left: bool,
    right: bool,
    sigma: Vector,
    out: Vector,
) -> None:  # pragma: no cover - compiled
    """``out`` = ``J sigma + df/dc`` for the parameters ``columns`` (``sigma`` and ``out`` 4 x k,
    row by row)."""
    k = len(columns)
    jac = np.empty(16)
    jacobian(y[0], y[1], y[2], y[3], c, s1, s2, left, right, jac)
    fc = np.empty((4, _SIZE))
    field_gradient(t, y, c, s1, s2, left, right, fc)
    for j in range(k):
        p = int(columns[j])
        for row in range(4):
            total = fc[row, p]
            for m in range(4):
                total += jac[4 * row + m] * sigma[m * k + j]
            out[row * k + j] = total


@njit(cache=True)
def map_rates(
    t: float, state: Vector, c: Vector, columns: np.ndarray, s1: int, s2: int, left: bool, right: bool, out: Vector
) -> None:  # pragma: no cover - compiled
    """The tangent system without the response integrals: ``y`` (4) and ``sigma`` (4 x k, row by
    row) in ``state`` and ``out`` (what the derivative of the period map in a parameter needs)."""
    k = len(columns)
    r = rates(t, state[0], state[1], state[2], state[3], c, s1, s2, left, right)
    out[0], out[1], out[2], out[3] = r[0], r[1], r[2], r[3]
    _sigma_rates(t, state[:4], c, columns, s1, s2, left, right, state[4 : 4 + 4 * k], out[4 : 4 + 4 * k])


@njit(cache=True)
def jacobian_gradient(
    y: Vector, c: Vector, direction: Vector, p: int, s1: int, s2: int, left: bool, right: bool, out: Vector
) -> None:  # pragma: no cover - compiled
    """Fill ``out`` (16, row by row) with the derivative of ``J = df/dy``
    (:func:`~oscillator.model.kernels.jacobian`) along the state ``direction`` (4) and in the
    parameter at position ``p`` of ``c`` (none when ``p < 0``): ``sum_m dJ/dy_m direction_m + dJ/dc_p``.

    ``J`` depends on the state only through the cubic spring and damper (``3 K2 x1^2``, ``3 C2 v1^2``,
    ...) and on the parameters through the stiffnesses and dampings over the masses; a resting mass's
    rows stay zero."""
    for k in range(16):
        out[k] = 0.0
    for mass in (1, 2):
        sign = s1 if mass == 1 else s2
        if sign == 0:
            continue
        own, other = 2 * mass - 2, 4 - 2 * mass
        linear_k, cubic_k, linear_c, cubic_c, m = (K1, K2, C1, C2, M1) if mass == 1 else (K4, K5, C4, C5, M2)
        x, v, weight = y[own], y[own + 1], c[m]
        stiffness = c[linear_k] + 3.0 * c[cubic_k] * x * x + (c[K3] if left else 0.0)
        damping = c[linear_c] + 3.0 * c[cubic_c] * v * v + (c[C3] if left else 0.0)
        d_stiffness = 6.0 * c[cubic_k] * x * direction[own] + (p == linear_k) + 3.0 * x * x * (p == cubic_k)
        d_damping = 6.0 * c[cubic_c] * v * direction[own + 1] + (p == linear_c) + 3.0 * v * v * (p == cubic_c)
        if left:
            d_stiffness += p == K3
            d_damping += p == C3
        if right and mass == 1:
            stiffness += c[K6]
            d_stiffness += p == K6
        d_weight = 1.0 if p == m else 0.0
        row = 4 * (2 * mass - 1)
        out[row + own] = -d_stiffness / weight + stiffness * d_weight / (weight * weight)
        out[row + own + 1] = -d_damping / weight + damping * d_weight / (weight * weight)
        if left:
            out[row + other] = (p == K3) / weight - c[K3] * d_weight / (weight * weight)
            out[row + other + 1] = (p == C3) / weight - c[C3] * d_weight / (weight * weight)


@njit(cache=True)
def monodromy_rates(
    t: float, state: Vector, c: Vector, columns: np.ndarray, s1: int, s2: int, left: bool, right: bool, out: Vector
) -> None:  # pragma: no cover - compiled
    """The right-hand side of the second-order tangent system for the parameters ``columns`` (``k``):
    the state, ``sigma_j' = J sigma_j + df/dc_j``, the flow's derivative ``Phi' = J Phi`` and its
    derivative in each parameter ``Psi_j' = J Psi_j + (dJ/dy . sigma_j + dJ/dc_j) Phi``
    (:mod:`oscillator.orbits.monodromy_derivative`).  Layout of ``state`` and ``out``: ``y`` (4),
    ``sigma`` (4 x k, row by row), ``Phi`` (4 x 4), ``Psi`` (k x 4 x 4)."""
    k = len(columns)
    y = state[:4]
    r = rates(t, y[0], y[1], y[2], y[3], c, s1, s2, left, right)
    out[0], out[1], out[2], out[3] = r[0], r[1], r[2], r[3]
    jac = np.empty(16)
    jacobian(y[0], y[1], y[2], y[3], c, s1, s2, left, right, jac)
    fc = np.empty((4, _SIZE))
    field_gradient(t, y, c, s1, s2, left, right, fc)
    sigma = state[4 : 4 + 4 * k]
    phi = state[4 + 4 * k : 20 + 4 * k]
    psi = state[20 + 4 * k :]
    for row in range(4):
        for col in range(4):
            total = 0.0
            for m in range(4):
                total += jac[4 * row + m] * phi[4 * m + col]
            out[4 + 4 * k + 4 * row + col] = total
    direction = np.empty(4)
    bent = np.empty(16)
    for j in range(k):
        p = columns[j]
        for row in range(4):
            direction[row] = sigma[row * k + j]
        for row in range(4):
            total = fc[row, p]
            for m in range(4):
                total += jac[4 * row + m] * direction[m]
            out[4 + row * k + j] = total
        jacobian_gradient(y, c, direction, p, s1, s2, left, right, bent)
        base = 16 * j
        for row in range(4):
            for col in range(4):
                total = 0.0
                for m in range(4):
                    total += jac[4 * row + m] * psi[base + 4 * m + col] + bent[4 * row + m] * phi[4 * m + col]
                out[20 + 4 * k + base + 4 * row + col] = total
