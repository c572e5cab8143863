"""A sweep's diagrams (Fig. 14's style): each mass's switching points against the swept
parameter, coloured by kind, the rest intervals shaded, both ways of a hysteresis sweep apart."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from oscillator.io.files import inner_folder
from oscillator.model.events import EventKind
from oscillator.model.parameters import labelled
from oscillator.report.figures import KIND_STYLE, MASS_COLOR, event_marker, outside_legend, save_figure

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes

__all__ = ["draw_sweep_figures", "write_sweep_figures"]


#: The sweep diagrams' switching points: a mass reaching its velocity boundary (passing or coming
#: to rest) or leaving rest; every other kind is drawn grey.
_SWEEP_COLORS = {
    EventKind.PASSABLE: "tab:blue",
    EventKind.SLIDING_ONSET: "tab:red",
    EventKind.SLIDING_VANISH: "tab:green",
}


#: How a both-ways sweep draws each way: shading of the rests, and the Poincaré points (the way
#: up in larger open circles, the way down in small dots inside them, so both show where equal).
_WAYS: dict[str, tuple[dict[str, Any], dict[str, Any]]] = {
    "up": (
        {"color": "tab:blue", "alpha": 0.15},
        {"s": 22, "facecolor": "none", "edgecolor": "tab:blue", "linewidths": 0.8},
    ),
    "down": (
        {"facecolor": "none", "edgecolor": "tab:orange", "hatch": "//", "linewidth": 0.0},
        {"s": 5, "color": "tab:orange"},
    ),
}


def _shade_rests(ax: Axes, summary: pd.DataFrame, param: str, mass: int, ways: list[str], half: float) -> None:
    """The swept values at which the mass rests, shaded: one style per way of a both-ways sweep."""
    from oscillator.analysis.sweep_points import sliding_ranges

    for way in ways:
        style = _WAYS[way][0] if len(ways) > 1 else {"color": "tab:orange", "alpha": 0.15}
        label = f"m{mass} rests (sliding)" + (f", going {way}" if len(ways) > 1 else "")
        for i, (a, b) in enumerate(sliding_ranges(summary, param, way if len(ways) > 1 else None)):
            ax.axvspan(a - half, b + half, label=None if i else label, **style)


def draw_sweep_figures(tables: dict[str, Any], param: str, mass: int, *, title: str = "") -> dict[str, Figure]:
    """Fig. 14-style diagrams of a sweep: ``fig-14-bifurcation`` (the switching displacement and
    phase of the mass against the parameter, sliding ranges shaded) and ``fig-14-poincare``.

    A both-ways sweep (``direction`` "up" and "down") shades each way's rests in its own style
    and draws each way's Poincaré points in its own colour: where they differ, two motions
    coexist (hysteresis)."""
    switches, summary, poincare = tables["switches"], tables["summary"], tables["poincare"]
    ways = list(dict.fromkeys(summary.direction)) if "direction" in summary.columns else ["up"]
    values = np.unique(summary[param].to_numpy())
    half = 0.5 * np.min(np.diff(values)) if len(values) > 1 else 0.0
    both = len(ways) > 1
    going = dict(zip(summary["index"], summary.direction, strict=True)) if both else {}

    fig = Figure(figsize=(10, 7), layout="constrained")
    axes = fig.subplots(2, 1, sharex=True)
    for ax, column, label in (
        (axes[0], "x", f"switching displacement $x_{mass}$ (m)"),
        (axes[1], "phase", r"switching phase $\Omega t$ mod $2\pi$ (rad)"),
    ):
        _shade_rests(ax, summary, param, mass, ways, half)
        for way in ways:  # a both-ways sweep: the way down in smaller markers edged in orange, inside the way up's
            down = both and way == ways[-1]
            shown = switches[switches["index"].map(going) == way] if both else switches
            for kind, rows in shown.groupby("kind"):
                scale = 0.1 if down else 0.45 if both else 0.3
                style = event_marker(kind, scale) | {
                    "facecolor": _SWEEP_COLORS.get(kind, "grey"),
                    "linewidths": 0.6 if down else 0.4,
                    "edgecolor": "tab:orange" if down else "black",
                }
                if down:
                    style["zorder"] += len(KIND_STYLE)
                name = kind.replace("_", " ") + (f", going {way}" if both else "")
                ax.scatter(rows[param], rows[column], label=name, **style)
        ax.set(ylabel=label)
        outside_legend(ax, markerscale=2)
    axes[-1].set(xlabel=labelled(param))
    axes[-1].xaxis.set_major_locator(MaxNLocator(8))
    both_words = " (both ways)" if both else ""
    fig.suptitle(
        f"{title} — switching points of m{mass} after the transient{both_words} (Fig. 14 style)", parse_math=False
    )
    bifurcation = fig

    fig = Figure(figsize=(11, 4.5), layout="constrained")
    axes = fig.subplots(1, 2)
    units = {"x": "m", "v": "m/s"}
    for ax, quantity in zip(axes, ("x", "v"), strict=True):
        _shade_rests(ax, summary, param, mass, ways, half)
        for way in ways:
            rows = poincare[poincare["index"].map(going) == way] if both else poincare
            style = _WAYS[way][1] if both else {"s": 4, "color": MASS_COLOR[mass]}
            ax.scatter(
                rows[param],
                rows[f"{quantity}{mass}"],
                label=f"Poincaré points, going {way}" if both else "Poincaré points",
                **style,
            )
        ax.set(xlabel=labelled(param), ylabel=f"${quantity}_{mass}$ at $t_0 + nT$ ({units[quantity]})")
        ax.xaxis.set_major_locator(MaxNLocator(5))
    axes[1].legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, fontsize=8)
    fig.suptitle(f"{title} — Poincaré bifurcation diagram{both_words} (sliding ranges shaded)", parse_math=False)
    return {"fig-14-bifurcation": bifurcation, "fig-14-poincare": fig}


def write_sweep_figures(
    tables: dict[str, Any], param: str, mass: int, directory: Path, *, title: str = ""
) -> list[Path]:
    """Write the Fig. 14-style diagrams of a sweep as PNG and SVG (see :func:`draw_sweep_figures`)."""
    directory.parent.mkdir(parents=True, exist_ok=True)
    inner_folder(directory)
    written = []
    for name, fig in draw_sweep_figures(tables, param, mass, title=title).items():
        written += save_figure(fig, directory, name)
    return written
