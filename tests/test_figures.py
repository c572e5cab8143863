"""What can be checked of a figure without looking at it: markers, legends, units, windows."""

import re

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import PathCollection
from matplotlib.figure import Figure

from oscillator import SweepSettings, load_case, simulate
from oscillator.analysis.sweep_points import run_point
from oscillator.report.figures import KIND_STYLE, SAVED_DPI, draw_figures, figure_window, save_figure
from oscillator.report.sweep_figures import draw_sweep_figures

#: Runs that show, between them, every kind of event.
RUNS = {
    "instance-1": {},  # leaving rest (sliding vanishes)
    "instance-2": {},  # grazing
    "instance-3": {},  # left contact onset and release, passable
    "instance-5": {},  # right contact onset and release
    "instance-1 at Omega = 1.6 for 6 periods": {"t_end": 1.0 + 6 * 2 * 3.141592653589793 / 1.6},  # sliding onsets
}


@pytest.fixture(scope="module")
def figures():
    drawn = {}
    for label, changes in RUNS.items():
        result = simulate(label.split()[0], **changes)
        case = result.case
        start = (case.initial.t0, *case.initial.y)
        drawn[label] = draw_figures(result.trajectory, result.events, case.parameters, start, title=case.name)
    return drawn


def _legend_markers(figure) -> dict[str, str]:
    markers = {}
    for ax in figure.axes:
        legend = ax.get_legend()
        if legend is None:
            continue
        for text, handle in zip(legend.get_texts(), legend.legend_handles, strict=True):
            if hasattr(handle, "get_paths") and text.get_text().replace(" ", "_") in KIND_STYLE:
                markers[text.get_text()] = handle
    return markers


def test_every_kind_has_its_own_marker_the_same_in_every_figure(figures):
    kinds_seen: dict[str, set] = {}
    for by_name in figures.values():
        for figure in by_name.values():
            for ax in figure.axes:
                for collection in ax.collections:
                    label = collection.get_label().replace(" ", "_")
                    if label in KIND_STYLE:
                        path = collection.get_paths()[0]
                        kinds_seen.setdefault(label, set()).add(tuple(map(tuple, path.vertices.round(6))))
    assert set(kinds_seen) == set(KIND_STYLE), set(KIND_STYLE) - set(kinds_seen)
    assert all(len(shapes) == 1 for shapes in kinds_seen.values()), kinds_seen  # one marker per kind everywhere
    shapes = [next(iter(s)) for s in kinds_seen.values()]
    assert len(set(shapes)) == len(shapes)  # and no two kinds share one
    assert len({marker for marker, _, _ in KIND_STYLE.values()}) == len(KIND_STYLE)


def test_legends_hide_no_data(figures):
    for by_name in figures.values():
        for name, figure in by_name.items():
            renderer = FigureCanvasAgg(figure).get_renderer()
            figure.draw(renderer)
            boxes = [ax.get_window_extent(renderer) for ax in figure.axes]
            for ax in figure.axes:
                legend = ax.get_legend()
                if legend is None:
                    continue
                extent = legend.get_window_extent(renderer)
                for box in boxes:
                    assert not extent.overlaps(box), (name, ax.get_title())


UNIT = re.compile(r"\([^()]+\)$")


def test_every_axis_names_its_unit(figures):
    for by_name in figures.values():
        for name, figure in by_name.items():
            for ax in figure.axes:
                assert UNIT.search(ax.get_ylabel()), (name, ax.get_ylabel())
                assert UNIT.search(ax.get_xlabel()) or ax.get_xlabel() == "", (name, ax.get_xlabel())
            assert UNIT.search(figure.axes[-1].get_xlabel()), name  # axes sharing x label it once, below


def test_the_phase_portrait_names_each_side_of_its_velocity_boundary_on_that_side(figures):
    for by_name in figures.values():
        figure = by_name["fig-c-phase"]
        for ax in figure.axes:
            low, high = ax.get_ylim()
            assert low < 0 < high  # v = 0 and both sides of it are shown
            for text in ax.texts:
                _, y = text.get_position()  # axes coordinates
                value = low + y * (high - low)
                assert (value > 0) == ("> 0" in text.get_text()), text.get_text()


def test_a_long_run_is_drawn_over_its_last_periods_and_says_so():
    result = simulate("instance-1", t_end=1.0 + 60 * 2 * 3.141592653589793 / 1.6, t_eval=None)
    case = result.case
    figure = draw_figures(result.trajectory, result.events, case.parameters, (case.initial.t0, *case.initial.y),
                          title="long")["fig-b-velocity"]  # fmt: skip
    (ax,) = figure.axes
    assert "the last 10 of 60 forcing periods" in ax.get_title()
    left, right = ax.get_xlim()
    period = case.parameters.period
    assert left > case.t_end - 11 * period and right < case.t_end + period


def test_a_window_must_lie_in_the_run():
    assert figure_window(0.0, 10.0, 1.0, (2.0, 3.0)).label == "t in [2, 3] s"
    assert figure_window(0.0, 10.0, 1.0).label == ""  # 10 periods: the whole run
    for window in ((3.0, 2.0), (-1.0, 2.0), (2.0, 11.0)):
        with pytest.raises(ValueError, match="must be two times T0 < T1 within the run"):
            figure_window(0.0, 10.0, 1.0, window)


def test_the_sweep_diagrams_name_their_units():
    case = load_case("bifurcation-omega")
    settings = SweepSettings(param="Omega", start=1.59, stop=1.61, steps=3, transient=3, record=2)
    points = [run_point(case, settings, i, v) for i, v in enumerate(settings.values)]
    import pandas as pd

    tables = {name: pd.concat([p.table(name) for p in points], ignore_index=True)
              for name in ("switches", "poincare", "summary")}  # fmt: skip
    for name, figure in draw_sweep_figures(tables, "Omega", 2, title="scene").items():
        for ax in figure.axes:
            assert ax.get_xlabel() in ("Omega (rad/s)", ""), name
            assert UNIT.search(ax.get_ylabel()), (name, ax.get_ylabel())


def hidden_markers(figure) -> list[str]:
    """The markers no pixel of the image shows: for each scatter (the start's star, each kind of
    event), the image drawn without it is compared with the whole image within each of its
    markers' extent; a marker wholly covered by others changes nothing there."""
    canvas = FigureCanvasAgg(figure)
    canvas.draw()
    whole = np.asarray(canvas.buffer_rgba()).copy()
    height, width = whole.shape[:2]
    hidden = []
    for ax in figure.axes:
        box = ax.get_window_extent()
        for collection in ax.collections:
            if not isinstance(collection, PathCollection) or not len(collection.get_offsets()):
                continue
            points = collection.get_offset_transform().transform(collection.get_offsets())
            collection.set_visible(False)
            canvas.draw()
            without = np.asarray(canvas.buffer_rgba())
            collection.set_visible(True)
            changed = np.any(whole != without, axis=2)
            radius = max(1, int(np.sqrt(collection.get_sizes()[0]) / 2 * figure.dpi / 72))
            for x, y in points:
                if not box.contains(x, y):
                    continue  # outside the axes: clipped
                row, column = round(height - y), round(x)
                around = changed[max(row - radius, 0):min(row + radius + 1, height),
                                 max(column - radius, 0):min(column + radius + 1, width)]  # fmt: skip
                if not around.any():
                    hidden.append(f"{ax.get_title() or figure.get_suptitle()}: {collection.get_label()} at "
                                  f"{ax.transData.inverted().transform((x, y))}")  # fmt: skip
    return hidden


@pytest.mark.parametrize("label", ["instance-4", "instance-5", "instance-1 at Omega = 1.6 for 6 periods"])
def test_every_marker_shows_where_markers_coincide(label):
    """Instances 4 and 5 leave rest at their start (the diamond on the star); at Omega = 1.6 m2
    stops and leaves rest at one displacement (square and diamond on one point of panel c)."""
    result = simulate(label.split()[0], **RUNS.get(label, {}))
    case = result.case
    drawn = draw_figures(result.trajectory, result.events, case.parameters, (case.initial.t0, *case.initial.y),
                         title=case.name)  # fmt: skip
    for name in ("fig-a-displacement", "fig-c-phase"):
        assert hidden_markers(drawn[name]) == [], name


def test_a_marker_under_another_is_found():
    """The check above can fail: a small marker drawn under a large one is reported."""
    figure = Figure()
    ax = figure.subplots()
    ax.scatter([1.0], [1.0], s=30, marker="D", zorder=2, label="small")
    ax.scatter([1.0], [1.0], s=300, marker="s", zorder=3, label="large")
    ax.scatter([2.0], [2.0], s=30, marker="o", label="apart")
    assert [text.split(" at ")[0] for text in hidden_markers(figure)] == [": small"]


def test_sweep_markers_show_where_onset_and_vanish_coincide():
    """A resting mass starts and leaves its rest at one displacement: in the sweep diagram the
    onset's square and the vanish's diamond lie on one point, and both show."""
    case = load_case("bifurcation-omega")
    settings = SweepSettings(param="Omega", start=1.6, stop=1.605, steps=2, transient=3, record=2)
    points = [run_point(case, settings, i, v) for i, v in enumerate(settings.values)]
    import pandas as pd

    tables = {name: pd.concat([p.table(name) for p in points], ignore_index=True)
              for name in ("switches", "poincare", "summary")}  # fmt: skip
    assert {"sliding_onset", "sliding_vanish"} <= set(tables["switches"].kind)
    figure = draw_sweep_figures(tables, "Omega", 2, title="scene")["fig-14-bifurcation"]
    assert hidden_markers(figure) == []


def test_a_both_ways_sweep_draws_each_way_and_hides_neither(tmp_path):
    from oscillator.analysis.sweeps import read_sweep, run_sweep

    settings = SweepSettings(param="Q2", start=71.15, stop=71.18, steps=4, transient=20, record=2, both_ways=True)
    run_sweep(load_case("bifurcation-q2"), settings, tmp_path / "both", workers=1)
    drawn = draw_sweep_figures(read_sweep(tmp_path / "both"), "Q2", 2, title="scene")
    for name, figure in drawn.items():
        labels = {text.get_text() for ax in figure.axes if ax.get_legend() for text in ax.get_legend().get_texts()}
        assert {"m2 rests (sliding), going up", "m2 rests (sliding), going down"} <= labels, name
        assert any(label.endswith("going down") and "rests" not in label for label in labels), name
        assert hidden_markers(figure) == [], name


def test_a_figure_laid_out_once_is_saved_as_matplotlib_saves_it_and_left_as_it_was(tmp_path):
    """save_figure lays a figure out once for its two files and then draws it once for each (three
    draws, where matplotlib draws again before each file a figure with a layout engine): the PNG is
    matplotlib's own ``bbox_inches="tight"`` file pixel for pixel, the SVG the same size, and the
    figure keeps its layout engine and resolution."""
    import matplotlib.image
    from matplotlib.figure import Figure

    result = simulate("instance-3")
    case = result.case
    start = (case.initial.t0, *case.initial.y)

    def drawn():
        return draw_figures(result.trajectory, result.events, case.parameters, start, title=case.name)["fig-d-forces"]

    fig = drawn()
    engine, dpi = fig.get_layout_engine(), fig.get_dpi()
    draws = []
    draw = Figure.draw
    with pytest.MonkeyPatch.context() as patched:
        patched.setattr(Figure, "draw", lambda self, renderer: draws.append(renderer) or draw(self, renderer))
        save_figure(fig, tmp_path, "ours")
    assert len(draws) == 3
    assert fig.get_layout_engine() is engine and fig.get_dpi() == dpi
    reference = drawn()
    for suffix in ("png", "svg"):
        reference.savefig(tmp_path / f"theirs.{suffix}", format=suffix, dpi=SAVED_DPI, bbox_inches="tight")
    ours, theirs = (matplotlib.image.imread(tmp_path / f"{n}.png") for n in ("ours", "theirs"))
    assert ours.shape == theirs.shape and np.array_equal(ours, theirs)

    def size(name: str) -> tuple[float, float]:
        head = (tmp_path / f"{name}.svg").read_text(encoding="utf-8")[:2000]
        return tuple(float(re.search(rf'{key}="([\d.]+)pt"', head).group(1)) for key in ("width", "height"))

    assert size("ours") == pytest.approx(size("theirs"), rel=0.01)
