"""Theorems 5.1-5.9 on constructed G-function values, before any simulation uses them."""

import pytest

from oscillator.model.theorems import (
    theorem_5_1_passable,
    theorem_5_2_sliding_exists,
    theorem_5_3_sliding_appears,
    theorem_5_4_sliding_vanishes,
    theorem_5_5_grazing,
    theorem_5_6_right_contact,
    theorem_5_7_right_contact_in_left_contact,
    theorem_5_8_left_contact,
    theorem_5_9_left_contact_in_right_contact,
)

TOL = 1e-9


def triple(decision):
    return (decision.holds, decision.theorem, decision.equation)


@pytest.mark.parametrize(
    ("mass", "alpha", "beta", "g_alpha", "g_beta", "holds", "equation"),
    [
        # m1 in Omega_1 (v1 > 0) decelerating, the field across also negative: passes.
        (1, 1, 2, -2.0, -0.5, True, "(5.12)"),
        # the field across points back (F^(2) > 0): no passing.
        (1, 1, 2, -2.0, 0.5, False, "(5.12)"),
        # m2's domains are reversed: Omega_1(2) has v2 < 0, so it arrives with F > 0.
        (2, 1, 2, 2.0, 0.5, True, "(5.12)"),
        (2, 1, 2, 2.0, -0.5, False, "(5.12)"),
        (2, 2, 1, -1.0, -3.0, True, "(5.12)"),
        (1, 4, 3, 1.0, 2.0, True, "(5.12)"),
        (1, 5, 6, -1.0, -1.0, True, "(5.13)"),
        (2, 6, 5, -1.0, -1.0, True, "(5.13)"),
        (1, 8, 7, 1.0, -1.0, False, "(5.13)"),
    ],
)
def test_theorem_5_1(mass, alpha, beta, g_alpha, g_beta, holds, equation):
    decision = theorem_5_1_passable(mass, alpha, beta, g_alpha, g_beta)
    assert decision.holds is holds
    assert (decision.theorem, decision.equation) == ("5.1", equation)


@pytest.mark.parametrize(
    ("mass", "pair", "g_odd", "g_even", "holds", "equation"),
    [
        (1, (1, 2), -1.0, 1.0, True, "(5.16)"),  # both sides point at v1 = 0
        (1, (1, 2), -1.0, -1.0, False, "(5.16)"),  # Omega_2 side points away
        (2, (1, 2), 1.0, -1.0, True, "(5.16)"),  # m2: Omega_1 has v2 < 0
        (1, (3, 4), -1.0, 1.0, True, "(5.17)"),
        (2, (5, 6), 1.0, -1.0, True, "(5.18)"),
        (1, (7, 8), -1.0, 1.0, True, "(5.19)"),
        (1, (7, 8), 1.0, 1.0, False, "(5.19)"),
    ],
)
def test_theorem_5_2(mass, pair, g_odd, g_even, holds, equation):
    decision = theorem_5_2_sliding_exists(mass, pair, g_odd, g_even)
    assert decision.holds is holds
    assert decision.equation == equation


def test_theorem_5_3_requires_the_far_field_to_vanish_and_turn_back():
    # m1 arrives from Omega_1 (F^(1) < 0); F^(2) = 0 and D F^(2) > 0 turns it into a sink.
    assert theorem_5_3_sliding_appears(1, 1, 2, -1.0, 0.0, 2.0, tolerance=TOL).holds
    assert theorem_5_3_sliding_appears(1, 1, 2, -1.0, 0.0, 2.0, tolerance=TOL).equation == "(5.22)"
    # turning outward: the flow would pass, so sliding does not appear
    assert not theorem_5_3_sliding_appears(1, 1, 2, -1.0, 0.0, -2.0, tolerance=TOL)
    # far field not zero: not this theorem's situation
    assert not theorem_5_3_sliding_appears(1, 1, 2, -1.0, 0.3, 2.0, tolerance=TOL)
    assert theorem_5_3_sliding_appears(2, 6, 5, -1.0, 0.0, 1.0, tolerance=TOL).equation == "(5.24)"


@pytest.mark.parametrize(
    ("mass", "delta", "g_barrier", "dg_barrier", "g_delta", "holds", "equation"),
    [
        # m2 leaves into Omega_1(2) (v2 < 0): the barrier G-function reaches 0 going down.
        (2, 1, 0.0, -3.0, -0.98, True, "(5.28)"),
        (2, 1, 0.0, 3.0, -0.98, False, "(5.28)"),  # turning back: stays at rest
        (1, 2, 0.0, -1.0, -0.98, True, "(5.28)"),
        (1, 1, 0.0, 1.0, 0.98, True, "(5.28)"),
        (1, 1, -0.5, 1.0, 0.98, False, "(5.28)"),  # barrier not reached yet
        (1, 1, 0.5, -1.0, 0.98, True, "(5.28)"),  # already past it (start, or a contact jump)
        (1, 4, 0.0, -1.0, -0.5, True, "(5.29)"),
        (1, 3, 0.0, 1.0, 0.5, True, "(5.30)"),
        (2, 6, 0.0, 1.0, 0.5, True, "(5.31)"),
        (1, 8, 0.0, -1.0, -0.5, True, "(5.32)"),
        (1, 7, 0.0, 1.0, 0.5, True, "(5.33)"),
    ],
)
def test_theorem_5_4(mass, delta, g_barrier, dg_barrier, g_delta, holds, equation):
    decision = theorem_5_4_sliding_vanishes(mass, delta, g_barrier, dg_barrier, g_delta, tolerance=TOL)
    assert decision.holds is holds
    assert (decision.theorem, decision.equation) == ("5.4", equation)


def test_theorem_5_4_refuses_a_field_pointing_back_after_leaving():
    # Barrier crossed, but the kinetic field across would push the mass straight back.
    assert not theorem_5_4_sliding_vanishes(1, 1, 0.0, 1.0, -0.2, tolerance=TOL)


@pytest.mark.parametrize(
    ("mass", "alpha", "g", "dg", "holds", "equation"),
    [
        (1, 1, 0.0, 1.0, True, "(5.37)"),  # v1 > 0 has a minimum: grazes and turns back
        (1, 1, 0.0, -1.0, False, "(5.37)"),  # a maximum of v1 is no grazing
        (2, 1, 0.0, -1.0, True, "(5.37)"),  # m2 in Omega_1 has v2 < 0: |v2| minimum
        (1, 5, 0.0, 1.0, True, "(5.38)"),
        (1, 1, 0.1, 1.0, False, "(5.37)"),
    ],
)
def test_theorem_5_5(mass, alpha, g, dg, holds, equation):
    decision = theorem_5_5_grazing(mass, alpha, g, dg, tolerance=TOL)
    assert decision.holds is holds
    assert decision.equation == equation


def test_theorems_5_6_and_5_7_right_contact():
    assert triple(theorem_5_6_right_contact(1, 3, 0.4, 0.4)) == (True, "5.6", "(5.40)")
    assert not theorem_5_6_right_contact(1, 3, -0.4, -0.4)
    assert theorem_5_6_right_contact(4, 2, -0.4, -0.4).equation == "(5.41)"
    assert theorem_5_6_right_contact(4, 2, -0.4, -0.4).holds
    assert not theorem_5_6_right_contact(4, 2, 0.4, 0.4)
    assert not theorem_5_6_right_contact(2, 4, -0.4, -0.4)  # cannot enter with v1 < 0
    assert triple(theorem_5_7_right_contact_in_left_contact(5, 7, 1.0, 1.0)) == (True, "5.7", "(5.45)")
    assert triple(theorem_5_7_right_contact_in_left_contact(8, 6, -1.0, -1.0)) == (True, "5.7", "(5.46)")
    assert not theorem_5_7_right_contact_in_left_contact(8, 6, 1.0, 1.0)


def test_theorems_5_8_and_5_9_left_contact():
    assert triple(theorem_5_8_left_contact(True, -0.3, -0.3)) == (True, "5.8", "(5.50)")
    assert not theorem_5_8_left_contact(True, 0.3, 0.3)
    assert triple(theorem_5_8_left_contact(False, 0.3, 0.3)) == (True, "5.8", "(5.51)")
    assert not theorem_5_8_left_contact(False, -0.3, -0.3)
    assert triple(theorem_5_9_left_contact_in_right_contact(True, -0.3, -0.3)) == (True, "5.9", "(5.55)")
    assert triple(theorem_5_9_left_contact_in_right_contact(False, 0.3, 0.3)) == (True, "5.9", "(5.56)")
    assert not theorem_5_9_left_contact_in_right_contact(False, -0.3, 0.3)
