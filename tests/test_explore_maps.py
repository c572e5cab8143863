"""The explorer opened on a sweep's or a frequency response's folder (issue 40): its picture is
the folder's own points; a click shows what the folder holds there and what `find_attractors`
finds there, and draws the motion from it."""

from __future__ import annotations

import json
import shutil
from types import SimpleNamespace
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

import oscillator as osc
from oscillator.analysis.axes import STATE
from oscillator.analysis.sweeps import read_sweep
from oscillator.cli.app import app
from oscillator.errors import InputError
from oscillator.exploring.maps import picture_of

if TYPE_CHECKING:
    from oscillator.exploring.app import Explorer


@pytest.fixture(scope="module")
def sweep_folder(tmp_path_factory):
    folder = tmp_path_factory.mktemp("sweep") / "sweep"
    command = ["sweep", "instance-1", "--param", "Omega", "--from", "1.55", "--to", "1.65", "--steps", "5"]
    command += ["--transient", "20", "--record", "10", "--both-ways", "--out", str(folder), "--no-plots", "--quiet"]
    assert CliRunner().invoke(app, command).exit_code == 0
    return folder


def _click(picture, x: float, y: float, periods: int = 10) -> Explorer:
    from oscillator.exploring.app import Explorer  # Panel and Bokeh: imported where a test needs them

    explorer = Explorer(picture.case, periods, picture=picture)
    explorer._tap(SimpleNamespace(x=x, y=y))  # what Bokeh's Tap event carries: the data coordinates
    return explorer


def _near(points: np.ndarray, state: np.ndarray, tolerance: float) -> bool:
    return bool(np.min(np.max(np.abs(points - state), axis=1)) < tolerance)


def test_a_sweeps_picture_is_its_bifurcation_diagram_and_a_click_finds_the_attractor_it_recorded(sweep_folder):
    """A sweep up and down (each value run twice): every Poincaré point drawn with the period
    recorded at its run; a click shows the run it belongs to and finds the attractor recorded."""
    tables = read_sweep(sweep_folder)
    poincare, summary = tables["poincare"], tables["summary"]
    assert list(summary.direction) == ["up"] * 5 + ["down"] * 5
    picture = picture_of(sweep_folder)
    assert (picture.kind, picture.x, picture.y, picture.cells) == ("sweep", "Omega", "x2", False)
    np.testing.assert_array_equal(picture.points.x, poincare.Omega)
    np.testing.assert_array_equal(picture.points.y, poincare.x2)
    period = dict(zip(summary["index"], summary.period, strict=True))
    assert list(picture.points.label) == [f"period-{period[k]}" for k in poincare["index"]]

    last = poincare[poincare["index"] == 7].iloc[-1]  # a point of the sweep down, at its third value
    explorer = _click(picture, float(last.Omega), float(last.x2))
    run = summary.iloc[int(picture.points.at[picture.nearest(last.Omega, last.x2), "at"])]
    assert run.Omega == last.Omega and explorer.values()["Omega"] == last.Omega
    recorded = poincare[poincare["index"] == run["index"]]
    case = osc.resolve_case(picture.case, Omega=float(run.Omega))
    end = run[[f"end_{name}" for name in STATE]].to_numpy(float)
    found = osc.find_attractors(case, states=[case.initial.y, end])
    assert found.attractors
    for attractor in found.attractors:  # each attractor met is the one the sweep recorded there
        assert attractor.period == run.period
        for point in attractor.points:
            assert _near(recorded[list(STATE)].to_numpy(float), point, 1e-6), point
        assert attractor.name in explorer.picked.object
    start = [explorer.values()[name] for name in STATE]
    assert start == pytest.approx(found.attractors[0].points[0], abs=1e-9)
    assert f"the sweep {run.direction} recorded period-{run.period}, ending at (" in explorer.picked.object


def test_a_frequency_responses_picture_is_its_branch_points_and_a_click_draws_the_orbit_held(small_frc):
    points = pd.read_parquet(small_frc / "points.parquet")
    picture = picture_of(small_frc)
    assert (picture.kind, picture.x, picture.y) == ("frc", "Omega", "x_pp")
    assert len(picture.points) == 2 * len(points)
    for mass in (1, 2):
        drawn = picture.points.iloc[(mass - 1) * len(points) : mass * len(points)]
        np.testing.assert_array_equal(drawn.y, points[f"x_pp_m{mass}"])
        assert list(drawn.label) == [f"m{mass} {'stable' if s else 'unstable'}" for s in points.stable]

    stable = points[points.stable]
    row = stable.iloc[len(stable) // 2]
    explorer = _click(picture, float(row.Omega), float(row.x_pp_m2), periods=8)
    held = row[list(STATE)].to_numpy(float)
    assert explorer.values()["Omega"] == row.Omega
    assert [explorer.values()[name] for name in STATE] == list(held)  # the orbit clicked, on the sliders
    assert f"branch {row.branch}: a stable period-{row.period} orbit through (" in explorer.picked.object
    strobe = explorer.scene.strobe[list(STATE)].to_numpy(float)
    assert len(strobe) >= 8
    np.testing.assert_allclose(strobe, np.tile(held, (len(strobe), 1)), atol=1e-6)  # it returns each period
    case = osc.resolve_case(picture.case, Omega=float(row.Omega))
    found = osc.find_attractors(case, states=[case.initial.y, held])
    assert any(_near(a.points, held, 1e-5) for a in found.attractors)  # a stable orbit is an attractor found
    assert f"{len(found.attractors)} attractor(s)" in explorer.picked.object


def test_a_damaged_sweep_or_frequency_response_folder_is_refused_naming_the_file(tmp_path, sweep_folder, small_frc):
    sweep = tmp_path / "sweep"
    shutil.copytree(sweep_folder, sweep)
    (sweep / "summary.parquet").unlink()
    with pytest.raises(InputError, match=r"not a complete sweep folder: summary\.parquet is missing"):
        picture_of(sweep)
    (sweep / "summary.parquet").write_bytes(b"not parquet")
    with pytest.raises(InputError, match=r"summary\.parquet is damaged: it cannot be read as a table"):
        picture_of(sweep)

    frc = tmp_path / "frc"
    shutil.copytree(small_frc, frc)
    marker = json.loads((frc / "frc.json").read_text())
    marker["identity"]["param"] = "Omegaa"
    (frc / "frc.json").write_text(json.dumps(marker))
    with pytest.raises(InputError, match=r"frc\.json is damaged: its parameter 'Omegaa' is not a parameter"):
        picture_of(frc)
    result = CliRunner().invoke(app, ["explore", str(frc), "--port", "0"])
    assert result.exit_code == 2
    assert "did you mean 'Omega'" in result.stderr and "Traceback" not in result.stderr


# The Duffing fixture (docs/frequency.md's example, 20 s) is the slow tier's, as tests/test_frequency.py
# is, until its frequency response runs on the compiled path (issue 53).
@pytest.mark.slow
def test_a_click_on_an_unstable_branch_point_finds_the_attractors_on_either_side_of_it(tmp_path, duffing):
    """The Duffing oscillator between its folds: a click on the unstable orbit draws the motion
    from it, and find_attractors, started on either side of it, finds the two stable orbits that
    coexist there (those of the branch's stable stretches at that value), not the saddle: started
    on it, it found one attractor only at 1.1232 and a landing on the saddle without an orbit at
    1.1069."""
    from oscillator.attractors.frequency import frequency_store
    from oscillator.report.frequency import write_frequency

    folder = tmp_path / "frc"
    frequency_store(folder, duffing.case, "Omega", (0.8, 1.6)).open()
    write_frequency(duffing, folder, plots=False)  # the folder as `oscillator frc` leaves it
    picture = picture_of(folder)
    points = duffing.points
    unstable, stable = points[~points.stable], points[points.stable]
    row = unstable.iloc[len(unstable) // 2]
    explorer = _click(picture, float(row.Omega), float(row.x_pp_m1), periods=4)
    assert explorer.values()["Omega"] == row.Omega
    assert [explorer.values()[name] for name in STATE] == list(row[list(STATE)])
    text = explorer.picked.object
    assert "an unstable period-1 orbit" in text and "starts on either side of it" in text
    assert "2 attractor(s)" in text, text
    for k in np.linspace(0, len(unstable) - 1, 9).astype(int)[1:-1]:  # inside the folds (|mu| 1.1 to 1.25)
        row = unstable.iloc[k]
        found = picture.attractors(picture.site(picture.nearest(float(row.Omega), float(row.x_pp_m1))))
        assert all(a.orbit is not None and max(abs(m) for m in a.orbit.multipliers) < 1 for a in found.attractors)
        expected = []
        for stretch in (stable[stable.x_pp_m1 < row.x_pp_m1], stable[stable.x_pp_m1 > row.x_pp_m1]):
            stretch = stretch.sort_values("Omega")  # the branch's small and large stable stretches
            expected.append(np.interp(row.Omega, stretch.Omega, stretch.x_pp_m1))
        amplitudes = sorted(a.measures["x_pp_m1"] for a in found.attractors)
        assert amplitudes == pytest.approx(expected, rel=1e-3), row.Omega  # the small and the large motion


def test_points_that_are_not_numbers_are_not_picked_and_a_folder_without_any_is_refused(
    tmp_path, sweep_folder, small_frc
):
    frc = tmp_path / "frc"
    shutil.copytree(small_frc, frc)
    points = pd.read_parquet(frc / "points.parquet")
    points.loc[points.index[:-1], ["x_pp_m1", "x_pp_m2"]] = np.nan  # one branch point left measured
    points.to_parquet(frc / "points.parquet", index=False)
    picture = picture_of(frc)
    kept = points.index[-1]
    for x, y in ((points.Omega.iloc[0], 0.0), (1.6, 1e3)):
        assert picture.points.at[picture.nearest(x, y), "at"] == kept

    sweep = tmp_path / "sweep"
    shutil.copytree(sweep_folder, sweep)
    poincare = pd.read_parquet(sweep / "poincare.parquet")
    poincare.iloc[:0].to_parquet(sweep / "poincare.parquet", index=False)  # every value failed: no point
    with pytest.raises(InputError, match=r"holds no point to show \(its sweep has no finite value\)"):
        picture_of(sweep)


def test_a_click_on_a_map_of_cells_is_outlined_and_one_outside_them_picks_nothing(tmp_path):
    """Basins of a 3 x 3 slice: a click on a cell outlines that cell (the picture's picked source)
    and says the attractors there; a click outside the cells (it picked the nearest cell, which
    the map did not show) is said and picks nothing."""
    from oscillator.cli.app import main

    folder = tmp_path / "basins"
    command = ["basins", "instance-1", "--x", "x1", "2", "4", "3", "--y", "v1", "-1", "1", "3", "--transient", "20"]
    with pytest.raises(SystemExit) as done:
        main([*command, "--record", "4", "--workers", "1", "--no-plots", "-q", "--out", str(folder)])
    assert done.value.code == 0
    picture = picture_of(folder)
    assert picture.cells and picture.frame == pytest.approx((1.5, 4.5, -1.5, 1.5))
    explorer = _click(picture, 3.1, 0.2)
    assert explorer._picked_source.data == {"x": [3.0], "y": [0.0]}
    assert explorer.clicks == 1 and "x1 = 3, v1 = 0" in explorer.picked.object
    explorer._tap(SimpleNamespace(x=5.0, y=0.0))
    assert "click inside the map" in explorer.picked.object and explorer.clicks == 1
    assert explorer._picked_source.data == {"x": [3.0], "y": [0.0]}
