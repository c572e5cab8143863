"""The explorer's page: move a parameter, see the motion, its switches and its theorems.

:class:`Explorer` holds the controls (:mod:`oscillator.exploring.controls`), the figures and the
tables; on every change it simulates again (:func:`~oscillator.exploring.scene.scene_of`) and
replaces the figures' data and the status line in one batch, one message to the page.  The
controls, texts and figures are Bokeh's own models (a Panel widget adds a round of messages and a
layout of the page on every change, which the latency benchmark measured); Panel lays them out,
serves them (:mod:`oscillator.exploring.serving`), displays the same object in a notebook, and
offers the case file as a download.

Every text from a case file (its title, description, name) reaches the page as text: through
:func:`html.escape` into the markup of a ``Div``, or as a figure's title, which Bokeh draws on a
canvas.  The page loads nothing but from the server that serves it.
"""

from __future__ import annotations

import html
import io
import math
import re
import time
from typing import Any

import numpy as np
import panel as pn
from bokeh.events import DoubleTap, Tap
from bokeh.layouts import column
from bokeh.models import ColumnDataSource, DataRange1d
from bokeh.models.widgets.buttons import Button
from bokeh.models.widgets.inputs import NumericInput, TextInput
from bokeh.models.widgets.markups import Div
from bokeh.models.widgets.sliders import Slider
from bokeh.models.widgets.tables import DataTable, NumberFormatter, StringFormatter, TableColumn
from bokeh.palettes import Category10
from bokeh.plotting import figure
from bokeh.transform import factor_cmap

from oscillator.analysis.axes import STATE
from oscillator.errors import InputError, OscillatorError
from oscillator.exploring.controls import START, Control, controls_of
from oscillator.exploring.maps import WHAT, Picture
from oscillator.exploring.scene import (
    EVENT_COLUMNS,
    PERIODS,
    TIME_AGREEMENT,
    Scene,
    check_periods,
    differences,
    scene_of,
    with_changes,
)
from oscillator.io.cases import Case, case_to_toml, resolve_case
from oscillator.io.expressions import parse_value

__all__ = ["Explorer"]

#: The masses' colours, as the report's figures draw them.
COLOURS = {1: "#1f77b4", 2: "#d62728"}
#: The contacts' shading: between the masses (left) and on the right stop.
CONTACT = {"left": "#2ca02c", "right": "#9467bd"}
#: The response measures shown with an orbit or an attractor.
MEASURES = (
    "x_max_m1",
    "x_max_m2",
    "v_peak_m1",
    "v_peak_m2",
    "rest_m1",
    "rest_m2",
    "impact_max_right",
    "impact_max_left",
)
#: The integrator that draws each change: the compiled one, checked against CVODE after it.
DRAWING_ENGINE = "dop853"
#: How long the controls rest before CVODE's check starts (ms): a change sooner cancels it (a
#: change during the check waits for it: 60-100 ms for 50 periods of Instance 1).
CHECK_DELAY_MS = 400
_SHADE = 0.15
_FAR = 1e9
_TOOLS = "pan,wheel_zoom,box_zoom,reset"


def _plain(text: str) -> str:
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


def _spans(intervals: list[tuple[float, float]]) -> dict[str, list[float]]:
    return {
        "left": [a for a, _ in intervals],
        "right": [b for _, b in intervals],
        "bottom": [-_FAR] * len(intervals),
        "top": [_FAR] * len(intervals),
    }


class _Text(pn.pane.HTML):
    """A line of HTML whose change replaces its content only: Bokeh's ``Div`` lays out the whole
    page again at each new text, and Panel's pane sends its style sheets again with it, which does
    the same (30 ms a change, measured); this pane sends the text alone."""

    def _update(self, ref: str, model: Any) -> None:
        model.update(text=self._get_properties(model.document)["text"])

    def __init__(self, text: str, **params: Any) -> None:
        super().__init__(text, **params)  # type: ignore[no-untyped-call]  # Panel's is not annotated

    def set_text(self, text: str) -> None:
        """Show ``text`` (HTML) now: in a batch, which Panel sends at its end; outside one, from a
        Bokeh event's callback (a click on the map), the change waited for the page's next event."""
        with pn.io.hold():
            self.object = text


class Explorer:
    """The explorer of one case, or of a folder's map: controls, time series with rests and
    contacts shaded, phase portraits with the stroboscopic points, the event table, the orbit
    and its multipliers on request, and the case on screen as a case file.

    Parameters
    ----------
    case : Case or str
        The case (a name, a file, or a Case).
    periods : int
        Forcing periods simulated on every change.
    picture : Picture, optional
        A folder's map (:func:`~oscillator.exploring.maps.picture_of`): a click on it shows the
        attractors there.
    engine : str
        The integrator that draws each change (:mod:`oscillator.engines`): the compiled DOP853 by
        default, whose motion CVODE runs again once the controls rest (:data:`CHECK_DELAY_MS`) and
        either confirms, event by event, or replaces; ``"cvode"`` draws with the reference
        itself.
    """

    def __init__(
        self,
        case: Case | str,
        periods: int = PERIODS,
        *,
        picture: Picture | None = None,
        engine: str = DRAWING_ENGINE,
    ) -> None:
        from oscillator.engines import check_engine

        check_engine(engine)
        self.engine = engine
        self._check_handle: Any = None
        self.case = resolve_case(case)
        self.picture = picture
        self.periods = check_periods(periods)
        self.revision = 0
        self.clicks = 0
        self.scene: Scene | None = None
        self.sources = {
            "line": ColumnDataSource({name: [] for name in ("t", *STATE)}),
            "strobe": ColumnDataSource({name: [] for name in ("k", *STATE)}),
            "events": ColumnDataSource({name: [] for name in (*EVENT_COLUMNS, "x")}),
            "orbit": ColumnDataSource({name: [] for name in STATE}),
            **{f"rest{mass}": _quads() for mass in (1, 2)},
            **{f"contact_{side}": _quads() for side in CONTACT},
        }
        self.status = _Text("", width=900, height=24)
        self.orbit_text = _Text("", width=900)
        self.picked = _Text("", width=900)
        self.widgets = {control.name: self._slider(control) for control in controls_of(self.case)}
        self.set_box = TextInput(title="set NAME=VALUE (any value)", placeholder="e.g. K3=2.5", width=230)
        self.set_box.on_change("value", lambda attr, old, new: self._set(new))
        self.periods_box = NumericInput(title="periods", value=self.periods, low=1, high=10_000, mode="int", width=120)
        self.periods_box.on_change("value", lambda attr, old, new: self.update())
        self.orbit_button = Button(label="Orbit and multipliers", width=180)
        self.orbit_button.on_click(self._orbit)
        self.download = pn.widgets.FileDownload(
            callback=self._case_file, filename=self._file_name(), label="Save as case file", width=180
        )
        self.layout = self._layout()
        self.update()

    # -- building -----------------------------------------------------------------------------
    def _slider(self, control: Control) -> Slider:
        slider = Slider(
            title=control.name,
            value=control.value,
            start=control.start,
            end=control.end,
            step=control.step,
            format="0[.]00000",
            width=230,
            name=control.name,
            css_classes=[f"control-{control.name}"],
        )
        slider.on_change("value_throttled", lambda attr, old, new: self.update())  # a drag runs once, when let go
        return slider

    def _layout(self) -> pn.viewable.Viewable:
        heading = f"<h2 class='oscillator-title'>{_plain(self.case.full_title)}</h2>"
        if self.case.description:
            heading += f"<p>{_plain(self.case.description)}</p>"
        parameters = [widget for name, widget in self.widgets.items() if name not in START]
        sidebar = column(
            Div(text="<b>Parameters</b>"),
            *parameters,
            Div(text="<b>Start</b>"),
            *(self.widgets[name] for name in START),
            self.set_box,
            self.periods_box,
            width=260,
        )
        figures = self._figures()
        picture = [] if self.picture is None else [self._map(self.picture), self.picked]
        main = pn.Column(
            Div(text=heading, width=900),
            *picture,
            self.status,
            pn.Row(self.orbit_button, self.download),
            self.orbit_text,
            figures["x"],
            figures["v"],
            pn.Row(figures["p1"], figures["p2"]),
            Div(text="<b>Switching events</b>"),
            self._event_table(),
        )
        return pn.Row(pn.Column(sidebar, height=900, scroll=True, width=280), main)

    def _figures(self) -> dict[str, Any]:
        found = {}
        line = self.sources["line"]
        for key, label, title in (("x", "displacement (m)", "displacements"), ("v", "velocity (m/s)", "velocities")):
            fig = figure(title=title, height=300, width=760, x_axis_label="t (s)", y_axis_label=label, tools=_TOOLS)
            self._shade(fig)
            lines = [
                _keyed(fig, "line", f"m{mass}", "t", f"{key}{mass}", source=line, color=COLOURS[mass])
                for mass in (1, 2)
            ]
            fig.x_range = DataRange1d(renderers=lines)
            fig.y_range = DataRange1d(renderers=lines)  # the shading spans any height: not in the range
            if key == "x":
                _keyed(fig, "scatter", "events", "t", "x", source=self.sources["events"], size=3, color="#444444")
            fig.add_layout(fig.legend[0], "right")
            found[key] = fig
        for mass in (1, 2):
            fig = figure(
                title=f"m{mass}: phase portrait, stroboscopic points",
                height=340,
                width=440,
                x_axis_label=f"x{mass} (m)",
                y_axis_label=f"v{mass} (m/s)",
                tools=_TOOLS,
            )
            x, v = f"x{mass}", f"v{mass}"
            drawn = [
                fig.line(x, v, source=line, color=COLOURS[mass], alpha=0.5),
                _keyed(fig, "line", "orbit", x, v, source=self.sources["orbit"], color="orange", line_width=3),
                _keyed(fig, "scatter", "t0 + kT", x, v, source=self.sources["strobe"], size=6, color="black"),
            ]
            fig.x_range, fig.y_range = DataRange1d(renderers=drawn), DataRange1d(renderers=drawn)
            fig.legend.location = "top_left"
            fig.legend.background_fill_alpha = 0.6
            found[f"p{mass}"] = fig
        return found

    def _shade(self, fig: Any) -> None:
        sides = [(f"rest{mass}", f"m{mass} at rest", COLOURS[mass], _SHADE) for mass in (1, 2)]
        sides += [(f"contact_{side}", f"{side} contact", colour, 2 * _SHADE) for side, colour in CONTACT.items()]
        for name, label, colour, alpha in sides:
            _keyed(fig, "quad", label, source=self.sources[name], color=colour, alpha=alpha, line_width=0)

    def _event_table(self) -> DataTable:
        text = StringFormatter()
        titles = {"from_domain": "from", "to_domain": "to"}
        columns = [TableColumn(field="t", title="t (s)", formatter=NumberFormatter(format="0.000000"))] + [
            TableColumn(field=name, title=titles.get(name, name), formatter=text) for name in EVENT_COLUMNS[1:]
        ]
        return DataTable(
            source=self.sources["events"],
            columns=columns,
            width=900,
            height=300,
            index_position=None,
            name="events",
            styles={"will-change": "transform"},  # its own layer: its rows' change recomposites the page 40 ms less
        )

    def _map(self, picture: Picture) -> Any:
        labels = sorted(set(picture.points.label))
        palette = (list(Category10[10]) * (len(labels) // 10 + 1))[: max(len(labels), 3)]
        source = ColumnDataSource({"x": picture.points.x, "y": picture.points.y, "label": picture.points.label})
        fig = figure(
            title=f"{WHAT[picture.kind]} of {picture.case.name}: click a {'cell' if picture.cells else 'point'} "
            "for its attractors",
            height=380,
            width=760,
            x_axis_label=picture.x,
            y_axis_label=picture.y,
            tools="tap,pan,wheel_zoom,reset",  # no hover: its label under the pointer took clicks meant for the map
            name="map",
        )
        colour = factor_cmap("label", palette=palette, factors=labels)
        if picture.cells:
            fig.rect(
                "x",
                "y",
                width=picture.width,
                height=picture.height,
                source=source,
                line_width=0,
                fill_color=colour,
                nonselection_fill_alpha=0.5,
                legend_field="label",
            )
        else:
            fig.scatter("x", "y", source=source, size=4, color=colour, nonselection_alpha=0.4, legend_field="label")
        fig.add_layout(fig.legend[0], "right")
        fig.on_event(Tap, self._tap)
        fig.on_event(DoubleTap, self._tap)  # a click within 0.3 s of the one before is a double tap to Bokeh
        return fig

    # -- computing ----------------------------------------------------------------------------
    def values(self) -> dict[str, float]:
        """The controls' values: every parameter and the start."""
        return {name: float(widget.value) for name, widget in self.widgets.items()}

    def current_case(self) -> Case:
        """The case on screen: the controls' values applied to the case (checked)."""
        return with_changes(self.case, self.values())

    def update(self) -> None:
        """Simulate the case on screen and redraw, the status line with it (one message to the
        page); an impossible value or a failed run is said in the status line and the last
        motion stays."""
        self._cancel_check()
        try:
            periods = check_periods(self.periods_box.value)
            scene = scene_of(self.current_case(), periods, engine=self.engine)
        except OscillatorError as error:
            self._say(str(error), error=True)
            return
        self.scene = scene
        self.revision += 1
        checked = scene.engine != "cvode"
        checking = "; CVODE checks it" if checked else ""
        self._draw(scene, f"<span data-revision='{self.revision}'>{self._summary(scene)}{checking}</span>")
        if checked:
            self._schedule_check()

    def _summary(self, scene: Scene) -> str:
        return (
            f"#{self.revision}: {scene.periods} periods, {len(scene.events)} events; {scene.engine} in "
            f"{1e3 * scene.seconds:.0f} ms ({_plain(scene.status)})"
        )

    def _schedule_check(self) -> None:
        """CVODE's check of the motion drawn, once the controls rest: at once outside a server."""
        document = pn.state.curdoc
        if document is None or document.session_context is None:
            self.check()
            return
        self._check_handle = document.add_timeout_callback(self.check, CHECK_DELAY_MS)

    def _cancel_check(self) -> None:
        handle, self._check_handle = self._check_handle, None
        document = pn.state.curdoc
        if handle is not None and document is not None:
            try:
                document.remove_timeout_callback(handle)
            except ValueError:  # it has run
                pass

    def check(self) -> None:
        """Run the motion on screen again with CVODE, the reference: the status line says that the
        two agree event by event (times within :data:`TIME_AGREEMENT`), or CVODE's motion replaces
        the one drawn and the status line says where they parted."""
        self._check_handle = None
        shown = self.scene
        if shown is None or shown.engine == "cvode":
            return
        try:
            reference = scene_of(shown.case, shown.periods, engine="cvode")
        except OscillatorError as error:
            self._say(f"CVODE could not check the motion: {error}", error=True)
            return
        differ, largest = differences(shown, reference)
        mark = f"data-revision='{self.revision}' data-checked='1'"
        if differ is None:
            gap = f"; largest time difference {largest:.1e} s" if not math.isnan(largest) else ""
            self.status.set_text(
                f"<span {mark}>{self._summary(shown)}; CVODE agrees, event by event "
                f"(in {1e3 * reference.seconds:.0f} ms{gap})</span>"
            )
            return
        self.scene = reference
        self._draw(
            reference,
            f"<span class='oscillator-differs' {mark}>{self._summary(reference)}: CVODE's motion, drawn "
            f"instead of {_plain(shown.engine)}'s: {_plain(differ)} (times compared to {TIME_AGREEMENT:g} s)</span>",
        )

    def _say(self, text: str, *, error: bool = False) -> None:
        self.revision += 1
        kind = " class='oscillator-error'" if error else ""
        self.status.set_text(f"<span{kind} data-revision='{self.revision}'>{_plain(text)}</span>")

    def _draw(self, scene: Scene, status: str) -> None:
        events = scene.events
        x = np.where(events["mass"].to_numpy() == 1, events["x1"].to_numpy(), events["x2"].to_numpy())
        table = {name: events[name].astype(str).to_numpy() for name in EVENT_COLUMNS[1:]}
        with pn.io.hold():
            self.sources["line"].data = {name: scene.trajectory[name].to_numpy() for name in ("t", *STATE)}
            # lists, not arrays: a few points each, sent in the message's text instead of one frame each
            self.sources["strobe"].data = {name: scene.strobe[name].tolist() for name in ("k", *STATE)}
            self.sources["events"].data = {"t": events["t"].to_numpy(), **table, "x": x}
            for mass in (1, 2):
                self.sources[f"rest{mass}"].data = _spans(scene.rests[mass])
            for side in CONTACT:
                self.sources[f"contact_{side}"].data = _spans(scene.contacts[side])
            if len(self.sources["orbit"].data["x1"]):
                self.sources["orbit"].data = {name: [] for name in STATE}
                self.orbit_text.set_text("")
            self.status.set_text(status)

    def _set(self, text: str) -> None:
        """``NAME=VALUE`` typed in the box: the control set to it (its slider widened to hold it)."""
        if not text.strip():
            return
        name, _, value = (part.strip() for part in text.partition("="))
        try:
            if name not in self.widgets:
                raise InputError(f"{name or text!r} is not a parameter or start value; write NAME=VALUE, e.g. K3=2.5")
            number = parse_value(value, field=name)
            if isinstance(number, bool) or not isinstance(number, int | float) or not np.isfinite(number):
                raise InputError(f"{name} must be a finite number, got {value!r}", field=name)
        except OscillatorError as error:
            self._say(str(error), error=True)
            return
        self._put({name: float(number)})
        self.update()

    def _put(self, values: dict[str, float]) -> None:
        """Put ``values`` on the controls (none of them runs: their callbacks follow a drag's end)."""
        for name, value in values.items():
            slider = self.widgets[name]
            slider.start, slider.end = min(slider.start, value), max(slider.end, value)
            slider.value = value

    def _orbit(self, *_: Any) -> None:
        """The periodic orbit near the motion's end, its multipliers and measures (on request)."""
        from oscillator.orbits.shooting import find_orbit

        if self.scene is None:
            return
        try:
            end = self.scene.trajectory.iloc[-1][list(STATE)].to_numpy(float)
            orbit = find_orbit(self.current_case(), guess=end, section=self.scene.t_end)
            one = scene_of(orbit.case, orbit.period, t0=orbit.section, **dict(zip(STATE, orbit.state, strict=True)))
        except OscillatorError as error:
            self.orbit_text.set_text(f"<span class='oscillator-error'>no orbit: {_plain(str(error))}</span>")
            return
        with pn.io.hold():
            self.orbit_text.set_text(_orbit_html(orbit))
            self.sources["orbit"].data = {name: one.trajectory[name].to_numpy() for name in STATE}

    def _tap(self, event: Any) -> None:
        """A click on the map: the attractors there now; the motion from the site's orbit (a
        branch point's) or the first attractor's point on the next tick."""
        assert self.picture is not None
        index = self.picture.nearest(float(event.x), float(event.y))
        started = time.perf_counter()
        try:
            site = self.picture.site(index)
            found = self.picture.attractors(site)
        except OscillatorError as error:
            self.picked.set_text(f"<span class='oscillator-error'>{_plain(str(error))}</span>")
            return
        self.clicks += 1
        seconds = time.perf_counter() - started
        self.picked.set_text(_picked_html(self.picture.label_at(index), site.held, found, seconds, self.clicks))
        state = site.state if site.state is not None else (found.attractors[0].points[0] if found.attractors else None)
        if state is None:
            return
        case = site.case
        values = {name: float(getattr(case.parameters, name)) for name in self.widgets if name not in START}
        self._put(values | dict(zip(START, (float(v) for v in state), strict=True)))
        document = pn.state.curdoc
        if document is not None and document.session_context is not None:
            document.add_next_tick_callback(self.update)  # the attractors reach the page first
        else:
            self.update()

    def _case_file(self) -> io.StringIO:
        return io.StringIO(case_to_toml(self.current_case()))

    def _file_name(self) -> str:
        stem = re.sub(r"[^A-Za-z0-9_.-]+", "-", self.case.name).strip(".-") or "case"
        return f"{stem[:60]}-explored.toml"

    # -- display ------------------------------------------------------------------------------
    def __panel__(self) -> pn.viewable.Viewable:
        return self.layout

    def _repr_mimebundle_(self, include: Any = None, exclude: Any = None) -> Any:
        pn.extension()
        return self.layout._repr_mimebundle_(include, exclude)


def _multipliers(values: Any) -> str:
    return ", ".join(f"{abs(mu):.4g}" for mu in values)


def _picked_html(where: str, held: str, found: Any, seconds: float, click: int) -> str:
    items = []
    for attractor in found.attractors:
        point = ", ".join(f"{v:.6g}" for v in attractor.points[0])
        multipliers = f" |multipliers| {_multipliers(attractor.orbit.multipliers)};" if attractor.orbit else ""
        measures = ", ".join(f"{k} = {attractor.measures[k]:.5g}" for k in MEASURES if k in attractor.measures)
        items.append(
            f"<li data-period='{attractor.period}'><b>{_plain(attractor.name)}</b>: section point "
            f"<span class='point'>({point})</span>;{_plain(multipliers)} {_plain(measures)}</li>"
        )
    return (
        f"<div class='oscillator-picked-found' data-click='{click}' data-count='{len(found.attractors)}'>"
        f"{_plain(where)}: {len(found.attractors)} attractor(s), found in {seconds:.2f} s"
        + (f"<p class='oscillator-held'>{_plain(held)}</p>" if held else "")
        + f"<ul>{''.join(items)}</ul></div>"
    )


def _orbit_html(orbit: Any) -> str:
    rows = "".join(f"<tr><td>{mu.real:+.6g}{mu.imag:+.6g}i</td><td>{abs(mu):.6g}</td></tr>" for mu in orbit.multipliers)
    measures = orbit.response().columns()
    shown = ", ".join(f"{name} = {measures[name]:.6g}" for name in MEASURES if name in measures)
    return (
        f"<div class='oscillator-orbit-found'><b>Period-{orbit.period} orbit</b> at t = {orbit.section:.6g} s: "
        f"{_plain(orbit.verdict)}; residual {orbit.residual:.1e}"
        f"<table><tr><th>multiplier</th><th>modulus</th></tr>{rows}</table><p>{_plain(shown)}</p></div>"
    )
