"""The explorer's page (Panel on Bokeh): move a parameter, see the motion, its switches and theorems.

:class:`Explorer` holds the controls (:mod:`oscillator.exploring.controls`), the figures and the
tables; on every change it simulates again (:func:`~oscillator.exploring.scene.scene_of`) and
replaces the figures' data in one batch.  The same object is served by ``oscillator explore``
(:mod:`oscillator.exploring.serving`) and displayed by a notebook.

Every text that comes from a case file (its title, description, a name) reaches the page as
text: through :func:`html.escape` into the page's markup, or as a figure title, which Bokeh
draws on a canvas.  The page loads nothing but from the server that serves it.
"""

from __future__ import annotations

import html
import io
import re
import time
from typing import Any

import numpy as np
import panel as pn
from bokeh.events import Tap
from bokeh.models import ColumnDataSource, DataRange1d
from bokeh.models.widgets.tables import DataTable, NumberFormatter, StringFormatter, TableColumn
from bokeh.palettes import Category10
from bokeh.plotting import figure
from bokeh.transform import factor_cmap

from oscillator.errors import OscillatorError
from oscillator.exploring.controls import START, Control, controls_of
from oscillator.exploring.maps import Picture
from oscillator.exploring.scene import EVENT_COLUMNS, PERIODS, Scene, scene_of, with_changes
from oscillator.io.cases import Case, case_to_toml, resolve_case

__all__ = ["Explorer"]

#: The masses' colours, as the report's figures draw them.
COLOURS = {1: "#1f77b4", 2: "#d62728"}
#: The contacts' shading: between the masses (left) and on the right stop.
CONTACT = {"left": "#2ca02c", "right": "#9467bd"}
_SHADE = 0.15
_TOOLS = "pan,wheel_zoom,box_zoom,reset"
_FAR = 1e9


def _plain(text: str) -> str:
    """Untrusted text as HTML text."""
    return html.escape(text, quote=True)


def _quads() -> ColumnDataSource:
    return ColumnDataSource({"left": [], "right": [], "bottom": [], "top": []})


def _spans(intervals: list[tuple[float, float]]) -> dict[str, list[float]]:
    return {
        "left": [a for a, _ in intervals],
        "right": [b for _, b in intervals],
        "bottom": [-_FAR] * len(intervals),
        "top": [_FAR] * len(intervals),
    }


class Explorer:
    """The explorer of one case: controls, time series, phase portraits with the stroboscopic
    points, the event table, the orbit on request, and "save as case file".

    Parameters
    ----------
    case : Case or str
        The case (a name, a file, or a Case).
    periods : int
        Forcing periods simulated on every change.
    """

    def __init__(self, case: Case | str, periods: int = PERIODS, *, picture: Picture | None = None) -> None:
        self.picture = picture
        self.case = resolve_case(case)
        self.periods = periods
        self.revision = 0
        self.sources = {
            "line": ColumnDataSource({"t": [], "x1": [], "v1": [], "x2": [], "v2": []}),
            "strobe": ColumnDataSource({"k": [], "x1": [], "v1": [], "x2": [], "v2": []}),
            "events": ColumnDataSource({name: [] for name in (*EVENT_COLUMNS, "x")}),
            "orbit": ColumnDataSource({"x1": [], "v1": [], "x2": [], "v2": []}),
            **{f"rest{mass}": _quads() for mass in (1, 2)},
            **{f"contact_{side}": _quads() for side in CONTACT},
        }
        self.status = pn.pane.HTML("", name="status", css_classes=["oscillator-status"])
        self.orbit_text = pn.pane.HTML("", name="orbit", css_classes=["oscillator-orbit"])
        self.picked = pn.pane.HTML("", name="picked", css_classes=["oscillator-picked"], sizing_mode="stretch_width")
        self.widgets = self._controls(controls_of(self.case))
        self.periods_box = pn.widgets.IntInput(label="periods", value=periods, start=1, end=10_000, width=120)
        self.periods_box.param.watch(self._changed, "value")
        self.orbit_button = pn.widgets.Button(label="Orbit and multipliers")
        self.orbit_button.on_click(self._orbit)
        self.download = pn.widgets.FileDownload(
            callback=self._case_file, filename=self._file_name(), label="Save as case file"
        )
        self.layout = self._layout()
        self.scene: Scene | None = None
        self.update()

    # -- building ---------------------------------------------------------------------------
    def _controls(self, controls: list[Control]) -> dict[str, pn.widgets.EditableFloatSlider]:
        widgets = {}
        for control in controls:
            widget = pn.widgets.EditableFloatSlider(
                label=control.name,
                value=control.value,
                start=control.start,
                end=control.end,
                step=control.step,
                format="0[.]00000",
                width=250,
                css_classes=[f"control-{control.name}"],
            )
            widget.param.watch(self._changed, "value_throttled")  # a drag runs once, when let go
            widgets[control.name] = widget
        return widgets

    def _layout(self) -> pn.viewable.Viewable:
        title = pn.pane.HTML(
            f"<h2 class='oscillator-title'>{_plain(self.case.full_title)}</h2>"
            + (f"<p>{_plain(self.case.description)}</p>" if self.case.description else ""),
            sizing_mode="stretch_width",
        )
        parameters = [w for name, w in self.widgets.items() if name not in ("x1", "v1", "x2", "v2")]
        start = [self.widgets[name] for name in ("x1", "v1", "x2", "v2")]
        sidebar = pn.Column(
            pn.pane.HTML("<b>Parameters</b>"),
            *parameters,
            pn.pane.HTML("<b>Start</b>"),
            *start,
            self.periods_box,
            width=260,
            scroll=True,
            height=900,
        )
        figures = self._figures()
        table = self._event_table()
        picture = [] if self.picture is None else [self._map(self.picture), self.picked]
        main = pn.Column(
            title,
            *picture,
            self.status,
            pn.Row(self.orbit_button, self.download),
            self.orbit_text,
            figures["x"],
            figures["v"],
            pn.Row(figures["p1"], figures["p2"]),
            pn.pane.HTML("<b>Switching events</b>"),
            pn.pane.Bokeh(table),
        )
        return pn.Row(sidebar, main)

    def _figures(self) -> dict[str, Any]:
        found = {}
        for key, label in (("x", "displacement (m)"), ("v", "velocity (m/s)")):
            title = "displacements" if key == "x" else "velocities"
            fig = figure(title=title, height=300, width=620, x_axis_label="t (s)", y_axis_label=label, tools=_TOOLS)
            self._shade(fig)
            lines: list[Any] = [
                fig.line("t", f"{key}{mass}", source=self.sources["line"], color=COLOURS[mass], legend_label=f"m{mass}")
                for mass in (1, 2)
            ]
            fig.y_range = DataRange1d(renderers=lines)  # the shading spans any height: not in the range
            fig.legend.click_policy = "hide"
            fig.add_layout(fig.legend[0], "right")
            found[key] = fig
        found["x"].scatter("t", "x", source=self.sources["events"], size=3, color="#444444", legend_label="events")
        for mass in (1, 2):
            fig = figure(
                title=f"phase portrait of m{mass}, stroboscopic points",
                height=320,
                width=420,
                x_axis_label=f"x{mass} (m)",
                y_axis_label=f"v{mass} (m/s)",
                tools=_TOOLS,
            )
            fig.line(f"x{mass}", f"v{mass}", source=self.sources["line"], color=COLOURS[mass], alpha=0.5)
            fig.line(
                f"x{mass}", f"v{mass}", source=self.sources["orbit"], color="orange", line_width=3, legend_label="orbit"
            )
            fig.scatter(
                f"x{mass}", f"v{mass}", source=self.sources["strobe"], size=6, color="black", legend_label="t0 + kT"
            )
            fig.legend.location = "top_left"
            fig.legend.background_fill_alpha = 0.6
            found[f"p{mass}"] = fig
        return found

    def _shade(self, fig: Any) -> None:
        for mass in (1, 2):
            fig.quad(
                source=self.sources[f"rest{mass}"],
                color=COLOURS[mass],
                alpha=_SHADE,
                line_width=0,
                legend_label=f"m{mass} at rest",
            )
        for side, colour in CONTACT.items():
            fig.quad(
                source=self.sources[f"contact_{side}"],
                color=colour,
                alpha=_SHADE,
                line_width=0,
                legend_label=f"{side} contact",
            )

    def _event_table(self) -> DataTable:
        text = StringFormatter()
        columns = [
            TableColumn(field="t", title="t (s)", formatter=NumberFormatter(format="0.000000")),
            TableColumn(field="mass", title="mass", formatter=text),
            TableColumn(field="kind", title="kind", formatter=text),
            TableColumn(field="from_domain", title="from", formatter=text),
            TableColumn(field="to_domain", title="to", formatter=text),
            TableColumn(field="theorem", title="theorem", formatter=text),
            TableColumn(field="equation", title="equation", formatter=text),
            TableColumn(field="boundary", title="boundary", formatter=text),
        ]
        return DataTable(
            source=self.sources["events"], columns=columns, width=860, height=300, index_position=None, name="events"
        )

    def _map(self, picture: Picture) -> Any:
        labels = sorted(set(picture.points.label))
        palette = (Category10[10] * (len(labels) // 10 + 1))[: max(len(labels), 3)]
        source = ColumnDataSource({"x": picture.points.x, "y": picture.points.y, "label": picture.points.label})
        fig = figure(
            title=f"{picture.kind} of {picture.case.name}: click a cell for its attractors",
            height=360,
            width=620,
            x_axis_label=picture.x,
            y_axis_label=picture.y,
            tools="tap,hover,pan,wheel_zoom,reset",
            tooltips=[("", "@label")],
            name="map",
        )
        fig.rect(
            "x",
            "y",
            width=picture.width,
            height=picture.height,
            source=source,
            line_width=0,
            fill_color=factor_cmap("label", palette=palette, factors=labels),
            legend_field="label",
        )
        fig.add_layout(fig.legend[0], "right")
        fig.on_event(Tap, self._tap)
        return fig

    def _tap(self, event: Any) -> None:
        """A click on the map: the attractors there, the first one's motion on screen."""
        assert self.picture is not None
        index = self.picture.nearest(float(event.x), float(event.y))
        started = time.perf_counter()
        try:
            found = self.picture.attractors_at(index)
        except OscillatorError as error:
            self.picked.object = f"<span class='oscillator-error'>{_plain(str(error))}</span>"
            return
        seconds = time.perf_counter() - started
        self.picked.object = _picked_html(self.picture.label_at(index), found, seconds)
        if found.attractors:
            self._show(found.case, found.attractors[0].points[0])

    def _show(self, case: Case, state: np.ndarray) -> None:
        """Put ``case``'s parameters and ``state`` on the controls, and simulate once."""
        values = {name: float(getattr(case.parameters, name)) for name in self.widgets if name not in START}
        values |= dict(zip(START, (float(v) for v in state), strict=True))
        for name, value in values.items():  # the watchers follow value_throttled: these run nothing
            widget = self.widgets[name]
            widget.start, widget.end = min(widget.start, value), max(widget.end, value)
            widget.value = value
        self.update()

    # -- computing --------------------------------------------------------------------------
    def values(self) -> dict[str, float]:
        """The controls' values: every parameter and the start."""
        return {name: float(widget.value or 0.0) for name, widget in self.widgets.items()}

    def current_case(self) -> Case:
        """The case on screen: the controls' values applied to the case (checked)."""
        return with_changes(self.case, self.values())

    def _changed(self, *_: Any) -> None:
        self.update()

    def update(self) -> None:
        """Simulate the case on screen and redraw; an impossible value or a failed run is said
        in the status line and the last motion stays."""
        started = time.perf_counter()
        try:
            scene = scene_of(self.current_case(), int(self.periods_box.value or self.periods))
        except OscillatorError as error:
            self.revision += 1
            self.status.object = (
                f"<span class='oscillator-error' data-revision='{self.revision}'>{_plain(str(error))}</span>"
            )
            return
        self.scene = scene
        self._draw(scene)
        self.revision += 1
        seconds = time.perf_counter() - started
        self.status.object = (
            f"<span data-revision='{self.revision}'>#{self.revision}: {scene.periods} periods, "
            f"{len(scene.events)} events; simulated in {1e3 * scene.seconds:.0f} ms, "
            f"drawn in {1e3 * (seconds - scene.seconds):.0f} ms ({_plain(scene.status)})</span>"
        )

    def _draw(self, scene: Scene) -> None:
        events = scene.events
        x = np.where(events["mass"].to_numpy() == 1, events["x1"].to_numpy(), events["x2"].to_numpy())
        with pn.io.hold():
            self.sources["line"].data = {
                name: scene.trajectory[name].to_numpy() for name in ("t", "x1", "v1", "x2", "v2")
            }
            self.sources["strobe"].data = {
                name: scene.strobe[name].to_numpy() for name in ("k", "x1", "v1", "x2", "v2")
            }
            table = {name: events[name].astype(str).to_numpy() for name in EVENT_COLUMNS if name != "t"}
            self.sources["events"].data = {"t": events["t"].to_numpy(), **table, "x": x}
            for mass in (1, 2):
                self.sources[f"rest{mass}"].data = _spans(scene.rests[mass])
            for side in CONTACT:
                self.sources[f"contact_{side}"].data = _spans(scene.contacts[side])
            self.sources["orbit"].data = {"x1": [], "v1": [], "x2": [], "v2": []}
            self.orbit_text.object = ""
            self.download.filename = self._file_name()

    def _orbit(self, *_: Any) -> None:
        """The periodic orbit near the motion's end, its multipliers and measures (on request)."""
        from oscillator.orbits.shooting import find_orbit

        if self.scene is None:
            return
        try:
            end = self.scene.trajectory.iloc[-1][["x1", "v1", "x2", "v2"]].to_numpy(float)
            orbit = find_orbit(self.current_case(), guess=end, section=self.scene.t_end)
        except OscillatorError as error:
            self.orbit_text.object = f"<span class='oscillator-error'>no orbit: {_plain(str(error))}</span>"
            return
        self.orbit_text.object = _orbit_html(orbit)
        one = scene_of(
            orbit.case,
            orbit.period,
            **dict(zip(("t0", "x1", "v1", "x2", "v2"), (orbit.section, *orbit.state), strict=True)),
        )
        self.sources["orbit"].data = {name: one.trajectory[name].to_numpy() for name in ("x1", "v1", "x2", "v2")}

    def _case_file(self) -> io.StringIO:
        return io.StringIO(case_to_toml(self.current_case()))

    def _file_name(self) -> str:
        stem = re.sub(r"[^A-Za-z0-9_.-]+", "-", self.case.name).strip(".-") or "case"
        return f"{stem[:60]}-explored.toml"

    # -- display ----------------------------------------------------------------------------
    def __panel__(self) -> pn.viewable.Viewable:
        return self.layout

    def _repr_mimebundle_(self, include: Any = None, exclude: Any = None) -> Any:
        pn.extension()
        return self.layout._repr_mimebundle_(include, exclude)


def _picked_html(where: str, found: Any, seconds: float) -> str:
    items = []
    for attractor in found.attractors:
        point = ", ".join(f"{v:.6g}" for v in attractor.points[0])
        multipliers = (
            " multipliers " + ", ".join(f"{abs(mu):.4g}" for mu in attractor.orbit.multipliers)
            if attractor.orbit is not None
            else ""
        )
        measures = ", ".join(f"{k} = {attractor.measures[k]:.5g}" for k in _MEASURES if k in attractor.measures)
        items.append(
            f"<li data-period='{attractor.period}'><b>{_plain(attractor.name)}</b>: section point ({point});"
            f"{_plain(multipliers)}; {_plain(measures)}</li>"
        )
    return (
        f"<div class='oscillator-picked-found' data-count='{len(found.attractors)}'>{_plain(where)}: "
        f"{len(found.attractors)} attractor(s) found in {seconds:.2f} s<ul>{''.join(items)}</ul></div>"
    )


def _orbit_html(orbit: Any) -> str:
    rows = "".join(f"<tr><td>{mu.real:+.6g}{mu.imag:+.6g}i</td><td>{abs(mu):.6g}</td></tr>" for mu in orbit.multipliers)
    measures = orbit.response().columns()
    shown = ", ".join(f"{name} = {value:.6g}" for name, value in measures.items() if name in _MEASURES)
    return (
        f"<div class='oscillator-orbit-found'><b>Period-{orbit.period} orbit</b> at t = {orbit.section:.6g} s: "
        f"{_plain(orbit.verdict)}; residual {orbit.residual:.1e}"
        f"<table><tr><th>multiplier</th><th>modulus</th></tr>{rows}</table>"
        f"<p>{_plain(shown)}</p></div>"
    )


_MEASURES = (
    "x_max_m1",
    "x_max_m2",
    "v_peak_m1",
    "v_peak_m2",
    "rest_m1",
    "rest_m2",
    "impact_max_right",
    "impact_max_left",
)
