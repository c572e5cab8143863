"""Constructed cases that reach every domain, checked against an independent SciPy implementation.

``tests/independent.py`` implements docs/model.md on SciPy's DOP853 with its own code; here the
switching sequences (time, mass, kind, velocity sign entered) must agree.
"""

import dataclasses

import numpy as np
import pytest

from conftest import random_case
from independent import run
from oscillator import case_names, load_case, simulate
from oscillator.model.phase_space import velocity_sign

#: Seeds of ``random_case`` whose runs visit every domain of m1 (1, 145, 179), rest while in
#: one or both contacts (141, 145, 149, 190), re-stick many times (200) or touch a stop briefly (268).
SEEDS = [1, 141, 145, 149, 179, 190, 200, 268]


def switching_sequence(result):
    events = result.events
    keep = events[(events.kind != "grazing") & ~(events.kind.str.startswith("left_contact") & (events.mass == 2))]
    return [
        (t, mass, kind, velocity_sign(mass, domain))
        for t, mass, kind, domain in zip(keep.t, keep.mass, keep.kind, keep.to_domain, strict=True)
    ]


def assert_same_switching(case, t_tol=1e-7):
    ours = switching_sequence(simulate(case, rtol=1e-12, atol=1e-12, record_trajectory=False))
    theirs = run(dataclasses.asdict(case.parameters), case.initial.t0, case.initial.y, case.t_end)
    assert [e[1:] for e in ours] == [e[1:] for e in theirs]
    assert np.max(np.abs([a[0] - b[0] for a, b in zip(ours, theirs, strict=True)]), initial=0.0) < t_tol


#: The two scenes of Sec. 7 run 600 s each through the independent implementation: slow.
LONG_SCENES = ("bifurcation-omega", "bifurcation-q2")


@pytest.mark.parametrize(
    "name", [pytest.param(n, marks=pytest.mark.slow) if n in LONG_SCENES else n for n in case_names()]
)
def test_instances_agree_with_the_independent_implementation(name):
    assert_same_switching(load_case(name))


@pytest.mark.parametrize("seed", SEEDS)
def test_constructed_cases_agree_with_the_independent_implementation(seed):
    assert_same_switching(random_case(seed))


def test_the_constructed_cases_reach_every_domain_and_state():
    domains1, domains2, states, kinds = set(), set(), set(), set()
    for seed in SEEDS:
        result = simulate(random_case(seed))
        domains1 |= set(result.trajectory.domain1)
        domains2 |= set(result.trajectory.domain2)
        states |= set(result.trajectory.system_state)
        kinds |= set(result.events.kind)
    assert domains1 == set(range(9))
    assert domains2 == {0, 1, 2, 5, 6}
    # rest while in contact: m1 or m2 at rest with the left or right contact on
    assert {"II-b", "II-c", "II-d", "III-b", "III-c", "III-d", "IV-b", "IV-c"} <= states
    assert {"passable", "sliding_onset", "sliding_vanish", "left_contact_onset", "right_contact_onset"} <= kinds
    assert len(states) >= 13


def test_re_sticking_happens_and_rests_are_held():
    """A mass that comes to rest again (sliding onset after leaving rest) stays put until its
    force leaves the static band."""
    result = simulate(random_case(200))
    events, trajectory = result.events, result.trajectory
    assert (events.kind == "sliding_onset").sum() >= 10
    for mass in (1, 2):
        mine = events[events.mass == mass]
        onsets = mine[mine.kind == "sliding_onset"].t.to_numpy()
        for start in onsets:
            later = mine[(mine.t > start) & (mine.kind == "sliding_vanish")].t
            end = later.iloc[0] if len(later) else result.final_state[0]
            during = trajectory[(trajectory.t > start) & (trajectory.t < end)]
            assert (during[f"v{mass}"] == 0).all() and (during[f"domain{mass}"] == 0).all()
            assert during[f"x{mass}"].nunique() <= 1
