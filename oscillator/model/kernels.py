"""The right-hand sides CVODE calls: compiled from the same formulas as everything else.

The state is ``(x1, v1, x2, v2)`` followed by the four work integrals of
:mod:`oscillator.model.energy` (:func:`derivative`); when the derivative of the flow is carried
along, the 16 entries of ``Phi = d y(t) / d y(t_0)`` row by row follow (:func:`variational_derivative`):
in a mode the field ``f(t, y) = (v1, F1, v2, F2)`` (4.9)-(4.14) is smooth and ``Phi' = J(t, y) Phi``
with ``J = df/dy`` (:func:`jacobian`).  The root functions' kernel is
:func:`oscillator.model.roots.root_kernel`.
"""

from __future__ import annotations

import numpy as np

from oscillator.compiled import njit
from oscillator.model.energy import powers
from oscillator.model.fields import (
    C1,
    C2,
    C3,
    C4,
    C5,
    K1,
    K2,
    K3,
    K4,
    K5,
    K6,
    M1,
    M2,
    MU_K,
    P1,
    P2,
    G,
    coefficients,
    drives,
    mass_forces,
)
from oscillator.model.parameters import Parameters
from oscillator.model.phase_space import Mode
from oscillator.model.types import VARIATIONAL, Vector

__all__ = ["derivative", "field_jacobian", "jacobian", "rates", "variational_derivative"]


@njit(inline="always", cache=True)
def rates(
    t: float, x1: float, v1: float, x2: float, v2: float, c: Vector, s1: int, s2: int, left: bool, right: bool
) -> tuple[float, float, float, float, float, float, float, float]:  # pragma: no cover - compiled
    """The mode's field (4.9)-(4.14) and the powers of the energy audit, as one scalar function:
    ``(v1, a1, v2, a2, forcing, feedback, damping loss, friction loss)``.

    The forces of :func:`~oscillator.model.fields.mass_forces`, the powers of
    :func:`~oscillator.model.energy.powers`, each forcing's sine once
    (:func:`~oscillator.model.fields.drives`), all inlined into the caller: the integrators call it
    at every stage, where a call costs more than the arithmetic."""
    drive1, drive2 = drives(t, c)
    f1, f2 = mass_forces(x1, v1, x2, v2, left, right, c, drive1, drive2)
    a1 = 0.0 if s1 == 0 else f1 / c[M1] - s1 * (c[MU_K] * c[G] + c[P1] / c[M1])
    a2 = 0.0 if s2 == 0 else f2 / c[M2] - s2 * (c[MU_K] * c[G] + c[P2] / c[M2])
    forcing, feedback, damping, friction = powers(v1, v2, s1, s2, left, c, drive1, drive2)
    return v1, a1, v2, a2, forcing, feedback, damping, friction


@njit(cache=True)
def derivative(  # pragma: no cover - compiled
    t: float, y: Vector, yp: Vector, c: Vector, s1: int, s2: int, left: bool, right: bool
) -> None:
    """Fill ``yp`` with the mode's field (4.9)-(4.14) and the powers of the energy audit (:func:`rates`)."""
    r = rates(t, y[0], y[1], y[2], y[3], c, s1, s2, left, right)
    yp[0], yp[1], yp[2], yp[3] = r[0], r[1], r[2], r[3]
    yp[4], yp[5], yp[6], yp[7] = r[4], r[5], r[6], r[7]


@njit(cache=True)
def jacobian(  # pragma: no cover - compiled
    x1: float, v1: float, x2: float, v2: float, c: Vector, s1: int, s2: int, left: bool, right: bool, out: Vector
) -> None:
    """Fill ``out`` (16, row by row) with ``df/dy`` of the mode's field.

    For a moving mass, row ``x_i`` is ``dx_i'/dy = e_(v_i)`` and row ``v_i`` is ``dA_i/dy`` (the
    friction term ``s_i (mu_k g + p_i)`` is constant in a mode).  A resting mass's field is
    ``(0, 0)`` whatever the state (4.12): both its rows are zero, so a displacement of a resting
    mass stays as it is (it rests where it was put) and nothing moves it.  Its velocity
    perturbation is removed where the rest begins (:func:`oscillator.model.saltation.rest_projection`).
    """
    for k in range(16):
        out[k] = 0.0
    if s1 != 0:
        out[1] = 1.0
        out[4] = (-c[K1] - 3.0 * c[K2] * x1 * x1 - (c[K3] if left else 0.0) - (c[K6] if right else 0.0)) / c[M1]
        out[5] = (-c[C1] - 3.0 * c[C2] * v1 * v1 - (c[C3] if left else 0.0)) / c[M1]
        if left:
            out[6] = c[K3] / c[M1]
            out[7] = c[C3] / c[M1]
    if s2 != 0:
        out[11] = 1.0
        out[14] = (-c[K4] - 3.0 * c[K5] * x2 * x2 - (c[K3] if left else 0.0)) / c[M2]
        out[15] = (-c[C4] - 3.0 * c[C5] * v2 * v2 - (c[C3] if left else 0.0)) / c[M2]
        if left:
            out[12] = c[K3] / c[M2]
            out[13] = c[C3] / c[M2]


@njit(cache=True)
def variational_derivative(  # pragma: no cover - compiled
    t: float, y: Vector, yp: Vector, c: Vector, s1: int, s2: int, left: bool, right: bool
) -> None:
    """:func:`derivative` and ``J(t, y) Phi`` for the 24-vector ``(y, works, Phi)``."""
    derivative(t, y, yp, c, s1, s2, left, right)
    j = np.empty(16)
    jacobian(y[0], y[1], y[2], y[3], c, s1, s2, left, right, j)
    for row in range(4):
        for col in range(4):
            total = 0.0
            for k in range(4):
                total += j[4 * row + k] * y[VARIATIONAL + 4 * k + col]
            yp[VARIATIONAL + 4 * row + col] = total


def field_jacobian(y: np.ndarray, p: Parameters, mode: Mode) -> np.ndarray:
    """``df/dy`` (4 x 4) of ``mode``'s field at ``y`` (it does not depend on ``t``)."""
    out = np.empty(16)
    jacobian(
        float(y[0]),
        float(y[1]),
        float(y[2]),
        float(y[3]),
        coefficients(p),
        mode.sign(1),
        mode.sign(2),
        mode.left,
        mode.right,
        out,
    )
    return out.reshape(4, 4)
