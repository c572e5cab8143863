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

from oscillator.analysis.axes import STATE
from oscillator.exploring.maps import WHAT, Picture
from oscillator.exploring.scene import EVENT_COLUMNS, Scene

__all__ = ["COLOURS", "CONTACT", "SHOWN_PERIODS", "Figures", "event_table", "map_figure", "plain", "url_keeper"]

#: The masses' colours, as the report's figures draw them.
COLOURS = {1: "#1f77b4", 2: "#d62728"}
#: The contacts' shading: between the masses (left) and on the right stop.
CONTACT = {"left": "#2ca02c", "right": "#9467bd"}
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
    mass's phase portrait with its stroboscopic points and the orbit asked for."""

    def __init__(self) -> None:
        self.sources = {
            "line": ColumnDataSource({name: [] for name in ("t", *STATE)}),
            "overview": ColumnDataSource({name: [] for name in ("t", "x1", "x2")}),
            "strobe": ColumnDataSource({name: [] for name in ("k", *STATE)}),
            "events": ColumnDataSource({name: [] for name in (*EVENT_COLUMNS, "x")}),
            "orbit": ColumnDataSource({name: [] for name in STATE}),
            **{f"rest{mass}": _quads() for mass in (1, 2)},
            **{f"contact_{side}": _quads() for side in CONTACT},
        }
        self.shown = Range1d(start=0.0, end=1.0)  # the time series' window
        self.series = {key: self._series(key, label, title) for key, label, title in _SERIES}
        self.overview = self._overview()
        self.phase = {mass: self._phase(mass) for mass in (1, 2)}

    def _series(self, key: str, label: str, title: str) -> Any:
        line = self.sources["line"]
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
        sides = [(f"rest{mass}", f"m{mass} at rest", COLOURS[mass], _SHADE) for mass in (1, 2)]
        sides += [(f"contact_{side}", f"{side} contact", colour, 2 * _SHADE) for side, colour in CONTACT.items()]
        for name, legend, colour, alpha in sides:
            _keyed(fig, "quad", legend, source=self.sources[name], color=colour, alpha=alpha, line_width=0)
        lines: list[Any] = [
            _keyed(fig, "line", f"m{mass}", "t", f"{key}{mass}", source=line, color=COLOURS[mass]) for mass in (1, 2)
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
        drawn: list[Any] = [fig.line("t", f"x{mass}", source=source, color=COLOURS[mass]) for mass in (1, 2)]
        fig.x_range = DataRange1d(renderers=drawn)
        fig.y_range = DataRange1d(renderers=drawn)
        box = RangeTool(x_range=self.shown)
        box.overlay.fill_color, box.overlay.fill_alpha = "navy", 0.15
        fig.add_tools(box)
        return fig

    def _phase(self, mass: int) -> Any:
        fig = figure(
            title=f"m{mass}: phase portrait, stroboscopic points",
            height=340,
            sizing_mode="stretch_width",
            x_axis_label=f"x{mass} (m)",
            y_axis_label=f"v{mass} (m/s)",
            tools=_TOOLS,
            name=f"phase-{mass}",
        )
        x, v = f"x{mass}", f"v{mass}"
        drawn = [
            fig.line(x, v, source=self.sources["line"], color=COLOURS[mass], alpha=0.5),
            _keyed(fig, "line", "orbit", x, v, source=self.sources["orbit"], color="orange", line_width=3),
            _keyed(fig, "scatter", "t0 + kT", x, v, source=self.sources["strobe"], size=6, color="black"),
        ]
        fig.x_range, fig.y_range = DataRange1d(renderers=drawn), DataRange1d(renderers=drawn)
        fig.legend.location = "top_left"
        fig.legend.background_fill_alpha = 0.6
        return fig

    def draw(self, scene: Scene) -> None:
        """The figures' data: ``scene``'s motion, the last :data:`SHOWN_PERIODS` periods in view."""
        events = scene.events
        x = np.where(events["mass"].to_numpy() == 1, events["x1"].to_numpy(), events["x2"].to_numpy())
        table = {name: events[name].astype(str).to_numpy() for name in EVENT_COLUMNS[1:]}
        self.sources["line"].data = {name: scene.trajectory[name].to_numpy() for name in ("t", *STATE)}
        every = max(1, len(scene.trajectory) // OVERVIEW_POINTS)  # a sample of the path: drawn whole, 45 ms a change
        self.sources["overview"].data = {name: scene.trajectory[name].to_numpy()[::every] for name in ("t", "x1", "x2")}
        # lists, not arrays: a few points each, sent in the message's text instead of one frame each
        self.sources["strobe"].data = {name: scene.strobe[name].tolist() for name in ("k", *STATE)}
        self.sources["events"].data = {"t": events["t"].to_numpy(), **table, "x": x}
        for mass in (1, 2):
            self.sources[f"rest{mass}"].data = spans(scene.rests[mass])
        for side in CONTACT:
            self.sources[f"contact_{side}"].data = spans(scene.contacts[side])
        end = float(scene.trajectory.t.iloc[-1])
        period = float(scene.case.parameters.period)
        self.shown.start, self.shown.end = max(scene.t0, end - SHOWN_PERIODS * period), end
        if len(self.sources["orbit"].data["x1"]):
            self.sources["orbit"].data = {name: [] for name in STATE}


_SERIES = (("x", "displacement (m)", "displacements"), ("v", "velocity (m/s)", "velocities"))


def event_table(source: ColumnDataSource) -> DataTable:
    """The switching events of ``source``, every row (the table scrolls), redrawn whenever its data
    change: SlickGrid kept the old rows where the new run had as many events (the page showed
    Omega = 1.58's events with 1.54's in its data), so a change of the data tells the table."""
    text = StringFormatter()
    titles = {"from_domain": "from", "to_domain": "to"}
    columns = [TableColumn(field="t", title="t (s)", formatter=NumberFormatter(format="0.000000"))] + [
        TableColumn(field=name, title=titles.get(name, name), formatter=text) for name in EVENT_COLUMNS[1:]
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
