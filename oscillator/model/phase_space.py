"""Domains, boundaries and system states of the phase space (article Sec. 3.2 and 4.1).

Domain numbers are the article's (4.1)-(4.8):

* m1, ``delta1``: 1 free ``v1>0``, 2 free ``v1<0``, 3/4 right contact ``v1>0``/``<0``, 5/6 left
  contact, 7/8 both contacts, 0 at rest on a velocity boundary.
* m2, ``delta2``: **1 free ``v2<0``, 2 free ``v2>0``** (reversed against m1), 5/6 in contact
  ``v2<0``/``>0``, 0 at rest.

A *mode* is the pair of domains together with the contact flags: a resting mass (domain 0) does
not carry the contact flags in its number, yet its field and its flow barrier depend on them.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

from oscillator.errors import InputError
from oscillator.model.numbering import (
    LEFT_STOP_LABEL,
    RIGHT_STOP_LABEL,
    displacement_boundary_code,
    domain_code,
    state_code,
    velocity_boundary_code,
    velocity_sign_code,
)

__all__ = [
    "Mode",
    "boundary_label",
    "contact_flags",
    "contacts_of_state",
    "displacement_boundary_label",
    "domain_label",
    "domain_of",
    "state_label",
    "system_state",
    "velocity_boundary",
    "velocity_boundary_label",
    "velocity_sign",
]


def domain_of(mass: int, sign: int, *, left: bool, right: bool = False) -> int:
    """The article's domain number of mass ``mass`` moving with velocity sign ``sign``.

    ``sign = 0`` (at rest on a velocity boundary) gives domain 0.  m2 ignores ``right``.
    """
    return domain_code(mass, sign, int(left), int(right))


def velocity_sign(mass: int, domain: int) -> int:
    """Velocity sign ``s`` of a domain: +1, -1, or 0 for the velocity boundary itself."""
    return velocity_sign_code(mass, domain)


def contact_flags(domain1: int) -> tuple[bool, bool] | None:
    """``(left, right)`` encoded in m1's domain number, or ``None`` for domain 0."""
    if domain1 == 0:
        return None
    return (domain1 >= 5, domain1 in (3, 4, 7, 8))


def boundary_label(code: int) -> str:
    """The label of a boundary code (:mod:`oscillator.model.numbering`): ``∂Ω12(2)``, or the
    constraint ``x1 = d1`` / ``z1 = -d``."""
    if code == RIGHT_STOP_LABEL:
        return "x1 = d1"
    if code == LEFT_STOP_LABEL:
        return "z1 = -d"
    return f"∂Ω{code // 100}{code // 10 % 10}({code % 10})"


def velocity_boundary(mass: int, *, left: bool, right: bool = False) -> tuple[int, int]:
    """The velocity boundary ``(alpha, beta)`` that mass ``mass`` rests on or crosses.

    m1: (1, 2), (3, 4), (5, 6) or (7, 8); m2: (1, 2) or (5, 6) (4.2), (4.4), (4.6), (4.8).
    """
    code = velocity_boundary_code(mass, int(left), int(right))
    return (code // 100, code // 10 % 10)


def velocity_boundary_label(mass: int, *, left: bool, right: bool = False) -> str:
    """Label such as ``∂Ω12(2)``."""
    return boundary_label(velocity_boundary_code(mass, int(left), int(right)))


def displacement_boundary_label(mass: int, domain_a: int, domain_b: int) -> str:
    """Label of the displacement boundary between two domains, e.g. ``∂Ω13(1)``.

    A resting mass crosses no boundary of its own phase plane; its contact change is named by
    the constraint instead (``z1 = -d``).
    """
    return boundary_label(displacement_boundary_code(mass, domain_a, domain_b))


def domain_label(mass: int, domain: int, *, left: bool, right: bool = False) -> str:
    """``Ω2(1)`` for a domain, or the velocity boundary's label for a resting mass."""
    if domain == 0:
        return velocity_boundary_label(mass, left=left, right=right)
    return f"Ω{domain}({mass})"


#: mass -> domain -> velocity sign, for :meth:`Mode.sign` (called at every root, many times).
_SIGNS = {
    mass: {domain: velocity_sign(mass, domain) for domain in ((0, *range(1, 9)) if mass == 1 else (0, 1, 2, 5, 6))}
    for mass in (1, 2)
}
_REGIONS = {"I": (False, False), "II": (False, True), "III": (True, False), "IV": (True, True)}
_LETTERS = {(False, False): "a", (True, False): "b", (False, True): "c", (True, True): "d"}
#: The system states' labels, by code (:func:`oscillator.model.numbering.state_code`).
_STATES = {
    state_code(int(left), int(right), int(resting1), int(resting2)): f"{region}-{_LETTERS[(resting1, resting2)]}"
    for region, (left, right) in _REGIONS.items()
    for resting1 in (False, True)
    for resting2 in (False, True)
}


def system_state(left: bool, right: bool, resting1: bool, resting2: bool) -> str:
    """The system state of Sec. 3.2, e.g. ``III-b``.

    Region I no contact, II right contact only, III left contact only, IV both; letter a both
    moving, b m1 at rest, c m2 at rest, d both at rest.
    """
    return _STATES[state_code(int(left), int(right), int(resting1), int(resting2))]


def state_label(code: int) -> str:
    """The system state of a code (:func:`oscillator.model.numbering.state_code`), e.g. ``III-b``."""
    return _STATES[code]


def contacts_of_state(label: str) -> tuple[bool, bool]:
    """``(left, right)`` of a system-state label such as ``III-b``."""
    return _REGIONS[label.split("-")[0]]


@dataclass(frozen=True, slots=True)
class Mode:
    """Both masses' domains and the contact flags: one smooth vector field.

    ``left`` is the left contact ``z1 <= -d`` (m1 on m2's stop), ``right`` the right contact
    ``x1 >= d1``.  A moving m1's domain must agree with the flags; a moving m2's domain with
    ``left``.
    """

    domain1: int
    domain2: int
    left: bool
    right: bool

    def __post_init__(self) -> None:
        if self.domain1 not in range(9) or self.domain2 not in (0, 1, 2, 5, 6):
            raise InputError(
                f"Mode domains out of range: m1 in 0..8, m2 in 0,1,2,5,6; got {self.domain1}, {self.domain2}",
                field="domain",
            )
        flags = contact_flags(self.domain1)
        if flags is not None and flags != (self.left, self.right):
            raise InputError(
                f"Mode: m1's domain {self.domain1} means contacts {flags}, but left={self.left}, right={self.right}",
                field="domain1",
            )
        if self.domain2 != 0 and (self.domain2 >= 5) != self.left:
            raise InputError(
                f"Mode: m2's domain {self.domain2} disagrees with left={self.left}",
                field="domain2",
            )

    @classmethod
    def from_signs(cls, s1: int, s2: int, *, left: bool, right: bool) -> Mode:
        """The mode of velocity signs ``s1, s2`` (0 = at rest) under the given contacts (one
        object per mode: the switching rules build them at every root)."""
        return _from_signs(s1, s2, bool(left), bool(right))

    def domain(self, mass: int) -> int:
        return self.domain1 if mass == 1 else self.domain2

    def sign(self, mass: int) -> int:
        """Velocity sign of mass ``mass`` in this mode (0 when at rest)."""
        return _SIGNS[mass][self.domain1 if mass == 1 else self.domain2]

    def resting(self, mass: int) -> bool:
        return (self.domain1 if mass == 1 else self.domain2) == 0

    def with_sign(self, mass: int, sign: int) -> Mode:
        """The same contacts with mass ``mass`` moved to velocity sign ``sign``."""
        s1 = sign if mass == 1 else self.sign(1)
        s2 = sign if mass == 2 else self.sign(2)
        return Mode.from_signs(s1, s2, left=self.left, right=self.right)

    def with_contacts(self, *, left: bool, right: bool) -> Mode:
        """The same velocity signs under new contact flags."""
        return Mode.from_signs(self.sign(1), self.sign(2), left=left, right=right)

    @property
    def system_state(self) -> str:
        """Label of Sec. 3.2, e.g. ``I-a``."""
        return system_state(self.left, self.right, self.resting(1), self.resting(2))

    def boundary_label(self, mass: int) -> str:
        """The velocity boundary mass ``mass`` rests on or would cross."""
        return velocity_boundary_label(mass, left=self.left, right=self.right)


@functools.cache
def _from_signs(s1: int, s2: int, left: bool, right: bool) -> Mode:
    return Mode(domain_of(1, s1, left=left, right=right), domain_of(2, s2, left=left), left, right)
