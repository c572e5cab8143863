"""A declared system's frequency response with its branches (issue 52): every period-1 branch the
seeds and sweeps reach, followed through folds and grazings, against closed forms (a linear
chain, Den Hartog's oscillator), a hardening oscillator's two folds, and an oscillator with a stop
whose branch turns where its free orbit's amplitude reaches the stop; ``oscillator frc FILE
--seeds N`` writes them."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy.optimize import brentq
from typer.testing import CliRunner

import oscillator
from oscillator import InputError
from oscillator.attractors.chain_frequency import chain_frequency_response, on_branch
from oscillator.cli.app import app
from test_chain_following import free_amplitude
from test_chain_orbits import _den_hartog_amplitude, den_hartog_chain, linear_chain

SYSTEMS = Path(__file__).resolve().parents[1] / "docs" / "systems"


def test_a_linear_chains_branch_is_its_closed_form_response():
    response = chain_frequency_response(linear_chain(), "Omega", (1.2, 1.8), seeds=2, sweep=3)  # between its resonances
    (branch,) = response.branches
    assert branch.bifurcations.empty and branch.points.stable.all()
    mass, damping = np.diag([1.0, 0.5]), np.diag([0.1, 0.05])
    stiffness = np.array([[3.0, -1.0], [-1.0, 1.0]])
    for row in branch.points.itertuples(index=False):
        omega = row.Omega
        exact = np.abs(np.linalg.solve(stiffness - omega**2 * mass + 1j * omega * damping, [1.0, 0.0]))
        assert [row[branch.points.columns.get_loc(f"x_max:{m}")] for m in "ab"] == pytest.approx(exact, abs=1e-9)
    assert branch.points.Omega.min() <= 1.2 and branch.points.Omega.max() >= 1.8


def test_den_hartogs_branch_turns_at_his_amplitude():
    response = chain_frequency_response(
        den_hartog_chain(), "Omega", (0.55, 0.75), seeds=1, sweep=2, transient=40, step=0.2
    )
    (branch,) = response.branches
    inside = branch.points[branch.points.Omega.between(0.55, 0.75)]
    assert len(inside) >= 3 and (inside["stuck:floor"] == 0).all()
    exact = [_den_hartog_amplitude(w) for w in inside.Omega]
    assert inside["x_max:m"].to_numpy() == pytest.approx(exact, abs=1e-8)


@pytest.fixture(scope="module")
def hardening():
    chain = oscillator.load_system(SYSTEMS / "hardening.toml")
    return chain, chain_frequency_response(chain, "Omega", (0.8, 1.6), seeds=3, sweep=9)


@pytest.mark.slow
def test_the_hardening_oscillators_one_branch_folds_twice_and_carries_every_sweep(hardening):
    chain, response = hardening
    (branch,) = response.branches
    folds = sorted(branch.folds.Omega)
    alone = oscillator.continue_orbit(chain, param="Omega", start=0.8, stop=1.6, transient=200)
    assert folds == pytest.approx(sorted(alone.folds.Omega), abs=1e-4)  # each on the parabola of its 3 points
    points = branch.points
    here = points.iloc[np.flatnonzero(np.diff(np.sign(points.Omega.to_numpy() - 1.3)))]
    assert len(here) == 3 and here.stable.tolist() == [True, False, True]  # large, unstable, small
    state = list(chain.system.state)
    for row in response.sweeps.itertuples(index=False):
        values = response.sweeps.loc[response.sweeps.Omega == row.Omega, state].to_numpy(float)
        assert all(on_branch(chain, "Omega", branch, row.Omega, y) for y in values)
    up = response.sweeps[response.sweeps.direction == "up"]
    assert up["x_max:m"].diff().min() < -0.5  # the sweep up jumps down past the upper fold


@pytest.mark.slow
def test_the_impacting_branch_turns_where_the_free_orbit_grazes_the_stop():
    chain = oscillator.load_system(SYSTEMS / "impacts.toml")
    response = chain_frequency_response(chain, "Omega", (1.0, 1.6), seeds=3, sweep=7)
    (branch,) = response.branches
    gap = next(e for e in chain.elements if e.type == "stop").values["at"]
    grazing = brentq(lambda w: free_amplitude(chain, w) - gap, 1.05, 1.5)
    low, high = sorted(branch.folds.Omega)
    # the step across a change of the cycle of switches is 1e-4 of the span: the turn within 1e-4
    assert low == pytest.approx(grazing, abs=1e-4) and high == pytest.approx(1.44577, abs=1e-4)
    free = branch.points[branch.points["closings:wall"] == 0]
    assert free["x_max:m"].to_numpy() == pytest.approx([free_amplitude(chain, w) for w in free.Omega], rel=1e-8)
    table = response.table()
    assert (table.branch == 0).all() and len(table) == len(branch.points)
    assert set(response.bifurcations().kind) == {"fold"}


def test_bad_spans_and_counts_are_refused_with_the_field():
    chain = oscillator.load_system(SYSTEMS / "impacts.toml")
    for span, field in (((1.6, 1.0), "span"), ((1.0, float("nan")), "span")):
        with pytest.raises(InputError) as raised:
            chain_frequency_response(chain, "Omega", span)
        assert raised.value.field == field
    with pytest.raises(InputError, match="seeds"):
        chain_frequency_response(chain, "Omega", (1.0, 1.6), seeds=0)
    with pytest.raises(InputError, match="is no number of the system"):
        chain_frequency_response(chain, "wall.K3", (1.0, 1.6))


@pytest.mark.slow
def test_frc_of_a_system_file_with_seeds_writes_its_branches(tmp_path):
    folder = tmp_path / "frc"
    arguments = ["frc", str(SYSTEMS / "impacts.toml"), "--param", "Omega", "1.3", "1.6", "--seeds", "1"]
    done = CliRunner().invoke(app, [*arguments, "--starts", "4", "--sweep", "3", "--out", str(folder)])
    assert done.exit_code == 0, done.stderr
    branches = pd.read_parquet(folder / "branches.parquet")
    bifurcations = pd.read_csv(folder / "bifurcations.csv")
    # from 1.3 the impacting orbit folds back at 1.4458 and leaves the span; the free one starts another
    assert set(branches.branch) == {0, 1} and bifurcations.Omega.round(3).tolist() == [1.446]
    assert {"closings:wall", "x:m", "stable"} <= set(branches.columns)
    assert "fold at Omega = 1.44577" in done.stdout and (folder / "figures" / "frequency.png").stat().st_size > 0
    refused = CliRunner().invoke(app, [*arguments[:6], "--starts", "3", "--out", str(tmp_path / "no")])
    assert refused.exit_code == 2 and "--starts goes with --seeds" in refused.stderr
    assert not (tmp_path / "no").exists()


def test_frequency_response_takes_a_system_and_refuses_the_articles_options():
    chain = oscillator.load_system(SYSTEMS / "hardening.toml")
    response = oscillator.frequency_response(chain, "Omega", (1.45, 1.6), seeds=1, sweep=2)
    (branch,) = response.branches
    assert branch.bifurcations.empty and branch.points.stable.all()
    figure = response.plot()
    assert figure.axes[0].get_ylabel() == "x_max:m (m)" and figure.axes[0].get_xlabel() == "Omega (rad/s)"
    assert response.plot("a_max:m").axes[0].get_ylabel() == "a_max:m (m/s^2)"
    with pytest.raises(InputError, match="settings applies to the article's cases"):
        oscillator.frequency_response(chain, "Omega", (1.45, 1.6), settings=oscillator.AttractorSettings())
    with pytest.raises(InputError, match="period-1"):
        oscillator.frequency_response(chain, "Omega", (1.45, 1.6), period=2)
    with pytest.raises(InputError, match="no measure named"):
        response.plot("x_pp_m2")
