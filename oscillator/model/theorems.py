"""Switching theorems 5.1-5.9 of the article, each in one place.

Every theorem is one compiled (numba) function of G-function values (never the state), called by
the compiled switching rules (:mod:`oscillator.model.switching`) at every root.  It returns a
*decision code* ``(holds, theorem, equation, branch)`` of numbers: whether the flow switches,
the theorem (``1`` for 5.1, ...), the equation that carries the condition (``12`` for (5.12))
and, for Theorem 5.4, which alternative decided.  :class:`Decision` reads a code as text; the
``theorem_5_*`` functions give the decision as a :class:`Decision` directly.

The sign factor ``(-1)^(i+alpha)`` of the article equals the velocity sign of domain ``alpha``
of mass ``i`` (m2's domains are numbered against m1's), so the formulas are written as in the
article.  Where the article's text and the physics disagree, the physics wins and the
docstring says so (see also ``docs/model.md``).
"""

from __future__ import annotations

from dataclasses import dataclass

from numba import types

from oscillator.compiled import njit
from oscillator.model.numbering_kernels import velocity_sign_code

__all__ = [
    "Decision",
    "grazing",
    "is_zero",
    "left_contact",
    "left_contact_in_right_contact",
    "passable",
    "right_contact",
    "right_contact_in_left_contact",
    "sliding_appears",
    "sliding_exists",
    "sliding_vanishes",
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

#: Theorem codes of the definitions that decide a grazing of a stop (docs/model.md, rule 6).
DEFINITION_5_2, DEFINITION_5_4 = 102, 104
#: Branch codes of Theorem 5.4.
NO_BRANCH, REACHES_ZERO, ALREADY_PAST = 0, 1, 2
_BRANCHES = ("", "reaches_zero", "already_past")

# The kernels carry explicit signatures: one compiled version each, whatever literal constants the
# callers pass (numba would compile one per literal otherwise, and the rules' compile time doubles).
_i, _f, _b = types.int64, types.float64, types.boolean
#: The type of a decision code ``(holds, theorem, equation, branch)``.
DECISION = types.Tuple((_b, _i, _i, _i))


@dataclass(frozen=True, slots=True)
class Decision:
    """Outcome of a switching theorem.

    Attributes
    ----------
    holds : bool
        Whether the theorem's condition holds (the flow passes, slides, leaves, grazes, ...).
    theorem : str
        The theorem, e.g. ``"5.1"`` (``"Def. 5.2"`` for a definition).
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

    @classmethod
    def of(cls, code: tuple[bool, int, int, int]) -> Decision:
        """The decision a theorem's code ``(holds, theorem, equation, branch)`` stands for."""
        holds, theorem, equation, branch = code
        return cls(bool(holds), theorem_text(theorem), equation_text(equation), branch_text(branch))


def theorem_text(code: int) -> str:
    """``"5.4"`` for 4, ``"Def. 5.2"`` for :data:`DEFINITION_5_2`."""
    code = int(code)
    return f"Def. 5.{code - 100}" if code > 100 else f"5.{code}"


def equation_text(code: int) -> str:
    """``"(5.12)"`` for 12."""
    return f"(5.{int(code)})"


def branch_text(code: int) -> str:
    """``"reaches_zero"`` / ``"already_past"`` for Theorem 5.4's branches, else empty."""
    return _BRANCHES[int(code)]


@njit(_b(_f, _f), cache=True)
def is_zero(value: float, tolerance: float) -> bool:  # pragma: no cover - compiled
    """Whether a G-function value counts as zero (a root located by the integrator)."""
    return abs(value) <= tolerance


@njit(_i(_i), cache=True)
def _pair_index(domain: int) -> int:  # pragma: no cover - compiled
    """0, 1, 2, 3 for the velocity boundaries ∂Ω12, ∂Ω34, ∂Ω56, ∂Ω78 that ``domain`` borders."""
    return (domain - 1) // 2


@njit(DECISION(_i, _i, _i, _f, _f), cache=True)
def passable(mass: int, alpha: int, beta: int, g_alpha: float, g_beta: float) -> tuple[bool, int, int, int]:
    """Theorem 5.1: passable flow across a velocity boundary from ``Omega_alpha`` to ``Omega_beta``.

    (5.12), (5.13): ``(-1)^(i+alpha) F_i^(alpha)(t_m-) < 0`` and
    ``(-1)^(i+alpha) F_i^(beta)(t_m+) < 0`` (``H`` in place of ``F`` on ``∂Ω56``, ``∂Ω78``).
    """
    s = velocity_sign_code(mass, alpha)
    equation = 12 if _pair_index(alpha) < 2 else 13
    return s * g_alpha < 0 and s * g_beta < 0, 1, equation, NO_BRANCH


@njit(DECISION(_i, _i, _f, _f), cache=True)
def sliding_exists(mass: int, low: int, g_odd: float, g_even: float) -> tuple[bool, int, int, int]:
    """Theorem 5.2: sliding (rest on the floor) exists on the velocity boundary ``∂Ω_(ab)``.

    (5.16)-(5.19): ``(-1)^i F_i^(a)(t_m-) > 0`` and ``(-1)^i F_i^(b)(t_m-) < 0`` with ``a = low``
    the odd and ``b`` the even domain of the pair: both sides' fields point at the boundary.
    """
    s = -1 if mass % 2 else 1
    return s * g_odd > 0 and s * g_even < 0, 2, 16 + _pair_index(low), NO_BRANCH


@njit(DECISION(_i, _i, _i, _f, _f, _f, _f), cache=True)
def sliding_appears(
    mass: int, alpha: int, beta: int, g_alpha: float, g_beta: float, dg_beta: float, tolerance: float
) -> tuple[bool, int, int, int]:
    """Theorem 5.3: sliding appears when a flow from ``Omega_alpha`` arrives where ``F_i^(beta) = 0``.

    (5.22)-(5.25): ``F_i^(beta)(t_m) = 0``, the flow arrives (``(-1)^(i+alpha) F^(alpha) < 0``)
    and the field across turns back towards the boundary, ``(-1)^(i+beta) D F_i^(beta) < 0``.
    The printed article has ``> 0`` in that last factor, which would make the boundary a
    source on the beta side just after ``t_m`` (a passable flow); we implement the sink.
    """
    s_alpha, s_beta = velocity_sign_code(mass, alpha), velocity_sign_code(mass, beta)
    holds = is_zero(g_beta, tolerance) and s_alpha * g_alpha < 0 and s_beta * dg_beta < 0
    return holds, 3, 22 + _pair_index(alpha), NO_BRANCH


@njit(_i(_i), cache=True)
def _sliding_vanishes_equation(delta: int) -> int:  # pragma: no cover - compiled
    pair = _pair_index(delta)
    if pair == 0:
        return 28
    if pair == 2:
        return 31
    if pair == 1:
        return 29 if delta == 4 else 30
    return 32 if delta == 8 else 33


@njit(DECISION(_i, _i, _f, _f, _f, _f), cache=True)
def sliding_vanishes(
    mass: int, delta: int, g_barrier: float, dg_barrier: float, g_delta: float, tolerance: float
) -> tuple[bool, int, int, int]:
    """Theorem 5.4: a resting mass leaves its velocity boundary into ``Omega_delta`` (flow barrier).

    (5.28)-(5.33): ``F_i^(0>0_delta)(t_m) = 0`` with ``(-1)^(i+delta) D F_i^(0>0_delta) > 0``
    and ``(-1)^(i+delta) F_i^(delta)(t_m+) > 0`` (``>= 0`` when ``mu_s = mu_k``).  A barrier
    value already past zero, ``(-1)^(i+delta) F_i^(0>0_delta) > 0`` (at the start or after a
    contact makes the force jump), also leaves at once.
    """
    s = velocity_sign_code(mass, delta)
    on_barrier = is_zero(g_barrier, tolerance)
    crossing = (on_barrier and s * dg_barrier > 0) or (not on_barrier and s * g_barrier > 0)
    holds = crossing and s * g_delta >= -tolerance
    branch = REACHES_ZERO if on_barrier else ALREADY_PAST
    return holds, 4, _sliding_vanishes_equation(delta), branch


@njit(DECISION(_i, _i, _f, _f, _f), cache=True)
def grazing(mass: int, alpha: int, g_alpha: float, dg_alpha: float, tolerance: float) -> tuple[bool, int, int, int]:
    """Theorem 5.5: grazing of a velocity boundary inside ``Omega_alpha``.

    (5.37), (5.38): ``F_i^(alpha)(t_m) = 0`` and ``(-1)^(i+alpha) D F_i^(alpha) > 0``: the
    speed has a minimum there and the flow turns back into ``Omega_alpha``.
    """
    s = velocity_sign_code(mass, alpha)
    equation = 37 if _pair_index(alpha) < 2 else 38
    return is_zero(g_alpha, tolerance) and s * dg_alpha > 0, 5, equation, NO_BRANCH


@njit(_b(_i, _f, _f), cache=True)
def _enters_with(sign_needed: int, g_minus: float, g_plus: float) -> bool:  # pragma: no cover - compiled
    return sign_needed * g_minus > 0 and sign_needed * g_plus > 0


@njit(DECISION(_i, _i, _f, _f), cache=True)
def right_contact(from_domain: int, to_domain: int, v1_minus: float, v1_plus: float) -> tuple[bool, int, int, int]:
    """Theorem 5.6: right contact without left contact, at ``x1 = d1`` (absolute coordinates).

    (5.40): onset ``Omega_1 -> Omega_3`` iff ``v1(t_m-) > 0`` and ``v1(t_m+) > 0`` (the article
    prints ``Omega_1 -> Omega_2``).  (5.41): release ``Omega_4 -> Omega_2`` iff both ``< 0``.
    """
    if from_domain == 1 and to_domain == 3:
        return _enters_with(1, v1_minus, v1_plus), 6, 40, NO_BRANCH
    if from_domain == 4 and to_domain == 2:
        return _enters_with(-1, v1_minus, v1_plus), 6, 41, NO_BRANCH
    return False, 6, 40 if to_domain == 3 else 41, NO_BRANCH


@njit(DECISION(_i, _i, _f, _f), cache=True)
def right_contact_in_left_contact(
    from_domain: int, to_domain: int, v1_minus: float, v1_plus: float
) -> tuple[bool, int, int, int]:
    """Theorem 5.7: right contact while in left contact (double contact), at ``x1 = d1``.

    (5.45): onset ``Omega_5 -> Omega_7`` iff ``v1 > 0`` on both sides (the article prints
    ``Omega_2 -> Omega_2``).  (5.46): release ``Omega_8 -> Omega_6`` iff ``v1 < 0``.
    """
    if from_domain == 5 and to_domain == 7:
        return _enters_with(1, v1_minus, v1_plus), 7, 45, NO_BRANCH
    if from_domain == 8 and to_domain == 6:
        return _enters_with(-1, v1_minus, v1_plus), 7, 46, NO_BRANCH
    return False, 7, 45 if to_domain == 7 else 46, NO_BRANCH


@njit(DECISION(_b, _f, _f), cache=True)
def left_contact(onset: bool, zdot1_minus: float, zdot1_plus: float) -> tuple[bool, int, int, int]:
    """Theorem 5.8: left contact without right contact, at ``z1 = -d`` (relative coordinates).

    (5.50): onset (``∂Ω26``, and by the same rule ``∂Ω15``) iff ``zdot1 < 0`` on both sides.
    (5.51): release (``∂Ω15``, and by the same rule ``∂Ω26``) iff ``zdot1 > 0`` on both sides.
    The article states the rule for Ω2 -> Ω6 and Ω5 -> Ω1 only; it holds on all four
    boundaries ∂Ω15, ∂Ω26 (docs/model.md, rule 5; Instance 3 enters with ``v1 > 0``).
    """
    if onset:
        return _enters_with(-1, zdot1_minus, zdot1_plus), 8, 50, NO_BRANCH
    return _enters_with(1, zdot1_minus, zdot1_plus), 8, 51, NO_BRANCH


@njit(DECISION(_b, _f, _f), cache=True)
def left_contact_in_right_contact(onset: bool, zdot1_minus: float, zdot1_plus: float) -> tuple[bool, int, int, int]:
    """Theorem 5.9: left contact while in right contact, at ``z1 = -d`` (relative coordinates).

    (5.55): onset (``∂Ω48``, and likewise ``∂Ω37``) iff ``zdot1 < 0`` on both sides.
    (5.56): release (``∂Ω37``, and likewise ``∂Ω48``) iff ``zdot1 > 0`` on both sides.
    """
    if onset:
        return _enters_with(-1, zdot1_minus, zdot1_plus), 9, 55, NO_BRANCH
    return _enters_with(1, zdot1_minus, zdot1_plus), 9, 56, NO_BRANCH


# --------------------------------------------------------------------------- as Decisions


def theorem_5_1_passable(mass: int, alpha: int, beta: int, g_alpha: float, g_beta: float) -> Decision:
    """Theorem 5.1 as a :class:`Decision` (:func:`passable`)."""
    return Decision.of(passable(mass, alpha, beta, float(g_alpha), float(g_beta)))


def theorem_5_2_sliding_exists(mass: int, boundary: tuple[int, int], g_odd: float, g_even: float) -> Decision:
    """Theorem 5.2 on the boundary ``(a, b)`` as a :class:`Decision` (:func:`sliding_exists`)."""
    return Decision.of(sliding_exists(mass, min(boundary), float(g_odd), float(g_even)))


def theorem_5_3_sliding_appears(
    mass: int, alpha: int, beta: int, g_alpha: float, g_beta: float, dg_beta: float, *, tolerance: float
) -> Decision:
    """Theorem 5.3 as a :class:`Decision` (:func:`sliding_appears`)."""
    return Decision.of(
        sliding_appears(mass, alpha, beta, float(g_alpha), float(g_beta), float(dg_beta), float(tolerance))
    )


def theorem_5_4_sliding_vanishes(
    mass: int, delta: int, g_barrier: float, dg_barrier: float, g_delta: float, *, tolerance: float
) -> Decision:
    """Theorem 5.4 as a :class:`Decision` (:func:`sliding_vanishes`)."""
    return Decision.of(
        sliding_vanishes(mass, delta, float(g_barrier), float(dg_barrier), float(g_delta), float(tolerance))
    )


def theorem_5_5_grazing(mass: int, alpha: int, g_alpha: float, dg_alpha: float, *, tolerance: float) -> Decision:
    """Theorem 5.5 as a :class:`Decision` (:func:`grazing`)."""
    return Decision.of(grazing(mass, alpha, float(g_alpha), float(dg_alpha), float(tolerance)))


def theorem_5_6_right_contact(from_domain: int, to_domain: int, v1_minus: float, v1_plus: float) -> Decision:
    """Theorem 5.6 as a :class:`Decision` (:func:`right_contact`)."""
    return Decision.of(right_contact(from_domain, to_domain, float(v1_minus), float(v1_plus)))


def theorem_5_7_right_contact_in_left_contact(
    from_domain: int, to_domain: int, v1_minus: float, v1_plus: float
) -> Decision:
    """Theorem 5.7 as a :class:`Decision` (:func:`right_contact_in_left_contact`)."""
    return Decision.of(right_contact_in_left_contact(from_domain, to_domain, float(v1_minus), float(v1_plus)))


def theorem_5_8_left_contact(onset: bool, zdot1_minus: float, zdot1_plus: float) -> Decision:
    """Theorem 5.8 as a :class:`Decision` (:func:`left_contact`)."""
    return Decision.of(left_contact(bool(onset), float(zdot1_minus), float(zdot1_plus)))


def theorem_5_9_left_contact_in_right_contact(onset: bool, zdot1_minus: float, zdot1_plus: float) -> Decision:
    """Theorem 5.9 as a :class:`Decision` (:func:`left_contact_in_right_contact`)."""
    return Decision.of(left_contact_in_right_contact(bool(onset), float(zdot1_minus), float(zdot1_plus)))
