"""G-functions of Definitions 5.1-5.4, of order 0 and 1.

Each function returns ``(G0, G1)``: the 0th-order G-function (normal component of a field on a
boundary) and the 1st-order one (its total time derivative along the flow, computed
analytically by :func:`~oscillator.model.fields.non_friction_force_rate`).

The *side* of a velocity boundary is given by its velocity sign ``s`` (+1 or -1); the article's
domain number of that side is ``phase_space.domain_of(mass, s, ...)``.  Normals are (5.1)-(5.3):
``(0, 1)`` on velocity boundaries, ``(1, 0)`` on displacement boundaries.
"""

from __future__ import annotations

import numpy as np

from oscillator.compiled import njit
from oscillator.model.fields import (
    barrier,
    coefficients,
    force_rates,
    forces,
    kinetic,
)
from oscillator.model.parameters import Parameters
from oscillator.model.phase_space import Mode
from oscillator.model.types import StateLike, Vector

__all__ = [
    "barrier_index",
    "displacement_g",
    "displacement_values",
    "flow_barrier_g",
    "g_values",
    "velocity_g",
    "velocity_index",
]


@njit(cache=True)
def g_values(  # pragma: no cover - compiled
    t: float,
    x1: float,
    v1: float,
    x2: float,
    v2: float,
    left: bool,
    right: bool,
    s1: int,
    s2: int,
    c: Vector,
    out: Vector,
) -> None:
    """Every velocity and flow-barrier G-function of both masses at one point under one mode, into
    ``out`` (16 values; see :func:`velocity_index` and :func:`barrier_index`).

    The same formulas in the same order as evaluated one at a time, so the same numbers: the
    field of the side (4.13)-(4.14) or the barrier's (4.22), and its rate along the flow with
    the other mass following the mode's field and the mass itself accelerating at ``G0``
    (velocity boundary) or resting (flow barrier).
    """
    f1, f2 = forces(t, x1, v1, x2, v2, left, right, c)
    a1, a2 = kinetic(c, 1, s1, f1), kinetic(c, 2, s2, f2)
    k = 0
    for barrier_side in (False, True):
        for mass in (1, 2):
            for sign in (1, -1):
                force = f1 if mass == 1 else f2
                g0 = barrier(c, mass, sign, force) if barrier_side else kinetic(c, mass, sign, force)
                own = 0.0 if barrier_side else g0
                rates = force_rates(
                    t, x1, v1, x2, v2, left, right, own if mass == 1 else a1, a2 if mass == 1 else own, c
                )
                out[k], out[k + 1] = g0, rates[0] if mass == 1 else rates[1]
                k += 2


@njit(cache=True)
def velocity_index(mass: int, sign: int) -> int:  # pragma: no cover - compiled
    """Position of ``(G0, G1)`` of ``velocity_g(mass, sign)`` in the vector of :func:`g_values`."""
    return 4 * (mass - 1) + (0 if sign > 0 else 2)


@njit(cache=True)
def barrier_index(mass: int, sign: int) -> int:  # pragma: no cover - compiled
    """Position of ``(G0, G1)`` of ``flow_barrier_g(mass, sign)`` in the vector of :func:`g_values`."""
    return 8 + velocity_index(mass, sign)


@njit(cache=True)
def displacement_values(
    t: float,
    x1: float,
    v1: float,
    x2: float,
    v2: float,
    left: bool,
    right: bool,
    s1: int,
    s2: int,
    c: Vector,
    right_stop: bool,
) -> tuple[float, float]:  # pragma: no cover - compiled
    """:func:`displacement_g` on the parameter vector: ``(v1, a1)`` or ``(zdot1, a1 - a2)``."""
    f1, f2 = forces(t, x1, v1, x2, v2, left, right, c)
    a1, a2 = kinetic(c, 1, s1, f1), kinetic(c, 2, s2, f2)
    if right_stop:
        return v1, a1
    return v1 - v2, a1 - a2


def _values(t: float, y: StateLike, p: Parameters, mode: Mode) -> Vector:
    values = np.empty(16)
    x1, v1, x2, v2 = (float(v) for v in y[:4])
    g_values(float(t), x1, v1, x2, v2, mode.left, mode.right, mode.sign(1), mode.sign(2), coefficients(p), values)
    return values


def velocity_g(t: float, y: StateLike, p: Parameters, mode: Mode, mass: int, sign: int) -> tuple[float, float]:
    """``G^(0,delta)``, ``G^(1,delta)`` on m_i's velocity boundary, side ``s`` (5.4)-(5.5).

    ``G^(0,delta) = F_i^(delta)`` (or ``H_i^(delta)`` under left contact) and
    ``G^(1,delta) = D F_i^(delta)``, the field of side ``delta`` evaluated at ``y`` under the
    mode's contacts; the other mass follows the mode's field.
    """
    k = velocity_index(mass, sign)
    values = _values(t, y, p, mode)
    return float(values[k]), float(values[k + 1])


def flow_barrier_g(t: float, y: StateLike, p: Parameters, mode: Mode, mass: int, sign: int) -> tuple[float, float]:
    """``G^(0,0>0_delta)``, ``G^(1,0>0_delta)`` of a resting mass, side ``s`` (5.8)-(5.9).

    ``G^(0) = A_i - s (mu_s g + p_i)``; ``G^(1) = D A_i`` with the resting mass's acceleration
    zero.  Side ``s = +1`` is reached when ``A_i`` rises to ``mu_s g + p_i``, side ``s = -1``
    when it falls to ``-(mu_s g + p_i)``.
    """
    k = barrier_index(mass, sign)
    values = _values(t, y, p, mode)
    return float(values[k]), float(values[k + 1])


def displacement_g(t: float, y: StateLike, p: Parameters, mode: Mode, boundary: str) -> tuple[float, float]:
    """G-functions on a displacement boundary under the mode's field (5.6)-(5.7), (5.10)-(5.11).

    ``boundary = "right"`` (``x1 = d1``, absolute coordinates): ``(v1, a1)``.
    ``boundary = "left"`` (``z1 = -d``, relative coordinates): ``(zdot1, a1 - a2)``.
    """
    if boundary not in ("right", "left"):
        raise ValueError(f"boundary must be 'right' or 'left', got {boundary!r}")
    x1, v1, x2, v2 = (float(v) for v in y[:4])
    s1, s2, c = mode.sign(1), mode.sign(2), coefficients(p)
    g0, g1 = displacement_values(float(t), x1, v1, x2, v2, mode.left, mode.right, s1, s2, c, boundary == "right")
    return float(g0), float(g1)
