"""Attractors, basins and Lyapunov spectra of declared systems (issue 52): the hardening
oscillator's two coexisting orbits and their basins, each start's attractor against a plain long
run, the multipliers and exponents against the closed forms of a damped smooth system (Liouville:
``log |det M| = -(c/m) T``), a stick-slip chain's rests against its orbit's measures."""

from __future__ import annotations

import math

import numpy as np
import pytest

import oscillator
from oscillator import AttractorSettings, Axis, FrictionChain, InputError
from oscillator.attractors.chain_attractors import chain_signature, find_chain_basins
from oscillator.hybrid.chain_run import simulate_chain
from oscillator.orbits.chain_orbits import find_chain_orbit

QUICK = AttractorSettings(transient=200, record=8)


def hardening(Omega: float = 1.3) -> FrictionChain:
    """``x'' + 0.1 x' + x + 0.4 x^3 = 0.25 sin(Omega t)``: at Omega = 1.3 a large and a small
    stable orbit coexist (the folds are at 1.2164 and 1.4036: tests/test_chain_branch.py)."""
    chain = FrictionChain(Omega=Omega).mass("m", 1.0).spring("m", k=1.0, k3=0.4).damper("m", c=0.1)
    return chain.force("m", Q=0.25)


@pytest.fixture(scope="module")
def basins() -> oscillator.attractors.chain_attractors.ChainBasins:
    return find_chain_basins(hardening(), Axis("x:m", -1.5, 1.5, 5), Axis("v:m", -1.5, 1.5, 4), settings=QUICK)


def test_the_hardening_oscillator_has_two_attractors_with_their_closed_form_multipliers(basins):
    found = basins.found.attractors
    assert [(a.period, a.stable) for a in found] == [(1, True), (1, True)]
    amplitudes = sorted(a.measures["x_pp:m"] / 2 for a in found)
    assert amplitudes[0] < 0.5 < 1.2 < amplitudes[1]
    period = hardening().period
    for attractor in found:
        # no switch, so M = Phi(T) and det M = exp(-c T) (Liouville); a complex pair: |mu| = exp(-c T / 2)
        assert np.abs(attractor.orbit.multipliers) == pytest.approx(math.exp(-0.05 * period), rel=1e-9)
        assert attractor.lyapunov == pytest.approx(-0.05, rel=1e-9)
        assert attractor.masses == ("m",) and attractor.signature == "" and attractor.rests == (0.0,)
        assert attractor.name.startswith(f"A{attractor.id}: period-1")


def test_each_cell_reaches_the_attractor_a_plain_long_run_reaches(basins):
    chain, labels = hardening(), basins.found.labels
    assert list(labels.columns[1:3]) == ["x:m", "v:m"] and basins.grid.shape == (4, 5)
    assert set(labels.attractor) == {0, 1}
    states = {a.id: a.orbit.state for a in basins.found.attractors}
    for row in labels.itertuples(index=False):
        start = np.array([row[1], row[2]])
        end = simulate_chain(chain, 400 * chain.period, start_state=start).y_end[:2]
        nearest = min(states, key=lambda ident: np.linalg.norm(states[ident] - end))
        assert np.linalg.norm(states[nearest] - end) < 1e-6
        assert nearest == row.attractor


def test_the_lyapunov_spectrum_of_a_smooth_damped_chain_sums_to_minus_c_over_m():
    spectrum = oscillator.lyapunov(hardening(), periods=40, transient=20)
    assert len(spectrum.exponents) == 2 and list(spectrum.convergence.columns) == ["period", "t", "lambda1", "lambda2"]
    assert spectrum.exponents.sum() == pytest.approx(-0.1, rel=1e-9)
    assert spectrum.exponents == pytest.approx([-0.05, -0.05], abs=2e-3)  # the pair's split averages out
    assert spectrum.case.title == hardening().title


def stick_slip() -> FrictionChain:
    """A forced mass on a belt: it sticks to the belt and slips off it once a period (the orbit of
    tests/test_chain_sensitivities.py)."""
    chain = FrictionChain(Omega=0.6).mass("m", 1.0).spring("m", k=1.0).damper("m", c=0.05)
    return chain.friction("m", name="belt", mu_s=0.4, mu_k=0.25, N=1.0, w=0.3).force("m", Q=0.4)


def test_a_stick_slip_attractor_carries_its_rests_and_cycle_of_switches():
    found = oscillator.find_attractors(stick_slip(), states=[[0.0, 0.0], [1.0, -1.0]], settings=QUICK)
    assert len(found.attractors) == 1 and list(found.labels.attractor) == [0, 0]
    (attractor,) = found.attractors
    orbit = attractor.orbit
    assert attractor.period == 1 and orbit is not None
    sticks = int((orbit.events.kind == "sticks").sum())
    assert sticks >= 1 and attractor.rests == (pytest.approx(sticks, abs=1e-12),)
    assert attractor.rest_time[0] == pytest.approx(attractor.measures["stuck:belt"], abs=1e-6)
    assert attractor.signature == chain_signature(orbit.run, orbit.section, stick_slip().period)
    assert "belt: " in attractor.signature and "sticks" in attractor.signature
    assert attractor.name == f"A0: period-1, m rests {sticks:g}/period"


def test_bad_starts_and_axes_are_refused_with_the_field():
    chain = hardening()
    with pytest.raises(InputError, match=r"rows of 2 finite numbers \(x:m, v:m\)"):
        oscillator.find_attractors(chain, states=[[0.0, 0.0, 0.0]])
    with pytest.raises(InputError, match="x: axis 'x:other' is not a state component; give one of x:m, v:m"):
        oscillator.find_basins(chain, Axis("x:other", 0, 1, 2), Axis("v:m", 0, 1, 2))
    with pytest.raises(InputError, match="guess must be one state"):
        oscillator.lyapunov(chain, guess=[[0.0, 0.0], [1.0, 0.0]])
    with pytest.raises(InputError, match="is no number of the system"):
        oscillator.find_attractors(chain, Zeta=1.0)


def test_a_sticking_mass_annihilates_a_direction_and_the_other_exponent_is_the_multipliers():
    chain = stick_slip()
    spectrum = oscillator.lyapunov(chain, periods=10, transient=50)
    orbit = find_chain_orbit(chain)
    assert orbit.free == ("x:m",)  # stuck at the section: its velocity is the belt's
    assert spectrum.exponents[1] == -math.inf  # the stick's saltation zeroes the velocity disturbance
    # the runs' CVODE tolerance is 1e-10 (the orbit's 1e-12): they agree to 1e-7
    assert spectrum.exponents[0] == pytest.approx(math.log(abs(orbit.multipliers[0])) / chain.period, rel=1e-7)
    assert spectrum.dimension == 0.0


def test_a_chains_spectrum_is_saved_with_its_system_and_read_back(tmp_path):
    spectrum = oscillator.lyapunov(stick_slip(), periods=5, transient=10)
    written = spectrum.save(tmp_path / "spectrum")
    assert (written / "system.toml").is_file() and not (written / "case.toml").exists()
    back = oscillator.read_run(written)
    assert back.case == stick_slip() and list(back.exponents) == list(spectrum.exponents)
    assert back.convergence.equals(spectrum.convergence)


def test_the_articles_basins_run_without_a_folder_too(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    case = oscillator.resolve_case("instance-1", Omega=1.85)
    basins = oscillator.find_basins(case, Axis("x1", 2, 5, 2), Axis("v1", -3, 3, 2), settings=QUICK)
    assert isinstance(basins, oscillator.Basins) and basins.grid.shape == (2, 2)
    assert [a.period for a in basins.found.attractors] == [1] and (basins.grid == 0).all()
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    "call",
    [
        lambda chain: oscillator.response(chain),
    ],
)
def test_an_analysis_of_the_articles_cases_refuses_a_declared_system_naming_those_that_take_one(call):
    with pytest.raises(
        InputError,
        match=r"takes the article's cases .* not a declared system; the ones that take a system: simulate, find_orbit",
    ):
        call(hardening())


def test_a_basins_figure_shows_a_systems_names_as_text_not_mathtext():
    name = "$x^2$ **m**"
    chain = FrictionChain(Omega=0.6).mass(name, 1.0).spring(name, k=1.0).damper(name, c=0.05)  # stick_slip()'s
    chain = chain.friction(name, name="belt", mu_s=0.4, mu_k=0.25, N=1.0, w=0.3).force(name, Q=0.4)
    basins = find_chain_basins(chain, Axis(f"x:{name}", -1.5, 1.5, 2), Axis(f"v:{name}", -1.5, 1.5, 2), settings=QUICK)
    ax = basins.plot().axes[0]
    texts = [ax.xaxis.label, ax.yaxis.label, *ax.get_legend().get_texts()]
    assert all("$x^2$" in t.get_text() for t in texts) and not any(t.get_parse_math() for t in texts)
