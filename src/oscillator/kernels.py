"""The right-hand side CVODE calls: compiled from the same formulas as everything else.

The state is ``(x1, v1, x2, v2)`` followed by the four work integrals of
:mod:`oscillator.energy`.  The root functions' kernel is :func:`oscillator.detection.root_kernel`.
"""

from __future__ import annotations

from numba import njit

from oscillator.energy import power_terms
from oscillator.fields import forces, kinetic

__all__ = ["derivative"]


@njit(cache=True)
def derivative(t, y, yp, c, s1, s2, left, right):  # pragma: no cover - compiled
    """Fill ``yp`` with the mode's field (4.9)-(4.14) and the powers of the energy audit."""
    f1, f2 = forces(t, y[0], y[1], y[2], y[3], left, right, c)
    yp[0] = y[1]
    yp[1] = kinetic(c, 1, s1, f1)
    yp[2] = y[3]
    yp[3] = kinetic(c, 2, s2, f2)
    forcing, feedback, damping, friction = power_terms(t, y[1], y[3], s1, s2, left, c)
    yp[4] = forcing
    yp[5] = feedback
    yp[6] = damping
    yp[7] = friction
