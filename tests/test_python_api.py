"""Working from Python: a run, an orbit and a branch plot themselves, save themselves as the
commands' folders, and come back from those folders with :func:`oscillator.read_run`."""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

import oscillator as osc
from oscillator.orbits.branch import Branch
from oscillator.report.figures import rest_spans

PERIOD = 2 * np.pi / 1.6  # instance-1's forcing period


@pytest.fixture(scope="module")
def modified():
    return osc.simulate("instance-1", Omega=1.7, t_end=4.0)


def test_each_panel_is_a_figure_titled_with_what_was_changed(modified):
    for panel, words in (("a", "(a) displacements"), ("velocity", "(b) velocities"), ("c", "(c) phase portraits"),
                         ("d", "(d) G-function")):  # fmt: skip
        figure = modified.plot(panel)
        assert isinstance(figure, Figure)
        title = figure.get_suptitle() or figure.axes[0].get_title()
        assert title.startswith("instance-1 (Omega 1.6 → 1.7) — ") and words in title, title
    with pytest.raises(osc.InputError, match="panel must be one of a, displacement"):
        modified.plot("e")
    with pytest.raises(osc.InputError, match="no trajectory"):
        osc.simulate("instance-1", record_trajectory=False).plot()


def test_rests_are_shaded_from_the_events_on_a_coarse_grid():
    """m2's rests last about 0.011 s; sampled every 0.05 s, most fall between two samples.  Each
    is shaded all the same, from its onset to its end."""
    result = osc.simulate("instance-1", t_end=100.0, t_eval=np.arange(1.0, 100.0, 0.05))
    events = result.events
    inside = events[(events.mass == 2) & (events.t >= 80.0) & (events.t <= 100.0)]
    onsets = inside[inside.kind == "sliding_onset"].t.to_numpy()
    vanishes = inside[inside.kind == "sliding_vanish"].t.to_numpy()
    assert len(onsets) >= 8 and len(onsets) == len(vanishes) and np.all(vanishes - onsets < 0.05)
    (ax,) = result.plot("b", window=(80.0, 100.0)).axes
    shaded = sorted((patch.get_x(), patch.get_x() + patch.get_width()) for patch in ax.patches
                    if patch.get_facecolor()[:3] == (0.0, 0.0, 0.0))  # m2's colour (black)  # fmt: skip
    np.testing.assert_allclose(np.array(shaded), np.column_stack([onsets, vanishes]), atol=1e-9)


def test_rest_spans_begin_at_a_rest_at_the_first_row_and_close_at_the_last():
    trajectory = pd.DataFrame({"t": [0.0, 1.0, 2.0], "domain1": [0, 1, 1], "domain2": [1, 1, 1]})
    events = pd.DataFrame({"t": [0.5, 1.5], "mass": [1, 1], "from_domain": [0, 1], "to_domain": [1, 0]})
    assert rest_spans(trajectory, events, 1) == [(0.0, 0.5), (1.5, 2.0)]
    assert rest_spans(trajectory, events, 2) == []


def test_a_stop_far_from_the_motion_is_named_not_drawn_to_scale():
    """With d = 1000 the left stop is a kilometre away: the displacement axis keeps the motion's
    scale (about ±5 m) and the stop's legend entry says where it is."""
    result = osc.simulate("instance-1", d=1000.0, t_end=12.0)
    (ax,) = result.plot("a").axes
    low, high = ax.get_ylim()
    assert -6.0 < low < -4.0 and 4.0 < high < 6.0
    labels = [text.get_text() for text in ax.get_legend().get_texts()]
    assert any("left stop" in label and "off the scale ↓ at -995" in label for label in labels), labels
    assert not any("right stop" in label and "off the scale" in label for label in labels)  # d1 = 4.5 is near


def test_a_mass_that_never_moves_is_marked_in_its_phase_portrait():
    result = osc.simulate("instance-1", t_end=3.0, Q1=0.0, Q2=0.0, P1=0.0, P2=0.0, x1=0.0, x2=0.0, v1=0.0, v2=0.0)
    figure = result.plot("c")
    assert figure.get_suptitle().startswith("instance-1 (6 values changed: Q1, Q2, P1, P2, x1, x2)")
    for ax, mass in zip(figure.axes, (1, 2), strict=True):
        assert any(f"m{mass} does not move" in text.get_text() for text in ax.texts)
        assert ax.get_ylim() == (-1.0, 1.0)


def test_a_saved_run_reads_back_as_the_same_result(tmp_path, modified):
    folder = modified.save(tmp_path / "run")
    assert {"events.csv", "events.parquet", "trajectory.parquet", "case.toml", "run.json", "report.md"} <= {
        p.name for p in folder.iterdir()}  # fmt: skip
    again = osc.read_run(folder)
    assert isinstance(again, osc.Result)
    pd.testing.assert_frame_equal(again.events, modified.events)
    pd.testing.assert_frame_equal(again.trajectory, modified.trajectory)
    assert again.energy == modified.energy and again.stats == modified.stats
    assert again.final_state == modified.final_state and again.status == modified.status
    assert again.case.parameters == modified.case.parameters and again.case.modified == modified.case.modified
    with pytest.raises(osc.OscillatorError, match="exists already"):
        modified.save(folder)
    with pytest.raises(osc.InputError, match="formats must be one of"):
        modified.save(tmp_path / "other", formats="xlsx")
    assert not (tmp_path / "other").exists()


def test_a_saved_orbit_reads_back_as_the_same_orbit(tmp_path):
    orbit = osc.find_orbit("instance-1", Q2=71.0)
    folder = orbit.save(tmp_path / "orbit")
    again = osc.read_run(folder)
    assert isinstance(again, osc.Orbit)
    np.testing.assert_array_equal(again.state, orbit.state)
    np.testing.assert_array_equal(again.multipliers, orbit.multipliers)
    np.testing.assert_array_equal(again.monodromy, orbit.monodromy)
    assert (again.verdict, again.period, again.section, again.signature) == (orbit.verdict, orbit.period,
                                                                            orbit.section, orbit.signature)  # fmt: skip
    # one return of the orbit closes: the run saved with it ends where it started
    run = pd.read_parquet(folder / "trajectory.parquet")
    np.testing.assert_allclose(run[["x1", "v1", "x2", "v2"]].iloc[-1], orbit.state, atol=1e-6)
    assert isinstance(orbit.plot(), Figure)


def test_a_branch_keeps_its_complex_multipliers_and_reads_back(tmp_path):
    branch = osc.continue_orbit("instance-1", param="Q2", start=71.0, stop=70.9, max_points=6)
    assert branch.points.mu1.dtype == complex
    at = branch.points.iloc[-1]
    orbit = osc.find_orbit("instance-1", Q2=float(at.Q2), guess=tuple(at[["x1", "v1", "x2", "v2"]]))
    np.testing.assert_allclose(at[["mu1", "mu2", "mu3", "mu4"]].to_numpy(complex), orbit.multipliers, atol=1e-6)
    # a period doubling's -1 and a torus's complex pair survive the folder
    points = branch.points.copy()
    points.loc[0, ["mu1", "mu2", "mu3", "mu4"]] = [-0.98 + 0j, 0.5 + 0.7j, 0.5 - 0.7j, 0j]
    edited = dataclasses.replace(branch, points=points)
    again = osc.read_run(edited.save(tmp_path / "branch"))
    assert isinstance(again, Branch) and again.case is not None and again.case.name == "instance-1"
    pd.testing.assert_frame_equal(again.points, edited.points)
    pd.testing.assert_frame_equal(again.bifurcations, edited.bifurcations)
    assert isinstance(branch.plot(), Figure) and isinstance(branch.plot_multipliers(), Figure)
    with pytest.raises(osc.InputError, match="coordinate must be one of"):
        branch.plot("x3")


def test_a_parked_mass_is_not_the_coordinate_a_branch_is_drawn_in():
    points = pd.DataFrame({"Q2": [1.0, 2.0], "x1": [0.1, 0.2], "v1": [0.0, 0.1], "x2": [3.0, 3.0], "v2": [0.0, 0.0]})
    parked = Branch("Q2", points, pd.DataFrame(), 1.0, 1)
    assert parked.coordinate == "x1"
    moving = Branch("Q2", points.assign(x2=[3.0, 3.5]), pd.DataFrame(), 1.0, 1)
    assert moving.coordinate == "x2"


def test_read_run_names_what_is_not_a_folder_of_ours(tmp_path):
    with pytest.raises(osc.InputError, match="not a run folder"):
        osc.read_run(tmp_path)


def test_rich_displays_escape_the_case_text(tmp_path):
    case = dataclasses.replace(osc.load_case("instance-1"), name="<b>x</b>", title="<script>alert(1)</script>")
    result = osc.simulate(case, t_end=1.5)
    shown = result._repr_html_()
    assert "<script>" not in shown and "&lt;script&gt;alert(1)&lt;/script&gt;" in shown and "&lt;b&gt;x" in shown
    assert "energy audit residual" in shown and "<table>" in shown and "complete" in shown
    orbit_shown = osc.find_orbit(case)._repr_html_()
    assert "<script>" not in orbit_shown and "multiplier" in orbit_shown


def test_a_save_whose_figures_fail_keeps_the_tables_and_warns(tmp_path, modified, monkeypatch):
    def broken(*args, **kwargs):
        raise RuntimeError("no display")

    monkeypatch.setattr("oscillator.report.figures.write_figures", broken)
    with pytest.warns(UserWarning, match=r"could not be made \(RuntimeError: no display\); the tables are written"):
        folder = modified.save(tmp_path / "run")
    assert not (folder / "figures").exists()
    pd.testing.assert_frame_equal(osc.read_run(folder).events, modified.events)


@pytest.fixture(scope="module")
def saved_orbit(tmp_path_factory):
    return osc.find_orbit("instance-1").save(tmp_path_factory.mktemp("orbits") / "orbit")


@pytest.mark.parametrize(
    ("key", "value", "fragment"),
    [("resting", 5, "orbit.resting must be a list"), ("discontinuous", "v2", "orbit.discontinuous must be a list"),
     ("history", {"a": 1}, "orbit.history must be a list"), ("multipliers", [[1, 0]], "orbit.multipliers must be"),
     ("period", True, "orbit.period is not a whole number"), ("stable", "yes", "orbit.stable true or false")],
)  # fmt: skip
def test_a_damaged_orbit_folder_names_the_field(tmp_path, saved_orbit, key, value, fragment):
    import json
    import shutil

    folder = shutil.copytree(saved_orbit, tmp_path / "orbit")
    info = json.loads((folder / "run.json").read_text())
    info["orbit"][key] = value
    (folder / "run.json").write_text(json.dumps(info))
    with pytest.raises(osc.InputError, match=fragment):
        osc.read_run(folder)
