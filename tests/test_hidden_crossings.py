"""Two crossings of a boundary inside one CVODE step are found through the watched extrema."""

import math

import pytest

import oscillator.model.roots as detection
from oscillator import simulate

THRESHOLD = 0.2 * 9.8  # mu_s g with mu_s = 0.2, no feedback


@pytest.fixture
def brief_excursion(build):
    """m1 rests; its force exceeds the static threshold for only 0.135 of a period, and the
    first excursion comes almost a period after the start (CVODE's steps have grown by then)."""
    phi = math.pi / 2 + 0.9
    case = build(6.0, initial=(0.0, -0.5 * THRESHOLD, 0.0, 0.0, 0.0), K1=1.0, Q1=0.55 * THRESHOLD, phi1=phi)
    leave = (math.asin(0.5 / 0.55) - phi) % (2 * math.pi)
    return case, leave


def test_a_brief_excursion_past_the_flow_barrier_is_found(brief_excursion):
    case, leave = brief_excursion
    events = simulate(case, max_step_fraction=0.25).events
    assert events.kind.iloc[0] == "sliding_vanish"
    assert events.t.iloc[0] == pytest.approx(leave, abs=1e-9)


def test_without_the_extremum_roots_it_would_be_missed(brief_excursion, monkeypatch):
    """The control: hold the force-extremum root off and the same step hides both crossings."""
    case, leave = brief_excursion
    original = detection.root_kernel

    def without_extrema(t, y, g, *args):
        original(t, y, g, *args)
        g[detection.Root.EXTREMUM_1] = 1.0

    # on the scikit-sundae engine, whose root function is a Python function that can be replaced
    monkeypatch.setattr("oscillator.engines.sksundae.root_kernel", without_extrema)
    events = simulate(case, max_step_fraction=0.25, engine="sksundae").events
    assert events.empty or abs(events.t.iloc[0] - leave) > 1e-3


def test_a_brief_contact_is_found(build):
    """m1 touches the left stop for about 0.02 s (0.7 mm deep); found at every step cap."""
    from conftest import random_case

    case = random_case(268)
    for fraction in (0.02, 0.25):
        events = simulate(case, t_end=0.1, max_step_fraction=fraction).events
        onset = events[events.kind == "left_contact_onset"]
        assert onset.t.iloc[0] == pytest.approx(0.0171494652, abs=1e-8)
