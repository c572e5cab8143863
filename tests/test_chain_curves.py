"""A declared system's bifurcation curves (issue 52): ``trace_curve`` and ``oscillator curve FILE``
on the oscillator with a stop, whose free orbit grazes the stop exactly where its closed-form
amplitude equals the stop's distance, and the branch's changes located between two of its points
(:func:`~oscillator.orbits.chain_branch.locate_change`)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq
from typer.testing import CliRunner

import oscillator
from oscillator import InputError
from oscillator.cli.app import app
from oscillator.orbits.branch import Bifurcation
from oscillator.orbits.chain_branch import continue_chain_orbit, locate_change
from oscillator.orbits.chain_orbits import find_chain_orbit
from oscillator.orbits.chain_tangents import tangent_pass
from oscillator.orbits.curves import trace_curve
from test_chain_following import IMPACTS, free_amplitude


@pytest.fixture(scope="module")
def chain() -> oscillator.FrictionChain:
    return oscillator.load_system(IMPACTS).with_values({"m.x": 0.0})  # starts that settle on the free orbit


def test_the_grazing_and_the_fold_are_located_exactly_between_two_points(chain):
    """From the free orbit at 1.18 down: it grazes the stop where its amplitude is the stop's
    distance (closed form), strikes it, and the striking branch turns at a fold, where the
    monodromy has a multiplier 1."""
    response = 0.2 / (1.0 - 1.18**2 + 0.1j * 1.18)  # the free orbit Im(H Q e^{i Omega t}) at t = 0
    free = [response.imag, 1.18 * response.real]
    branch = continue_chain_orbit(chain, param="Omega", start=1.18, stop=1.17, guess=free, step=0.2, measures=False)
    signatures = branch.points.signature.tolist()
    assert signatures[0] == "no switches" and "wall stop_closes x1, wall stop_opens x1" in signatures
    k = next(i for i in range(len(signatures) - 1) if signatures[i] != signatures[i + 1])
    grazing, state = locate_change(branch, k, Bifurcation.GRAZING, 1e-11)
    exact = brentq(lambda omega: free_amplitude(chain, omega) - 0.5, 1.1, 1.3, xtol=1e-15)
    assert grazing == pytest.approx(exact, abs=1e-9)
    x, v = state  # on the free orbit of amplitude 0.5
    assert (x / 0.5) ** 2 + (v / (0.5 * grazing)) ** 2 == pytest.approx(1.0, abs=1e-6)
    (fold,) = branch.folds.itertuples(index=False)
    at_fold, y = locate_change(branch, int(fold.point), Bifurcation.FOLD, 1e-11)
    assert abs(at_fold - fold.Omega) < 1e-5 < exact - at_fold  # the fold lies below the grazing
    orbit = find_chain_orbit(chain.with_values({"Omega": at_fold}), y, transient=0)
    monodromy = tangent_pass(orbit.run, ["Omega"]).monodromy
    assert np.min(np.abs(np.linalg.eigvals(monodromy) - 1.0)) < 1e-4


def test_what_a_systems_curve_cannot_take_is_refused(chain):
    window = ((0.58, 0.62), (0.25, 0.4))
    cases = [
        ({"kind": "sliding"}, "kind"),
        ({"period": 2}, "period"),
        ({"y": "wall.gap"}, "wall.gap"),
        ({"Q2": 70.0}, "Q2"),
    ]
    for given, field in cases:
        options = {"kind": "grazing", "x": "Omega", "y": "wall.at", "at": (0.6, 0.31), "window": window} | given
        with pytest.raises(InputError) as error:
            trace_curve(chain, **options)
        assert field in (error.value.field or "") or field in str(error.value)


@pytest.mark.slow
def test_a_systems_grazing_curve_is_the_closed_form(tmp_path, monkeypatch):
    """``oscillator curve FILE``: the free orbit's grazing curve in (Omega, wall.at) is the stop at
    the free orbit's amplitude, to the location's 1e-8 at every point, labelled with units, and
    read back as written."""
    from oscillator.report.plane import read_curve

    monkeypatch.chdir(tmp_path)
    arguments = ["curve", str(IMPACTS), "--kind", "grazing", "--at", "Omega=0.6,wall.at=0.31", "--x", "Omega", "0.59"]
    arguments += ["0.61", "--y", "wall.at", "0.25", "0.4", "--step", "0.25", "--set", "m.x=0", "--out", "c"]
    done = CliRunner().invoke(app, arguments)
    assert done.exit_code == 0, done.stderr
    found = read_curve(tmp_path / "c")
    chain = oscillator.load_system(IMPACTS)
    gaps = found.points["wall.at"].to_numpy()
    assert len(gaps) >= 5 and found.inside == "no switches"
    assert np.abs(gaps - free_amplitude(chain, found.points.Omega.to_numpy())).max() < 1e-8
    assert all(end.startswith("left the window") for end in found.ends)
    assert found.labels == ("Omega (rad/s)", "wall.at (m)") and (tmp_path / "c" / "figures" / "curve.png").is_file()
    assert "cycle of switches is: no switches" in (tmp_path / "c" / "report.md").read_text()
