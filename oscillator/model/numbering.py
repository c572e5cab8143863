"""The article's numbering of the phase space, written once, as integer functions (Sec. 3.2, 4.1).

Domains (4.1)-(4.8): m1, ``delta1``: 1 free ``v1 > 0``, 2 free ``v1 < 0``, 3/4 right contact,
5/6 left contact, 7/8 both contacts, 0 at rest on a velocity boundary; m2, ``delta2``: **1 free
``v2 < 0``, 2 free ``v2 > 0``** (reversed against m1), 5/6 in contact, 0 at rest.

Every function here takes and returns integers (flags as 0/1), calls no other and uses only
what numba compiles: :mod:`oscillator.model.phase_space` calls them as they are (with checks and
labels around them), and :mod:`oscillator.model.numbering_kernels` compiles them for the
switching rules, so that the command line's start, which needs the labels, does not wait for
numba.

Codes that event rows carry (:mod:`oscillator.model.events` reads them back):

* a velocity or displacement boundary ``∂Ω{lo}{hi}(mass)`` is ``100 lo + 10 hi + mass``; the
  constraints a resting m1 changes contact on are :data:`RIGHT_STOP_LABEL` (``x1 = d1``) and
  :data:`LEFT_STOP_LABEL` (``z1 = -d``);
* a system state of Sec. 3.2 is ``8 left + 4 right + 2 (m1 at rest) + (m2 at rest)``.
"""

from __future__ import annotations

__all__ = [
    "LEFT_STOP_LABEL",
    "RIGHT_STOP_LABEL",
    "boundary_code",
    "displacement_boundary_code",
    "domain_code",
    "state_code",
    "velocity_boundary_code",
    "velocity_sign_code",
]

#: Boundary codes of the two constraints (a domain boundary's code is at least 111).
RIGHT_STOP_LABEL, LEFT_STOP_LABEL = 0, 1


def domain_code(mass: int, sign: int, left: int, right: int) -> int:
    """The domain of mass ``mass`` moving with velocity sign ``sign`` (0: at rest) under the
    contacts ``left``, ``right`` (0 or 1; m2 ignores ``right``)."""
    if sign == 0:
        return 0
    if mass == 1:
        return 1 + 4 * left + 2 * right + (0 if sign > 0 else 1)
    return 1 + 4 * left + (0 if sign < 0 else 1)


def velocity_sign_code(mass: int, domain: int) -> int:
    """The velocity sign of a domain: +1, -1, or 0 for domain 0; the article's
    ``(-1)^(i+delta)`` for a moving mass."""
    if domain == 0:
        return 0
    return -1 if (mass + domain) % 2 else 1


def boundary_code(mass: int, low: int, high: int) -> int:
    """The code of ``∂Ω{low}{high}(mass)``."""
    return 100 * low + 10 * high + mass


def velocity_boundary_code(mass: int, left: int, right: int) -> int:
    """The velocity boundary ``∂Ω{a}{b}(mass)`` the mass rests on or crosses under the contacts
    (4.2), (4.4), (4.6), (4.8): ``a`` is :func:`domain_code` of m1 moving with ``v1 > 0`` or of
    m2 moving with ``v2 < 0``, ``b = a + 1``."""
    low = 1 + 4 * left + (2 * right if mass == 1 else 0)
    return 100 * low + 10 * (low + 1) + mass


def displacement_boundary_code(mass: int, domain_a: int, domain_b: int) -> int:
    """The displacement boundary between two domains; a resting mass crosses none of its own
    phase plane: its contact change is named by the constraint, ``z1 = -d`` (the right stop's
    change of a resting m1 is named by the caller, which knows which stop changed)."""
    if domain_a == 0 or domain_b == 0:
        return LEFT_STOP_LABEL
    return 100 * min(domain_a, domain_b) + 10 * max(domain_a, domain_b) + mass


def state_code(left: int, right: int, resting1: int, resting2: int) -> int:
    """The system state of Sec. 3.2 as a code (``system_state`` in phase_space reads it)."""
    return 8 * left + 4 * right + 2 * resting1 + resting2
