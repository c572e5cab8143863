"""A declared system's sweeps by simulation (issue 52): ``run_sweep(chain, ChainSweepSettings(...))``,
``oscillator sweep FILE`` and ``oscillator locate FILE`` on the oscillator with a stop, whose free
orbit has a closed form: it grazes the stop where its amplitude is the stop's distance, and
coexists with the impacting orbit between that grazing and the impacting branch's fold."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from scipy.optimize import brentq
from typer.testing import CliRunner

import oscillator
from oscillator import InputError
from oscillator.analysis.chain_sweeps import ChainSweepSettings
from oscillator.analysis.sweeps import read_sweep, run_sweep
from oscillator.cli.app import app
from test_chain_following import IMPACTS, free_amplitude

#: Where the free orbit grazes the stop coming down in Omega, and the impacting branch's fold
#: (tests/test_chain_curves.py locates both).
GRAZING, FOLD = 1.1757256, 1.4457716


@pytest.fixture(scope="module")
def chain() -> oscillator.FrictionChain:
    return oscillator.load_system(IMPACTS)


@pytest.fixture(scope="module")
def both_ways(chain, tmp_path_factory) -> dict[str, pd.DataFrame]:
    settings = ChainSweepSettings(param="Omega", start=1.0, stop=1.6, steps=13, transient=100, record=5, both_ways=True)
    folder = tmp_path_factory.mktemp("sweep")
    outcome = run_sweep(chain, settings, folder, workers=1)
    assert (outcome.points, outcome.failed) == (26, 0)
    return read_sweep(folder)


def test_the_two_ways_differ_exactly_where_both_orbits_exist(both_ways):
    summary = both_ways["summary"]
    closings = {way: dict(zip(rows.Omega.round(6), rows.closings_per_period, strict=True))
                for way, rows in summary.groupby("direction")}  # fmt: skip
    for omega in closings["up"]:
        both = GRAZING < omega < FOLD
        assert (closings["up"][omega], closings["down"][omega]) == (
            (1.0, 0.0) if both else (closings["up"][omega],) * 2
        )
    assert summary["closings:wall"].equals(summary.closings_per_period)  # the one stop's closings are all


def test_the_free_orbits_section_points_are_its_closed_form(both_ways, chain):
    """Where the stop stays open the section point is the forced response's at t = 0:
    ``Im(H Q)`` and ``Omega Re(H Q)`` with ``H = 1 / (k - m Omega^2 + i c Omega)``."""
    summary, poincare = both_ways["summary"], both_ways["poincare"]
    free = summary[summary.closings_per_period == 0]
    free = free[(free.Omega - FOLD).abs() > 0.01]  # just past the fold the jump lingers near its ghost
    assert len(free) >= 10 and free.period.eq(1).all()
    points = poincare[poincare["index"].isin(free["index"])]
    response = 0.2 / (1.0 - points.Omega**2 + 0.1j * points.Omega)
    np.testing.assert_allclose(points["x:m"], response.map(np.imag), atol=1e-7)
    np.testing.assert_allclose(points["v:m"], points.Omega * response.map(np.real), atol=1e-7)
    assert (free_amplitude(chain, free.Omega.to_numpy()) < 0.5).all()


def test_each_impact_is_an_event_of_the_switches_table_once_a_period(both_ways, chain):
    switches, summary = both_ways["switches"], both_ways["summary"]
    impacting = summary[(summary.closings_per_period == 1) & (summary.period == 1)]
    for index in impacting["index"].tolist()[:3]:
        mine = switches[switches["index"] == index]
        closes = mine[mine.kind == "stop_closes"]
        assert len(closes) == 5 and (closes.element == "wall").all() and (closes.G0 > 0).all()  # moving in
        assert np.ptp(closes.phase) < 1e-7  # the same phase each period
        assert np.allclose(np.diff(closes.t), 2 * np.pi / closes.Omega.iloc[0], atol=1e-7)


def test_a_sweeps_values_are_refused_by_the_systems_own_checks(chain, tmp_path):
    with pytest.raises(InputError, match="no number of the system"):
        run_sweep(chain, ChainSweepSettings(param="wall.gap", start=0.1, stop=0.2, steps=2), tmp_path / "a")
    with pytest.raises(InputError, match="stop = -1"):
        run_sweep(chain, ChainSweepSettings(param="m.m", start=1.0, stop=-1.0, steps=2), tmp_path / "b")
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()


def test_the_sweep_and_locate_commands_take_a_system_file(tmp_path, monkeypatch, both_ways):
    monkeypatch.chdir(tmp_path)
    runner = CliRunner()
    arguments = ["sweep", str(IMPACTS), "--param", "Omega", "--from", "1.0", "--to", "1.6", "--steps", "13"]
    arguments += ["--record", "5", "--both-ways", "--out", "s"]
    done = runner.invoke(app, arguments)
    assert done.exit_code == 0, done.stderr
    said = " ".join(done.stdout.split() + done.stderr.split())
    assert "hysteresis: at Omega = 1.2, 1.25, 1.3, 1.35, 1.4 the two ways end on different motions" in said
    written = read_sweep(tmp_path / "s")
    pd.testing.assert_frame_equal(written["poincare"], both_ways["poincare"])
    assert (tmp_path / "s" / "figures" / "sweep.png").is_file()
    again = runner.invoke(app, arguments)
    assert again.exit_code == 0 and "0 computed, 26 resumed" in " ".join(again.stdout.split())
    for refused, field in ((["--from", "1"], "--param"), (["--param", "Omega", "--from", "1", "--to", "2",
                           "--set", "Omega=1"], "--set")):  # fmt: skip
        done = runner.invoke(app, ["sweep", str(IMPACTS), *refused, "--out", "r"])
        assert done.exit_code == 2 and field in done.stderr and not (tmp_path / "r").exists()
    located = runner.invoke(app, ["locate", str(IMPACTS), "--param", "Omega", "--between", "0.75", "0.8", "--what",
                                  "grazing"])  # fmt: skip
    assert located.exit_code == 0, located.stderr
    value = float(located.stdout.split("changes at Omega = ")[1].split()[0])
    exact = brentq(lambda omega: free_amplitude(oscillator.load_system(IMPACTS), omega) - 0.5, 0.75, 0.8, xtol=1e-15)
    assert abs(value - exact) < 1e-8
