"""Orbits on which a mass rests: its variational dynamics, the verdict, and where the map jumps.

The monodromy matrix of an orbit whose mass rests all period, or rests across the section, is
checked against central finite differences of the map that ``simulate``'s supervisor computes,
in every direction where the map is differentiable; where the map is discontinuous (a mass held
by static friction alone), the test checks that it is.
"""

import numpy as np
import pytest

from conftest import random_case
from oscillator import SimulationFailed, continue_orbit, find_orbit, simulate
from oscillator.orbits.shooting import period_map

#: Instance 1's m1 driven alone: m2 unforced (Q2 = 0), parked at x2 = 0.5 where its spring's pull
#: (K4 x2 + K5 x2^3 = 0.875 N) is below even the kinetic threshold (mu_k g m2 + P2 = 1.37 N),
#: and the left stop out of reach.
PARKED = {"Q2": 0.0, "x2": 0.5, "d": 1000.0}
#: The same with m2 at x2 = 0.8 (pull 1.712 N): between the kinetic and the static thresholds
#: (1.37 N and 2.35 N), so that static friction alone holds it.
HELD = {"Q2": 0.0, "x2": 0.8, "d": 1000.0}
#: random_case seeds whose period-1 orbit (after 60 periods) has a mass at rest all period:
#: m2 resting while m1 strikes its stop and m2's (1); m1 resting in contact with m2 (5); m1
#: resting beside m2 sliding (15); m2 held between its thresholds (9).
RESTING_SEEDS = [1, 5, 15, 9]


def central_differences(case, section, state, periods=1, h=1e-5):
    """Columns of the map's derivative by central differences: ``None`` where the map jumps
    (a step of 1e-7 moves the image as far as one of 1e-5: no derivative)."""
    base = period_map(case, section, state, periods, derivative=False).end
    columns = []
    for j in range(4):
        e = np.zeros(4)
        e[j] = h
        plus = period_map(case, section, state + e, periods, derivative=False).end
        minus = period_map(case, section, state - e, periods, derivative=False).end
        small = period_map(case, section, state + e / 100, periods, derivative=False).end
        jumps = np.max(np.abs(small - base)) > 0.1 * np.max(np.abs(plus - base)) > 1e-3 * h
        columns.append(None if jumps else (plus - minus) / (2 * h))
    return columns


def assert_matches_differences(orbit, columns):
    scale = max(1.0, np.max(np.abs(orbit.monodromy)))
    for j, column in enumerate(columns):
        if column is not None:
            assert np.max(np.abs(column - orbit.monodromy[:, j])) < 2e-5 * scale, j


def test_a_parked_mass_is_neutral_in_its_displacement_not_a_free_particle():
    """m2 parked: the monodromy has the exact multipliers 1 (x2: it rests where it is put) and 0
    (v2: a push dies out), matching the differences of the map column by column, and the orbit
    is stable, not "unstable" (the old answer, from multipliers 1, 1 of a free particle)."""
    orbit = find_orbit("instance-1", **PARKED)
    assert orbit.resting == (2,) and orbit.discontinuous == ()
    np.testing.assert_array_equal(orbit.monodromy[2], [0.0, 0.0, 1.0, 0.0])
    np.testing.assert_array_equal(orbit.monodromy[3], np.zeros(4))
    np.testing.assert_array_equal(orbit.monodromy[:, 3], np.zeros(4))
    columns = central_differences(orbit.case, orbit.section, orbit.state)
    assert all(column is not None for column in columns)  # a push below the kinetic threshold dies out
    assert_matches_differences(orbit, columns)
    moduli = np.sort(np.abs(orbit.multipliers))
    assert moduli[0] < 1e-12 and abs(moduli[-1] - 1.0) < 1e-12 and moduli[-2] < 1
    assert orbit.stable and "neutral in x2" in orbit.verdict and orbit.verdict.startswith("stable")


def test_a_mass_held_by_static_friction_alone_makes_the_map_jump_in_its_velocity():
    """m2 parked between its thresholds: any push, either way, sets it sliding, so the map
    jumps in v2 (both signs); the derivative along the states where it rests still matches."""
    orbit = find_orbit("instance-1", **HELD)
    assert orbit.resting == (2,) and orbit.discontinuous == ("v2",)
    base = period_map(orbit.case, orbit.section, orbit.state, derivative=False).end
    for push in (1e-7, -1e-7):
        pushed = period_map(orbit.case, orbit.section, orbit.state + np.array([0, 0, 0, push]), derivative=False).end
        assert np.max(np.abs(pushed - base)) > 1e-2  # not of order 1e-7: it slid away
    columns = central_differences(orbit.case, orbit.section, orbit.state)
    assert columns[3] is None and all(c is not None for c in columns[:3])
    assert_matches_differences(orbit, columns)
    assert "discontinuous in v2" in orbit.verdict


@pytest.mark.parametrize("seed", RESTING_SEEDS)
def test_random_systems_with_a_mass_at_rest_all_period(seed):
    """The monodromy against the differences; the verdict against the multipliers of the
    moving masses' block of the differences (computed here, independently)."""
    orbit = find_orbit(random_case(seed), transient=60)
    assert orbit.resting and orbit.residual < 1e-8
    columns = central_differences(orbit.case, orbit.section, orbit.state)
    assert_matches_differences(orbit, columns)
    for mass in orbit.resting:
        assert np.min(np.abs(orbit.multipliers - 1.0)) < 1e-12
        assert f"neutral in x{mass}" in orbit.verdict
        assert (f"v{mass}" in orbit.discontinuous) == (columns[2 * mass - 1] is None)
    free = [k for k in range(4) if k // 2 + 1 not in orbit.resting]
    if free and all(columns[k] is not None for k in free):
        block = np.array([columns[k] for k in free]).T[free]
        assert orbit.stable == bool(np.all(np.abs(np.linalg.eigvals(block)) < 1.0))


def section_inside_a_rest(orbit, fraction):
    """The orbit's state at a time ``fraction`` of the way through its first rest interval."""
    events = orbit.events
    onset = events.t[events.kind == "sliding_onset"].iloc[0]
    end = events.t[(events.kind == "sliding_vanish") & (events.t > onset)].iloc[0]
    t = onset + fraction * (end - onset)
    start = dict(zip(("x1", "v1", "x2", "v2"), orbit.state, strict=True))
    run = simulate(orbit.case, t0=orbit.section, t_end=t, record_trajectory=False, **start)
    return t, np.array(run.final_state[1:])


def test_a_rest_across_the_section_matches_the_differences_in_every_direction():
    """The section inside m2's rest interval, early (force below the kinetic threshold): the map
    is differentiable in all four directions and the monodromy matches the differences (the v2
    column is zero: a push dies out; before the fix it was 0.77 off).  The multipliers do not
    depend on the section."""
    orbit = find_orbit("instance-1", Q2=70.5)
    t, state = section_inside_a_rest(orbit, 0.1)
    inside = find_orbit(orbit.case, section=t, guess=state)
    assert inside.state[3] == 0.0 and inside.discontinuous == () and inside.resting == ()
    columns = central_differences(inside.case, inside.section, inside.state)
    assert all(column is not None for column in columns)
    assert_matches_differences(inside, columns)
    np.testing.assert_array_equal(inside.monodromy[:, 3], np.zeros(4))
    np.testing.assert_allclose(np.sort(np.abs(inside.multipliers)), np.sort(np.abs(orbit.multipliers)), atol=1e-7)


def test_late_in_a_rest_the_map_jumps_in_the_resting_velocity():
    """Late in the rest interval the force has passed the kinetic threshold: a push makes m2
    slide before the orbit's release, and the map jumps in v2 (said so in the orbit)."""
    orbit = find_orbit("instance-1", Q2=70.5)
    t, state = section_inside_a_rest(orbit, 0.9)
    inside = find_orbit(orbit.case, section=t, guess=state)
    assert inside.discontinuous == ("v2",)
    columns = central_differences(inside.case, inside.section, inside.state)
    assert columns[3] is None and all(c is not None for c in columns[:3])
    assert_matches_differences(inside, columns)


def test_continuing_a_parked_mass_ends_where_static_friction_lets_go():
    """Up in K4 the parked m2 stays where it stuck until its spring's pull reaches the static
    threshold, K4 = (mu_s g m2 + P2 - K5 x2^3) / x2; there the orbit ends (the mass slides to
    a new rest), which the branch reports although the cycle of switches is the same."""
    branch = continue_orbit("instance-1", param="K4", start=4.0, stop=5.0, **PARKED)
    assert branch.complete
    p = branch.points
    assert (p.x2[p.K4 < 4.45] == 0.5).all() and (p.x2[p.K4 > 4.46] != 0.5).all()
    assert (p.piece[p.x2 == 0.5] == 0).all() and (p.piece[p.x2 != 0.5] == 1).all()  # the figure breaks there
    (row,) = branch.bifurcations.itertuples()
    expected = (0.2 * 9.8 * 1.0 + np.pi / 8 - 1.0 * 0.5**3) / 0.5
    assert row.kind == "sliding_vanish" and abs(row.K4 - expected) < 1e-8 and row.jump > 0.1


def test_both_masses_at_rest_all_period_and_a_guess_beside_them():
    """Both masses parked: the map is the identity in the displacements and zero in the
    velocities; Newton keeps both where they are, from the rest itself or from a guess with a
    push that dies out (the case that raised NumPy's LinAlgError before)."""
    parked_both = {**PARKED, "Q1": 0.0, "x1": 0.3, "v1": 0.0}
    orbit = find_orbit("instance-1", **parked_both)
    assert orbit.resting == (1, 2) and orbit.stable and orbit.iterations == 0
    np.testing.assert_array_equal(orbit.monodromy, np.diag([1.0, 0.0, 1.0, 0.0]))
    nudged = find_orbit("instance-1", guess=(0.3, 1e-5, 0.5, -1e-5), **parked_both)
    assert nudged.resting == (1, 2) and np.max(np.abs(nudged.state - [0.3, 0.0, 0.5, 0.0])) < 1e-8


def test_a_singular_newton_system_is_the_library_s_error():
    from oscillator.orbits.stroboscopic import solve_step

    with pytest.raises(SimulationFailed, match=r"singular.*give another guess"):
        solve_step(np.zeros((4, 4)), np.ones(4), "Newton's method at the guess")
