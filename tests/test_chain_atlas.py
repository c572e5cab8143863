"""The regime atlas of a declared system over two of its numbers (issue 52): ``regime_atlas`` and
``oscillator atlas FILE`` on an oscillator with a stop, whose orbit that misses the stop has its
closed-form amplitude and exists only where that amplitude is short of the stop; the measure names
a chain's orbits have, known before any orbit."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

import oscillator
from oscillator import Axis, InputError
from oscillator.analysis.axes import chain_plane
from oscillator.attractors.atlas import regime_atlas
from oscillator.cli.app import app
from oscillator.orbits.chain_orbits import find_chain_orbit
from oscillator.orbits.chain_response import measure_names, measure_unit, orbit_measures
from oscillator.report.plane import atlas_figure_name
from test_chain_following import free_amplitude
from test_chain_sensitivities import belt_chain, blade_chain, impact_chain

IMPACTS = Path(__file__).resolve().parents[1] / "docs" / "systems" / "impacts.toml"
OMEGA, AT = Axis("Omega", 1.0, 1.6, 7), Axis("wall.at", 0.3, 0.9, 4)


@pytest.mark.parametrize("make", [belt_chain, impact_chain, blade_chain])
def test_the_measure_names_are_those_of_the_orbits_in_their_order(make):
    orbit = find_chain_orbit(make(), transient=150)
    names = list(orbit_measures(orbit))
    assert list(measure_names(orbit.chain)) == names
    assert {measure_unit(name) for name in names} <= {"m", "", "m/s", "m/s^2", "N", "J", "1/s", "W", "N s"}


@pytest.fixture(scope="module")
def chain() -> oscillator.FrictionChain:
    return oscillator.load_system(IMPACTS)


@pytest.fixture(scope="module")
def atlas(chain):
    return regime_atlas(chain, OMEGA, AT, settings=None, measures=["x_max:m", "impact_velocity:wall"])


def test_the_orbit_that_misses_the_stop_is_there_only_short_of_it_with_its_closed_form_amplitude(chain, atlas):
    table = atlas.table
    assert (table.status == "ok").all() and set(table.regime) == {"P1", "P1 contact"}
    free = table[table.regime == "P1"]
    amplitudes = np.array([free_amplitude(chain, w) for w in free.Omega])
    assert free["x_max:m"].to_numpy() == pytest.approx(amplitudes, rel=1e-8)
    assert (amplitudes < free["wall.at"]).all() and (free["impact_velocity:wall"] == 0).all()
    strikes = table[table.regime == "P1 contact"]
    assert (strikes["x_max:m"] > strikes["wall.at"]).all() and (strikes["impact_velocity:wall"] > 0).all()
    reach = np.array([free_amplitude(chain, w) >= at for w, at in zip(table.Omega, table["wall.at"], strict=True)])
    assert set(table.regime[reach]) == {"P1 contact"}  # where the free orbit would reach the stop, it is not
    assert table.lyapunov.to_numpy() == pytest.approx(np.full(len(table), -0.05), abs=1e-9)  # det M = exp(-c T)
    several = table[table.coexisting > 1]
    assert len(several) and set(several.regime) == {"P1", "P1 contact"}
    assert list(table.columns[:4]) == ["row", "column", "Omega", "wall.at"]
    assert {"rests:m", "x:m", "v:m"} <= set(table.columns) and atlas.measures == ("x_max:m", "impact_velocity:wall")


def test_the_atlas_of_a_system_draws_its_own_names_and_no_article_marks(atlas):
    figure = atlas.plot("impact_velocity:wall")
    ax = figure.axes[0]
    assert ax.get_xlabel() == "Omega (rad/s)" and ax.get_ylabel() == "wall.at (m)"
    assert "Fig. 14" not in " ".join(text.get_text() for text in figure.findobj(lambda a: hasattr(a, "get_text")))
    assert atlas_figure_name("x_max:m") == "atlas-x-max-m" and atlas_figure_name("x_pp_m2") == "atlas-x-pp-m2"
    odd = [atlas_figure_name(f"x_max:{name}") for name in ("a-b", "a_b", "A", "<m>")]
    assert len(set(odd)) == 4 and all(name.startswith("atlas-x-max-") for name in odd)


def test_bad_axes_and_measures_of_a_system_are_refused_with_the_field(chain):
    with pytest.raises(InputError, match="is no number of the system") as raised:
        chain_plane(chain, Axis("wall.K3", 1, 2, 2), AT)
    assert raised.value.field == "x"
    with pytest.raises(InputError, match="K must not be negative"):
        chain_plane(chain, OMEGA, Axis("wall.K", -1.0, 1.0, 2))
    with pytest.raises(InputError, match="not a response measure") as raised:
        regime_atlas(chain, OMEGA, AT, measures=["x_pp_m2"])
    assert raised.value.field == "measures"
    with pytest.raises(InputError, match="nor a parameter"):
        Axis("wall", 0, 1, 2)


@pytest.mark.slow
def test_the_atlas_command_takes_a_system_file_and_resumes(tmp_path, chain):
    folder = tmp_path / "atlas"
    arguments = ["atlas", str(IMPACTS), "--x", "Omega", "1.2", "1.4", "3", "--y", "wall.at", "0.4", "0.6", "2"]
    options = ["--measures", "x_max:m", "--workers", "1", "--out", str(folder)]
    done = CliRunner().invoke(app, [*arguments, *options])
    assert done.exit_code == 0, done.stderr
    assert oscillator.load_system(folder / "system.toml") == chain
    assert (folder / "figures" / "atlas-x-max-m.png").stat().st_size > 0 and (folder / "report.html").exists()
    table = pd.read_parquet(folder / "atlas.parquet")
    found = regime_atlas(chain, Axis("Omega", 1.2, 1.4, 3), Axis("wall.at", 0.4, 0.6, 2), measures=["x_max:m"])
    assert table.drop(columns="x_max:m").equals(found.table.drop(columns="x_max:m"))
    assert table["x_max:m"].tolist() == pytest.approx(found.table["x_max:m"].tolist(), rel=1e-12)
    assert "P1 contact:" in done.stdout
    again = CliRunner().invoke(app, [*arguments, *options])
    assert again.exit_code == 0, again.stderr
    assert "resumed" in " ".join(again.stderr.split() + again.stdout.split())
    shutil.rmtree(folder / "figures")
    rebuilt = CliRunner().invoke(app, ["report", str(folder)])  # from its landings and its measures
    assert rebuilt.exit_code == 0, rebuilt.stderr
    assert (folder / "figures" / "atlas-x-max-m.png").stat().st_size > 0
    back = oscillator.read_run(folder)
    assert back.case == chain and back.table.equals(pd.read_parquet(folder / "atlas.parquet"))


@pytest.mark.slow
def test_report_rebuilds_an_articles_atlas_computed_with_measures(tmp_path):
    folder = tmp_path / "atlas"
    arguments = ["atlas", "instance-1", "--x", "Omega", "1.59", "1.61", "2", "--y", "Q2", "71.1", "71.2", "2"]
    done = CliRunner().invoke(app, [*arguments, "--measures", "x_pp_m2", "--workers", "1", "--out", str(folder)])
    assert done.exit_code == 0, done.stderr
    table = pd.read_parquet(folder / "atlas.parquet")
    rebuilt = CliRunner().invoke(app, ["report", str(folder)])  # was refused: its identity has the measures
    assert rebuilt.exit_code == 0, rebuilt.stderr
    assert pd.read_parquet(folder / "atlas.parquet").equals(table) and "x_pp_m2" in table


@pytest.mark.parametrize(
    ("options", "said"),
    [
        (("--x", "wall.K3", "1", "2", "2", "--y", "wall.at", "0.4", "0.6", "2"), "is no number of the system"),
        (("--x", "Omega", "1", "2", "2", "--y", "wall.at", "0.4", "0.6", "2", "--measures", "x_pp_m2"), "--measures"),
        (("--x", "Omega", "1", "2", "2", "--y", "wall.at", "0.4", "0.6", "2", "--engine", "cvode"), "--engine applies"),
        (("--x", "Omega", "1", "2", "2", "--y", "Q2", "60", "70", "2"), "is no number of the system"),
    ],
)
def test_the_atlas_command_refuses_what_a_system_cannot_take_creating_nothing(tmp_path, options, said):
    done = CliRunner().invoke(app, ["atlas", str(IMPACTS), *options, "--out", str(tmp_path / "a")])
    assert done.exit_code == 2 and said in done.stderr, done.stderr
    assert not (tmp_path / "a").exists()
