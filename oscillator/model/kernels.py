"""The right-hand side CVODE calls: compiled from the same formulas as everything else.

The state is ``(x1, v1, x2, v2)`` followed by the four work integrals of
:mod:`oscillator.model.energy`.  The root functions' kernel is :func:`oscillator.model.roots.root_kernel`.
"""

from __future__ import annotations

from oscillator.compiled import njit
from oscillator.model.energy import power_terms
from oscillator.model.fields import forces, kinetic
from oscillator.model.types import Vector

__all__ = ["derivative", "state_field"]


@njit(cache=True)
def state_field(  # pragma: no cover - compiled
    t: float, y: Vector, yp: Vector, c: Vector, s1: int, s2: int, left: bool, right: bool
) -> None:
    """Fill ``yp[:4]`` with the mode's field (4.9)-(4.14) at ``y[:4]``."""
    f1, f2 = forces(t, y[0], y[1], y[2], y[3], left, right, c)
    yp[0] = y[1]
    yp[1] = kinetic(c, 1, s1, f1)
    yp[2] = y[3]
    yp[3] = kinetic(c, 2, s2, f2)


@njit(cache=True)
def derivative(  # pragma: no cover - compiled
    t: float, y: Vector, yp: Vector, c: Vector, s1: int, s2: int, left: bool, right: bool
) -> None:
    """Fill ``yp`` with the mode's field (4.9)-(4.14) and the powers of the energy audit."""
    state_field(t, y, yp, c, s1, s2, left, right)
    forcing, feedback, damping, friction = power_terms(t, y[1], y[3], s1, s2, left, c)
    yp[4] = forcing
    yp[5] = feedback
    yp[6] = damping
    yp[7] = friction
