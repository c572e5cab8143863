"""A friction chain's figures: its motion (one panel per mass and per Jenkins slider) and its
schematic (what an engineer checks a model by).

Names in a system file are untrusted text: they are drawn as text (matplotlib's mathtext is off
for every label: ``usetex`` is never on and ``$`` is escaped), never read as a path.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import FancyArrowPatch, Rectangle

from oscillator.model.chains import FrictionChain
from oscillator.report.outputs import plain_label

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes

    from oscillator.hybrid.chain_run import ChainResult

__all__ = ["motion_figure", "schematic_figure"]

#: Colours: each quantity's, and the shading of stuck and closed intervals.
_X, _V, _STUCK, _CLOSED = "#1f4e9c", "#c4512b", "#d9d9d9", "#f4c7c3"


def _spans(ax: Axes, t: np.ndarray, on: np.ndarray, color: str, label: str) -> None:
    """Shade the intervals where ``on`` holds."""
    if not on.any():
        return
    if label in ax.get_legend_handles_labels()[1]:
        label = ""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], on.astype(int), [0]])))
    for k, (a, b) in enumerate(zip(edges[::2], edges[1::2], strict=True)):
        ax.axvspan(t[a], t[min(b, len(t) - 1)], color=color, lw=0, label=(label or None) if k == 0 else None, zorder=0)


def motion_figure(result: ChainResult) -> Figure:
    """Each mass's displacement and velocity against time, its stuck intervals (grey) and the
    intervals its stops and contacts are closed (rose); each slider's force ``kt (u - z)``."""
    chain, frame = result.chain, result.trajectory
    sliders = [e for e in chain.elements if e.type == "jenkins"]
    rows = len(chain.masses) + len(sliders)
    fig = Figure(figsize=(9.0, 1.9 * rows + 0.8), layout="constrained")
    axes = np.atleast_1d(fig.subplots(rows, 1, sharex=True, squeeze=False)[:, 0])
    t = frame["t"].to_numpy()
    for ax, mass in zip(axes, chain.masses, strict=False):
        x, v = frame[f"x:{mass.name}"].to_numpy(), frame[f"v:{mass.name}"].to_numpy()
        for e in chain.elements:
            column = f"mode:{e.name}"
            if e.type == "friction" and e.on == mass.name:
                _spans(ax, t, frame[column].to_numpy() == 0, _STUCK, "stuck")
            if e.type in ("stop", "contact") and mass.name in (e.on, e.with_):
                _spans(ax, t, frame[column].to_numpy() != 0, _CLOSED, "in contact")
        ax.plot(t, x, color=_X, lw=1.2, label="x (m)")
        twin = ax.twinx()
        twin.plot(t, v, color=_V, lw=0.9, ls="--", label="v (m/s)")
        twin.set_ylabel("v (m/s)", color=_V)
        ax.set_ylabel("x (m)", color=_X)
        ax.set_title(f"mass {plain_label(mass.name)} (m = {mass.m:g} kg)", loc="left", fontsize=10)
        handles = ax.get_legend_handles_labels()[0] + twin.get_legend_handles_labels()[0]
        ax.legend(handles=handles, loc="lower right", bbox_to_anchor=(1.0, 1.0), fontsize=8, ncol=4, frameon=False)
    for ax, element in zip(axes[len(chain.masses) :], sliders, strict=True):
        u = frame[f"x:{element.on}"].to_numpy() - (frame[f"x:{element.with_}"].to_numpy() if element.with_ else 0.0)
        force = element.values["kt"] * (u - frame[f"z:{element.name}"].to_numpy())
        _spans(ax, t, frame[f"mode:{element.name}"].to_numpy() == 0, _STUCK, "slider stuck")
        ax.plot(t, force, color=_X, lw=1.2, label="kt (u - z) (N)")
        for level in (-element.values["F"], element.values["F"]):
            ax.axhline(level, color="0.4", lw=0.8, ls=":")
        ax.set_ylabel("force (N)")
        ax.set_title(
            f"Jenkins slider {plain_label(element.name)} (F = {element.values['F']:g} N)", loc="left", fontsize=10
        )
        ax.legend(loc="lower right", bbox_to_anchor=(1.0, 1.0), fontsize=8, ncol=2, frameon=False)
    axes[-1].set_xlabel("t (s)")
    fig.suptitle(plain_label(chain.title or "friction chain"), fontsize=11)
    return fig


def _zigzag(ax: Axes, x0: float, x1: float, y: float, color: str = "k") -> None:
    xs = np.linspace(x0, x1, 14)
    ys = y + 0.06 * np.array([0, 0] + [(-1) ** k for k in range(10)] + [0, 0])
    ax.plot(xs, ys, color=color, lw=1.0)


def _dashpot(ax: Axes, x0: float, x1: float, y: float) -> None:
    mid = 0.5 * (x0 + x1)
    ax.plot([x0, mid + 0.05], [y, y], color="k", lw=1.0)
    ax.plot([mid - 0.08, mid + 0.12, mid + 0.12, mid - 0.08], [y + 0.08, y + 0.08, y - 0.08, y - 0.08], color="k", lw=1)
    ax.plot([mid + 0.05, mid + 0.05], [y - 0.05, y + 0.05], color="k", lw=1.4)
    ax.plot([mid + 0.12, x1], [y, y], color="k", lw=1.0)


def _jenkins(ax: Axes, x0: float, x1: float, y: float) -> None:
    mid = 0.5 * (x0 + x1)
    _zigzag(ax, x0, mid, y)
    ax.add_patch(Rectangle((mid, y - 0.07), 0.14, 0.14, facecolor="#e8d9b5", edgecolor="k", lw=1.0))
    ax.plot([mid + 0.14, x1], [y, y], color="k", lw=1.0)
    ax.plot([mid - 0.02, mid + 0.2], [y - 0.09, y - 0.09], color="k", lw=1.0)


def schematic_figure(chain: FrictionChain) -> Figure:
    """The machine drawn: the masses left to right in their order, the ground as a wall on the
    left and a floor below, each element where it acts (springs, dampers, Jenkins elements as
    spring and slider, stops with their side and place, contacts with their gap, friction as a
    hatched floor or a belt with its speed, forces as arrows), each labelled with its name and
    values."""
    count = len(chain.masses)
    fig = Figure(figsize=(max(6.0, 2.6 * count + 2.0), 4.2), layout="constrained")
    ax = fig.subplots()
    place = {m.name: 1.6 + 2.4 * k for k, m in enumerate(chain.masses)}
    ax.add_patch(Rectangle((0.0, -0.1), 0.15, 2.0, hatch="///", facecolor="white", edgecolor="k"))
    ax.plot([0.0, place[chain.masses[-1].name] + 1.6], [0.0, 0.0], color="k", lw=1.2)
    for m in chain.masses:
        ax.add_patch(Rectangle((place[m.name] - 0.4, 0.05), 0.8, 0.8, facecolor="#cfe0f5", edgecolor="k", lw=1.2))
        ax.text(place[m.name], 0.45, f"{plain_label(m.name)}\n{m.m:g} kg", ha="center", va="center", fontsize=8)
    used: dict[tuple[str, str], int] = {}
    for element in chain.elements:
        _draw(ax, chain, element, place, used)
    ax.set_xlim(-0.2, place[chain.masses[-1].name] + 1.8)
    ax.set_ylim(-0.55, 2.4)
    ax.set_aspect("equal")
    ax.axis("off")
    ax.set_title(plain_label(chain.title or "friction chain"), fontsize=10)
    return fig


def _values(element) -> str:  # type: ignore[no-untyped-def]
    shown = [f"{k}={v:g}" for k, v in element.values.items() if isinstance(v, float) and (v != 0 or k in ("at", "gap"))]
    side = element.values.get("side")
    return ", ".join(([side] if side else []) + shown)


def _draw(ax: Axes, chain: FrictionChain, element, place: dict[str, float], used: dict[tuple[str, str], int]) -> None:  # type: ignore[no-untyped-def]
    """One element of the schematic (the rows of a pair's elements stacked upwards)."""
    x = place[element.on]
    label = f"{plain_label(element.name)}: {plain_label(_values(element))}"
    if element.type == "force":
        ax.add_patch(FancyArrowPatch((x - 0.3, 2.0), (x + 0.3, 2.0), arrowstyle="-|>", mutation_scale=12, color="#a33"))
        ax.text(x, 2.08, label, ha="center", va="bottom", fontsize=6.5, color="#a33")
        return
    if element.type == "friction":
        belt = element.values.get("w", 0.0)
        ax.add_patch(
            Rectangle((x - 0.5, -0.12), 1.0, 0.1, hatch="xx" if belt else "///", facecolor="white", edgecolor="k")
        )
        ax.text(x, -0.2, label + (" (belt)" if belt else ""), ha="center", va="top", fontsize=6.5)
        return
    if element.type == "stop":  # above the mass: a finger on it, the wall it meets
        side = 1.0 if element.values["side"] == "right" else -1.0
        ax.plot([x + 0.25 * side, x + 0.25 * side, x + 0.5 * side], [0.85, 1.15, 1.15], color="k", lw=1.0)
        ax.add_patch(Rectangle((x + 0.6 * side - 0.04, 1.0), 0.08, 0.3, facecolor="#888", edgecolor="k"))
        ax.text(x + 0.6 * side, 1.33, label, ha="center", va="bottom", fontsize=6.5)
        return
    pair = (element.with_ or "", element.on)
    level = used.get(pair, 0)
    used[pair] = level + 1
    y = 0.25 + 0.3 * level
    if element.with_ is None and x > place[chain.masses[0].name]:  # above, to a ground post on the left
        y = 1.05 + 0.3 * level
        x0, x1 = x - 1.1, x
        ax.add_patch(Rectangle((x0 - 0.08, y - 0.12), 0.08, 0.24, hatch="///", facecolor="white", edgecolor="k"))
        ax.plot([x, x], [0.85, y], color="k", lw=1.0)
    elif element.with_ is None:
        x0, x1 = 0.15, x - 0.4
    else:
        a, b = sorted((x, place[element.with_]))
        x0, x1 = a + 0.4, b - 0.4
    if element.type == "spring":
        _zigzag(ax, x0, x1, y)
    elif element.type == "damper":
        _dashpot(ax, x0, x1, y)
    elif element.type == "jenkins":
        _jenkins(ax, x0, x1, y)
    elif element.type == "contact":
        ax.plot([x0, x0 + 0.25 * (x1 - x0)], [y, y], color="k", lw=1.0)
        ax.plot([x1 - 0.25 * (x1 - x0), x1], [y, y], color="k", lw=1.0)
        ax.plot([x0 + 0.25 * (x1 - x0)] * 2, [y - 0.08, y + 0.08], color="k", lw=1.6)
    ax.annotate(label, (0.5 * (x0 + x1), y + 0.08), ha="center", va="bottom", fontsize=6.5)
