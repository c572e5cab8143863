"""Figures in the article's style (Figs. 9-13, panels a-d, and Fig. 14), as PNG and SVG.

(a) displacements with the displacement boundaries ``x1 = d1`` and ``x1 = x2 - d``;
(b) velocities with the velocity boundary ``v = 0`` and rest intervals shaded;
(c) phase portraits of each mass with its domains and boundaries;
(d) G-function (force) histories: the real field solid, the other side's ("imaginary") field
dashed, and the flow-barrier fields dotted while a mass rests.

Start points are green stars; every kind of switching event has its own marker
(:data:`KIND_STYLE`), the same in every figure.  Legends sit outside the axes, so they hide no
data, and every axis names its unit.  A long run is drawn over a window of it
(:func:`figure_window`): its last 10 forcing periods by default, and the window is named in
the titles.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np
import pandas as pd

from oscillator.analysis.intervals import rest_intervals
from oscillator.errors import InputError
from oscillator.io.files import atomic_path, inner_folder
from oscillator.model.events import EventKind
from oscillator.model.fields import flow_barrier_field, kinetic_field, non_friction_force
from oscillator.model.parameters import Parameters
from oscillator.model.phase_space import contacts_of_state, velocity_sign
from oscillator.model.system import ARTICLE

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure
    from matplotlib.transforms import Bbox

    from oscillator.io.cases import Case

__all__ = [
    "FIGURES",
    "KIND_STYLE",
    "MASS_COLOR",
    "Window",
    "draw_figures",
    "draw_panel",
    "event_marker",
    "figure_title",
    "figure_window",
    "force_histories",
    "missing_figures",
    "outside_legend",
    "save_figure",
    "write_figures",
]

#: Figure files (without suffix) and what each shows.
FIGURES = {
    "fig-a-displacement": "(a) displacements and displacement boundaries",
    "fig-b-velocity": "(b) velocities, velocity boundary and rest intervals",
    "fig-c-phase": "(c) phase portraits with domains and boundaries",
    "fig-d-forces": "(d) G-function (force) histories",
}
MASS_COLOR = {1: "tab:blue", 2: "black"}
#: Marker, face colour and size (points², in the time panels) of each kind of event, in every
#: figure; the start is a green star.  Kinds whose events can fall on one point are drawn
#: largest first, each on top of the larger ones, so that every marker shows: a rest begins and
#: ends at one displacement (a square with a diamond inside), a contact's onset and release lie
#: on its stop, and an event at the start sits on the star (drawn under every event).
KIND_STYLE: dict[EventKind, tuple[str, str, float]] = {
    EventKind.PASSABLE: ("o", "gold", 46),
    EventKind.SLIDING_ONSET: ("s", "white", 110),
    EventKind.SLIDING_VANISH: ("D", "deepskyblue", 34),
    EventKind.GRAZING: ("v", "tab:red", 46),
    EventKind.RIGHT_CONTACT_ONSET: (">", "tab:red", 80),
    EventKind.RIGHT_CONTACT_RELEASE: ("<", "mistyrose", 30),
    EventKind.LEFT_CONTACT_ONSET: ("P", "tab:pink", 80),
    EventKind.LEFT_CONTACT_RELEASE: ("X", "lavenderblush", 30),
}
#: The start's star: larger than every event's marker, and under them.
_START_SIZE = 240
#: Each kind's layer: the larger its marker, the lower it lies.
_LAYER = {kind: 6 + rank for rank, kind in enumerate(sorted(KIND_STYLE, key=lambda k: -KIND_STYLE[k][2]))}
#: A run longer than this many forcing periods is drawn over its last :data:`SHOWN_PERIODS`.
LONG_RUN_PERIODS = 20
SHOWN_PERIODS = 10
#: Resolution of the PNG files (dots per inch).
SAVED_DPI = 110


@dataclass(frozen=True)
class Window:
    """The time window drawn, and how the titles name it (empty for the whole run)."""

    start: float
    stop: float
    label: str = ""


class Panel(NamedTuple):
    """What every panel (a)-(d) draws from: the run's tables over the window, its parameters
    and start, the figure's title and the window."""

    trajectory: pd.DataFrame
    events: pd.DataFrame
    p: Parameters
    t0: float
    y0: Sequence[float]
    title: str
    window: Window


def figure_window(t0: float, t_final: float, period: float, window: tuple[float, float] | None = None) -> Window:
    """The window to draw: ``window`` (checked to lie in the run), else the whole run, or its
    last :data:`SHOWN_PERIODS` forcing periods if it is longer than :data:`LONG_RUN_PERIODS`."""
    if window is not None:
        a, b = (float(v) for v in window)
        if not (math.isfinite(a) and math.isfinite(b) and t0 <= a < b <= t_final):
            raise InputError(
                f"window {a:g} {b:g} must be two times T0 < T1 within the run [{t0:.10g}, {t_final:.10g}] s",
                field="window",
            )
        return Window(a, b, f"t in [{a:.6g}, {b:.6g}] s")
    periods = (t_final - t0) / period
    if periods > LONG_RUN_PERIODS:
        return Window(
            t_final - SHOWN_PERIODS * period, t_final, f"the last {SHOWN_PERIODS} of {periods:.0f} forcing periods"
        )
    return Window(t0, t_final)


def _dense(trajectory: pd.DataFrame, points: int) -> pd.DataFrame:
    """The trajectory with extra rows, linear in the state, inside each step of one mode.

    During rest the state is constant, so the forces (driven by ``sin(Omega t)``) are then
    exact; during motion CVODE's steps are short against the motion's curvature.
    """
    t = trajectory.t.to_numpy()
    if len(t) < 2 or t[-1] == t[0]:
        return trajectory
    numbers = ["t", *ARTICLE.state]
    labels = ["domain1", "domain2", "system_state"]
    values = trajectory[numbers].to_numpy(float)
    same = np.ones(len(t) - 1, dtype=bool)
    for column in labels:
        label = trajectory[column].to_numpy()
        same &= label[:-1] == label[1:]
    # step i gives its start and, inside one mode, floor(h / spacing) evenly spaced points more
    extra = np.where(same, np.floor(np.diff(t) / ((t[-1] - t[0]) / points)), 0).astype(int)
    counts = np.where(extra >= 1, extra + 1, 1)
    step = np.repeat(np.arange(len(t) - 1), counts)
    w = ((np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)) / counts[step])[:, None]
    dense = pd.DataFrame((1 - w) * values[step] + w * values[step + 1], columns=numbers)
    for column in labels:
        dense[column] = trajectory[column].to_numpy()[step]
    return pd.concat([dense[trajectory.columns], trajectory.iloc[[-1]]], ignore_index=True)


def force_histories(trajectory: pd.DataFrame, p: Parameters, *, points: int = 2000) -> pd.DataFrame:
    """Per time and mass: the real field, the other side's, and the flow barriers.

    Columns ``F{i}_real`` (``F_i`` of the current domain, 0 at rest (4.12)), ``F{i}_plus`` and
    ``F{i}_minus`` (the kinetic fields of the ``v > 0`` and ``v < 0`` sides), ``F{i}_barrier_plus``
    and ``F{i}_barrier_minus`` (flow-barrier fields, NaN while the mass moves), on the
    trajectory's times plus about ``points`` more.
    """
    rows = []
    for row in _dense(trajectory, points).itertuples(index=False):
        left, right = contacts_of_state(row.system_state)
        forces = non_friction_force(row.t, (row.x1, row.v1, row.x2, row.v2), p, left, right)
        entry = {"t": row.t}
        for mass, domain in ((1, row.domain1), (2, row.domain2)):
            s = velocity_sign(mass, domain)
            force = forces[mass - 1]
            entry[f"F{mass}_real"] = kinetic_field(p, mass, s, force)
            entry[f"F{mass}_plus"] = kinetic_field(p, mass, 1, force)
            entry[f"F{mass}_minus"] = kinetic_field(p, mass, -1, force)
            resting = s == 0
            entry[f"F{mass}_barrier_plus"] = flow_barrier_field(p, mass, 1, force) if resting else np.nan
            entry[f"F{mass}_barrier_minus"] = flow_barrier_field(p, mass, -1, force) if resting else np.nan
        rows.append(entry)
    return pd.DataFrame(rows)


def rest_spans(trajectory: pd.DataFrame, events: pd.DataFrame, mass: int) -> list[tuple[float, float]]:
    """The intervals in which ``mass`` rests over the trajectory's span, from its events
    (:func:`~oscillator.analysis.intervals.rest_intervals`), not from the trajectory's rows: a
    coarse sampling grid misses short rests.  Whether it rests at the first row is read there."""
    if trajectory.empty:
        return []
    t = trajectory.t.to_numpy(float)
    resting = int(trajectory[f"domain{mass}"].iloc[0]) == 0
    return rest_intervals(events, mass, resting, float(t[0]), float(t[-1]))


def _far_boundaries(ax: Axes, motion: np.ndarray, boundaries: list[tuple[Any, np.ndarray]], axis: str) -> None:
    """Scale ``axis`` to the motion and to the boundaries near it.  A boundary (its line, its
    values) farther from the motion than the motion's own extent (a stop switched off with
    ``d = 1000``) is left out of the scale, and its legend entry says where it is."""
    values = np.asarray(motion, float)
    values = values[np.isfinite(values)]
    if not len(values):
        return
    low, high = float(values.min()), float(values.max())
    reach = high - low if high > low else max(1.0, abs(high))
    shown_low, shown_high = low, high
    for line, boundary in boundaries:
        b = np.asarray(boundary, float)
        b = b[np.isfinite(b)]
        if not len(b):
            continue
        if b.min() > high + reach or b.max() < low - reach:
            above = bool(b.min() > high)
            arrow = ("↑" if above else "↓") if axis == "y" else ("→" if above else "←")
            value = float(b.min() if above else b.max())
            line.set_label(f"{line.get_label()}: off the scale {arrow} at {value:.6g} m")
        else:
            shown_low, shown_high = min(shown_low, float(b.min())), max(shown_high, float(b.max()))
    margin = 0.06 * (shown_high - shown_low if shown_high > shown_low else reach)
    (ax.set_ylim if axis == "y" else ax.set_xlim)(shown_low - margin, shown_high + margin)


def event_marker(kind: str, scale: float = 1.0) -> dict[str, Any]:
    """The scatter options of a kind's markers (sizes times ``scale``), in the kind's layer."""
    marker, face, size = KIND_STYLE[EventKind(kind)]
    return {
        "marker": marker,
        "facecolor": face,
        "edgecolor": "black",
        "s": size * scale,
        "zorder": _LAYER[EventKind(kind)],
    }


def _mark_events(ax: Axes, events: pd.DataFrame, mass: int, column: str, label_kinds: set[Any]) -> None:
    for kind, rows in events[events.mass == mass].groupby("kind"):
        label = kind.replace("_", " ") if kind not in label_kinds else None
        label_kinds.add(kind)
        x, y = (rows[f"x{mass}"], rows[f"v{mass}"]) if column == "phase" else (rows.t, rows[column])
        ax.scatter(x, y, label=label, **event_marker(kind))


def _start(ax: Axes, x: float, y: float, label: str | None = None) -> None:
    ax.scatter([x], [y], s=_START_SIZE, marker="*", color="limegreen", edgecolor="black", zorder=5, label=label)


def outside_legend(ax: Axes, **options: Any) -> None:
    """The legend to the right of the axes, where it hides no data."""
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, fontsize=8, **options)


def _titled(title: str, panel: str, window: Window) -> str:
    return " — ".join(part for part in (title, panel, window.label) if part)


def _finish_time_panel(
    ax: Axes,
    events: pd.DataFrame,
    t0: float,
    y0: Sequence[float],
    quantity: str,
    ylabel: str,
    title: str,
    window: Window,
) -> None:
    """Start points, switching points of both masses (``quantity`` is ``x`` or ``v``), labels."""
    seen: set[Any] = set()
    offset = 0 if quantity == "x" else 1
    for mass in (1, 2):
        if window.start <= t0 <= window.stop:
            _start(ax, t0, y0[2 * mass - 2 + offset], label="start" if mass == 1 else None)
        _mark_events(ax, events, mass, f"{quantity}{mass}", seen)
    ax.set(xlabel="time t (s)", ylabel=ylabel)
    ax.set_title(title, parse_math=False)  # the case's name is text, never mathtext
    outside_legend(ax)


def _figure(width: float, height: float) -> Figure:
    """A new figure of ``width`` x ``height`` inches, laid out by matplotlib's constrained layout
    (matplotlib is imported here, when a figure is drawn: a run without figures never loads it)."""
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height), layout="constrained")


def _displacements(panel: Panel) -> Figure:
    trajectory, events, p, t0, y0, title, window = panel
    fig = _figure(10, 4.5)
    ax = fig.subplots()
    t = trajectory.t
    ax.plot(t, trajectory.x1, color=MASS_COLOR[1], label="$x_1$ (m1)")
    ax.plot(t, trajectory.x2, color=MASS_COLOR[2], label="$x_2$ (m2)")
    right = ax.axhline(p.d1, color="tab:red", ls="--", lw=1, label=r"$x_1 = d_1$ (right stop, $\partial\Omega_{13}$)")
    (left,) = ax.plot(
        t,
        trajectory.x2 - p.d,
        color="tab:pink",
        ls="--",
        lw=1,
        label=r"$x_1 = x_2 - d$ (left stop, $\partial\Omega_{15}$)",
    )
    _far_boundaries(
        ax,
        np.concatenate([trajectory.x1, trajectory.x2]),
        [(right, np.array([p.d1])), (left, trajectory.x2 - p.d)],
        "y",
    )
    _finish_time_panel(ax, events, t0, y0, "x", "displacement (m)", _titled(title, "(a) displacements", window), window)
    return fig


def _velocities(panel: Panel) -> Figure:
    trajectory, events, _, t0, y0, title, window = panel
    fig = _figure(10, 4.5)
    ax = fig.subplots()
    t = trajectory.t
    for mass in (1, 2):
        ax.plot(t, trajectory[f"v{mass}"], color=MASS_COLOR[mass], label=f"$v_{mass}$ (m{mass})")
        for i, (a, b) in enumerate(rest_spans(trajectory, events, mass)):
            ax.axvspan(a, b, color=MASS_COLOR[mass], alpha=0.12, label=f"m{mass} at rest (sliding)" if i == 0 else None)
    ax.axhline(0.0, color="black", ls="--", lw=1, label=r"velocity boundary $v = 0$ ($\partial\Omega_{12}$)")
    _finish_time_panel(ax, events, t0, y0, "v", "velocity (m/s)", _titled(title, "(b) velocities", window), window)
    return fig


def _with_velocity_boundary(ax: Axes) -> None:
    """Widen the velocity axis so that it shows ``v = 0`` with both sides of it."""
    low, high = ax.get_ylim()
    margin = 0.08 * (high - low)
    ax.set_ylim(min(low, -margin), max(high, margin))


def _phase(panel: Panel) -> Figure:
    trajectory, events, p, t0, y0, title, window = panel
    fig = _figure(11, 5)
    axes = fig.subplots(1, 2)
    for ax, mass in zip(axes, (1, 2), strict=True):
        x, v = trajectory[f"x{mass}"], trajectory[f"v{mass}"]
        still = len(x) > 0 and np.ptp(x.to_numpy(float)) == 0 and np.ptp(v.to_numpy(float)) == 0
        ax.plot(x, v, color=MASS_COLOR[mass], lw=1.2, label=f"m{mass}")
        if still:  # a curve of one point draws nothing: mark the point and say so
            ax.plot(x.iloc[:1], v.iloc[:1], "o", color=MASS_COLOR[mass], ms=5, zorder=4)
            ax.text(
                0.5,
                0.6,
                f"m{mass} does not move in this window: x{mass} = {x.iloc[0]:.6g} m, v{mass} = {v.iloc[0]:.3g} m/s",
                transform=ax.transAxes,
                ha="center",
                fontsize=8,
                parse_math=False,
            )
        ax.axhline(0.0, color="black", ls="--", lw=1, label="velocity boundary $v = 0$")
        motion = x.to_numpy(float)
        if still:
            motion = np.array([motion[0] - 1.0, motion[0] + 1.0])
            ax.set_ylim(-1.0, 1.0)
        if mass == 1:
            stop = ax.axvline(p.d1, color="tab:red", ls="--", lw=1, label=r"$x_1 = d_1$ (right stop)")
            _far_boundaries(ax, motion, [(stop, np.array([p.d1]))], "x")
        else:
            _far_boundaries(ax, motion, [], "x")
        if window.start <= t0 <= window.stop:
            _start(ax, y0[2 * mass - 2], y0[2 * mass - 1], label="start")
        _mark_events(ax, events, mass, "phase", set())
        if not still:
            _with_velocity_boundary(ax)  # the labels below sit on their own side of it
        names = ("Ω1(1): v1 > 0", "Ω2(1): v1 < 0") if mass == 1 else ("Ω2(2): v2 > 0", "Ω1(2): v2 < 0")
        ax.text(0.02, 0.97, names[0], transform=ax.transAxes, fontsize=8, va="top")
        ax.text(0.02, 0.03, names[1], transform=ax.transAxes, fontsize=8, va="bottom")
        ax.set(xlabel=f"displacement $x_{mass}$ (m)", ylabel=f"velocity $v_{mass}$ (m/s)", title=f"m{mass}")
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), fontsize=8, ncols=2)
    fig.suptitle(_titled(title, "(c) phase portraits", window), parse_math=False)
    return fig


def _forces(panel: Panel) -> Figure:
    trajectory, events, p, _, _, title, window = panel
    histories = force_histories(trajectory, p)
    fig = _figure(10, 7)
    axes = fig.subplots(2, 1, sharex=True)
    for ax, mass in zip(axes, (1, 2), strict=True):
        _force_lines(ax, histories, mass)
        ax.axhline(0.0, color="grey", lw=0.8)
        for a, b in rest_spans(trajectory, events, mass):
            ax.axvspan(a, b, color=MASS_COLOR[mass], alpha=0.1)
        times = events.t[events.mass == mass].to_numpy()
        ax.vlines(
            times,
            0,
            1,
            transform=ax.get_xaxis_transform(),
            color="tab:red",
            lw=0.6,
            alpha=0.6,
            label=f"switching times of m{mass}",
        )
        ax.set(ylabel=f"force per unit mass on m{mass} (N/kg)")
        outside_legend(ax)
    axes[-1].set(xlabel="time t (s)")
    fig.suptitle(_titled(title, "(d) G-functions (forces)", window), parse_math=False)
    return fig


#: The forces drawn per mass: column suffix, colour, line style, width and legend (``{m}`` the
#: mass, ``{side}`` the domain on the ``v > 0`` or ``v < 0`` side).
_FORCE_LINES = (
    ("plus", "tab:orange", "--", 1.0, "$F_{m}^{{({side})}}$ ($v_{m} > 0$ side)"),
    ("minus", "tab:green", "--", 1.0, "$F_{m}^{{({side})}}$ ($v_{m} < 0$ side)"),
    ("barrier_plus", "tab:orange", ":", 1.5, "flow barrier $F_{m}^{{(0>0_{side})}}$"),
    ("barrier_minus", "tab:green", ":", 1.5, "flow barrier $F_{m}^{{(0>0_{side})}}$"),
)


def _force_lines(ax: Axes, histories: pd.DataFrame, mass: int) -> None:
    """The real force on ``mass`` and the G-functions on either side of its velocity boundary."""
    t = histories.t
    ax.plot(t, histories[f"F{mass}_real"], color=MASS_COLOR[mass], label=f"real $F_{mass}$ (current domain)")
    plus, minus = (1, 2) if mass == 1 else (2, 1)
    for suffix, color, style, width, label in _FORCE_LINES:
        side = plus if suffix.endswith("plus") else minus
        ax.plot(
            t, histories[f"F{mass}_{suffix}"], color=color, ls=style, lw=width, label=label.format(m=mass, side=side)
        )


def save_figure(fig: Figure, directory: Path, name: str, *, tight: bool = True) -> list[Path]:
    """Save a figure as PNG and SVG, each atomically (temporary name, then rename); ``tight``:
    cropped to what is drawn."""
    paths = [directory / f"{name}{suffix}" for suffix in (".png", ".svg")]
    engine, dpi = fig.get_layout_engine(), fig.get_dpi()
    try:
        box = _laid_out(fig, tight)
        for path in paths:
            with atomic_path(path) as temporary:
                fig.savefig(temporary, format=path.suffix[1:], dpi=SAVED_DPI, bbox_inches=box)
    finally:  # the figure as it was: its layout engine and resolution
        fig.set_layout_engine(engine)
        fig.set_dpi(dpi)
    return paths


def _laid_out(fig: Figure, tight: bool) -> Bbox | None:
    """Lay ``fig`` out once at :data:`SAVED_DPI` and hold that layout for each format saved; its
    drawn extent, padded as matplotlib pads ``bbox_inches="tight"``, when ``tight``.

    matplotlib lays a figure out and measures its text again for every file it writes; a figure
    is most of a run's cost (``benchmarks/figures.py``), and laid out once it is drawn once per
    format."""
    import matplotlib as mpl
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fig.set_dpi(SAVED_DPI)
    renderer = FigureCanvasAgg(fig).get_renderer()  # type: ignore[no-untyped-call]
    fig.draw_without_rendering()  # the layout engine places the axes
    box = fig.get_tightbbox(renderer).padded(mpl.rcParams["savefig.pad_inches"]) if tight else None
    # no engine at all: matplotlib draws a figure with one (even "none"'s placeholder) once more
    # before each file, only to run it
    with mpl.rc_context({"figure.autolayout": False, "figure.constrained_layout.use": False}):
        fig.set_layout_engine(None)
    return box


def missing_figures(directory: Path) -> list[str]:
    """The figures of :data:`FIGURES` of which ``directory`` lacks the PNG or the SVG file, or
    holds an empty one (left by a full disk)."""

    def drawn(path: Path) -> bool:
        try:
            return path.is_file() and path.stat().st_size > 0
        except OSError:
            return False

    return [name for name in FIGURES if not all(drawn(directory / f"{name}{s}") for s in (".png", ".svg"))]


_PANELS: dict[str, Callable[[Panel], Figure]] = {
    "fig-a-displacement": _displacements,
    "fig-b-velocity": _velocities,
    "fig-c-phase": _phase,
    "fig-d-forces": _forces,
}


def _clipped(trajectory: pd.DataFrame, events: pd.DataFrame, window: Window) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The rows inside the window, and the state at its two ends interpolated between the rows
    around them: the curves reach the window's edges, even when no row (a coarse ``--sample``
    grid) falls inside it."""
    t = trajectory.t.to_numpy(float)
    inside = (t >= window.start) & (t <= window.stop)

    def at(edge: float) -> list[pd.DataFrame]:
        k = int(np.searchsorted(t, edge))
        if not 0 < k < len(t) or t[k] == edge:
            return []
        w = (edge - t[k - 1]) / (t[k] - t[k - 1])
        row = trajectory.iloc[[k - 1]].copy()
        for column in ("t", *ARTICLE.state):
            row[column] = (1 - w) * trajectory[column].iloc[k - 1] + w * trajectory[column].iloc[k]
        return [row]

    clipped = pd.concat([*at(window.start), trajectory[inside], *at(window.stop)])
    return clipped.reset_index(drop=True), events[(events.t >= window.start) & (events.t <= window.stop)]


#: What :func:`draw_panel` accepts for each panel.
PANEL_NAMES = {
    "a": "fig-a-displacement",
    "displacement": "fig-a-displacement",
    "b": "fig-b-velocity",
    "velocity": "fig-b-velocity",
    "c": "fig-c-phase",
    "phase": "fig-c-phase",
    "d": "fig-d-forces",
    "forces": "fig-d-forces",
}


def figure_title(case: Case) -> str:
    """The case's name, and what overrides changed (``instance-1 (Omega 1.6 → 1.7)``; four to six
    changes are named, not valued; more are counted)."""
    if not case.modified:
        return case.name
    if len(case.modified) <= 3:
        return f"{case.name} ({', '.join(case.modified)})"
    if len(case.modified) > 6:
        return f"{case.name} ({len(case.modified)} values changed)"
    names = ", ".join(change.split(" ")[0] for change in case.modified)
    return f"{case.name} ({len(case.modified)} values changed: {names})"


def draw_panel(
    trajectory: pd.DataFrame,
    events: pd.DataFrame,
    case: Case,
    panel: str = "a",
    *,
    window: tuple[float, float] | None = None,
    t_final: float | None = None,
) -> Figure:
    """One panel (``"a"``-``"d"`` or its name, :data:`PANEL_NAMES`) of a run of ``case`` that
    ended at ``t_final`` (by default, the trajectory's last time)."""
    name = PANEL_NAMES.get(str(panel).lower()) if isinstance(panel, str) else None
    if name is None:
        raise InputError(f"panel must be one of {', '.join(PANEL_NAMES)}, got {panel!r}", field="panel")
    if trajectory.empty:
        raise InputError(
            "this run kept no trajectory to draw; simulate it with record_trajectory=True", field="trajectory"
        )
    t0 = case.initial.t0
    end = float(trajectory.t.iloc[-1]) if t_final is None else t_final
    chosen = figure_window(t0, end, case.parameters.period, window)
    clipped, shown_events = _clipped(trajectory, events, chosen)
    return _PANELS[name](Panel(clipped, shown_events, case.parameters, t0, case.initial.y, figure_title(case), chosen))


def draw_figures(
    trajectory: pd.DataFrame,
    events: pd.DataFrame,
    p: Parameters,
    start: tuple[float, float, float, float, float],
    *,
    title: str = "",
    window: Window | None = None,
) -> dict[str, Figure]:
    """The four panels as matplotlib figures, over ``window`` (see :func:`figure_window`)."""
    t0, *y0 = start
    if window is None:
        t_final = float(trajectory.t.iloc[-1]) if len(trajectory) else t0
        window = figure_window(t0, t_final, p.period)
    trajectory, events = _clipped(trajectory, events, window)
    panel = Panel(trajectory, events, p, t0, y0, title, window)
    return {name: draw(panel) for name, draw in _PANELS.items()}


def write_figures(
    trajectory: pd.DataFrame,
    events: pd.DataFrame,
    p: Parameters,
    start: tuple[float, float, float, float, float],
    directory: Path,
    *,
    title: str = "",
    window: Window | None = None,
) -> list[Path]:
    """Write the four panels as PNG and SVG into ``directory``; return the files written."""
    directory.parent.mkdir(parents=True, exist_ok=True)
    inner_folder(directory)
    written = []
    for name, fig in draw_figures(trajectory, events, p, start, title=title, window=window).items():
        written += save_figure(fig, directory, name)
    return written
