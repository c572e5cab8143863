"""G-functions of Definitions 5.1-5.4, of order 0 and 1.

Each function returns ``(G0, G1)``: the 0th-order G-function (normal component of a field on a
boundary) and the 1st-order one (its total time derivative along the flow, computed
analytically by :func:`~oscillator.model.fields.non_friction_force_rate`).

The *side* of a velocity boundary is given by its velocity sign ``s`` (+1 or -1); the article's
domain number of that side is ``phase_space.domain_of(mass, s, ...)``.  Normals are (5.1)-(5.3):
``(0, 1)`` on velocity boundaries, ``(1, 0)`` on displacement boundaries.
"""

from __future__ import annotations

from oscillator.model.fields import (
    accelerations,
    flow_barrier_field,
    kinetic_field,
    non_friction_force,
    non_friction_force_rate,
)
from oscillator.model.parameters import Parameters
from oscillator.model.phase_space import Mode
from oscillator.model.types import StateLike

__all__ = ["displacement_g", "flow_barrier_g", "velocity_g"]


def _rate_of_force(t: float, y: StateLike, p: Parameters, mode: Mode, mass: int, own_acceleration: float) -> float:
    """``D A_i`` with mass ``mass`` accelerating at ``own_acceleration`` and the other mass
    following the mode's field."""
    a1, a2 = accelerations(t, y, p, mode)
    if mass == 1:
        a1 = own_acceleration
    else:
        a2 = own_acceleration
    rates = non_friction_force_rate(t, y, p, mode.left, mode.right, a1, a2)
    return rates[mass - 1]


def velocity_g(t: float, y: StateLike, p: Parameters, mode: Mode, mass: int, sign: int) -> tuple[float, float]:
    """``G^(0,delta)``, ``G^(1,delta)`` on m_i's velocity boundary, side ``s`` (5.4)-(5.5).

    ``G^(0,delta) = F_i^(delta)`` (or ``H_i^(delta)`` under left contact) and
    ``G^(1,delta) = D F_i^(delta)``, the field of side ``delta`` evaluated at ``y`` under the
    mode's contacts; the other mass follows the mode's field.
    """
    force = non_friction_force(t, y, p, mode.left, mode.right)[mass - 1]
    g0 = kinetic_field(p, mass, sign, force)
    return g0, _rate_of_force(t, y, p, mode, mass, g0)


def flow_barrier_g(t: float, y: StateLike, p: Parameters, mode: Mode, mass: int, sign: int) -> tuple[float, float]:
    """``G^(0,0>0_delta)``, ``G^(1,0>0_delta)`` of a resting mass, side ``s`` (5.8)-(5.9).

    ``G^(0) = A_i - s (mu_s g + p_i)``; ``G^(1) = D A_i`` with the resting mass's acceleration
    zero.  Side ``s = +1`` is reached when ``A_i`` rises to ``mu_s g + p_i``, side ``s = -1``
    when it falls to ``-(mu_s g + p_i)``.
    """
    force = non_friction_force(t, y, p, mode.left, mode.right)[mass - 1]
    return flow_barrier_field(p, mass, sign, force), _rate_of_force(t, y, p, mode, mass, 0.0)


def displacement_g(t: float, y: StateLike, p: Parameters, mode: Mode, boundary: str) -> tuple[float, float]:
    """G-functions on a displacement boundary under the mode's field (5.6)-(5.7), (5.10)-(5.11).

    ``boundary = "right"`` (``x1 = d1``, absolute coordinates): ``(v1, a1)``.
    ``boundary = "left"`` (``z1 = -d``, relative coordinates): ``(zdot1, a1 - a2)``.
    """
    a1, a2 = accelerations(t, y, p, mode)
    if boundary == "right":
        return y[1], a1
    if boundary == "left":
        return y[1] - y[3], a1 - a2
    raise ValueError(f"boundary must be 'right' or 'left', got {boundary!r}")
