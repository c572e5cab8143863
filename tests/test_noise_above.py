"""The forces' and accelerations' RMS above a cut-off as response measures (docs/noise.md):
``force_above`` and ``a_above``, wherever the response measures go (an orbit, its exact
derivatives, the attractors, the atlas's describer, a design's objective), the cut-off a setting."""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest

import oscillator as osc
from oscillator.attractors.atlas import AtlasSettings
from oscillator.errors import InputError

#: Instance 1 with its stops close in (docs/noise.md): m1 strikes both every period, m2 sticks.
ORBIT = {"d": 1, "d1": 3.5, "Omega": 1.6}
#: The measures above a cut-off.
ABOVE = ["force_above_right", "force_above_left", "a_above_m1", "a_above_m2"]


@pytest.fixture(scope="module")
def orbit():
    return osc.find_orbit("instance-1", **ORBIT)


def test_the_rms_above_a_cut_off_is_the_mean_square_less_the_harmonics_at_or_below_it(orbit):
    """Above 1 Hz (the return's harmonics 1 to 3 at or below it, 0.2546 Hz apart): each force's
    RMS about its mean less those harmonics, each acceleration's mean square less its mean and
    those, from the spectra's own coefficients (1e-9); above 0 Hz the force's is ``force_rms``,
    and an orbit's acceleration's, whose mean is 0, ``a_rms``; every other measure the same; in
    decibels, the levels that ``sensitivities(...).levels`` gives (1e-9 dB)."""
    whole, above = orbit.response().columns(), orbit.response(cutoff=1.0).columns()
    found = orbit.noise(harmonics=8)
    below = [k for k in range(1, 9) if k / found.span <= 1.0]
    assert below == [1, 2, 3]
    for name, contact in found.contacts.items():
        c = contact.force.coefficients
        expected = math.sqrt(whole[f"force_rms_{name}"] ** 2 - sum(2 * abs(c[k]) ** 2 for k in below))
        assert above[f"force_above_{name}"] == pytest.approx(expected, rel=1e-9)
        assert whole[f"force_above_{name}"] == whole[f"force_rms_{name}"]
    for i, mass in found.masses.items():
        c = mass.acceleration.coefficients
        expected = math.sqrt(whole[f"a_rms_m{i}"] ** 2 - abs(c[0]) ** 2 - sum(2 * abs(c[k]) ** 2 for k in below))
        assert above[f"a_above_m{i}"] == pytest.approx(expected, rel=1e-9)
        assert whole[f"a_above_m{i}"] == pytest.approx(whole[f"a_rms_m{i}"], rel=1e-9)
        assert above[f"a_above_m{i}"] < 0.8 * whole[f"a_above_m{i}"]  # the low harmonics carry much of it
    for name in set(whole) - set(ABOVE):
        assert above[name] == pytest.approx(whole[name], rel=1e-9, abs=1e-12), name
    levels = orbit.sensitivities(["C3"]).levels(1.0)["value"]
    assert 20 * math.log10(above["force_above_left"]) == pytest.approx(levels["force_level_left"], abs=1e-9)
    assert 20 * math.log10(above["a_above_m2"] / 1e-6) == pytest.approx(levels["acceleration_level_m2"], abs=1e-9)


def test_off_an_orbit_the_acceleration_above_0_hz_leaves_out_its_mean():
    """Two forcing periods from the case's own start (not an orbit: m1 speeds up): ``a_above``
    is the acceleration's RMS about its mean, the mean (the velocity's change over the span)
    read from the spectrum's quadrature (1e-9)."""
    case = osc.resolve_case("instance-1", **ORBIT)
    measured = osc.response(case, 2).columns()
    spectra = osc.noise(case, 2, harmonics=0)
    for i, mass in spectra.masses.items():
        mean = abs(mass.acceleration.coefficients[0])
        assert mean > 1e-3 * measured[f"a_rms_m{i}"]  # a mean worth leaving out
        expected = math.sqrt(measured[f"a_rms_m{i}"] ** 2 - mean**2)
        assert measured[f"a_above_m{i}"] == pytest.approx(expected, rel=1e-9)


def test_the_rms_above_a_cut_off_moves_as_richardson_says():
    """``sensitivities(params).above(cutoff)``: the four measures' derivatives in C3, Omega (which
    moves the harmonics across the cut-off's span) and d (which moves the contacts' switches)
    equal Richardson differences of the orbits found nearby, each to 1e-7 of its own scale; the
    other measures are ``measures``' own."""
    from test_sensitivities import NEWTON, richardson

    orbit = osc.find_orbit("instance-1", **ORBIT, tol=NEWTON)
    params = ["C3", "Omega", "d"]
    found = orbit.sensitivities(params)
    table = found.above(1.0)
    assert table.drop(index=ABOVE).equals(found.measures.drop(index=ABOVE))

    def seen(name: str, value: float) -> np.ndarray:
        moved = osc.find_orbit(osc.resolve_case(orbit.case, **{name: value}), guess=orbit.state, tol=NEWTON)
        columns = moved.response(1.0).columns()
        return np.array([columns[measure] for measure in ABOVE])

    differences = []
    for name in params:
        value = getattr(orbit.case.parameters, name)
        differences.append(richardson(functools.partial(seen, name), value, 1e-4 * max(1.0, abs(value))))
    exact = table.loc[ABOVE, [f"d/d{name}" for name in params]].to_numpy()
    error = np.abs(np.array(differences).T - exact).max(axis=1)
    assert (error <= 1e-7 * np.abs(exact).max(axis=1)).all(), dict(zip(ABOVE, error, strict=True))


def test_the_attractors_and_the_atlas_measure_above_the_settings_cut_off(orbit):
    """``AttractorSettings(cutoff=)``: the attractor found carries its refined orbit's measures
    above the cut-off; the atlas's describer (one return from the last section point, without
    Newton) too, to the attractor's convergence."""
    from oscillator.attractors.features import Measured

    settings = osc.AttractorSettings(transient=100, record=8, cutoff=1.0)
    found = osc.find_attractors(osc.resolve_case("instance-1", **ORBIT), settings=settings)
    expected = orbit.response(1.0).columns()
    (attractor,) = [a for a in found.attractors if a.period == 1 and a.orbit is not None]
    for name in ABOVE:
        assert attractor.measures[name] == pytest.approx(expected[name], rel=1e-8), name
    described = Measured(responses=tuple(ABOVE), cutoff=1.0)(found.case, attractor)
    for name in ABOVE:
        assert described.measures[name] == pytest.approx(expected[name], rel=1e-5), name
    assert described.measures["force_above_left"] < expected["force_rms_left"]


@pytest.mark.parametrize(
    "call",
    [
        lambda: osc.AttractorSettings(cutoff=-1.0),
        lambda: AtlasSettings(cutoff=math.nan),
        lambda: osc.response(osc.resolve_case("instance-1"), 1, "1"),
    ],
)
def test_a_cut_off_that_is_not_a_frequency_is_refused_naming_it(call):
    with pytest.raises(InputError, match="cutoff must be a frequency in Hz, 0 or more") as refused:
        call()
    assert refused.value.field == "cutoff"


@pytest.mark.parametrize(
    ("arguments", "words"),
    [
        (
            "design instance-1 --vary d=0.5,2.2 --over Omega 1.45 1.6 --objective force_above_left --cutoff -1",
            "--cutoff: cutoff must be a frequency in Hz, 0 or more, got -1.0",
        ),
        (
            "atlas docs/systems/impacts.toml --x Omega 1 1.6 3 --y wall.at 0.3 0.9 2 --cutoff 1",
            "--cutoff applies to the article's cases",
        ),
        (
            "frc docs/systems/impacts.toml --param Omega 1 1.6 --cutoff 1",
            "--cutoff",
        ),
        (
            "attractors docs/systems/impacts.toml --param Omega --from 1.6 --to 1.0 --steps 2 --cutoff 1",
            "--cutoff applies to the article's cases",
        ),
        (
            "basins docs/systems/blade-damper.toml --x x:blade -2 2 2 --y v:blade -2 2 2 --cutoff 1",
            "--cutoff applies to the article's cases",
        ),
        ("basins instance-1 --x x1 2 4 2 --y v1 -2 2 2 --cutoff -2", "--cutoff: cutoff must be a frequency in Hz"),
    ],
)
def test_the_commands_refuse_a_bad_or_inapplicable_cut_off_before_any_work(tmp_path, capsys, arguments, words):
    from pathlib import Path

    from oscillator.cli.app import main

    root = Path(__file__).resolve().parents[1]
    arguments = [str(root / a) if a.startswith("docs/") else a for a in arguments.split()]
    with pytest.raises(SystemExit) as done:
        main([*arguments, "--out", str(tmp_path / "out")])
    assert done.value.code == 2 and words in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_a_branch_and_a_designs_surveys_and_refinement_measure_above_the_cut_off(orbit):
    """``Branch.responses(cutoff)``: each point's orbit refined and measured above the cut-off,
    as the orbit found alone at its value (1e-8); a design surveyed with ``AttractorSettings(cutoff=)``
    and followed by its refinement with that cut-off carries the orbit's ``force_above_left`` and
    its exact derivative (``sensitivities(...).above``) in the design's parameter (1e-9)."""
    from oscillator.designing.judging import follow, survey
    from oscillator.designing.problem import Problem

    branch = osc.continue_orbit("instance-1", param="Omega", start=1.6, stop=1.59, max_points=3, d=1, d1=3.5)
    table = branch.responses(cutoff=1.0)
    assert len(table) >= 2
    for point in table.itertuples(index=False):
        alone = osc.find_orbit("instance-1", d=1, d1=3.5, Omega=point.Omega, guess=orbit.state).response(1.0)
        assert point.force_above_left == pytest.approx(alone.contact["left"]["force_above"], rel=1e-8)
        assert point.a_above_m2 == pytest.approx(alone.mass[2]["a_above"], rel=1e-8)
    problem = Problem.of(
        osc.resolve_case("instance-1", d1=3.5), {"d": (0.5, 2.2)}, {"Omega": (1.55, 1.6)}, "force_above_left", [], 2, 1
    )
    settings = osc.AttractorSettings(transient=100, record=8, cutoff=1.0)
    design = np.array([1.0])
    followed = follow(problem, survey(problem, settings, design), design, cutoff=1.0)
    assert [seen.band for seen in followed.seen] == [1.55, 1.6]
    for seen in followed.seen:
        found = osc.find_orbit("instance-1", d=1, d1=3.5, Omega=seen.band, guess=seen.state).sensitivities(["d"])
        above = found.above(1.0).loc["force_above_left"]
        assert seen.measures["force_above_left"] == pytest.approx(above["value"], rel=1e-9)
        assert seen.gradients["force_above_left"][0] == pytest.approx(above["d/dd"], rel=1e-7)
        assert above["value"] < found.measures.loc["force_rms_left", "value"]


def test_the_pages_section_prints_what_it_shows(capsys):
    from pathlib import Path

    page = (Path(__file__).resolve().parents[1] / "docs" / "noise.md").read_text(encoding="utf-8")
    section = page.split("## Above a cut-off, wherever the measures go", 1)[1]
    code = section.split("```python\n", 1)[1].split("```", 1)[0]
    shown = section.split("```text\n", 1)[1].split("```", 1)[0]
    exec(compile(code, "docs/noise.md", "exec"), {})
    assert capsys.readouterr().out == shown


def test_an_atlas_colours_by_the_measure_above_its_cut_off_names_it_and_keeps_it(tmp_path):
    """An atlas computed with ``AtlasSettings(cutoff=1.0)``: its column is each attractor's
    measure above 1 Hz (below the force's RMS), its colouring names the cut-off, and saved and
    read back it keeps it."""
    from oscillator.analysis.axes import Axis
    from oscillator.report.plane import atlas_measures

    case = osc.resolve_case("instance-1", d=1, d1=3.5)
    x, y = Axis("Omega", 1.55, 1.6, 2), Axis("C3", 0.5, 1.0, 2)
    found = osc.regime_atlas(case, x, y, settings=AtlasSettings(cutoff=1.0), measures=["force_above_left"])
    plain = osc.regime_atlas(case, x, y, measures=["force_above_left"])
    assert found.cutoff == 1.0 and plain.cutoff == 0.0
    assert (found.table["force_above_left"] < 0.99 * plain.table["force_above_left"]).all()
    assert atlas_measures(found)["force_above_left"].endswith("(N, above 1 Hz)")
    found.save(tmp_path / "atlas")
    again = osc.read_run(tmp_path / "atlas")
    assert again.cutoff == 1.0 and again.table["force_above_left"].equals(found.table["force_above_left"])


def test_the_basins_command_measures_its_attractors_above_its_cut_off(tmp_path, orbit):
    """``oscillator basins ... --cutoff 1``: the period-1 attractor's row in attractors.parquet has
    the orbit's measures above 1 Hz (1e-8)."""
    import pandas as pd

    from oscillator.cli.app import main

    arguments = "basins instance-1 --set d=1 --set d1=3.5 --set Omega=1.6 --x x1 2 4 2 --y v1 -2 2 2"
    arguments += " --transient 100 --record 8 --cutoff 1 --no-plots --quiet"
    with pytest.raises(SystemExit) as done:
        main([*arguments.split(), "--out", str(tmp_path / "b")])
    assert done.value.code == 0
    table = pd.read_parquet(tmp_path / "b" / "attractors.parquet")
    expected = orbit.response(1.0).columns()
    row = table[table.period == 1].iloc[0]
    for name in ABOVE:
        assert row[name] == pytest.approx(expected[name], rel=1e-8), name
