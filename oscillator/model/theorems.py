"""Switching theorems 5.1-5.9 of the article, each in one place.

Every function takes G-function values (never the state) and returns a :class:`Decision`: whether
the flow switches, and the theorem and equation that decided it.  The sign factor
``(-1)^(i+alpha)`` of the article equals the velocity sign of domain ``alpha`` of mass ``i``
(m2's domains are numbered against m1's), so the formulas are written as in the article.

Where the article's text and the physics disagree, the physics wins and the docstring says so
(see also ``docs/model.md``).
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = [
    "Decision",
    "is_zero",
    "theorem_5_1_passable",
    "theorem_5_2_sliding_exists",
    "theorem_5_3_sliding_appears",
    "theorem_5_4_sliding_vanishes",
    "theorem_5_5_grazing",
    "theorem_5_6_right_contact",
    "theorem_5_7_right_contact_in_left_contact",
    "theorem_5_8_left_contact",
    "theorem_5_9_left_contact_in_right_contact",
]


@dataclass(frozen=True, slots=True)
class Decision:
    """Outcome of a switching theorem.

    Attributes
    ----------
    holds : bool
        Whether the theorem's condition holds (the flow passes, slides, leaves, grazes, ...).
    theorem : str
        The theorem, e.g. ``"5.1"``.
    equation : str
        The equation that carries the condition, e.g. ``"(5.12)"``.
    branch : str
        Which of the theorem's alternatives decided, where it has several (Theorem 5.4:
        ``"reaches_zero"`` - the flow barrier's G-function reaches 0 and rises - or
        ``"already_past"`` - it is past 0 already); empty otherwise.
    """

    holds: bool
    theorem: str
    equation: str
    branch: str = ""

    def __bool__(self) -> bool:
        return self.holds


def _sign(mass: int, domain: int) -> int:
    """The article's ``(-1)^(i+delta)``."""
    return -1 if (mass + domain) % 2 else 1


def is_zero(value: float, tolerance: float) -> bool:
    """Whether a G-function value counts as zero (a root located by the integrator)."""
    return abs(value) <= tolerance


def _pair(domain: int) -> tuple[int, int]:
    low = domain - 1 if domain % 2 == 0 else domain
    return (low, low + 1)


def theorem_5_1_passable(mass: int, alpha: int, beta: int, g_alpha: float, g_beta: float) -> Decision:
    """Passable flow across a velocity boundary from ``Omega_alpha`` to ``Omega_beta``.

    (5.12), (5.13): ``(-1)^(i+alpha) F_i^(alpha)(t_m-) < 0`` and
    ``(-1)^(i+alpha) F_i^(beta)(t_m+) < 0`` (``H`` in place of ``F`` on ``∂Ω56``, ``∂Ω78``).
    """
    s = _sign(mass, alpha)
    equation = "(5.12)" if _pair(alpha)[0] in (1, 3) else "(5.13)"
    return Decision(s * g_alpha < 0 and s * g_beta < 0, "5.1", equation)


_SLIDING_EXISTS_EQUATION = {1: "(5.16)", 3: "(5.17)", 5: "(5.18)", 7: "(5.19)"}


def theorem_5_2_sliding_exists(mass: int, boundary: tuple[int, int], g_odd: float, g_even: float) -> Decision:
    """Sliding (rest on the floor) exists on the velocity boundary ``∂Ω_(ab)``.

    (5.16)-(5.19): ``(-1)^i F_i^(a)(t_m-) > 0`` and ``(-1)^i F_i^(b)(t_m-) < 0`` with ``a`` the
    odd and ``b`` the even domain of the pair: both sides' fields point at the boundary.
    """
    s = -1 if mass % 2 else 1
    return Decision(s * g_odd > 0 and s * g_even < 0, "5.2", _SLIDING_EXISTS_EQUATION[boundary[0]])


_SLIDING_APPEARS_EQUATION = {1: "(5.22)", 3: "(5.23)", 5: "(5.24)", 7: "(5.25)"}


def theorem_5_3_sliding_appears(
    mass: int, alpha: int, beta: int, g_alpha: float, g_beta: float, dg_beta: float, *, tolerance: float
) -> Decision:
    """Sliding appears when a flow from ``Omega_alpha`` arrives where ``F_i^(beta) = 0``.

    (5.22)-(5.25): ``F_i^(beta)(t_m) = 0``, the flow arrives (``(-1)^(i+alpha) F^(alpha) < 0``)
    and the field across turns back towards the boundary, ``(-1)^(i+beta) D F_i^(beta) < 0``.
    The printed article has ``> 0`` in that last factor, which would make the boundary a
    source on the beta side just after ``t_m`` (a passable flow); we implement the sink.
    """
    s_alpha, s_beta = _sign(mass, alpha), _sign(mass, beta)
    holds = is_zero(g_beta, tolerance) and s_alpha * g_alpha < 0 and s_beta * dg_beta < 0
    return Decision(holds, "5.3", _SLIDING_APPEARS_EQUATION[_pair(alpha)[0]])


def _sliding_vanishes_equation(mass: int, delta: int) -> str:
    low = _pair(delta)[0]
    if low == 1:
        return "(5.28)"
    if low == 5:
        return "(5.31)"
    if low == 3:
        return "(5.29)" if delta == 4 else "(5.30)"
    return "(5.32)" if delta == 8 else "(5.33)"


def theorem_5_4_sliding_vanishes(
    mass: int,
    delta: int,
    g_barrier: float,
    dg_barrier: float,
    g_delta: float,
    *,
    tolerance: float,
) -> Decision:
    """A resting mass leaves its velocity boundary into ``Omega_delta`` (flow barrier).

    (5.28)-(5.33): ``F_i^(0>0_delta)(t_m) = 0`` with ``(-1)^(i+delta) D F_i^(0>0_delta) > 0``
    and ``(-1)^(i+delta) F_i^(delta)(t_m+) > 0`` (``>= 0`` when ``mu_s = mu_k``).  A barrier
    value already past zero, ``(-1)^(i+delta) F_i^(0>0_delta) > 0`` (at the start or after a
    contact makes the force jump), also leaves at once.
    """
    s = _sign(mass, delta)
    on_barrier = is_zero(g_barrier, tolerance)
    crossing = (on_barrier and s * dg_barrier > 0) or (not on_barrier and s * g_barrier > 0)
    holds = crossing and s * g_delta >= -tolerance
    branch = "reaches_zero" if on_barrier else "already_past"
    return Decision(holds, "5.4", _sliding_vanishes_equation(mass, delta), branch)


def theorem_5_5_grazing(mass: int, alpha: int, g_alpha: float, dg_alpha: float, *, tolerance: float) -> Decision:
    """Grazing of a velocity boundary inside ``Omega_alpha``.

    (5.37), (5.38): ``F_i^(alpha)(t_m) = 0`` and ``(-1)^(i+alpha) D F_i^(alpha) > 0``: the
    speed has a minimum there and the flow turns back into ``Omega_alpha``.
    """
    s = _sign(mass, alpha)
    equation = "(5.37)" if _pair(alpha)[0] in (1, 3) else "(5.38)"
    return Decision(is_zero(g_alpha, tolerance) and s * dg_alpha > 0, "5.5", equation)


def _enters_with(sign_needed: int, g_minus: float, g_plus: float) -> bool:
    return sign_needed * g_minus > 0 and sign_needed * g_plus > 0


def theorem_5_6_right_contact(from_domain: int, to_domain: int, v1_minus: float, v1_plus: float) -> Decision:
    """Right contact without left contact, at ``x1 = d1`` (absolute coordinates).

    (5.40): onset ``Omega_1 -> Omega_3`` iff ``v1(t_m-) > 0`` and ``v1(t_m+) > 0`` (the article
    prints ``Omega_1 -> Omega_2``).  (5.41): release ``Omega_4 -> Omega_2`` iff both ``< 0``.
    """
    if (from_domain, to_domain) == (1, 3):
        return Decision(_enters_with(+1, v1_minus, v1_plus), "5.6", "(5.40)")
    if (from_domain, to_domain) == (4, 2):
        return Decision(_enters_with(-1, v1_minus, v1_plus), "5.6", "(5.41)")
    return Decision(False, "5.6", "(5.40)" if to_domain == 3 else "(5.41)")


def theorem_5_7_right_contact_in_left_contact(
    from_domain: int, to_domain: int, v1_minus: float, v1_plus: float
) -> Decision:
    """Right contact while in left contact (double contact), at ``x1 = d1``.

    (5.45): onset ``Omega_5 -> Omega_7`` iff ``v1 > 0`` on both sides (the article prints
    ``Omega_2 -> Omega_2``).  (5.46): release ``Omega_8 -> Omega_6`` iff ``v1 < 0``.
    """
    if (from_domain, to_domain) == (5, 7):
        return Decision(_enters_with(+1, v1_minus, v1_plus), "5.7", "(5.45)")
    if (from_domain, to_domain) == (8, 6):
        return Decision(_enters_with(-1, v1_minus, v1_plus), "5.7", "(5.46)")
    return Decision(False, "5.7", "(5.45)" if to_domain == 7 else "(5.46)")


def theorem_5_8_left_contact(onset: bool, zdot1_minus: float, zdot1_plus: float) -> Decision:
    """Left contact without right contact, at ``z1 = -d`` (relative coordinates).

    (5.50): onset (``∂Ω26``, and by the same rule ``∂Ω15``) iff ``zdot1 < 0`` on both sides.
    (5.51): release (``∂Ω15``, and by the same rule ``∂Ω26``) iff ``zdot1 > 0`` on both sides.
    The article states the rule for Ω2 -> Ω6 and Ω5 -> Ω1 only; it holds on all four
    boundaries ∂Ω15, ∂Ω26 (docs/model.md, rule 5; Instance 3 enters with ``v1 > 0``).
    """
    if onset:
        return Decision(_enters_with(-1, zdot1_minus, zdot1_plus), "5.8", "(5.50)")
    return Decision(_enters_with(+1, zdot1_minus, zdot1_plus), "5.8", "(5.51)")


def theorem_5_9_left_contact_in_right_contact(onset: bool, zdot1_minus: float, zdot1_plus: float) -> Decision:
    """Left contact while in right contact, at ``z1 = -d`` (relative coordinates).

    (5.55): onset (``∂Ω48``, and likewise ``∂Ω37``) iff ``zdot1 < 0`` on both sides.
    (5.56): release (``∂Ω37``, and likewise ``∂Ω48``) iff ``zdot1 > 0`` on both sides.
    """
    if onset:
        return Decision(_enters_with(-1, zdot1_minus, zdot1_plus), "5.9", "(5.55)")
    return Decision(_enters_with(+1, zdot1_minus, zdot1_plus), "5.9", "(5.56)")
