"""Vector fields of each domain (article Sec. 4.2, Eqs. (4.9)-(4.27)).

All functions are pure functions of ``(t, y, params, ...)`` with ``y = (x1, v1, x2, v2)``.
The contact terms are switched by the *mode's* flags, never by the state: each domain's field
is smooth and every switch is a root function watched by the supervisor.

Notation (docs/model.md, Sec. 1 and 3): ``A_i`` is the non-friction force per unit mass **without**
the feedback term; the field of a moving mass with velocity sign ``s`` is
``F_i = A_i - s (mu_k g + p_i)`` (the article writes F in domains 1-4 and H in 5-8; one formula
serves both, the contact terms being part of ``A_i``).
"""

from __future__ import annotations

import functools
import math

import numpy as np
from numba import types

from oscillator.compiled import njit
from oscillator.model.parameters import Parameters
from oscillator.model.phase_space import Mode
from oscillator.model.types import StateLike, Vector

__all__ = [
    "accelerations",
    "coefficients",
    "flow_barrier_field",
    "force_scale",
    "kinetic_field",
    "kinetic_threshold",
    "non_friction_force",
    "non_friction_force_rate",
    "scale_of",
    "state_derivative",
    "static_threshold",
]

#: The parameter vector's type in the compiled formulas' signatures.  The small formulas that many
#: kernels call with constant arguments (``kinetic(c, 1, ...)``) have their one signature given:
#: else numba compiles them again for each constant (17 versions, 3 s of the first run).
_C = types.Array(types.float64, 1, "C")
_f, _i, _b = types.float64, types.int64, types.boolean

# Each formula is written once, as a compiled (numba) scalar function of a parameter vector; the
# Python functions below and the CVODE kernels (``oscillator.model.kernels``) all call these.
# Positions in the vector: the order of Parameters.names().
_POSITION = {name: index for index, name in enumerate(Parameters.names())}
(M1, M2, C1, C2, C3, C4, C5, K1, K2, K3, K4, K5, K6, MU_K, MU_S, D, D1, Q1, Q2, OMEGA, PHI1, PHI2, P1, P2, G) = (
    _POSITION[name]
    for name in (
        "m1",
        "m2",
        "C1",
        "C2",
        "C3",
        "C4",
        "C5",
        "K1",
        "K2",
        "K3",
        "K4",
        "K5",
        "K6",
        "mu_k",
        "mu_s",
        "d",
        "d1",
        "Q1",
        "Q2",
        "Omega",
        "phi1",
        "phi2",
        "P1",
        "P2",
        "g",
    )
)


#: Parameters -> their vector, keyed by identity: called a few dozen times at every root, where
#: hashing the 25 fields (an lru_cache) cost more than the formulas.
_VECTORS: dict[int, tuple[Parameters, Vector]] = {}
_MAX_VECTORS = 64


def coefficients(p: Parameters) -> Vector:
    """The parameters as the vector the compiled formulas take (cached: shared, never written to).

    The vector is writable, as the C callbacks' view of CVODE's user data is: a read-only one would
    make numba compile every formula a second time for it (3 s of the first run)."""
    entry = _VECTORS.get(id(p))
    if entry is not None and entry[0] is p:
        return entry[1]
    if len(_VECTORS) >= _MAX_VECTORS:
        _VECTORS.clear()
    vector = _vector(p)
    _VECTORS[id(p)] = (p, vector)
    return vector


@functools.lru_cache(maxsize=64)
def _vector(p: Parameters) -> Vector:
    return np.array([getattr(p, name) for name in Parameters.names()], dtype=np.float64)


@njit(inline="always", cache=True)
def drives(t: float, c: Vector) -> tuple[float, float]:  # pragma: no cover - compiled
    """``(Q1 sin(Omega t + phi1), Q2 sin(Omega t + phi2))`` (N): one sine where the forcings are in phase."""
    phase = c[OMEGA] * t
    wave = math.sin(phase + c[PHI1])
    return c[Q1] * wave, c[Q2] * (wave if c[PHI2] == c[PHI1] else math.sin(phase + c[PHI2]))


@njit(inline="always", cache=True)
def mass_forces(
    x1: float, v1: float, x2: float, v2: float, left: bool, right: bool, c: Vector, drive1: float, drive2: float
) -> tuple[float, float]:  # pragma: no cover - compiled
    """``(m1 A1, m2 A2)`` (N): the forcing given, springs, dampers and contacts (cubes as products)."""
    f1 = drive1 - c[K1] * x1 - c[K2] * (x1 * x1 * x1) - c[C1] * v1 - c[C2] * ((v1 * v1) * v1)
    f2 = drive2 - c[K4] * x2 - c[K5] * (x2 * x2 * x2) - c[C4] * v2 - c[C5] * ((v2 * v2) * v2)
    if left:
        contact = c[K3] * (x1 - x2 + c[D]) + c[C3] * (v1 - v2)
        f1 -= contact
        f2 += contact
    if right:
        f1 -= c[K6] * (x1 - c[D1])
    return f1, f2


@njit(cache=True)
def forces(
    t: float, x1: float, v1: float, x2: float, v2: float, left: bool, right: bool, c: Vector
) -> tuple[float, float]:  # pragma: no cover - compiled
    """``(A1, A2)``, see :func:`non_friction_force`."""
    drive1, drive2 = drives(t, c)
    f1, f2 = mass_forces(x1, v1, x2, v2, left, right, c, drive1, drive2)
    return f1 / c[M1], f2 / c[M2]


@njit(cache=True)
def force_rates(
    t: float, x1: float, v1: float, x2: float, v2: float, left: bool, right: bool, a1: float, a2: float, c: Vector
) -> tuple[float, float]:  # pragma: no cover - compiled
    """``(DA1, DA2)``, see :func:`non_friction_force_rate`."""
    r1 = c[Q1] * c[OMEGA] * math.cos(c[OMEGA] * t + c[PHI1]) - (c[K1] + 3.0 * c[K2] * x1**2) * v1
    r1 -= (c[C1] + 3.0 * c[C2] * v1**2) * a1
    r2 = c[Q2] * c[OMEGA] * math.cos(c[OMEGA] * t + c[PHI2]) - (c[K4] + 3.0 * c[K5] * x2**2) * v2
    r2 -= (c[C4] + 3.0 * c[C5] * v2**2) * a2
    if left:
        contact_rate = c[K3] * (v1 - v2) + c[C3] * (a1 - a2)
        r1 -= contact_rate
        r2 += contact_rate
    if right:
        r1 -= c[K6] * v1
    return r1 / c[M1], r2 / c[M2]


@njit(_f(_C, _i, _b), cache=True)
def threshold(c: Vector, mass: int, static: bool) -> float:  # pragma: no cover - compiled
    """``mu g + p_i`` with ``mu = mu_s`` (static) or ``mu_k``: friction plus feedback per unit mass."""
    mu = c[MU_S] if static else c[MU_K]
    feedback = c[P1] / c[M1] if mass == 1 else c[P2] / c[M2]
    return float(mu * c[G] + feedback)


def kinetic_threshold(p: Parameters, mass: int) -> float:
    """``mu_k g + p_i``: kinetic friction plus feedback per unit mass (4.13)-(4.14)."""
    return float(threshold(coefficients(p), mass, False))


def static_threshold(p: Parameters, mass: int) -> float:
    """``mu_s g + p_i``: the flow barrier's edge ``tau_1`` per unit mass (4.22), (4.24)."""
    return float(threshold(coefficients(p), mass, True))


@njit(_f(_C, _i, _i, _f), cache=True)
def kinetic(c: Vector, mass: int, sign: int, force: float) -> float:  # pragma: no cover - compiled
    """``A_i - s (mu_k g + p_i)``, or 0 at rest; see :func:`kinetic_field`."""
    if sign == 0:
        return 0.0
    return force - sign * threshold(c, mass, False)


@njit(_f(_C, _i, _i, _f), cache=True)
def barrier(c: Vector, mass: int, sign: int, force: float) -> float:  # pragma: no cover - compiled
    """``A_i - s (mu_s g + p_i)``; see :func:`flow_barrier_field`."""
    return force - sign * threshold(c, mass, True)


def non_friction_force(t: float, y: StateLike, p: Parameters, left: bool, right: bool) -> tuple[float, float]:
    """``(A1, A2)``: non-friction, non-feedback force per unit mass (3.4)-(3.5), (4.14).

    ``A1 = [Q1 sin(Omega t + phi1) - K1 x1 - K2 x1^3 - C1 v1 - C2 v1^3
    - L (K3 (x1 - x2 + d) + C3 (v1 - v2)) - R K6 (x1 - d1)] / m1`` and likewise ``A2``.
    """
    a1, a2 = forces(float(t), float(y[0]), float(y[1]), float(y[2]), float(y[3]), left, right, coefficients(p))
    return a1, a2


def non_friction_force_rate(
    t: float,
    y: StateLike,
    p: Parameters,
    left: bool,
    right: bool,
    a1: float,
    a2: float,
) -> tuple[float, float]:
    """``(DA1, DA2)``: total time derivatives of ``A_i`` along a flow with accelerations ``a_i``.

    ``DA1 = [Q1 Omega cos(.) - (K1 + 3 K2 x1^2) v1 - (C1 + 3 C2 v1^2) a1
    - L (K3 (v1 - v2) + C3 (a1 - a2)) - R K6 v1] / m1`` (docs/model.md, Sec. 4); ``a_i`` is the
    acceleration of the field assumed for mass ``i`` (0 for a resting mass).
    """
    rates = force_rates(
        float(t),
        float(y[0]),
        float(y[1]),
        float(y[2]),
        float(y[3]),
        left,
        right,
        float(a1),
        float(a2),
        coefficients(p),
    )
    return rates[0], rates[1]


@njit(cache=True)
def scale_of(
    x1: float, v1: float, x2: float, v2: float, left: bool, right: bool, mass: int, c: Vector
) -> float:  # pragma: no cover - compiled
    """:func:`force_scale` on the parameter vector."""
    if mass == 1:
        terms = abs(c[Q1]) + c[K1] * abs(x1) + c[K2] * abs(x1) ** 3 + c[C1] * abs(v1) + c[C2] * abs(v1) ** 3
        if right:
            terms += c[K6] * abs(x1 - c[D1])
    else:
        terms = abs(c[Q2]) + c[K4] * abs(x2) + c[K5] * abs(x2) ** 3 + c[C4] * abs(v2) + c[C5] * abs(v2) ** 3
    if left:
        terms += c[K3] * abs(x1 - x2 + c[D]) + c[C3] * abs(v1 - v2)
    return float(terms / (c[M1] if mass == 1 else c[M2]) + threshold(c, mass, True))


def force_scale(t: float, y: StateLike, p: Parameters, mode: Mode, mass: int) -> float:
    """The size of the terms that make up ``A_i``, plus the static threshold (per unit mass).

    A force-like G-function counts as zero when it is small against this (rounding and the
    solver's tolerance act on each term), whatever the units and magnitudes of the case.
    """
    return float(
        scale_of(float(y[0]), float(y[1]), float(y[2]), float(y[3]), mode.left, mode.right, mass, coefficients(p))
    )


def kinetic_field(p: Parameters, mass: int, sign: int, force: float) -> float:
    """``F_i^(delta) = A_i - s (mu_k g + p_i)``: second component of the field (4.13)-(4.14).

    ``sign`` is the velocity sign ``s`` of domain ``delta``; ``sign = 0`` (at rest) gives the
    zero field of (4.12).
    """
    return float(kinetic(coefficients(p), mass, sign, float(force)))


def flow_barrier_field(p: Parameters, mass: int, sign: int, force: float) -> float:
    """``F_i^(0>0_delta) = A_i - s (mu_s g + p_i)`` at the barrier's edge ``tau_1`` (4.22), (4.24).

    The feedback belongs in it, as the article's (4.22) carries ``b_i`` (docs/model.md, Sec. 3).
    """
    return float(barrier(coefficients(p), mass, sign, float(force)))


def accelerations(t: float, y: StateLike, p: Parameters, mode: Mode) -> tuple[float, float]:
    """``(a1, a2)`` of the mode's fields; a resting mass has zero acceleration (4.12)."""
    force1, force2 = non_friction_force(t, y, p, mode.left, mode.right)
    return (
        kinetic_field(p, 1, mode.sign(1), force1),
        kinetic_field(p, 2, mode.sign(2), force2),
    )


def state_derivative(t: float, y: StateLike, p: Parameters, mode: Mode) -> tuple[float, float, float, float]:
    """``dy/dt = (v1, a1, v2, a2)`` in a mode: the vector fields F/H of (4.9)-(4.10)."""
    a1, a2 = accelerations(t, y, p, mode)
    return (y[1], a1, y[3], a2)
