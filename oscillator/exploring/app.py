"""The explorer's page: move a parameter, see the motion, its switches and its theorems.

:class:`Explorer` holds the controls (:mod:`oscillator.exploring.controls`, in groups with their
units, a box to find one, a reset), the figures and the table (:mod:`oscillator.exploring.page`).
A change asks for a simulation (:func:`~oscillator.exploring.scene.scene_of`), run off the server's
loop by a :class:`~oscillator.exploring.runner.Runner` (one at a time, the last change only, a
burst of key presses run at its first and its last); its result replaces the figures' data, the
title and the status line in one batch, and the page's address says the values changed, so that a
link or a reload shows the same view.  What one change may cost is bounded (events, points) and
said.  The controls, texts and figures are Bokeh's own models (a Panel widget adds a round of
messages and a layout of the page on every change); Panel lays them out, serves them
(:mod:`oscillator.exploring.serving`), displays the same object in a notebook and offers the case
file, the events and the trajectory as downloads.

Every text from a case file (its title, description, name) reaches the page as text.  The page
loads nothing but from the server that serves it.
"""

from __future__ import annotations

import io
import math
import re
import time
import urllib.parse
from typing import Any

import numpy as np
import panel as pn
from bokeh.events import DoubleTap, Tap
from bokeh.layouts import column
from bokeh.models import ColumnDataSource
from bokeh.models.widgets.buttons import Button
from bokeh.models.widgets.inputs import NumericInput, TextInput
from bokeh.models.widgets.markups import Div
from bokeh.models.widgets.sliders import Slider

from oscillator.analysis.axes import STATE
from oscillator.errors import InputError, OscillatorError
from oscillator.exploring.controls import START, Control, groups_of
from oscillator.exploring.maps import Picture
from oscillator.exploring.page import Figures, event_table, map_figure, plain, url_keeper
from oscillator.exploring.runner import Job, Runner
from oscillator.exploring.scene import PERIODS, TIME_AGREEMENT, Explored, Scene, check_periods, differences
from oscillator.exploring.subjects import CaseSubject, ChainSubject, subject_of
from oscillator.io.cases import Case
from oscillator.io.expressions import parse_value
from oscillator.model.chains import FrictionChain
from oscillator.text import did_you_mean

__all__ = ["Explorer", "css_class"]

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
    "impact_power_left",
)
#: The integrator that draws each change: the compiled one, checked against CVODE after it.
DRAWING_ENGINE = "dop853"
#: How long the controls rest before CVODE's check starts (s): a change sooner drops it, and one
#: during the check stops it.
CHECK_DELAY = 0.4


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
    """The explorer of one case or friction chain, or of a folder's map (module docstring).

    Parameters
    ----------
    case : Case, FrictionChain or str
        The system: a case (a name, a case file, or a Case), a friction chain or a system file
        (:mod:`oscillator.exploring.subjects`).
    periods : int
        Forcing periods simulated on every change.
    picture : Picture, optional
        A folder's map (:func:`~oscillator.exploring.maps.picture_of`): a click on it shows the
        attractors there.
    engine : str
        The integrator that draws each change (:mod:`oscillator.engines`): the compiled DOP853 by
        default, whose motion CVODE runs again once the controls rest (:data:`CHECK_DELAY`) and
        either confirms, event by event, or replaces; ``"cvode"`` draws with the reference itself.
        A friction chain is drawn by CVODE, its one engine.
    """

    def __init__(
        self,
        case: Case | FrictionChain | str | CaseSubject | ChainSubject,
        periods: int = PERIODS,
        *,
        picture: Picture | None = None,
        engine: str = DRAWING_ENGINE,
    ) -> None:
        from oscillator.engines import check_engine

        self.subject = subject_of(case)
        #: The system explored, as given (the controls' values apply to it).
        self.case = self.subject.system
        engine = check_engine(engine)
        self.engine = engine if engine in self.subject.engines else self.subject.engines[0]
        self.picture = picture
        self.periods = check_periods(periods)
        #: The number of the last change asked; the status line shows the one drawn.
        self.revision = 0
        self.clicks = 0
        self.scene: Scene | None = None
        self.figures = Figures(self.subject.outline, orbits=self.subject.orbits)
        self.sources = self.figures.sources
        found = self.subject.controls()
        self.groups = groups_of(found)
        self.controls = {control.name: control for control in found}
        self.widgets = {name: self._slider(control) for name, control in self.controls.items()}
        self.status = _Text("", sizing_mode="stretch_width", height=24)
        self.heading = _Text("", sizing_mode="stretch_width")
        self.orbit_text = _Text("", sizing_mode="stretch_width")
        self.picked = _Text("", sizing_mode="stretch_width")
        self.url = url_keeper()
        self.figures.overview.tags = [self.url]  # in the page's document with the figure that holds it
        self._address_problems: list[str] = []
        self.runner = Runner(self._delivered, _on_loop())
        document = pn.state.curdoc
        served = document is not None and document.session_context is not None
        if document is not None and served:  # a page closed: its work dropped
            document.on_session_destroyed(lambda context: self.runner.close())
        given = self._from_address()
        self._build_inputs(int(given.pop("periods", self.periods)))
        self._put(given)
        self.layout = self._layout()
        if served:
            # the first motion once the page is live: a result handed to the server's loop while the page's
            # session was still being set up was never run there (a chain's 20 ms run, under load: 6 pages in 10
            # stayed empty)
            pn.state.onload(self.update)
        else:
            self.update()

    # -- building -----------------------------------------------------------------------------
    def _slider(self, control: Control) -> Slider:
        slider = Slider(
            title=control.title,
            value=control.value,
            start=control.start,
            end=control.end,
            step=control.step,
            format="0[.]00000",
            width=250,
            name=control.name,
            css_classes=[css_class(control.name)],
        )
        slider.on_change("value_throttled", lambda attr, old, new: self.update())  # a drag runs once, when let go
        return slider

    def _build_inputs(self, periods: int) -> None:
        # an example of a control's name, as its owner names it: the article's K3, a chain's last element field
        example = "K3" if "K3" in self.controls else list(self.controls)[-1]
        self._example = f"{example}={2.5 if example == 'K3' else self.controls[example].value:g}"
        self.find_box = TextInput(title="find a control", placeholder=f"e.g. {example}", width=250, name="find")
        self.find_box.on_change("value_input", lambda attr, old, new: self._find(new))
        self.set_box = TextInput(title="set NAME=VALUE (any value)", placeholder=f"e.g. {self._example}", width=250)
        self.set_box.on_change("value", lambda attr, old, new: self._set(new))
        self.periods_box = NumericInput(title="periods", value=periods, low=1, high=10_000, mode="int", width=120)
        self.periods_box.on_change("value", lambda attr, old, new: self.update())
        self.reset_button = Button(label="Reset to the case's values", width=250, name="reset")
        self.reset_button.on_click(self._reset)
        self.orbit_button = Button(label="Orbit and multipliers", width=180)
        self.orbit_button.on_click(self._orbit)
        stem = re.sub(r"[^A-Za-z0-9_.-]+", "-", self.subject.name).strip(".-")[:60] or "case"
        self.downloads = [
            pn.widgets.FileDownload(callback=callback, filename=f"{stem}-{name}", label=label, width=180)
            for callback, name, label in (
                (self._case_file, "explored.toml", "Save as case file"),
                (self._events_file, "events.csv", "Save events (CSV)"),
                (self._trajectory_file, "trajectory.csv", "Save trajectory (CSV)"),
            )
        ]

    def _layout(self) -> pn.viewable.Viewable:
        sections: list[Any] = [self.find_box, self.reset_button]
        self._group_titles = {group: Div(text=f"<b>{plain(group)}</b>", name=f"group-{group}") for group in self.groups}
        for group, names in self.groups.items():
            sections += [self._group_titles[group], *(self.widgets[n] for n in names)]
        sidebar = column(*sections, self.set_box, self.periods_box, width=270)
        shown = self.subject.description
        self.description = Div(text=f"<p>{plain(shown)}</p>" if shown else "", sizing_mode="stretch_width")
        picture: list[Any] = []
        if self.picture is not None:
            self._picked_source = ColumnDataSource({"x": [], "y": []})
            shown_map = map_figure(self.picture, self._picked_source)
            shown_map.on_event(Tap, self._tap)
            shown_map.on_event(DoubleTap, self._tap)  # a click within 0.3 s of the one before is a double tap
            picture = [shown_map, self.picked]
        figures = self.figures
        phases = list(figures.phase.values())
        tools = [self.orbit_button] if self.subject.orbits else []
        main = pn.Column(
            self.heading,
            self.description,
            *picture,
            self.status,
            pn.Row(*tools, *self.downloads),
            self.orbit_text,
            figures.overview,
            figures.series["x"],
            figures.series["v"],
            *(pn.Row(*phases[k : k + 2], sizing_mode="stretch_width") for k in range(0, len(phases), 2)),
            Div(text="<b>Switching events</b>"),
            event_table(self.sources["events"], self.subject.outline.event_columns),
            sizing_mode="stretch_width",
        )
        return pn.Row(pn.Column(sidebar, height=900, scroll=True, width=290), main, sizing_mode="stretch_width")

    # -- the values on screen -----------------------------------------------------------------
    def values(self) -> dict[str, float]:
        """The controls' values: every parameter and the start."""
        return {name: float(widget.value) for name, widget in self.widgets.items()}

    def current_case(self) -> Explored:
        """The system on screen: the controls' values applied to the case or chain (checked)."""
        return self.subject.changed(self.values())

    def _put(self, values: dict[str, float]) -> None:
        """Put ``values`` on the controls (none of them runs: their callbacks follow a drag's end)."""
        for name, value in values.items():
            slider = self.widgets[name]
            slider.start, slider.end = min(slider.start, value), max(slider.end, value)
            slider.value = value

    def _reset(self, *_: Any) -> None:
        """Every control back to the case's value (its slider's range too), and the periods."""
        for name, control in self.controls.items():
            slider = self.widgets[name]
            slider.start, slider.end, slider.value = control.start, control.end, control.value
        if self.periods_box.value == self.periods:
            self.update()
        else:  # its own callback asks for the motion
            self.periods_box.value = self.periods

    def _find(self, text: str) -> None:
        """Show the controls whose name holds ``text`` (all for an empty one), each group's title
        where any of its controls shows."""
        wanted = text.strip().lower()
        for name, widget in self.widgets.items():
            widget.visible = not wanted or wanted in name.lower()
        for group, names in self.groups.items():
            self._group_titles[group].visible = any(self.widgets[name].visible for name in names)

    def _address(self) -> str:
        """The query that says the values changed from the case's (numbers only), or ``""``."""
        changed = {name: repr(value) for name, value in self.values().items() if value != self.controls[name].value}
        periods = self.periods_box.value
        if periods is not None and periods != self.periods:
            changed["periods"] = str(int(periods))
        return "?" + urllib.parse.urlencode(changed) if changed else ""

    def _from_address(self) -> dict[str, float]:
        """The values the page's address gives (``?Omega=1.54&periods=20``), each checked; a name
        or value that is not one is said in the status line, and left out."""
        document = pn.state.curdoc
        context = getattr(document, "session_context", None) if document is not None else None
        request = getattr(context, "request", None)
        arguments = getattr(request, "arguments", None) or {}
        given: dict[str, float] = {}
        for name, raw in arguments.items():
            text = raw[-1].decode("utf-8", "replace") if raw else ""
            try:
                if name != "periods" and name not in self.widgets:
                    raise InputError(f"the address names {name[:40]!r}, which is not a parameter or start value")
                number = _number(name, text)
                if name != "periods":
                    self.subject.changed({**given, name: number})  # refused here, not left on a slider
            except OscillatorError as error:
                self._address_problems.append(str(error))
                continue
            given[name] = number
        return given

    # -- computing ----------------------------------------------------------------------------
    def update(self) -> None:
        """Ask for the motion of the case on screen (drawn when it comes, if no later change came
        first); an impossible value is said in the status line and the last motion stays."""
        try:
            periods = check_periods(self.periods_box.value)
            case = self.current_case()
        except OscillatorError as error:
            self._say(str(error), error=True)
            return
        self.revision += 1
        number, engine, subject = self.revision, self.engine, self.subject

        def work(stop: Any) -> Scene:
            return subject.scene(case, periods, engine=engine, stop=stop)

        self.runner.ask(Job(work, number))

    def _delivered(self, job: Job, result: Any, error: BaseException | None) -> None:
        """A job's result, on the server's loop: drawn if it is the last change's."""
        if job.number != self.revision:  # a later change came: its own result will be drawn
            return
        if error is not None:
            self._say(
                str(error) if isinstance(error, OscillatorError) else f"{type(error).__name__}: {error}", error=True
            )
            return
        if isinstance(result, tuple):  # CVODE's check: (the motion checked, the reference)
            self._checked(*result)
            return
        self.scene = result
        checked = result.engine != "cvode"
        checking = "; CVODE checks it" if checked else ""
        self._draw(result, self._status(result, checking))
        if checked:
            shown = result

            subject = self.subject

            def check(stop: Any) -> tuple[Scene, Scene]:
                return shown, subject.scene(shown.case, shown.periods, engine="cvode", stop=stop)

            self.runner.ask(Job(check, job.number, wait=CHECK_DELAY, kind="check"), change=False)

    def _marks(self, kind: str = "", *, checked: bool = False) -> str:
        """The status line's attributes: its class (``kind``), the revision it shows, the
        simulations drawn and the bursts of changes seen, and whether CVODE checked it."""
        runner = self.runner
        marks = f" class='{kind}'" if kind else ""
        marks += f" data-revision='{self.revision}' data-runs='{runner.ran['draw']}' data-bursts='{runner.bursts}'"
        return marks + (" data-checked='1'" if checked else "")

    def _status(self, scene: Scene, tail: str = "", *, checked: bool = False, kind: str = "") -> str:
        text = (
            f"#{self.revision}: {scene.periods} periods, {len(scene.events)} events; {scene.engine} in "
            f"{1e3 * scene.seconds:.0f} ms ({plain(scene.status)}){tail}"
        )
        problems = "".join(f"; {plain(p)}" for p in self._address_problems)
        kind = kind or ("oscillator-bounded" if scene.bounded else "")
        return f"<span{self._marks(kind, checked=checked)}>{text}{problems}</span>"

    def check(self) -> None:
        """Run the motion on screen again with CVODE now (in this thread), and say how it compares."""
        if self.scene is not None and self.scene.engine != "cvode":
            self._checked(self.scene, self.subject.scene(self.scene.case, self.scene.periods, engine="cvode"))

    def _checked(self, shown: Scene, reference: Scene) -> None:
        """CVODE's verdict on the motion drawn: the status line says that the two agree event by
        event (times within :data:`TIME_AGREEMENT`), or CVODE's motion replaces the one drawn."""
        differ, largest = differences(shown, reference)
        if differ is None:
            gap = f"; largest time difference {largest:.1e} s" if not math.isnan(largest) else ""
            tail = f"; CVODE agrees, event by event (in {1e3 * reference.seconds:.0f} ms{gap})"
            self.status.set_text(self._status(shown, tail, checked=True))
            return
        self.scene = reference
        tail = (
            f": CVODE's motion, drawn instead of {plain(shown.engine)}'s: {plain(differ)} (times compared to "
            f"{TIME_AGREEMENT:g} s)"
        )
        self._draw(reference, self._status(reference, tail, checked=True, kind="oscillator-differs"))

    def _say(self, text: str, *, error: bool = False) -> None:
        """``text`` in the status line, as a revision of its own (a motion asked before is not drawn)."""
        self.revision += 1
        self.status.set_text(f"<span{self._marks('oscillator-error' if error else '')}>{plain(text)}</span>")

    def _draw(self, scene: Scene, status: str) -> None:
        with pn.io.hold():
            self.figures.draw(scene)
            self.heading.set_text(self._heading())
            self.orbit_text.set_text("")
            self.url.data = {"query": [self._address()]}
            self.status.set_text(status)

    def _heading(self) -> str:
        """The case's title and, below it, what the page changed from it (``Omega 1.6 -> 1.54``)."""
        changed = [
            f"{name} {_short(self.controls[name].value)} → {_short(value)}"
            for name, value in self.values().items()
            if value != self.controls[name].value
        ]
        listed = ", ".join(changed[:8]) + (f" and {len(changed) - 8} more" if len(changed) > 8 else "")
        below = f"<p class='oscillator-changed'>changed here: {plain(listed)}</p>" if changed else ""
        return f"<h2 class='oscillator-title'>{plain(self.subject.title)}</h2>{below}"

    def _set(self, text: str) -> None:
        """``NAME=VALUE`` typed in the box: the control set to it (its slider widened to hold it)."""
        if not text.strip():
            return
        name, _, value = (part.strip() for part in text.partition("="))
        try:
            if name not in self.widgets:
                raise InputError(
                    f"{name or text!r} is not a parameter or start value{did_you_mean(name, list(self.widgets))}; "
                    f"write NAME=VALUE, e.g. {self._example}"
                )
            number = _number(name, value)
            self.subject.changed({**self.values(), name: number})  # refused here, not left on the slider
        except OscillatorError as error:
            self._say(str(error), error=True)
            return
        self._put({name: number})
        self.update()

    def _orbit(self, *_: Any) -> None:
        """The periodic orbit near the motion's end, its multipliers and measures (on request)."""
        from oscillator.exploring.scene import scene_of
        from oscillator.orbits.shooting import find_orbit

        if self.scene is None or not isinstance(self.scene.case, Case):
            return
        try:
            end = self.scene.trajectory.iloc[-1][list(STATE)].to_numpy(float)
            orbit = find_orbit(self.scene.case, guess=end, section=self.scene.t_end)
            one = scene_of(orbit.case, orbit.period, t0=orbit.section, **dict(zip(STATE, orbit.state, strict=True)))
        except OscillatorError as error:
            self.orbit_text.set_text(f"<span class='oscillator-error'>no orbit: {plain(str(error))}</span>")
            return
        with pn.io.hold():
            self.orbit_text.set_text(_orbit_html(orbit))
            self.sources["orbit"].data = self.figures.state(one.trajectory)

    def _tap(self, event: Any) -> None:
        """A click on the map: the attractors there now; the motion from the site's orbit (a
        branch point's) or the first attractor's point on the next tick.  A click outside the
        cells is said, and picks nothing (it picked the nearest cell, which the map did not show)."""
        assert self.picture is not None and isinstance(self.case, Case)
        if not self.picture.inside(float(event.x), float(event.y)):
            self.picked.set_text(
                "<span class='oscillator-error'>click inside the map: that is outside its cells</span>"
            )
            return
        index = self.picture.nearest(float(event.x), float(event.y))
        started = time.perf_counter()
        try:
            site = self.picture.site(index)
            found = self.picture.attractors(site)
        except OscillatorError as error:
            self.picked.set_text(f"<span class='oscillator-error'>{plain(str(error))}</span>")
            return
        self.clicks += 1
        seconds = time.perf_counter() - started
        row = self.picture.points.iloc[index]
        self._picked_source.data = {"x": [float(row.x)], "y": [float(row.y)]}
        self.picked.set_text(_picked_html(self.picture.label_at(index), site.held, found, seconds, self.clicks))
        state = site.state if site.state is not None else (found.attractors[0].points[0] if found.attractors else None)
        if state is None:
            return
        values = {name: float(getattr(site.case.parameters, name)) for name in self.widgets if name not in START}
        self._put(values | dict(zip(START, (float(v) for v in state), strict=True)))
        self.update()

    def _case_file(self) -> io.StringIO:
        return io.StringIO(self.subject.toml(self.current_case()))

    def _events_file(self) -> io.StringIO:
        return io.StringIO("" if self.scene is None else self.scene.events.to_csv(index=False))

    def _trajectory_file(self) -> io.StringIO:
        return io.StringIO("" if self.scene is None else self.scene.trajectory.to_csv(index=False))

    # -- display ------------------------------------------------------------------------------
    def __panel__(self) -> pn.viewable.Viewable:
        return self.layout

    def _repr_mimebundle_(self, include: Any = None, exclude: Any = None) -> Any:
        pn.extension()
        return self.layout._repr_mimebundle_(include, exclude)


def css_class(name: str) -> str:
    """The class of ``name``'s control on the page: ``control-K3``; a chain's ``platform.F``,
    ``blade damping.c`` as ``control-platform-F``, ``control-blade-damping-c`` (one class, no
    selector's punctuation)."""
    return "control-" + re.sub(r"[^A-Za-z0-9_-]", "-", name)


def _on_loop() -> Any:
    """How a thread hands a call to the server's loop (the document's next tick), or None outside
    a server (a notebook: the jobs run at once)."""
    document = pn.state.curdoc
    if document is None or document.session_context is None:
        return None
    return document.add_next_tick_callback


def _number(name: str, text: str) -> float:
    """``text`` as a finite number for ``name`` (``pi/2`` allowed; periods a whole number)."""
    number = parse_value(text, field=name)
    if isinstance(number, bool) or not isinstance(number, int | float) or not np.isfinite(number):
        raise InputError(f"{name} must be a finite number, got {text!r}", field=name)
    if name == "periods":
        check_periods(int(number) if float(number).is_integer() else number)
    return float(number)


def _short(value: float) -> str:
    return f"{value:.6g}"


def _multipliers(values: Any) -> str:
    return ", ".join(f"{abs(mu):.4g}" for mu in values)


def _picked_html(where: str, held: str, found: Any, seconds: float, click: int) -> str:
    items = []
    for attractor in found.attractors:
        point = ", ".join(f"{v:.6g}" for v in attractor.points[0])
        multipliers = f" |multipliers| {_multipliers(attractor.orbit.multipliers)};" if attractor.orbit else ""
        measures = ", ".join(f"{k} = {attractor.measures[k]:.5g}" for k in MEASURES if k in attractor.measures)
        items.append(
            f"<li data-period='{attractor.period}'><b>{plain(attractor.name)}</b>: section point "
            f"<span class='point'>({point})</span>;{plain(multipliers)} {plain(measures)}</li>"
        )
    return (
        f"<div class='oscillator-picked-found' data-click='{click}' data-count='{len(found.attractors)}'>"
        f"{plain(where)}: {len(found.attractors)} attractor(s), found in {seconds:.2f} s"
        + (f"<p class='oscillator-held'>{plain(held)}</p>" if held else "")
        + f"<ul>{''.join(items)}</ul></div>"
    )


def _orbit_html(orbit: Any) -> str:
    rows = "".join(f"<tr><td>{mu.real:+.6g}{mu.imag:+.6g}i</td><td>{abs(mu):.6g}</td></tr>" for mu in orbit.multipliers)
    measures = orbit.response().columns()
    shown = ", ".join(f"{name} = {measures[name]:.6g}" for name in MEASURES if name in measures)
    return (
        f"<div class='oscillator-orbit-found'><b>Period-{orbit.period} orbit</b> at t = {orbit.section:.6g} s: "
        f"{plain(orbit.verdict)}; residual {orbit.residual:.1e}"
        f"<table><tr><th>multiplier</th><th>modulus</th></tr>{rows}</table><p>{plain(shown)}</p></div>"
    )
