"""Domains, boundaries, modes and system states keep the article's numbering (Sec. 3.2, 4.1)."""

import itertools

import pytest

from oscillator import Mode, OscillatorError
from oscillator.model.phase_space import (
    contact_flags,
    displacement_boundary_label,
    domain_of,
    system_state,
    velocity_boundary,
    velocity_sign,
)


def test_m1_domains_follow_4_1_and_4_5():
    assert [domain_of(1, s, left=L, right=R) for L, R in [(0, 0), (0, 1), (1, 0), (1, 1)] for s in (1, -1)] == [
        1, 2, 3, 4, 5, 6, 7, 8,
    ]  # fmt: skip


def test_m2_domains_are_reversed():
    assert domain_of(2, -1, left=False) == 1
    assert domain_of(2, 1, left=False) == 2
    assert domain_of(2, -1, left=True) == 5
    assert domain_of(2, 1, left=True) == 6


@pytest.mark.parametrize("mass", [1, 2])
def test_domain_and_sign_round_trip(mass):
    flags = [(False, False), (False, True), (True, False), (True, True)]
    for (left, right), s in itertools.product(flags, (-1, 0, 1)):
        domain = domain_of(mass, s, left=left, right=right)
        assert velocity_sign(mass, domain) == s
        if mass == 1 and s:
            assert contact_flags(domain) == (left, right)


def test_velocity_boundaries():
    assert velocity_boundary(1, left=False, right=True) == (3, 4)
    assert velocity_boundary(1, left=True, right=True) == (7, 8)
    assert velocity_boundary(2, left=True, right=True) == (5, 6)


def test_sixteen_system_states():
    labels = {system_state(*flags) for flags in itertools.product((False, True), repeat=4)}
    assert len(labels) == 16
    assert system_state(True, False, True, False) == "III-b"
    assert system_state(False, False, False, False) == "I-a"
    assert system_state(True, True, True, True) == "IV-d"


def test_displacement_boundary_labels():
    assert displacement_boundary_label(1, 1, 3) == "∂Ω13(1)"
    assert displacement_boundary_label(1, 6, 2) == "∂Ω26(1)"
    assert displacement_boundary_label(2, 5, 1) == "∂Ω15(2)"
    assert displacement_boundary_label(2, 0, 0) == "z1 = -d"


def test_mode_checks_consistency():
    # m1 in Omega_3 means right contact: a mode that says otherwise is refused.
    with pytest.raises(OscillatorError, match=r"domain 3 means contacts"):
        Mode(3, 1, left=False, right=False)
    # m2 in Omega_5 means left contact.
    with pytest.raises(OscillatorError, match="left"):
        Mode(1, 5, left=False, right=False)
    # domain numbers out of range
    with pytest.raises(OscillatorError, match="out of range"):
        Mode(9, 1, left=False, right=False)


def test_mode_transitions():
    mode = Mode.from_signs(1, -1, left=False, right=False)
    assert (mode.domain1, mode.domain2) == (1, 1)
    inside = mode.with_contacts(left=True, right=True)
    assert (inside.domain1, inside.domain2) == (7, 5)
    resting = inside.with_sign(2, 0)
    assert resting.domain2 == 0 and resting.system_state == "IV-c"
    assert resting.boundary_label(2) == "∂Ω56(2)"
    assert resting.boundary_label(1) == "∂Ω78(1)"


def test_the_compiled_numbering_is_the_numbering():
    """The switching rules' compiled numbering and phase_space's agree everywhere (one definition)."""
    from oscillator.model import numbering, numbering_kernels

    for mass in (1, 2):
        for left in (0, 1):
            for right in (0, 1):
                for sign in (-1, 0, 1):
                    expected = domain_of(mass, sign, left=bool(left), right=bool(right))
                    assert numbering_kernels.domain_code(mass, sign, left, right) == expected
                    assert numbering.domain_code(mass, sign, left, right) == expected
                code = numbering_kernels.velocity_boundary_code(mass, left, right)
                assert code == numbering.velocity_boundary_code(mass, left, right)
                a, b = velocity_boundary(mass, left=bool(left), right=bool(right))
                assert (velocity_sign(mass, a), velocity_sign(mass, b)) == ((1, -1) if mass == 1 else (-1, 1))
        for a in range(9):
            assert numbering_kernels.velocity_sign_code(mass, a) == velocity_sign(mass, a)
            for b in range(9):
                assert numbering_kernels.displacement_boundary_code(mass, a, b) == (
                    numbering.displacement_boundary_code(mass, a, b))  # fmt: skip
    codes = {numbering_kernels.state_code(*flags) for flags in itertools.product((0, 1), repeat=4)}
    assert codes == set(range(16))
