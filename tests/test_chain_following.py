"""The attractors of a declared system over one of its numbers (issue 52): ``follow_attractors``
and ``oscillator attractors FILE`` on an oscillator with a stop, whose orbit that misses the stop
ends exactly where its closed-form amplitude reaches the stop (a grazing), and whose impacting
orbit ends at the branch's fold."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy.optimize import brentq
from typer.testing import CliRunner

import oscillator
from oscillator import AttractorSettings, InputError
from oscillator.attractors.following import follow_attractors
from oscillator.cli.app import app

IMPACTS = Path(__file__).resolve().parents[1] / "docs" / "systems" / "impacts.toml"
QUICK = AttractorSettings(transient=200, record=8)
STARTS = [[x, v] for x in (-1.0, 1.0) for v in (-1.0, 1.0)]
FREE = "period-1, no rest"
STRIKES = "period-1, 1 contacts/period"


def free_amplitude(chain: oscillator.FrictionChain, omega: float) -> float:
    """The steady amplitude of ``m x'' + c x' + k x = Q sin(Omega t)`` without the stop."""
    values = {element.type: element.values for element in chain.elements}
    k, c, q = values["spring"]["k"], values["damper"]["c"], values["force"]["Q"]
    return q / np.hypot(k - chain.masses[0].m * omega**2, c * omega)


@pytest.fixture(scope="module")
def chain() -> oscillator.FrictionChain:
    return oscillator.load_system(IMPACTS)


@pytest.fixture(scope="module")
def over(chain):
    return follow_attractors(chain, "Omega", np.linspace(1.6, 1.0, 7), states=STARTS, settings=QUICK, tol=1e-5)


def test_the_orbit_that_misses_the_stop_ends_where_its_amplitude_reaches_it(chain, over):
    gap = next(e for e in chain.elements if e.name == "wall").values["at"]
    grazing = brentq(lambda w: free_amplitude(chain, w) - gap, 1.05, 1.5)
    (end,) = [e for e in over.ends if e.name == FREE]
    assert end.change(1.6, 1.0) == "ends" and abs(end.inside - end.outside) <= 1e-5
    # the seed's transient overshoots the orbit it settles on: 6e-5 past the grazing measured
    assert end.at == pytest.approx(grazing, abs=2e-4) and end.at > grazing
    assert end.becomes == STRIKES
    table = over.table()
    free = table[table.name == FREE]
    assert free["x_max:m"].to_numpy() == pytest.approx([free_amplitude(chain, w) for w in free.Omega], rel=1e-8)
    assert (free["closings:wall"] == 0).all() and (free["x_max:m"] < gap).all()


def test_the_impacting_orbit_ends_at_the_fold_of_its_branch(chain, over):
    k = int(np.argmin(np.abs(over.values - 1.4)))
    (largest,) = [a for a in over.found[k].attractors if a.name.endswith(STRIKES)]
    branch = oscillator.continue_orbit(
        chain, param="Omega", start=1.4, stop=1.6, guess=largest.orbit.state, transient=0
    )
    fold = float(branch.folds.Omega.iloc[0])
    (end,) = [e for e in over.ends if e.name == STRIKES]
    assert end.change(1.6, 1.0) == "appears" and end.outside > end.inside
    # beyond the fold the seed lingers near the ghost of the orbit: the run's 200 periods end 3e-4 short
    assert end.at == pytest.approx(fold, abs=1e-3)
    table = over.table()
    both = table[table.Omega.round(9) == 1.3]
    assert sorted(both.name) == sorted([FREE, STRIKES]) and both.fraction.sum() == pytest.approx(1.0)
    strikes = table[table.name == STRIKES]
    assert (strikes["closings:wall"] == 1).all() and (strikes["x_max:m"] > 0.5).all() and strikes.stable.all()
    assert {"rests:m", "rest_time:m", "impact_velocity:wall", "force_max:wall"} <= set(table.columns)
    assert len(set(table.id)) == 2 and table.groupby("name").id.nunique().eq(1).all()


def test_bad_numbers_and_starts_are_refused_with_the_field(chain):
    with pytest.raises(InputError, match="is no number of the system") as raised:
        follow_attractors(chain, "wall.K3", [1.0, 1.1])
    assert raised.value.field == "wall.K3"
    with pytest.raises(InputError, match="rows of 2 finite numbers") as raised:
        follow_attractors(chain, "Omega", [1.0, 1.1], states=[[0.0, 0.0, 0.0]])
    assert raised.value.field == "states"
    with pytest.raises(InputError, match="increase or decrease"):
        follow_attractors(chain, "Omega", [1.0, 1.2, 1.1])
    with pytest.raises(InputError, match="element 'wall': K must not be negative, got -1"):
        follow_attractors(chain, "wall.K", [10.0, -1.0])  # both ends checked before any start runs


def test_the_attractors_command_takes_a_system_file_and_resumes(tmp_path, chain):
    folder = tmp_path / "over"
    arguments = ("attractors", str(IMPACTS), "--param", "Omega", "--from", "1.6", "--to", "1.0", "--steps", "4")
    done = CliRunner().invoke(
        app, [*arguments, "--tol", "1e-4", "--workers", "1", "--no-branches", "--out", str(folder)]
    )
    assert done.exit_code == 0, done.stderr
    assert {"attractors.parquet", "ends.parquet", "system.toml", "attractors.json", "report.html"} <= {
        p.name for p in folder.iterdir()
    }
    assert oscillator.load_system(folder / "system.toml") == chain
    table = pd.read_parquet(folder / "attractors.parquet")
    found = follow_attractors(chain, "Omega", np.linspace(1.6, 1.0, 4), settings=AttractorSettings(), tol=1e-4)
    assert table["x_max:m"].tolist() == pytest.approx(found.table()["x_max:m"].tolist(), rel=1e-9)
    assert [json.loads(p) for p in table.points] == [json.loads(p) for p in found.table().points]
    ends = pd.read_parquet(folder / "ends.parquet")
    assert ends.name.tolist() == [e.name for e in found.ends] and "ends between Omega" in done.stdout
    again = CliRunner().invoke(
        app, [*arguments, "--tol", "1e-4", "--workers", "1", "--no-branches", "--out", str(folder)]
    )
    assert again.exit_code == 0, again.stderr
    assert "resumed" in " ".join(again.stderr.split() + again.stdout.split())
    assert pd.read_parquet(folder / "attractors.parquet").equals(table)


@pytest.mark.parametrize(
    ("options", "said"),
    [
        (("--param", "wall.K3"), "is no number of the system"),
        (("--param", "Omega", "--coordinate", "x2"), "--coordinate must be one of x:m, v:m"),
        (("--param", "Omega", "--engine", "cvode"), "--engine applies"),
        (("--param", "Omega", "--set", "Omega=1.2"), "is given by --param"),
        (("--param", "Omega", "--x", "x1", "0", "1", "2", "--y", "v:m", "0", "1", "2"), "give one of x:m, v:m"),
    ],
)
def test_the_attractors_command_refuses_what_a_system_cannot_take_creating_nothing(tmp_path, options, said):
    span = ("--from", "1.0", "--to", "1.2", "--steps", "2")
    done = CliRunner().invoke(app, ["attractors", str(IMPACTS), *options, *span, "--out", str(tmp_path / "o")])
    assert done.exit_code == 2 and said in done.stderr, done.stderr
    assert not (tmp_path / "o").exists()


def test_the_attractors_over_a_number_save_with_their_system(tmp_path, chain, over):
    folder = over.save(tmp_path / "saved")
    assert oscillator.load_system(folder / "system.toml") == chain
    assert pd.read_parquet(folder / "attractors.parquet")["x_max:m"].tolist() == over.table()["x_max:m"].tolist()
    assert json.loads((folder / "attractors.json").read_text())["case_name"] == chain.title
    with pytest.raises(InputError, match="declared system's attractors"):
        oscillator.read_run(folder)
