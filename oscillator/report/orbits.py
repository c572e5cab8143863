"""A branch drawn and told: its figures (Fig. 14 with the unstable parts, the multipliers) and
its report's blocks; :mod:`oscillator.report.orbit_folders` writes and reads the folders."""

from __future__ import annotations

import itertools
import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from oscillator.errors import Reason
from oscillator.io.cases import Case
from oscillator.io.files import atomic_path
from oscillator.model.parameters import UNITS, labelled
from oscillator.orbits.branch import Bifurcation, Branch
from oscillator.report import markup as mk

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = [
    "bifurcation_style",
    "branch_figure",
    "branch_status",
    "draw_branch",
    "draw_multipliers",
    "modified_blocks",
    "multipliers_figure",
    "report_blocks",
]


#: Each bifurcation kind's marker on the branch figures.
BIFURCATION_MARKERS = {
    Bifurcation.SLIDING_ONSET: "v",
    Bifurcation.SLIDING_VANISH: "^",
    Bifurcation.GRAZING: "s",
    Bifurcation.FOLD: "o",
    Bifurcation.PERIOD_DOUBLING: "D",
    Bifurcation.TORUS: "*",
}
#: Each kind's colour and size: two kinds located close together stay apart (a grazing's small
#: square inside a sliding onset's larger triangle).
BIFURCATION_STYLE = {
    Bifurcation.SLIDING_ONSET: ("tab:red", 9),
    Bifurcation.SLIDING_VANISH: ("tab:purple", 9),
    Bifurcation.GRAZING: ("tab:green", 5),
    Bifurcation.FOLD: ("black", 8),
    Bifurcation.PERIOD_DOUBLING: ("tab:brown", 7),
    Bifurcation.TORUS: ("tab:pink", 10),
}


def bifurcation_style(kind: Bifurcation) -> dict[str, Any]:
    """How a bifurcation of ``kind`` is marked (its marker, colour and size, hollow)."""
    colour, size = BIFURCATION_STYLE[kind]
    return {"marker": BIFURCATION_MARKERS[kind], "color": colour, "ms": size, "mfc": "none", "ls": "none", "mew": 1.3}


def _pieces(points: pd.DataFrame) -> list[slice]:
    """Slices of consecutive points drawn as one line: the branch's continuous pieces."""
    edges = [0, *(np.flatnonzero(np.diff(points.piece.to_numpy(int))) + 1).tolist(), len(points)]
    return [slice(a, b) for a, b in itertools.pairwise(edges)]


def _runs(stable: np.ndarray, piece: slice) -> list[slice]:
    """``piece`` cut into runs of the same stability (each overlapping the next by one point)."""
    inner = stable[piece]
    edges = [0, *(np.flatnonzero(np.diff(inner.astype(int))) + 1).tolist(), len(inner)]
    return [slice(piece.start + a, piece.start + min(b + 1, len(inner))) for a, b in itertools.pairwise(edges)]


def _gaps(branch: Branch) -> list[tuple[float, float]]:
    """The parameter intervals with no period-N orbit on the branch (between a row with an empty
    ``after`` and the next row, with an empty ``before``)."""
    rows, param = branch.bifurcations, branch.param
    return [
        (float(rows[param].iloc[k]), float(rows[param].iloc[k + 1]))
        for k in range(len(rows) - 1)
        if rows.after.iloc[k] == "" and rows.before.iloc[k + 1] == ""
    ]


def _label_values(ax: Axes, rows: pd.DataFrame, param: str, coordinate: str, span: float) -> None:
    """Each bifurcation's parameter beside its marker; labels of close values stacked, not overlaid."""
    decimals = min(10, max(0, math.ceil(-math.log10(span)) + 5)) if span > 0 else 7
    level, last = 0, -math.inf
    for value, y in sorted(zip(rows[param], rows[coordinate], strict=True)):
        level = level + 1 if value - last < 0.12 * span else 0
        last = value
        offset = (5, 6 + 9 * level)
        ax.annotate(f"{value:.{decimals}f}", (value, y), textcoords="offset points", xytext=offset, fontsize=7)


_STATE_UNITS = {"x1": "m", "v1": "m/s", "x2": "m", "v2": "m/s"}


def branch_figure(branch: Branch, coordinate: str, sweep_points: pd.DataFrame | None = None) -> Figure:
    """``coordinate`` at the section against the parameter: stable solid, unstable dashed,
    bifurcations marked, gaps shaded; the sweep's Poincaré points under it, if given."""
    from matplotlib.figure import Figure
    from matplotlib.ticker import MaxNLocator

    param, points = branch.param, branch.points
    fig = Figure(figsize=(7, 4.5), dpi=150, layout="constrained")
    ax = fig.subplots()
    if sweep_points is not None and len(sweep_points):
        ax.plot(
            sweep_points[param],
            sweep_points[coordinate],
            "o",
            color="k",
            ms=2.5,
            zorder=3,
            label="sweep (Poincaré points)",
        )
    stable = points.stable.to_numpy(bool)
    labelled_runs = set()
    for piece in _pieces(points):
        for part in _runs(stable, piece):
            is_stable = bool(stable[part.start])
            label = "stable" if is_stable else "unstable"
            ax.plot(
                points[param].iloc[part],
                points[coordinate].iloc[part],
                "-" if is_stable else "--",
                color="C0",
                lw=1.5,
                label=None if label in labelled_runs else label,
            )
            labelled_runs.add(label)
    for k, (lo, hi) in enumerate(_gaps(branch)):
        ax.axvspan(lo, hi, color="0.85", zorder=0, label=None if k else f"no period-{branch.period} orbit")
    for kind, rows in branch.bifurcations.groupby("kind"):
        ax.plot(
            rows[param], rows[coordinate], **bifurcation_style(Bifurcation(kind)), label=str(kind).replace("_", " ")
        )
    _label_values(ax, branch.bifurcations, param, coordinate, span=float(np.ptp(points[param])))
    ax.ticklabel_format(useOffset=False)
    ax.xaxis.set_major_locator(MaxNLocator(6))
    ax.set_xlabel(labelled(param))
    ax.set_ylabel(f"{coordinate} ({_STATE_UNITS[coordinate]}) at t0 + kT")
    ax.set_title(f"period-{branch.period} orbit continued in {param}", parse_math=False)
    ax.legend(fontsize=8, loc="best")
    ax.grid(alpha=0.3)
    return fig


def multipliers_figure(branch: Branch) -> Figure:
    """The multipliers' moduli against the parameter, with the unit circle's radius."""
    from matplotlib.figure import Figure
    from matplotlib.ticker import MaxNLocator

    param, points = branch.param, branch.points
    fig = Figure(figsize=(7, 3.5), dpi=150, layout="constrained")
    ax = fig.subplots()
    floor = 1e-16  # a multiplier of 0 (a resting mass's constrained velocity) is drawn here
    for k in range(1, 5):
        moduli = np.abs(points[f"mu{k}"].to_numpy(complex)).clip(min=floor)
        for j, piece in enumerate(_pieces(points)):
            ax.semilogy(
                points[param].iloc[piece],
                moduli[piece],
                "-",
                lw=1.2,
                color=f"C{k - 1}",
                label=None if j else f"|mu{k}|",
            )
    ax.axhline(1.0, color="k", lw=0.8, ls=":")
    for value in branch.bifurcations[param]:
        ax.axvline(value, color="C3", lw=0.6, ls="--")
    ax.ticklabel_format(axis="x", useOffset=False)
    ax.xaxis.set_major_locator(MaxNLocator(6))
    ax.set_xlabel(labelled(param))
    ax.set_ylabel("modulus of multiplier")
    ax.set_ylim(floor / 10, None)
    ax.text(0.99, 0.02, "0 is drawn at 1e-16", transform=ax.transAxes, ha="right", fontsize=7, color="0.4")
    ax.legend(fontsize=8, ncol=4, loc="center left")
    ax.grid(alpha=0.3)
    return fig


def _save(fig: Figure, path: Path) -> None:
    """Save ``fig`` atomically (a temporary name, then rename)."""
    with atomic_path(path) as temporary:
        fig.savefig(temporary, format=path.suffix[1:])


def draw_branch(branch: Branch, path: Path, coordinate: str, sweep_points: pd.DataFrame | None = None) -> None:
    """:func:`branch_figure` written to ``path``."""
    _save(branch_figure(branch, coordinate, sweep_points), path)


def draw_multipliers(branch: Branch, path: Path) -> None:
    """:func:`multipliers_figure` written to ``path``."""
    _save(multipliers_figure(branch), path)


def modified_blocks(case: Case) -> list[mk.Block]:
    """A paragraph naming what the overrides changed from the case as written (none if nothing)."""
    if not case.modified:
        return []
    return [mk.Paragraph(("Changed from the case as written: ", ", ".join(case.modified), "."))]


def report_blocks(branch: Branch, case: Case) -> list[mk.Block]:
    """The report: what was continued and which way, the bifurcations (named as the parameter
    increases, with the events on its lower and higher side), the fixed parameters and the
    figures (all text escaped)."""
    param = branch.param
    first, last = float(branch.points[param].iloc[0]), float(branch.points[param].iloc[-1])
    way = "up" if last > first else "down"
    unit = UNITS.get(param, "")
    blocks: list[mk.Block] = [
        mk.Heading(1, (f"{case.name}: period-{branch.period} orbit continued in {param}",)),
        mk.Paragraph(
            (
                f"{len(branch.points)} points, traced from {param} = {first:.10g} {way} to {last:.10g}"
                f"{' ' + unit if unit else ''}; section at t = {branch.section:g} s. ",
                "Complete." if branch.complete else f"Ended early: {branch.message}.",
            )
        ),
    ]
    blocks += modified_blocks(case)
    blocks += _bifurcation_blocks(branch, increasing=last > first)
    stable = branch.points.stable
    blocks.append(mk.Paragraph((f"{int(stable.sum())} stable and {int((~stable).sum())} unstable points.",)))
    fixed = tuple(
        (name, f"{getattr(case.parameters, name):.10g}", UNITS.get(name, "") or "-")
        for name in case.parameters.names()
        if name != param
    )
    blocks += [mk.Heading(2, ("Fixed parameters",)), mk.Table(("parameter", "value", "unit"), fixed)]
    blocks += [mk.Figure("branch", "the branch"), mk.Figure("multipliers", "the multipliers' moduli")]
    return blocks


def _bifurcation_blocks(branch: Branch, *, increasing: bool) -> list[mk.Block]:
    """The report's bifurcations: a table with the events on either side, and the gaps."""
    param = branch.param
    blocks: list[mk.Block] = []
    none = f"(no period-{branch.period} orbit)"
    rows = tuple(
        (
            f"{getattr(row, param):.10g}",
            str(row.kind),
            f"{row.x1:.6g}",
            f"{row.v1:.6g}",
            f"{row.x2:.6g}",
            f"{row.v2:.6g}",
            "-" if math.isnan(row.jump) else f"{row.jump:.2e}",
            *(
                (str(row.before) or none, str(row.after) or none)
                if increasing
                else (str(row.after) or none, str(row.before) or none)
            ),
        )
        for row in branch.bifurcations.itertuples(index=False)
    )
    blocks.append(mk.Heading(2, ("Bifurcations",)))
    if rows:
        blocks.append(
            mk.Paragraph(
                (
                    f"Each is named by what happens as {param} increases (sliding_onset: a rest "
                    "interval appears; sliding_vanish: it vanishes), whichever way the branch "
                    "was traced.",
                )
            )
        )
        header = (
            param,
            "kind",
            "x1 (m)",
            "v1 (m/s)",
            "x2 (m)",
            "v2 (m/s)",
            "jump",
            f"events at lower {param}",
            f"events at higher {param}",
        )
        blocks.append(mk.Table(header, rows))
    else:
        blocks.append(mk.Paragraph(("None in the range.",)))
    for lo, hi in _gaps(branch):
        blocks.append(
            mk.Paragraph(
                (
                    f"No period-{branch.period} orbit on this branch for {param} between {lo:.10g} "
                    f"and {hi:.10g}: simulate there, or look for an orbit of another period "
                    "(--period).",
                )
            )
        )
    return blocks


def branch_status(branch: Branch) -> str:
    """``"complete"``, ``"interrupted"`` or ``"incomplete"`` (it ended before ``stop``)."""
    if branch.complete:
        return "complete"
    return "interrupted" if branch.reason is Reason.INTERRUPTED else "incomplete"
