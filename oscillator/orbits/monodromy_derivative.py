"""The derivative of the monodromy in the parameters, and of the Floquet multipliers (docs/sensitivities.md).

The monodromy ``M = Phi(t1)`` is the flow's derivative in the state, carried along each smooth piece by
``Phi' = J Phi`` and through each switch by ``Phi+ = R S Phi-`` (:mod:`oscillator.model.saltation`).
Its derivative along the orbit family, ``Psi_j = dPhi/dc_j`` with the state moving by ``sigma_j``
(:mod:`oscillator.orbits.sensitivity`), obeys on each piece the second-order tangent equations

    Psi_j' = J Psi_j + (dJ/dy . sigma_j + dJ/dc_j) Phi          (:func:`~oscillator.orbits.tangent.monodromy_rates`)

from ``Psi = 0``.  At a switch at ``t_s`` the time moves by ``tau_j`` and the state by
``dy_s = sigma- + f- tau``; ``Phi-`` is met ``tau`` later (``Psi- + J- Phi- tau``), the saltation matrix
``S = I + (f+ - f-) n^T / (n . f- + h_t)`` moves with its point, and ``Phi+`` is left ``tau`` later too:

    Psi+ = R (dS Phi- + S (Psi- + J- Phi- tau)) - J+ R S Phi- tau,
    dS = ((df+ - df-) n^T + (f+ - f-) dn^T) / s - (f+ - f-) n^T ds / s^2,    s = n . f- + h_t,

with ``df = J dy_s + f_t tau + df/dc``, ``dn`` zero but on a flow barrier (the row of ``dJ`` of the
mode the mass leaves into) and ``ds = dn . f- + n . df- + dh_t``.  At the end ``t1`` moves with
``Omega``: ``dM = Psi(t1) + J Phi(t1) dt1``.  One crossing after another when a switch crosses several
boundaries at once (:func:`~oscillator.orbits.sensitivity.crossings`).

A simple multiplier ``mu`` with right and left eigenvectors ``v``, ``w`` moves by
``dmu = w^H dM v / (w^H v)``; a repeated one has no derivative (``nan``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from scipy.integrate import solve_ivp

from oscillator.hybrid.record import Segment
from oscillator.model.fields import coefficients
from oscillator.model.kernels import field_jacobian
from oscillator.model.parameters import Parameters
from oscillator.model.phase_space import Mode
from oscillator.model.saltation import rest_projection
from oscillator.orbits.pieces import mode_flags
from oscillator.orbits.sensitivity import Crossing, columns_of, crossings, selector_of
from oscillator.orbits.tangent import field_gradient, jacobian_gradient, monodromy_rates

__all__ = ["SIMPLE", "monodromy_derivative", "multiplier_derivatives"]

#: The smallest distance between two multipliers, relative to the larger (or to 1 below it), at
#: which each is simple and has a derivative.
SIMPLE = 1e-6
_TOLERANCE = 1e-12


def _piece(
    segment: Segment, sigma: np.ndarray, phi: np.ndarray, psi: np.ndarray, c: np.ndarray, columns: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(y, sigma, Phi, Psi)`` at the end of ``segment``, integrated from its start."""
    k = len(columns)
    flags = mode_flags(segment.mode)

    def rates(t: float, state: np.ndarray) -> np.ndarray:
        out = np.empty_like(state)
        monodromy_rates(t, state, c, columns, *flags, out)
        return out

    start = np.concatenate([segment.y0, sigma.ravel(), phi.ravel(), psi.ravel()])
    if segment.t1 > segment.t0:
        end = solve_ivp(rates, (segment.t0, segment.t1), start, method="DOP853", rtol=_TOLERANCE, atol=_TOLERANCE).y[
            :, -1
        ]
    else:
        end = start
    return (
        end[:4],
        end[4 : 4 + 4 * k].reshape(4, k),
        end[4 + 4 * k : 20 + 4 * k].reshape(4, 4),
        end[20 + 4 * k :].reshape(k, 4, 4),
    )


def _time_rate(t: float, p: Parameters, mode: Mode) -> np.ndarray:
    """``df/dt`` at fixed state: the forcing's rate in each moving mass's velocity row."""
    rate = np.zeros(4)
    for mass, amplitude, phase in ((1, p.Q1, p.phi1), (2, p.Q2, p.phi2)):
        if mode.sign(mass) != 0:
            rate[2 * mass - 1] = amplitude * p.Omega * math.cos(p.Omega * t + phase) / p.mass(mass)
    return rate


def _field_change(
    t: float, y: np.ndarray, p: Parameters, mode: Mode, moved: np.ndarray, tau: np.ndarray, columns: np.ndarray
) -> np.ndarray:
    """``df`` (4 x k) of ``mode``'s field at the switch point, which moves by ``moved`` (4 x k) and ``tau``."""
    c = coefficients(p)
    gradient = np.empty((4, len(c)))
    field_gradient(t, y, c, *mode_flags(mode), gradient)
    change: np.ndarray = field_jacobian(y, p, mode) @ moved + np.outer(_time_rate(t, p, mode), tau)
    return change + gradient[:, columns]


def _barrier_change(
    t: float, y: np.ndarray, p: Parameters, crossing: Crossing, moved: np.ndarray, columns: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``(dn, dh_t)``: ``k x 4`` and ``k`` of the boundary ``crossing`` crossed (zero but on a flow barrier)."""
    k = len(columns)
    dn, drate = np.zeros((k, 4)), np.zeros(k)
    if not crossing.name.startswith("barrier"):
        return dn, drate
    mass = int(crossing.name[-1])
    moving = crossing.before.with_sign(mass, crossing.after.sign(mass))
    c = coefficients(p)
    bent = np.empty(16)
    amplitude, phase, weight = (p.Q1, p.phi1, p.m1) if mass == 1 else (p.Q2, p.phi2, p.m2)
    wave, sine = math.cos(p.Omega * t + phase), math.sin(p.Omega * t + phase)
    partial = {
        "Q1" if mass == 1 else "Q2": p.Omega * wave / weight,
        "Omega": amplitude * (wave - p.Omega * t * sine) / weight,
        "phi1" if mass == 1 else "phi2": -amplitude * p.Omega * sine / weight,
        "m1" if mass == 1 else "m2": -amplitude * p.Omega * wave / weight**2,
    }
    names = Parameters.names()
    for j, column in enumerate(columns):
        jacobian_gradient(y, c, np.ascontiguousarray(moved[:, j]), int(column), *mode_flags(moving), bent)
        dn[j] = bent[4 * (2 * mass - 1) : 4 * (2 * mass)]
        drate[j] = -amplitude * p.Omega**2 * sine / weight * crossing.tau[j] + partial.get(names[column], 0.0)
    return dn, drate


def _cross(
    t: float, y: np.ndarray, p: Parameters, crossing: Crossing, phi: np.ndarray, psi: np.ndarray, columns: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``(Phi, Psi)`` carried through one boundary (module docstring), before the rest projection."""
    n, s, tau = crossing.boundary.normal, crossing.speed, crossing.tau
    jump = crossing.f_plus - crossing.f_minus
    moved = crossing.sigma + np.outer(crossing.f_minus, tau)
    df_minus = _field_change(t, y, p, crossing.before, moved, tau, columns)
    df_plus = _field_change(t, y, p, crossing.after, moved, tau, columns)
    dn, drate = _barrier_change(t, y, p, crossing, moved, columns)
    saltation = np.eye(4) + np.outer(jump, n) / s
    j_minus, j_plus = field_jacobian(y, p, crossing.before), field_jacobian(y, p, crossing.after)
    carried = np.empty_like(psi)
    for j in range(len(columns)):
        ds = dn[j] @ crossing.f_minus + n @ df_minus[:, j] + drate[j]
        d_saltation = (np.outer(df_plus[:, j] - df_minus[:, j], n) + np.outer(jump, dn[j])) / s - np.outer(
            jump, n
        ) * ds / s**2
        carried[j] = (
            d_saltation @ phi + saltation @ (psi[j] + j_minus @ phi * tau[j]) - j_plus @ saltation @ phi * tau[j]
        )
    return saltation @ phi, carried


def monodromy_derivative(
    segments: Sequence[Segment], p: Parameters, params: tuple[str, ...], sigma0: np.ndarray, dt_end: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``(M, dM/dc)`` (4 x 4 and k x 4 x 4) of the run ``segments`` (to ``segments[-1].t1``, which
    moves by ``dt_end``), the start moving by ``sigma0`` (4 x k): the module docstring's pass."""
    c = coefficients(p)
    selector = selector_of(params)
    columns = columns_of(params)
    k = len(params)
    projection = rest_projection(segments[0].mode)
    sigma, phi, psi = projection @ np.asarray(sigma0, dtype=float).reshape(4, k), projection, np.zeros((k, 4, 4))
    for index, segment in enumerate(segments):
        y, sigma, phi, psi = _piece(segment, sigma, phi, psi, c, columns)
        if index + 1 == len(segments):
            break
        following = segments[index + 1]
        crossed = crossings(following.t0, y, following.y0, sigma, p, segment.mode, following.mode, selector)
        for crossing in crossed:
            phi, psi = _cross(following.t0, y, p, crossing, phi, psi, columns)
        after = rest_projection(following.mode)
        sigma = after @ crossed[-1].sigma_after
        phi, psi = after @ phi, np.einsum("ab,jbc->jac", after, psi)
    jac = field_jacobian(y, p, segments[-1].mode)
    return phi, psi + np.einsum("ab,bc,j->jac", jac, phi, np.asarray(dt_end, dtype=float))


def multiplier_derivatives(monodromy: np.ndarray, derivative: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The multipliers (largest modulus first, as :func:`~oscillator.orbits.multipliers.multipliers_of`)
    and their derivatives (multipliers x k, complex): ``w^H dM v / (w^H v)``; ``nan`` for a multiplier
    within :data:`SIMPLE` of another (a repeated one has no derivative)."""
    values, right = np.linalg.eig(monodromy)
    order = np.argsort(-np.abs(values), kind="stable")
    values, right = values[order], right[:, order]
    left = np.linalg.inv(right).conj().T
    found = np.full((len(values), len(derivative)), np.nan + 0j)
    for i, value in enumerate(values):
        others = np.delete(values, i)
        if len(others) and np.min(np.abs(others - value)) < SIMPLE * max(1.0, abs(value)):
            continue
        v, w = right[:, i], left[:, i]
        found[i] = [w.conj() @ d @ v / (w.conj() @ v) for d in derivative]
    return values, found
