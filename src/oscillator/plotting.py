"""Figures in the article's style (Figs. 9-13, panels a-d), as PNG and SVG.

(a) displacements with the displacement boundaries ``x1 = d1`` and ``x1 = x2 - d``;
(b) velocities with the velocity boundary ``v = 0`` and rest intervals shaded;
(c) phase portraits of each mass with its domains and boundaries;
(d) G-function (force) histories: the real field solid, the other side's ("imaginary") field
dashed, and the flow-barrier fields dotted while a mass rests.
Start points are green, switching points marked by kind, as in the article.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only; never a window

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from oscillator._files import atomic_path
from oscillator.fields import flow_barrier_field, kinetic_field, non_friction_force
from oscillator.parameters import Parameters
from oscillator.phase_space import contacts_of_state, velocity_sign

__all__ = ["FIGURES", "force_histories", "missing_figures", "write_figures", "write_sweep_figures"]

#: Figure files (without suffix) and what each shows.
FIGURES = {
    "fig-a-displacement": "(a) displacements and displacement boundaries",
    "fig-b-velocity": "(b) velocities, velocity boundary and rest intervals",
    "fig-c-phase": "(c) phase portraits with domains and boundaries",
    "fig-d-forces": "(d) G-function (force) histories",
}
_MASS_COLOR = {1: "tab:blue", 2: "black"}
_KIND_STYLE = {
    "passable": ("o", "gold"),
    "sliding_onset": ("s", "white"),
    "sliding_vanish": ("D", "white"),
    "grazing": ("v", "tab:red"),
    "right_contact_onset": ("o", "tab:red"),
    "right_contact_release": ("o", "tab:red"),
    "left_contact_onset": ("o", "tab:pink"),
    "left_contact_release": ("o", "tab:pink"),
}


def _dense(trajectory: pd.DataFrame, points: int) -> pd.DataFrame:
    """The trajectory with extra rows, linear in the state, inside each step of one mode.

    During rest the state is constant, so the forces (driven by ``sin(Omega t)``) are then
    exact; during motion CVODE's steps are short against the motion's curvature.
    """
    t = trajectory.t.to_numpy()
    if len(t) < 2 or t[-1] == t[0]:
        return trajectory
    numbers = ["t", "x1", "v1", "x2", "v2"]
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


def _rest_spans(trajectory: pd.DataFrame, mass: int) -> list[tuple[float, float]]:
    resting = (trajectory[f"domain{mass}"] == 0).to_numpy()
    t = trajectory.t.to_numpy()
    spans, start = [], None
    for i, flag in enumerate(resting):
        if flag and start is None:
            start = t[i]
        if not flag and start is not None:
            spans.append((start, t[i]))
            start = None
    if start is not None:
        spans.append((start, t[-1]))
    return spans


def _mark_events(ax, events: pd.DataFrame, mass: int, column: str, label_kinds: set) -> None:
    for kind, rows in events[events.mass == mass].groupby("kind"):
        marker, face = _KIND_STYLE.get(kind, ("o", "white"))
        label = kind.replace("_", " ") if kind not in label_kinds else None
        label_kinds.add(kind)
        ax.scatter(rows.t if column != "phase" else rows[f"x{mass}"], rows[column] if column != "phase" else
                   rows[f"v{mass}"], marker=marker, s=42, facecolor=face, edgecolor="black", zorder=5,
                   label=label)  # fmt: skip


def _start(ax, x, y) -> None:
    ax.scatter([x], [y], s=60, color="limegreen", edgecolor="black", zorder=6)


def _finish_time_panel(ax, events, t0, y0, quantity: str, ylabel: str, title: str) -> None:
    """Start points, switching points of both masses (``quantity`` is ``x`` or ``v``), labels."""
    seen: set = set()
    offset = 0 if quantity == "x" else 1
    for mass in (1, 2):
        _start(ax, t0, y0[2 * mass - 2 + offset])
        _mark_events(ax, events, mass, f"{quantity}{mass}", seen)
    ax.set(xlabel="time t (s)", ylabel=ylabel)
    ax.set_title(title, parse_math=False)  # the case's name is text, never mathtext
    ax.legend(fontsize=8, loc="best")


def _displacements(trajectory, events, p, t0, y0, title):
    fig, ax = plt.subplots(figsize=(8, 4.5))
    t = trajectory.t
    ax.plot(t, trajectory.x1, color=_MASS_COLOR[1], label="$x_1$ (m1)")
    ax.plot(t, trajectory.x2, color=_MASS_COLOR[2], label="$x_2$ (m2)")
    ax.axhline(p.d1, color="tab:red", ls="--", lw=1, label=r"$x_1 = d_1$ (right stop, $\partial\Omega_{13}$)")
    ax.plot(t, trajectory.x2 - p.d, color="tab:pink", ls="--", lw=1,
            label=r"$x_1 = x_2 - d$ (left stop, $\partial\Omega_{15}$)")  # fmt: skip
    _finish_time_panel(ax, events, t0, y0, "x", "displacement (m)", f"{title} — (a) displacements")
    return fig


def _velocities(trajectory, events, p, t0, y0, title):
    fig, ax = plt.subplots(figsize=(8, 4.5))
    t = trajectory.t
    for mass in (1, 2):
        ax.plot(t, trajectory[f"v{mass}"], color=_MASS_COLOR[mass], label=f"$v_{mass}$ (m{mass})")
        for i, (a, b) in enumerate(_rest_spans(trajectory, mass)):
            ax.axvspan(
                a, b, color=_MASS_COLOR[mass], alpha=0.12, label=f"m{mass} at rest (sliding)" if i == 0 else None
            )
    ax.axhline(0.0, color="black", ls="--", lw=1, label=r"velocity boundary $v = 0$ ($\partial\Omega_{12}$)")
    _finish_time_panel(ax, events, t0, y0, "v", "velocity (m/s)", f"{title} — (b) velocities")
    return fig


def _phase(trajectory, events, p, t0, y0, title):
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
    for ax, mass in zip(axes, (1, 2), strict=True):
        x, v = trajectory[f"x{mass}"], trajectory[f"v{mass}"]
        ax.plot(x, v, color=_MASS_COLOR[mass], lw=1.2)
        ax.axhline(0.0, color="black", ls="--", lw=1, label="velocity boundary $v = 0$")
        if mass == 1:
            ax.axvline(p.d1, color="tab:red", ls="--", lw=1, label=r"$x_1 = d_1$ (right stop)")
        top, bottom = ax.get_ylim()[1], ax.get_ylim()[0]
        names = ("Ω1(1): v1 > 0", "Ω2(1): v1 < 0") if mass == 1 else ("Ω2(2): v2 > 0", "Ω1(2): v2 < 0")
        ax.text(0.02, 0.95, names[0], transform=ax.transAxes, fontsize=8, va="top")
        ax.text(0.02, 0.05, names[1], transform=ax.transAxes, fontsize=8, va="bottom")
        ax.set_ylim(bottom, top)
        _start(ax, y0[2 * mass - 2], y0[2 * mass - 1])
        _mark_events(ax, events, mass, "phase", set())
        ax.set(xlabel=f"displacement $x_{mass}$ (m)", ylabel=f"velocity $v_{mass}$ (m/s)", title=f"m{mass}")
        ax.legend(fontsize=8, loc="lower right")
    fig.suptitle(f"{title} — (c) phase portraits", parse_math=False)
    fig.tight_layout()
    return fig


def _forces(trajectory, events, p, t0, y0, title):
    histories = force_histories(trajectory, p)
    fig, axes = plt.subplots(2, 1, figsize=(8, 6.5), sharex=True)
    for ax, mass in zip(axes, (1, 2), strict=True):
        t = histories.t
        ax.plot(t, histories[f"F{mass}_real"], color=_MASS_COLOR[mass], label=f"real $F_{mass}$ (current domain)")
        plus, minus = (1, 2) if mass == 1 else (2, 1)
        ax.plot(t, histories[f"F{mass}_plus"], color="tab:orange", ls="--", lw=1,
                label=f"$F_{mass}^{{({plus})}}$ ($v_{mass} > 0$ side)")  # fmt: skip
        ax.plot(t, histories[f"F{mass}_minus"], color="tab:green", ls="--", lw=1,
                label=f"$F_{mass}^{{({minus})}}$ ($v_{mass} < 0$ side)")  # fmt: skip
        ax.plot(t, histories[f"F{mass}_barrier_plus"], color="tab:orange", ls=":", lw=1.5,
                label=f"flow barrier $F_{mass}^{{(0>0_{plus})}}$")  # fmt: skip
        ax.plot(t, histories[f"F{mass}_barrier_minus"], color="tab:green", ls=":", lw=1.5,
                label=f"flow barrier $F_{mass}^{{(0>0_{minus})}}$")  # fmt: skip
        ax.axhline(0.0, color="grey", lw=0.8)
        for a, b in _rest_spans(trajectory, mass):
            ax.axvspan(a, b, color=_MASS_COLOR[mass], alpha=0.1)
        times = events.t[events.mass == mass].to_numpy()
        ax.vlines(times, 0, 1, transform=ax.get_xaxis_transform(), color="tab:red", lw=0.6, alpha=0.6)
        ax.set(ylabel=f"force per unit mass on m{mass} (N/kg)")
        ax.legend(fontsize=7, loc="best", ncol=2)
    axes[-1].set(xlabel="time t (s)")
    fig.suptitle(f"{title} — (d) G-functions (forces); switching times as red lines", parse_math=False)
    fig.tight_layout()
    return fig


def _save(fig, directory: Path, name: str) -> list[Path]:
    """Save a figure as PNG and SVG, each atomically (temporary name, then rename); close it."""
    paths = [directory / f"{name}{suffix}" for suffix in (".png", ".svg")]
    try:
        for path in paths:
            with atomic_path(path) as temporary:
                fig.savefig(temporary, format=path.suffix[1:], dpi=110, bbox_inches="tight")
    finally:
        plt.close(fig)
    return paths


def missing_figures(directory: Path) -> list[str]:
    """The figures of :data:`FIGURES` of which ``directory`` lacks the PNG or the SVG file."""
    return [name for name in FIGURES if not all((directory / f"{name}{s}").is_file() for s in (".png", ".svg"))]


_PANELS = {
    "fig-a-displacement": _displacements,
    "fig-b-velocity": _velocities,
    "fig-c-phase": _phase,
    "fig-d-forces": _forces,
}


def write_figures(
    trajectory: pd.DataFrame,
    events: pd.DataFrame,
    p: Parameters,
    start: tuple[float, float, float, float, float],
    directory: Path,
    *,
    title: str = "",
) -> list[Path]:
    """Write the four panels as PNG and SVG into ``directory``; return the files written."""
    directory.mkdir(parents=True, exist_ok=True)
    t0, *y0 = start
    written = []
    for name, panel in _PANELS.items():
        fig = panel(trajectory, events, p, t0, y0, title)
        written += _save(fig, directory, name)
    return written


def write_sweep_figures(tables: dict, param: str, mass: int, directory: Path, *, title: str = "") -> list[Path]:
    """Fig. 14-style diagrams of a sweep, PNG and SVG.

    ``fig-14-bifurcation``: the switching displacement and phase of the mass against the
    parameter, coloured by kind, sliding ranges shaded; ``fig-14-poincare``: the Poincaré points.
    """
    directory.mkdir(parents=True, exist_ok=True)
    switches, summary, poincare = tables["switches"], tables["summary"], tables["poincare"]
    from oscillator.sweep import sliding_ranges

    values = np.sort(summary[param].to_numpy())
    half = 0.5 * np.min(np.diff(values)) if len(values) > 1 else 0.0
    spans = [(a - half, b + half) for a, b in sliding_ranges(summary, param)]
    written = []

    fig, axes = plt.subplots(2, 1, figsize=(9, 7), sharex=True)
    for ax, column, label in ((axes[0], "x", f"switching displacement $x_{mass}$ (m)"),
                              (axes[1], "phase", r"switching phase $\Omega t$ mod $2\pi$ (rad)")):  # fmt: skip
        for i, (a, b) in enumerate(spans):
            ax.axvspan(a, b, color="tab:orange", alpha=0.15, label=f"sliding (m{mass} rests)" if i == 0 else None)
        for kind, rows in switches.groupby("kind"):
            marker = _KIND_STYLE.get(kind, ("o", "white"))[0]
            color = {"passable": "tab:blue", "sliding_onset": "tab:red", "sliding_vanish": "tab:green"}.get(
                kind, "grey"
            )
            ax.scatter(rows[param], rows[column], s=6, marker=marker, color=color, label=kind.replace("_", " "))
        ax.set(ylabel=label)
        ax.legend(fontsize=8, loc="best", markerscale=2)
    axes[-1].set(xlabel=f"{param}")
    fig.suptitle(f"{title} — switching points of m{mass} after the transient (Fig. 14 style)", parse_math=False)
    fig.tight_layout()
    written += _save(fig, directory, "fig-14-bifurcation")

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
    for ax, column in zip(axes, (f"x{mass}", f"v{mass}"), strict=True):
        for a, b in spans:
            ax.axvspan(a, b, color="tab:orange", alpha=0.15)
        ax.scatter(poincare[param], poincare[column], s=4, color=_MASS_COLOR[mass])
        ax.set(xlabel=param, ylabel=f"{column} at t0 + nT")
    fig.suptitle(f"{title} — Poincaré bifurcation diagram (sliding ranges shaded)", parse_math=False)
    fig.tight_layout()
    written += _save(fig, directory, "fig-14-poincare")
    return written
