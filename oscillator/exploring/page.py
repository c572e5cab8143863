"""The explorer's figures, table and map, as Bokeh models: built once, then fed new data.

Every text from a case file reaches the page as text (:func:`plain` into a ``Div``'s markup, or
a figure's title drawn on a canvas).  The figures keep a stretch of the motion in view (the last
:data:`SHOWN_PERIODS` forcing periods: the rests and contacts stay visible) under an overview of
the whole run whose box moves it; every figure saves itself as PNG (Bokeh's save tool).
"""

from __future__ import annotations

import html
import math
from typing import Any

import numpy as np
from bokeh.models import ColumnDataSource, CustomJS, DataRange1d, Range1d, RangeTool
from bokeh.models.annotations import BoxAnnotation
from bokeh.models.widgets.tables import DataTable, NumberFormatter, StringFormatter, TableColumn
from bokeh.palettes import Category10
from bokeh.plotting import figure
from bokeh.transform import factor_cmap

from oscillator.exploring.maps import WHAT, Picture
from oscillator.exploring.scene import ARTICLE, Outline, Scene

__all__ = ["COLOURS", "CONTACT", "SHOWN_PERIODS", "Figures", "event_table", "map_figure", "plain", "url_keeper"]

#: The masses' colours in order, the first two as the report's figures draw the article's masses.
COLOURS = ("#1f77b4", "#d62728", "#8c564b", "#e377c2", "#bcbd22", "#17becf", "#ff7f0e", "#7f7f7f")
#: The contacts' shading in order: the article's between the masses (left) and on the right stop.
CONTACT = ("#2ca02c", "#9467bd", "#17becf", "#bcbd22", "#8c564b", "#e377c2")
#: The forcing periods the time series show at first (the overview's box moves them).
SHOWN_PERIODS = 10
#: The overview draws about this many points of each mass's path.
OVERVIEW_POINTS = 800
_SHADE = 0.15
_FAR = 1e9
_TOOLS = "pan,xwheel_zoom,box_zoom,reset,save"


def plain(text: str) -> str:
    """Untrusted text as HTML text."""
    return html.escape(text, quote=True)


def _quads() -> ColumnDataSource:
    return ColumnDataSource({"left": [], "right": [], "bottom": [], "top": []})


def _keyed(fig: Any, glyph: str, label: str, *fields: str, source: ColumnDataSource, **style: Any) -> Any:
    """``fig.<glyph>(*fields, source=source, **style)``, keyed in the legend by the same glyph
    drawn from a point that is not a number (nothing on the plot; the figure's ranges follow the
    drawn renderers only): a legend whose items hold the drawn renderers builds its entries again
    at every change of their data (10 ms a change for the page's four legends, measured), one of
    renderers that never change draws them once."""
    draw = getattr(fig, glyph)
    nowhere = ColumnDataSource({name: [math.nan] for name in fields or ("left", "right", "bottom", "top")})
    draw(*fields, source=nowhere, legend_label=label, **style)
    return draw(*fields, source=source, **style)


def spans(intervals: list[tuple[float, float]]) -> dict[str, list[float]]:
    """Quads spanning the figure's height over each interval."""
    return {
        "left": [a for a, _ in intervals],
        "right": [b for _, b in intervals],
        "bottom": [-_FAR] * len(intervals),
        "top": [_FAR] * len(intervals),
    }


class Figures:
    """The motion's figures and their data: an overview of the whole run (its box sets what the
    time series show), the displacements and velocities with rests and contacts shaded, and each
    mass's phase portrait with its stroboscopic points and the orbit asked for.  What they draw
    comes from ``outline`` (the system's masses and contacts); the sources name the ``i``-th
    mass's columns ``x<i>``, ``v<i>`` (the article's own names), the shading ``rest<i>`` and
    ``contact<j>``."""

    def __init__(self, outline: Outline = ARTICLE, *, orbits: bool = True) -> None:
        self.outline, self.orbits = outline, orbits
        self.keys = tuple(str(i + 1) for i in range(len(outline.masses)))
        state = [f"{q}{i}" for i in self.keys for q in ("x", "v")]
        self.sources = {
            "line": ColumnDataSource({name: [] for name in ("t", *state)}),
            "overview": ColumnDataSource({name: [] for name in ("t", *(f"x{i}" for i in self.keys))}),
            "strobe": ColumnDataSource({name: [] for name in ("k", *state)}),
            "events": ColumnDataSource({name: [] for name in (*outline.event_columns, "x")}),
            "orbit": ColumnDataSource({name: [] for name in state}),
            **{f"rest{i}": _quads() for i in self.keys},
            **{f"contact{j + 1}": _quads() for j in range(len(outline.contacts))},
        }
        self.shown = Range1d(start=0.0, end=1.0)  # the time series' window
        self.series = {key: self._series(key, label, title) for key, label, title in _SERIES}
        self.overview = self._overview()
        self.phase = {i: self._phase(i) for i in self.keys}

    def colour(self, i: str) -> str:
        """The ``i``-th mass's colour (counted from 1)."""
        return COLOURS[(int(i) - 1) % len(COLOURS)]

    def state(self, frame: Any) -> dict[str, Any]:
        """``frame``'s positions and velocities under the sources' names (``x1``, ``v1``, ...)."""
        return {
            f"{q}{i}": frame[column].to_numpy()
            for i, (_, _, x, v) in zip(self.keys, self.outline.masses, strict=True)
            for q, column in (("x", x), ("v", v))
        }

    def _series(self, key: str, label: str, title: str) -> Any:
        line, outline = self.sources["line"], self.outline
        fig = figure(
            title=title,
            height=280,
            sizing_mode="stretch_width",
            x_axis_label="t (s)",
            y_axis_label=label,
            tools=_TOOLS,
            x_range=self.shown,
            name=f"series-{key}",
        )
        labels = [mass[1] for mass in outline.masses]
        sides = [
            (f"rest{i}", f"{mass[1]} {outline.rest}", self.colour(i), _SHADE)
            for i, mass in zip(self.keys, outline.masses, strict=True)
            if outline.resting is None or mass[0] in outline.resting
        ]
        sides += [
            (
                f"contact{j + 1}",
                f"{name} contact" if outline is ARTICLE else f"{name} closed",
                CONTACT[j % len(CONTACT)],
                2 * _SHADE,
            )
            for j, name in enumerate(outline.contacts)
        ]
        for name, legend, colour, alpha in sides:
            _keyed(fig, "quad", legend, source=self.sources[name], color=colour, alpha=alpha, line_width=0)
        lines: list[Any] = [
            _keyed(fig, "line", n, "t", f"{key}{i}", source=line, color=self.colour(i))
            for i, n in zip(self.keys, labels, strict=True)
        ]
        fig.y_range = DataRange1d(renderers=lines)  # the shading spans any height: not in the range
        if key == "x":
            _keyed(fig, "scatter", "events", "t", "x", source=self.sources["events"], size=3, color="#444444")
        fig.add_layout(fig.legend[0], "right")
        return fig

    def _overview(self) -> Any:
        fig = figure(
            title="the whole run: drag the box to choose what the figures below show",
            height=130,
            sizing_mode="stretch_width",
            tools="",
            toolbar_location=None,
            x_axis_label="t (s)",
            y_axis_label="x (m)",
            name="overview",
        )
        source = self.sources["overview"]
        drawn: list[Any] = [fig.line("t", f"x{i}", source=source, color=self.colour(i)) for i in self.keys]
        fig.x_range = DataRange1d(renderers=drawn)
        fig.y_range = DataRange1d(renderers=drawn)
        box = RangeTool(x_range=self.shown)
        box.overlay.fill_color, box.overlay.fill_alpha = "navy", 0.15
        fig.add_tools(box)
        return fig

    def _phase(self, i: str) -> Any:
        _, label, x_name, v_name = self.outline.masses[int(i) - 1]
        fig = figure(
            title=f"{label}: phase portrait, stroboscopic points",
            height=340,
            sizing_mode="stretch_width",
            x_axis_label=f"{x_name} (m)",
            y_axis_label=f"{v_name} (m/s)",
            tools=_TOOLS,
            name=f"phase-{i}",
        )
        x, v = f"x{i}", f"v{i}"
        drawn: list[Any] = [fig.line(x, v, source=self.sources["line"], color=self.colour(i), alpha=0.5)]
        if self.orbits:
            drawn.append(_keyed(fig, "line", "orbit", x, v, source=self.sources["orbit"], color="orange", line_width=3))
        drawn.append(_keyed(fig, "scatter", "t0 + kT", x, v, source=self.sources["strobe"], size=6, color="black"))
        fig.x_range, fig.y_range = DataRange1d(renderers=drawn), DataRange1d(renderers=drawn)
        fig.legend.location = "top_left"
        fig.legend.background_fill_alpha = 0.6
        return fig

    def draw(self, scene: Scene) -> None:
        """The figures' data: ``scene``'s motion, the last :data:`SHOWN_PERIODS` periods in view."""
        events, trajectory, outline = scene.events, scene.trajectory, self.outline
        times = trajectory.t.to_numpy(float)
        where = {key: trajectory[x].to_numpy(float) for key, _, x, _ in outline.masses}
        x = np.array(
            [
                np.interp(t, times, where[m]) if m in where else math.nan
                for t, m in zip(events.t, events["mass"], strict=True)
            ]
        )
        table = {name: events[name].astype(str).to_numpy() for name in outline.event_columns[1:]}
        state = self.state(trajectory)
        self.sources["line"].data = {"t": times, **state}
        every = max(1, len(trajectory) // OVERVIEW_POINTS)  # a sample of the path: drawn whole, 45 ms a change
        self.sources["overview"].data = {
            name: values[::every] for name, values in {"t": times, **state}.items() if not name.startswith("v")
        }
        # lists, not arrays: a few points each, sent in the message's text instead of one frame each
        self.sources["strobe"].data = {"k": scene.strobe.k.tolist()} | {
            name: values.tolist() for name, values in self.state(scene.strobe).items()
        }
        self.sources["events"].data = {"t": events["t"].to_numpy(), **table, "x": x}
        for i, (key, *_) in zip(self.keys, outline.masses, strict=True):
            self.sources[f"rest{i}"].data = spans(scene.rests[key])
        for j, name in enumerate(outline.contacts):
            self.sources[f"contact{j + 1}"].data = spans(scene.contacts[name])
        end = float(times[-1])
        self.shown.start, self.shown.end = max(scene.t0, end - SHOWN_PERIODS * scene.period), end
        if len(self.sources["orbit"].data["x1"]):
            self.sources["orbit"].data = {name: [] for name in self.sources["orbit"].data}


_SERIES = (("x", "displacement (m)", "displacements"), ("v", "velocity (m/s)", "velocities"))


def event_table(source: ColumnDataSource, names: tuple[str, ...] = ARTICLE.event_columns) -> DataTable:
    """The switching events of ``source`` (its columns ``names``, time first), every row (the table
    scrolls), redrawn whenever its data change: SlickGrid kept the old rows where the new run had
    as many events (the page showed Omega = 1.58's events with 1.54's in its data), so a change of
    the data tells the table."""
    text = StringFormatter()
    titles = {"from_domain": "from", "to_domain": "to", "mode_before": "from", "mode_after": "to"}
    columns = [TableColumn(field="t", title="t (s)", formatter=NumberFormatter(format="0.000000"))] + [
        TableColumn(field=name, title=titles.get(name, name), formatter=text) for name in names[1:]
    ]
    table = DataTable(
        source=source,
        columns=columns,
        height=360,
        sizing_mode="stretch_width",
        index_position=None,
        name="events",
        styles={"will-change": "transform"},  # its own layer: its rows' change recomposites the page 40 ms less
    )
    source.js_on_change("data", CustomJS(args={"table": table}, code="table.view.change.emit()"))
    return table


def url_keeper() -> ColumnDataSource:
    """A source whose one value, when set (``{"query": ["?Omega=1.54&periods=20"]}``: numbers
    only), becomes the page's address without a reload: a link or a reload shows the same view.
    A source, not a hidden ``Div``: a ``Div``'s new text lays the whole page out again."""
    keeper = ColumnDataSource({"query": [""]}, name="url")
    code = (
        "const query = cb_obj.data.query[0];"
        "window.history.replaceState(null, '', query === '' ? window.location.pathname : query)"
    )
    keeper.js_on_change("data", CustomJS(code=code))
    return keeper


def map_figure(picture: Picture, picked: ColumnDataSource) -> Any:
    """A folder's picture: its cells (or points) coloured by label, its marks (a frequency
    response's bifurcations), and the cell or point last clicked, outlined."""
    fig = figure(
        title=f"{WHAT[picture.kind]} of {picture.case.name}: click a {'cell' if picture.cells else 'point'} "
        "for its attractors",
        height=380,
        sizing_mode="stretch_width",
        x_axis_label=_axis(picture.x),
        y_axis_label=_axis(picture.y),
        tools="tap,pan,wheel_zoom,reset,save",  # no hover: its label under the pointer took clicks meant for the map
        name="map",
    )
    _sites(fig, picture, picked)
    if len(picture.marks):
        marks = ColumnDataSource({"x": picture.marks.x, "y": picture.marks.y, "label": picture.marks.label})
        fig.scatter(
            "x",
            "y",
            source=marks,
            marker="triangle",
            size=10,
            fill_alpha=0,
            line_color="black",
            legend_label="bifurcations",
        )
    fig.add_layout(fig.legend[0], "right")
    return fig


def _axis(name: str) -> str:
    """A map's axis label with its unit (``Omega (rad/s)``, ``x2 (m)``, ``x_pp (m)``)."""
    from oscillator.orbits.response import UNITS
    from oscillator.report.outputs import quantity_label

    return f"{name} ({UNITS[name]})" if UNITS.get(name) else quantity_label(name)


def _sites(fig: Any, picture: Picture, picked: ColumnDataSource) -> None:
    """The picture's cells (outlined by the frame a click must fall in) or points, coloured by
    label, and the one ``picked`` outlined."""
    labels = sorted(set(picture.points.label))
    palette = (list(Category10[10]) * (len(labels) // 10 + 1))[: max(len(labels), 3)]
    source = ColumnDataSource({"x": picture.points.x, "y": picture.points.y, "label": picture.points.label})
    colour = factor_cmap("label", palette=palette, factors=labels)
    if not picture.cells:
        fig.scatter("x", "y", source=source, size=4, color=colour, nonselection_alpha=0.4, legend_field="label")
        fig.scatter("x", "y", source=picked, size=14, fill_alpha=0, line_color="black", line_width=2.5)
        return
    size = {"width": picture.width, "height": picture.height}
    fig.rect(
        "x",
        "y",
        **size,
        source=source,
        line_width=0,
        fill_color=colour,
        nonselection_fill_alpha=0.5,
        legend_field="label",
    )
    fig.rect("x", "y", **size, source=picked, fill_alpha=0, line_color="black", line_width=2.5)
    left, right, bottom, top = picture.frame
    frame = BoxAnnotation(left=left, right=right, bottom=bottom, top=top, fill_alpha=0, line_color="#666666")
    frame.line_dash = "dotted"
    fig.add_layout(frame)
