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

import math
from collections.abc import Sequence

from oscillator.parameters import Parameters
from oscillator.phase_space import Mode

__all__ = ["POWER_NAMES", "mechanical_energy", "powers"]

#: Names of the integrated work terms, in the order :func:`powers` returns them.
POWER_NAMES = ("forcing", "feedback", "damping", "friction")


def mechanical_energy(y: Sequence[float], p: Parameters, left: bool, right: bool) -> float:
    """Kinetic plus potential energy (J) under the given contacts."""
    x1, v1, x2, v2 = y[0], y[1], y[2], y[3]
    energy = (
        0.5 * p.m1 * v1**2
        + 0.5 * p.m2 * v2**2
        + 0.5 * p.K1 * x1**2
        + 0.25 * p.K2 * x1**4
        + 0.5 * p.K4 * x2**2
        + 0.25 * p.K5 * x2**4
    )
    if left:
        energy += 0.5 * p.K3 * (x1 - x2 + p.d) ** 2
    if right:
        energy += 0.5 * p.K6 * (x1 - p.d1) ** 2
    return energy


def powers(t: float, y: Sequence[float], p: Parameters, mode: Mode) -> tuple[float, float, float, float]:
    """``(forcing, feedback, damping loss, friction loss)`` power (W) in a mode.

    Feedback ``-P_i s_i v_i`` and friction loss ``mu_k m_i g s_i v_i`` use the mode's velocity
    signs ``s_i``; both vanish for a resting mass.
    """
    v1, v2 = y[1], y[3]
    s1, s2 = mode.sign(1), mode.sign(2)
    forcing = p.Q1 * math.sin(p.Omega * t + p.phi1) * v1 + p.Q2 * math.sin(p.Omega * t + p.phi2) * v2
    feedback = -(p.P1 * s1 * v1 + p.P2 * s2 * v2)
    damping = p.C1 * v1**2 + p.C2 * v1**4 + p.C4 * v2**2 + p.C5 * v2**4
    if mode.left:
        damping += p.C3 * (v1 - v2) ** 2
    friction = p.mu_k * p.g * (p.m1 * s1 * v1 + p.m2 * s2 * v2)
    return forcing, feedback, damping, friction
