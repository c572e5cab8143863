"""Work-energy audit: mechanical energy and the powers that change it.

Multiplying each equation of motion by its velocity and adding gives, in every mode,

    dE/dt = P_forcing + P_feedback - P_damping - P_friction

with ``E = m1 v1^2/2 + m2 v2^2/2 + K1 x1^2/2 + K2 x1^4/4 + K4 x2^2/2 + K5 x2^4/4
+ L K3 (z1 + d)^2/2 + R K6 (x1 - d1)^2/2`` (the contact potentials vanish on their boundaries,
so ``E`` is continuous across contact switches).  Static friction does no work on a resting
mass.  The supervisor integrates the four powers alongside the state; the residual
``E(t1) - E(t0) - (W_forcing + W_feedback - W_damping - W_friction)`` measures the integration
and switching error.
"""

from __future__ import annotations

from oscillator.compiled import njit
from oscillator.model.fields import C1, C2, C3, C4, C5, M1, M2, MU_K, P1, P2, G, drives
from oscillator.model.parameters import Parameters
from oscillator.model.types import StateLike, Vector

__all__ = ["POWER_NAMES", "mechanical_energy", "power_terms", "powers"]

#: Names of the integrated work terms, in the order :func:`power_terms` returns them.
POWER_NAMES = ("forcing", "feedback", "damping", "friction")


def mechanical_energy(y: StateLike, p: Parameters, left: bool, right: bool) -> float:
    """Kinetic plus potential energy (J) under the given contacts (``inf`` past floating point)."""
    x1, v1, x2, v2 = (float(v) for v in y[:4])  # Python floats: an overflow gives inf, never raises
    squares = (x1 * x1, x2 * x2)
    energy = (
        0.5 * p.m1 * (v1 * v1)
        + 0.5 * p.m2 * (v2 * v2)
        + 0.5 * p.K1 * squares[0]
        + 0.25 * p.K2 * (squares[0] * squares[0])
        + 0.5 * p.K4 * squares[1]
        + 0.25 * p.K5 * (squares[1] * squares[1])
    )
    if left:
        gap = x1 - x2 + p.d
        energy += 0.5 * p.K3 * (gap * gap)
    if right:
        overlap = x1 - p.d1
        energy += 0.5 * p.K6 * (overlap * overlap)
    return energy


@njit(inline="always", cache=True)
def powers(
    v1: float, v2: float, s1: int, s2: int, left: bool, c: Vector, drive1: float, drive2: float
) -> tuple[float, float, float, float]:  # pragma: no cover - compiled
    """``(forcing, feedback, damping loss, friction loss)`` with the forcings ``drive_i`` given."""
    forcing = drive1 * v1 + drive2 * v2
    feedback = -(c[P1] * s1 * v1 + c[P2] * s2 * v2)
    square1, square2 = v1 * v1, v2 * v2
    damping = c[C1] * square1 + c[C2] * (square1 * square1) + c[C4] * square2 + c[C5] * (square2 * square2)
    if left:
        damping += c[C3] * ((v1 - v2) * (v1 - v2))
    friction = c[MU_K] * c[G] * (c[M1] * s1 * v1 + c[M2] * s2 * v2)
    return forcing, feedback, damping, friction


@njit(cache=True)
def power_terms(
    t: float, v1: float, v2: float, s1: int, s2: int, left: bool, c: Vector
) -> tuple[float, float, float, float]:  # pragma: no cover - compiled
    """``(forcing, feedback, damping loss, friction loss)`` of a mode at a point."""
    drive1, drive2 = drives(t, c)
    return powers(v1, v2, s1, s2, left, c, drive1, drive2)
