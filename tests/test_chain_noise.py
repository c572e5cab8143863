"""A declared system's spectra (docs/noise.md, "Declared systems"): a stop's half-sine force
against its closed-form series, the article's system declared as a chain against the article's
own spectra (another integrator, another interpolation), Parseval against the orbit's force RMS."""

from __future__ import annotations

import functools
import math
from pathlib import Path

import numpy as np
import pytest

import oscillator as osc
from oscillator import FrictionChain, SolverOptions
from oscillator.errors import InputError
from oscillator.hybrid.chain_run import simulate_chain
from oscillator.model.chains import article_chain
from oscillator.orbits.chain_noise import chain_noise
from oscillator.orbits.chain_orbits import find_chain_orbit
from oscillator.orbits.spectra import mean_square_above
from test_noise import half_sine_series
from test_sensitivities import richardson

TIGHT = SolverOptions(rtol=1e-12, atol=1e-12)
ROOT = Path(__file__).resolve().parents[1]


def test_a_free_mass_struck_by_an_elastic_stop_feels_a_half_sine_force():
    """A free mass (m = 2) at 1 m/s meets a stop (K = 50) 0.5 m ahead: the stop's force on it is
    ``-m v0 w sin(w (t - 0.5))`` for ``pi / w`` s (``w^2 = K / m``), and its acceleration that
    divided by ``m``; over the run's 3 s, taken as the period, their coefficients are the
    closed-form series' (1e-9 of the largest)."""
    chain = FrictionChain(Omega=1.0).mass("m", m=2.0, x=0.0, v=1.0).stop("m", name="wall", side="right", at=0.5, K=50.0)
    found = chain_noise(simulate_chain(chain, 3.0, options=TIGHT), harmonics=150)
    w = np.sqrt(50.0 / 2.0)
    exact = half_sine_series(-2.0 * 1.0 * w, np.pi / w, 3.0, 0.5, 150)
    wall, acceleration = found.forces["wall"].coefficients, found.accelerations["m"].coefficients
    assert np.abs(wall - exact).max() < 1e-9 * np.abs(exact).max()
    assert np.abs(acceleration - exact / 2.0).max() < 1e-9 * np.abs(exact).max()
    assert found.span == 3.0 and found.periods == pytest.approx(3.0 / (2 * np.pi)) and found.measures == {}
    assert found.forces["wall"].unit == "N" and found.accelerations["m"].reference == 1e-6


@pytest.fixture(scope="module")
def article():
    """The orbit of docs/noise.md (both contacts struck, m2 sticking twice), found by the article's
    path and by the chain's from its section state."""
    orbit = osc.find_orbit("instance-1", d=1, d1=3.5, Omega=1.6)
    case = orbit.one_period()
    chained = find_chain_orbit(article_chain(case.parameters, case.initial), orbit.state.copy(), transient=0)
    return orbit, chained


def test_the_article_declared_as_a_chain_has_the_articles_spectra(article):
    """The chain's spectra (CVODE's steps, the quintic through them) equal the article's (each
    smooth piece integrated again by DOP853) to 1e-9 of each spectrum's largest harmonic: the
    contact forces as the force on m1 (the article's are compressive: the right stop's with the
    other sign), the accelerations as they are."""
    orbit, chained = article
    found, theirs = chained.noise(harmonics=100), orbit.noise(harmonics=100)
    assert abs(chained.section - orbit.section) < 1e-12 and np.abs(chained.state - orbit.state).max() < 1e-8
    names = {"contact-9": ("left", 1.0), "stop-10": ("right", -1.0)}
    assert list(found.forces) == list(names)
    for element, (contact, sign) in names.items():
        ours, article_force = found.forces[element].coefficients, theirs.contacts[contact].force.coefficients
        assert np.abs(ours - sign * article_force).max() < 1e-9 * np.abs(article_force).max()
    for mass, i in (("m1", 1), ("m2", 2)):
        ours, article_acceleration = found.accelerations[mass].coefficients, theirs.masses[i].acceleration.coefficients
        assert np.abs(ours - article_acceleration).max() < 1e-9 * np.abs(article_acceleration).max()
    assert found.columns(1.0)["force_level:contact-9"] == pytest.approx(
        theirs.columns(1.0)["force_level_left"], abs=1e-6
    )


def test_the_chains_noise_measures_are_its_orbit_measures_and_parseval_holds(article):
    """The measures kept are the orbit's own; the stop's mean force is its impulse rate (the
    force's integral by the quintic's mean, another quadrature); the harmonics' mean square
    approaches the article's force RMS squared from below, as Parseval says."""
    orbit, chained = article
    found = chained.noise(harmonics=600)
    response = orbit.response()
    measures = osc.orbits.chain_response.orbit_measures(chained)
    assert found.measures == {k: v for k, v in measures.items() if k.partition(":")[0] in {
        "impact_rate", "impact_velocity", "impulse", "impulse_rate", "impact_energy", "impact_power", "force_max",
        "slip_steps", "slip_step_max"}}  # fmt: skip
    assert found.measures["impulse_rate:stop-10"] == pytest.approx(abs(found.forces["stop-10"].mean), rel=1e-9)
    assert found.measures["slip_steps:friction-8"] == 4 and found.measures["slip_steps:friction-4"] == 0
    rms = response.contact["right"]["force_rms"]
    harmonics = mean_square_above(found.forces["stop-10"].coefficients, found.forces["stop-10"].fundamental)
    assert 0 < rms**2 - harmonics < 1e-6 * rms**2  # a force with kinks: its tail falls as 1/K^3


def test_the_spectra_table_and_figure_name_every_signal(article):
    _, chained = article
    found = chained.noise(harmonics=50)
    table = found.spectra()
    assert list(table.signal.unique()) == ["force:contact-9", "force:stop-10", "acceleration:m1", "acceleration:m2"]
    assert (table.groupby("signal").size() == 51).all()
    assert table[table.signal == "acceleration:m2"].unit.iloc[0] == "m/s^2"
    fig = found.plot()
    titles = [ax.get_title(loc="left") for ax in fig.axes if ax.get_title(loc="left")]
    assert titles == ['contact "contact-9": its force on m1', 'stop "stop-10": its force on m1',
                      "acceleration of m1", "acceleration of m2"]  # fmt: skip


@pytest.mark.parametrize(
    ("call", "field"),
    [
        (lambda: chain_noise("instance-1"), "motion"),
        (
            lambda: chain_noise(simulate_chain(FrictionChain(Omega=1.0).mass("m", m=1.0), 1.0), harmonics=-1),
            "harmonics",
        ),
    ],
)
def test_bad_arguments_are_refused_naming_the_field(call, field):
    with pytest.raises(InputError) as caught:
        call()
    assert caught.value.field == field


def test_the_orbit_command_prints_a_systems_noise_and_writes_its_spectra(tmp_path, monkeypatch):
    """``oscillator orbit FILE --noise --noise-table T --noise-figure F`` prints the library's
    measures and levels for each stop, mass and friction element, writes its spectra table and
    draws its figure; a name of another kind is refused before anything is computed."""
    import pandas as pd
    from typer.testing import CliRunner

    from oscillator.cli import console
    from oscillator.cli.app import app

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(console.out, "width", 200)
    system = str(ROOT / "docs" / "systems" / "rattler.toml")
    done = CliRunner().invoke(
        app, ["orbit", system, "--noise", "--noise-table", "s.parquet", "--noise-figure", "s.png"]
    )
    assert done.exit_code == 0, done.output
    found = find_chain_orbit(osc.load_system(system), transient=100).noise()
    lines = {line.split()[0]: line.split()[1:] for line in done.stdout.splitlines() if line.strip()}
    kinds = ("impact_rate", "impact_velocity", "impulse", "impact_energy", "impact_power")
    assert lines["stop"] == [
        *(f"{found.measures[f'{k}:stop']:.4g}" for k in kinds),
        f"{found.forces['stop'].level():.2f}",
    ]
    assert lines["part"] == [f"{found.accelerations['part'].level():.2f}"]
    assert lines["floor"] == ["2", f"{found.measures['slip_step_max:floor']:.6g}"]
    written = pd.read_parquet(tmp_path / "s.parquet")
    assert list(written.signal.unique()) == ["force:stop", "acceleration:part"]
    assert np.allclose(written.amplitude, found.spectra().amplitude, rtol=1e-6, atol=1e-12)
    assert (tmp_path / "s.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    refused = CliRunner().invoke(app, ["orbit", system, "--noise-table", "s.txt"])
    assert refused.exit_code == 2 and "must end in .csv or .parquet" in refused.stderr and not refused.stdout


def test_the_page_prints_what_it_shows(capsys, monkeypatch):
    """docs/noise.md's declared system's example prints what the page shows."""
    page = (ROOT / "docs" / "noise.md").read_text(encoding="utf-8").split("## Declared systems", 1)[1]
    code = page.split("```python\n", 1)[1].split("```", 1)[0]
    shown = page.split("```text\n", 1)[1].split("```", 1)[0]
    monkeypatch.chdir(ROOT)  # the example reads docs/systems/rattler.toml
    exec(compile(code, "docs/noise.md", "exec"), {})
    assert capsys.readouterr().out == shown


def test_an_attractors_spectra_are_its_orbits_or_a_windows(basins_like):
    """``Attractors.noise(k)``: a refined periodic attractor's are its orbit's; an aperiodic set's
    are those of the run of its window (from its first section point, a forcing period per
    recorded point), whose acceleration's mean is the velocity's change over the window divided by
    its span (the theorem of calculus: a check of the window's ends; 1e-7); a number not found is refused
    naming the field."""
    import dataclasses

    from oscillator.attractors.finding import Attractors

    found = basins_like
    (periodic,) = found.attractors
    ours, orbit = found.noise(0, harmonics=30), periodic.orbit.noise(harmonics=30)
    assert np.array_equal(ours.contacts["left"].force.coefficients, orbit.contacts["left"].force.coefficients)
    initial = found.case.initial  # a window is its first point, a forcing period a point recorded
    start = np.array([initial.x1, initial.v1, initial.x2, initial.v2])
    window = dataclasses.replace(periodic, period=0, orbit=None, points=np.array([start, start, start]))
    aperiodic = Attractors(found.case, found.settings, (window,), found.labels).noise(0, harmonics=30)
    assert aperiodic.periods == 3 and aperiodic.span == pytest.approx(3 * found.case.parameters.period, rel=1e-15)
    end = osc.simulate(found.case, t_end=found.case.initial.t0 + 3 * found.case.parameters.period).final_state[1:]
    for i, v in ((1, 1), (2, 3)):
        change = (end[v] - start[v]) / aperiodic.span
        assert aperiodic.masses[i].acceleration.mean == pytest.approx(change, rel=1e-7)
    with pytest.raises(InputError) as refused:
        found.noise(1)
    assert refused.value.field == "attractor" and "(0)" in str(refused.value)


@pytest.fixture(scope="module")
def basins_like():
    """docs/noise.md's rattling orbit as the one attractor of two starts, from a start away from
    its orbit (so that a window's velocity changes)."""
    case = osc.resolve_case("instance-1", d=1, d1=3.5, Omega=1.6, x1=0.5, v1=2.0)
    return osc.find_attractors(
        case, states=[[0.5, 2.0, 0.0, 0.0]], settings=osc.AttractorSettings(transient=40, record=4)
    )


def test_a_chain_attractors_spectra_are_its_orbits_or_a_windows():
    """The same for a declared system's attractors: the refined orbit's spectra and measures, or a
    window's (the acceleration's mean the velocity's change over the span)."""
    import dataclasses

    from oscillator.attractors.chain_attractors import ChainAttractors

    chain = FrictionChain(Omega=0.6).mass("m", 1.0, x=1.0).spring("m", k=1.0).damper("m", c=0.05)
    chain = chain.friction("m", name="belt", mu_s=0.4, mu_k=0.25, N=1.0, w=0.3).force("m", Q=0.4)
    found = osc.find_attractors(chain, states=[[0.0, 0.0]], settings=osc.AttractorSettings(transient=100, record=4))
    (periodic,) = found.attractors
    assert found.noise(0, 20).measures == periodic.orbit.noise(20).measures != {}
    window = dataclasses.replace(periodic, period=0, orbit=None, points=np.array([[1.0, 0.0], [0.0, 0.0]]))
    spectra = ChainAttractors(chain, found.settings, (window,), found.labels).noise(0, 20)
    run = simulate_chain(chain, chain.t0 + 2 * chain.period, options=TIGHT, start_state=np.array([1.0, 0.0]))
    change = (run.states[-1, 1] - 0.0) / spectra.span
    assert spectra.periods == pytest.approx(2.0) and spectra.measures == {}
    assert spectra.accelerations["m"].mean == pytest.approx(change, abs=1e-9)


def test_a_hostile_element_name_is_printed_and_drawn_as_text(tmp_path, monkeypatch):
    """A stop named like markup (rich's, matplotlib's mathtext) is printed as it is and titled
    with its dollars escaped (drawn as dollars, not as mathematics)."""
    from typer.testing import CliRunner

    from oscillator.cli import console
    from oscillator.cli.app import app

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(console.out, "width", 200)
    text = (ROOT / "docs" / "systems" / "rattler.toml").read_text(encoding="utf-8")
    (tmp_path / "odd.toml").write_text(text.replace('name = "stop"', 'name = "[bold]$x^2$"'), encoding="utf-8")
    done = CliRunner().invoke(app, ["orbit", "odd.toml", "--noise"])
    assert done.exit_code == 0, done.output
    assert "[bold]$x^2$" in done.stdout
    fig = find_chain_orbit(osc.load_system(tmp_path / "odd.toml"), transient=100).noise(20).plot()
    titles = [ax.get_title(loc="left") for ax in fig.axes]
    assert 'stop "[bold]\\$x^2\\$": its force on part' in titles


def test_a_declared_systems_levels_above_a_cut_off_are_every_harmonic_above_it():
    """``orbit.sensitivities(names).levels(cutoff)`` on a chain with a damped stop, a damped
    contact and a floor: each level is a 600-harmonic spectrum's but for its tail."""
    from test_chain_sensitivities import impact_chain

    orbit = find_chain_orbit(impact_chain(), transient=150)
    levels = orbit.sensitivities(["wall.C"]).levels(cutoff=0.3)
    assert list(levels.index) == ["force_level:wall", "force_level:gap", "acceleration_level:a", "acceleration_level:b"]
    heard = orbit.noise(600).columns(0.3)
    for name in levels.index:
        assert heard[name] == pytest.approx(levels.loc[name, "value"], abs=1e-3), name
    with pytest.raises(InputError, match="cutoff must be a frequency"):
        orbit.sensitivities(["wall.C"]).levels(math.nan)


@pytest.mark.slow
def test_a_declared_systems_levels_move_as_richardson_says():
    """Their derivatives in the stop's damper and in Omega (which moves every harmonic and the
    return's end) equal Richardson differences of the nearby orbits' levels, each level to 1e-7
    of its own scale."""
    from test_chain_sensitivities import impact_chain

    orbit = find_chain_orbit(impact_chain(), transient=150)
    params = ["wall.C", "Omega"]
    levels = orbit.sensitivities(params).levels(cutoff=0.3)

    def seen(name: str, value: float) -> np.ndarray:
        moved = find_chain_orbit(orbit.chain.with_values({name: value}), orbit.state, transient=0, tol=1e-13)
        return moved.sensitivities(["wall.C"]).levels(0.3)["value"].to_numpy()

    differences = []
    for name in params:
        value = orbit.chain.value(name)
        differences.append(richardson(functools.partial(seen, name), value, 1e-4 * max(1.0, abs(value))))
    exact = levels[[f"d/d{name}" for name in params]].to_numpy()
    error = np.abs(np.array(differences).T - exact).max(axis=1)
    assert (error <= 1e-7 * np.abs(exact).max(axis=1)).all(), dict(zip(levels.index, error, strict=True))


def test_the_frc_command_measures_a_systems_sweeps_noise(tmp_path, monkeypatch):
    """``oscillator frc FILE ... --noise``: noise.parquet holds each orbit the sweeps found (both
    ways) with its levels, spectra.parquet its spectra, each the orbit's found again from its state
    at its value; the spectra's figure is drawn."""
    import pandas as pd
    from typer.testing import CliRunner

    from oscillator.cli.app import app

    monkeypatch.chdir(tmp_path)
    system = str(ROOT / "docs" / "systems" / "impacts.toml")
    done = CliRunner().invoke(
        app, ["frc", system, "--param", "Omega", "1.3", "1.4", "--sweep", "3", "--noise", "--out", "s"]
    )
    assert done.exit_code == 0, done.output
    sweeps, heard = (
        pd.read_parquet(tmp_path / "s" / "sweeps.parquet"),
        pd.read_parquet(tmp_path / "s" / "noise.parquet"),
    )
    spectra = pd.read_parquet(tmp_path / "s" / "spectra.parquet")
    assert len(heard) == (sweeps.status != "failed").sum() == 6
    assert list(heard.columns) == ["direction", "Omega", "stable", "force_level:wall", "acceleration_level:m"]
    assert len(spectra) == 6 * 2 * 201 and list(spectra.columns[:3]) == ["direction", "Omega", "stable"]
    row = sweeps.iloc[1]
    chain = osc.load_system(system).with_values({"Omega": float(row.Omega)})
    alone = find_chain_orbit(chain, row[["x:m", "v:m"]].to_numpy(float), transient=0).noise()
    assert heard.iloc[1]["acceleration_level:m"] == pytest.approx(alone.columns()["acceleration_level:m"], abs=1e-9)
    assert (tmp_path / "s" / "figures" / "frequency-spectra.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
