"""Saltation matrices: how a perturbation passes a switch (docs/orbits.md, Sec. 2).

At a switch the state is continuous (the stops are compliant: no impact law) but the field jumps
from ``f-`` (the mode before) to ``f+`` (the mode after).  When the switching time ``t_s`` is set
by one boundary ``h(t, y) = 0`` that the flow crosses transversally, a perturbation ``dy`` just
before the switch becomes, just after it (Müller 1995; Leine & Nijmeijer 2004, Sec. 3.5;
di Bernardo et al. 2008, Sec. 2.5),

    S = I + (f+ - f-) n^T / (n . f- + h_t),      n = dh/dy,  h_t = dh/dt.

Which boundary set the time follows from what changed between the two modes
(:func:`elementary_switches`):

* a contact flag: the left stop ``h = z1 + d = x1 - x2 + d`` or the right stop ``h = x1 - d1``
  (the domains 1-8 boundaries ``∂Ω13``, ``∂Ω24`` ... of Sec. 4.1);
* a moving mass's velocity sign (a crossing, Thm 5.1, or an arrival at rest, Thm 5.2/5.3):
  ``h = v_i``; an arrival's ``f+`` has ``v_i' = 0``, so ``S`` removes ``dv_i`` (the resting mass's
  velocity is constrained);
* a resting mass leaving (Thm 5.4): the flow barrier, a time-dependent boundary
  ``h = A_i(t, y) - s (mu_s g + p_i)`` with ``n = dA_i/dy`` and ``h_t = Q_i Omega cos(Omega t +
  phi_i) / m_i`` (4.22), (4.24).

A contact's change is the cause when one occurs, since a mass can leave rest *because* the
contact damper made its force jump; a release is the cause only when nothing else changed.

A resting mass's velocity is constrained to zero (4.12).  A velocity disturbance ``dv_i`` given
to it while it rests sets it sliding against kinetic friction.  Where ``|A_i| < mu_k g + p_i``
friction brings it back to zero velocity after a time of order ``|dv_i|``, displaced by
``O(dv_i^2)``, and there it stops (Thm 5.2: the field beyond also points back): to first order
the disturbance is removed (:func:`rest_projection`, the arrival's saltation matrix in the limit
of a zero-length slide).  Where ``mu_k g + p_i < |A_i| < mu_s g + p_i`` only static friction
holds the mass: a disturbance along the force grows, one against it is reversed and passes zero
velocity (Thm 5.1), and the mass slides away either way; the map is discontinuous in ``v_i``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from oscillator.compiled import njit
from oscillator.model.fields import M1, M2, OMEGA, PHI1, PHI2, Q1, Q2, coefficients, forces, kinetic, state_derivative
from oscillator.model.kernels import field_jacobian, jacobian
from oscillator.model.parameters import Parameters
from oscillator.model.phase_space import Mode

__all__ = [
    "Boundary",
    "boundary_of",
    "carried_through",
    "carry_compiled",
    "elementary_switches",
    "rest_projection",
    "saltation_matrix",
]


@dataclass(frozen=True, slots=True)
class Boundary:
    """The boundary ``h(t, y) = 0`` whose crossing set a switch's time: its gradient and rate.

    Attributes
    ----------
    name : str
        ``"left stop"``, ``"right stop"``, ``"v1 = 0"``, ``"v2 = 0"``, ``"flow barrier of m1"``, ...
    normal : ndarray
        ``dh/dy`` (4,).
    rate : float
        ``dh/dt`` at fixed ``y`` (non-zero only for the flow barrier).
    """

    name: str
    normal: np.ndarray
    rate: float = 0.0


def _unit(index: int) -> np.ndarray:
    e = np.zeros(4)
    e[index] = 1.0
    return e


def elementary_switches(before: Mode, after: Mode) -> list[tuple[Mode, Mode, str]]:
    """The switch ``before -> after`` as a sequence of switches across one boundary each.

    Several boundaries can be crossed at one instant (both masses reversing together in a
    symmetric case; a contact and a mass leaving rest because of it).  Each contact change and
    each moving mass's change of sign is a crossing of its own boundary, taken one after the
    other (their saltation matrices commute: each jump lies in its own mass's rows).  A mass
    that leaves rest when a contact changes leaves *because* its force jumped: its release is
    part of the contact's jump, not a crossing of its flow barrier; otherwise it crosses the
    barrier.  Returns ``(mode before, mode after, boundary)`` triples, boundary one of
    ``"left"``, ``"right"``, ``"v1"``, ``"v2"``, ``"barrier1"``, ``"barrier2"``.
    """
    steps: list[tuple[Mode, Mode, str]] = []
    current = before
    released = [mass for mass in (1, 2) if before.sign(mass) == 0 and after.sign(mass) != 0]
    contacts = [side for side in ("left", "right") if getattr(before, side) != getattr(after, side)]
    for k, side in enumerate(contacts):
        flags = {"left": current.left, "right": current.right, side: getattr(after, side)}
        new = current.with_contacts(**flags)
        if k == len(contacts) - 1:
            for mass in released:
                new = new.with_sign(mass, after.sign(mass))
        steps.append((current, new, side))
        current = new
    for mass in (1, 2):
        if before.sign(mass) != 0 and after.sign(mass) != before.sign(mass):
            new = current.with_sign(mass, after.sign(mass))
            steps.append((current, new, f"v{mass}"))
            current = new
    if not contacts:
        for mass in released:
            new = current.with_sign(mass, after.sign(mass))
            steps.append((current, new, f"barrier{mass}"))
            current = new
    if current != after:
        raise ValueError(f"the switch {before} -> {after} is not a sequence of boundary crossings")
    return steps


def boundary_of(name: str, t: float, y: np.ndarray, p: Parameters, mode: Mode, after: Mode) -> Boundary:
    """The boundary ``name`` (see :func:`elementary_switches`) at ``(t, y)``, left from ``mode``."""
    if name == "left":
        return Boundary("left stop", np.array([1.0, 0.0, -1.0, 0.0]))
    if name == "right":
        return Boundary("right stop", _unit(0))
    mass = int(name[-1])
    if name.startswith("v"):
        return Boundary(f"v{mass} = 0", _unit(2 * mass - 1))
    moving = mode.with_sign(mass, after.sign(mass))
    normal = field_jacobian(y, p, moving)[2 * mass - 1].copy()
    amplitude, phase = (p.Q1, p.phi1) if mass == 1 else (p.Q2, p.phi2)
    rate = amplitude * p.Omega * math.cos(p.Omega * t + phase) / p.mass(mass)
    return Boundary(f"flow barrier of m{mass}", normal, rate)


def rest_projection(mode: Mode) -> np.ndarray:
    """The identity with the velocity rows of ``mode``'s resting masses zeroed.

    Applied where a segment at rest begins (at the section, when a mass rests there): a
    velocity disturbance of a resting mass dies in finite time with a displacement of second
    order, so its first-order effect is nil (the module's docstring).  After an arrival the
    saltation matrix has already zeroed that row, and this changes nothing.
    """
    matrix = np.eye(4)
    for mass in (1, 2):
        if mode.sign(mass) == 0:
            matrix[2 * mass - 1, 2 * mass - 1] = 0.0
    return matrix


def saltation_matrix(
    t: float, y_before: np.ndarray, y_after: np.ndarray, p: Parameters, before: Mode, after: Mode
) -> np.ndarray:
    """``S = I + (f+ - f-) n^T / (n . f- + h_t)`` of the switch ``before -> after`` at ``t``;
    the product of those of its :func:`elementary_switches` when it crosses several boundaries.

    ``y_before`` is the state the flow of ``before`` reached, ``y_after`` the state the switch
    left (they differ only by the rounding a switch settles, e.g. ``v_i = 0`` exactly for an
    arrival at rest).  A grazing contact (``n . f- + h_t = 0``) has no saltation matrix: the
    map is not differentiable there, and this raises ``ZeroDivisionError``.
    """
    matrix = np.eye(4)
    for mode, new, name in elementary_switches(before, after):
        boundary = boundary_of(name, t, y_before, p, mode, new)
        f_minus = np.array(state_derivative(t, y_before, p, mode))
        f_plus = np.array(state_derivative(t, y_after, p, new))
        speed = float(boundary.normal @ f_minus + boundary.rate)
        if speed == 0.0:
            raise ZeroDivisionError(f"the flow is tangent to the {boundary.name} at t = {t!r}")
        matrix = (np.eye(4) + np.outer(f_plus - f_minus, boundary.normal) / speed) @ matrix
    return matrix


def carried_through(
    phi: np.ndarray, t: float, y_before: np.ndarray, y_after: np.ndarray, p: Parameters, before: Mode, after: Mode
) -> np.ndarray:
    """The derivative of the flow ``Phi`` (4 x 4) just after the switch ``before -> after`` at
    ``t``, from the one just before: ``R(after) S Phi`` with ``S`` the :func:`saltation_matrix`
    and ``R`` the :func:`rest_projection` of the mode the run goes on in (docs/orbits.md, Sec. 2),
    computed by :func:`carry_compiled` (the supervisor's every switch).

    Raises ``ZeroDivisionError`` at a grazing contact (no saltation matrix there).
    """
    out = np.empty(16)
    status = carry_compiled(
        np.ascontiguousarray(phi, dtype=np.float64).ravel(),
        float(t),
        np.ascontiguousarray(y_before[:4], dtype=np.float64),
        np.ascontiguousarray(y_after[:4], dtype=np.float64),
        coefficients(p),
        _flags(before),
        _flags(after),
        out,
    )
    if status == _GRAZING:
        saltation_matrix(t, y_before, y_after, p, before, after)  # raises, naming the boundary
    if status != _CARRIED:
        raise ValueError(f"the switch {before} -> {after} is not a sequence of boundary crossings")
    return out.reshape(4, 4)


def _flags(mode: Mode) -> np.ndarray:
    return np.array([mode.sign(1), mode.sign(2), int(mode.left), int(mode.right)], dtype=np.int64)


#: :func:`carry_compiled`'s outcomes: carried; a grazing crossing; modes no crossings join.
_CARRIED, _GRAZING, _NOT_A_SEQUENCE = 0, 1, 2


@njit(cache=True)
def _crossed(
    matrix: np.ndarray,
    t: float,
    yb: np.ndarray,
    ya: np.ndarray,
    c: np.ndarray,
    mode: np.ndarray,
    new: np.ndarray,
    which: int,
) -> bool:  # pragma: no cover - compiled
    """``matrix <- (I + (f+ - f-) n^T / (n . f- + h_t)) matrix`` for the crossing ``mode -> new`` of
    the boundary ``which`` (0 left stop, 1 right stop, 2 + i the velocity of mass i, 4 + i its
    flow barrier; :func:`boundary_of`); False at a grazing (``n . f- + h_t = 0``)."""
    normal, rate = np.zeros(4), 0.0
    if which == 0:
        normal[0], normal[2] = 1.0, -1.0
    elif which == 1:
        normal[0] = 1.0
    elif which < 4:
        normal[2 * (which - 2) + 1] = 1.0
    else:
        mass = which - 3
        rows = np.empty(16)
        jacobian(yb[0], yb[1], yb[2], yb[3], c, new[0], new[1], new[2] != 0, new[3] != 0, rows)
        normal[:] = rows[8 * mass - 4 : 8 * mass]
        amplitude, phase, m = (c[Q1], c[PHI1], c[M1]) if mass == 1 else (c[Q2], c[PHI2], c[M2])
        rate = amplitude * c[OMEGA] * math.cos(c[OMEGA] * t + phase) / m
    before_forces = forces(t, yb[0], yb[1], yb[2], yb[3], mode[2] != 0, mode[3] != 0, c)
    after_forces = forces(t, ya[0], ya[1], ya[2], ya[3], new[2] != 0, new[3] != 0, c)
    f_minus = np.array(
        [yb[1], kinetic(c, 1, mode[0], before_forces[0]), yb[3], kinetic(c, 2, mode[1], before_forces[1])]
    )
    f_plus = np.array([ya[1], kinetic(c, 1, new[0], after_forces[0]), ya[3], kinetic(c, 2, new[1], after_forces[1])])
    speed = normal @ f_minus + rate
    if speed == 0.0:
        return False
    jump = np.outer(f_plus - f_minus, normal) / speed
    matrix[:, :] = matrix + jump @ matrix
    return True


@njit(cache=True)
def carry_compiled(
    phi: np.ndarray,
    t: float,
    yb: np.ndarray,
    ya: np.ndarray,
    c: np.ndarray,
    before: np.ndarray,
    after: np.ndarray,
    out: np.ndarray,
) -> int:  # pragma: no cover - compiled
    """:func:`carried_through` compiled: ``out`` (16, row by row) = ``R(after) S Phi`` for ``phi``
    (16), the crossings taken in :func:`elementary_switches`' order; the outcome (0 carried, 1 a
    grazing, 2 no sequence of crossings joins the modes).  A mode is ``(s1, s2, left, right)``."""
    matrix = np.eye(4)
    current = before.copy()
    released = np.array([before[0] == 0 and after[0] != 0, before[1] == 0 and after[1] != 0])
    changed = [side for side in (2, 3) if before[side] != after[side]]
    for k in range(len(changed)):
        new = current.copy()
        new[changed[k]] = after[changed[k]]
        if k == len(changed) - 1:
            for i in range(2):
                if released[i]:
                    new[i] = after[i]
        if not _crossed(matrix, t, yb, ya, c, current, new, changed[k] - 2):
            return _GRAZING
        current = new
    for i in range(2):
        if before[i] != 0 and after[i] != before[i]:
            new = current.copy()
            new[i] = after[i]
            if not _crossed(matrix, t, yb, ya, c, current, new, 2 + i):
                return _GRAZING
            current = new
    if not changed:
        for i in range(2):
            if released[i]:
                new = current.copy()
                new[i] = after[i]
                if not _crossed(matrix, t, yb, ya, c, current, new, 4 + i):
                    return _GRAZING
                current = new
    for k in range(4):
        if current[k] != after[k]:
            return _NOT_A_SEQUENCE
    carried = matrix @ phi.reshape(4, 4)
    for i in range(2):
        if after[i] == 0:
            carried[2 * i + 1, :] = 0.0
    out[:] = carried.ravel()
    return _CARRIED
