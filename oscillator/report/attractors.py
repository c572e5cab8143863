"""Basins and Lyapunov spectra written out: tables, figures, a report (text escaped).

A basins folder holds ``basins.parquet`` (one row per cell: the two axes' values, the
attractor, the run's status), ``attractors.parquet`` (one row per attractor: its name, kind,
period, cycle of switches, share of the starts with a confidence interval, stability and
largest multiplier, Lyapunov exponent, section points), ``figures/basins.png`` (and ``.svg``),
``report.md`` and ``report.html``, beside ``basins.json``, ``case.toml`` and ``parts/``.
"""

from __future__ import annotations

import functools
import json
import textwrap
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from oscillator.analysis.axes import STATE
from oscillator.attractors.atlas import Atlas
from oscillator.attractors.basins import Basins
from oscillator.attractors.finding import share_text
from oscillator.attractors.following import AttractorsOver
from oscillator.attractors.grouping import Attractor
from oscillator.attractors.lyapunov import LyapunovSpectrum
from oscillator.errors import InputError, OscillatorError
from oscillator.io.files import atomic_path
from oscillator.model.parameters import labelled
from oscillator.orbits.curves import Curve
from oscillator.report import markup as mk
from oscillator.report.figures import figure_title
from oscillator.report.orbits import modified_blocks
from oscillator.text import printable

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

    from oscillator.io.cases import Case
    from oscillator.orbits.branch import Branch

__all__ = [
    "atlas_figure",
    "attractor_table",
    "basins_figure",
    "curve_figure",
    "following_figure",
    "lyapunov_figure",
    "write_atlas",
    "write_basins",
    "write_curve",
    "write_following",
    "write_lyapunov",
]

#: A colour per attractor (more attractors cycle through them), and the failed cells' grey.
COLORS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown", "tab:pink", "tab:olive")
FAILED = "0.6"
#: A marker per attractor for its own section points, so that coinciding ones stay apart.
MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*")


#: The columns of ``attractors.parquet`` (the same when every start failed and there is no attractor).
ATTRACTOR_COLUMNS = (
    "attractor name kind period signature rests_m1 rests_m2 contacts rest_time_m1 rest_time_m2 starts fraction low "
    "high stable largest_multiplier lyapunov points note"
).split()


def attractor_table(basins: Basins) -> pd.DataFrame:
    """One row per attractor (and one for failed starts, if any): what it is and its share."""
    shares = basins.found.fractions().set_index("attractor")
    rows = []
    for attractor in basins.found.attractors:
        share = shares.loc[attractor.id]
        orbit = attractor.orbit
        rows.append(
            {
                "attractor": attractor.id,
                "name": attractor.name,
                "kind": attractor.kind,
                "period": attractor.period,
                "signature": attractor.signature,
                "rests_m1": attractor.rests[0],
                "rests_m2": attractor.rests[1],
                "contacts": attractor.contacts,
                "rest_time_m1": attractor.rest_time[0],
                "rest_time_m2": attractor.rest_time[1],
                "starts": int(share.starts),
                "fraction": float(share.fraction),
                "low": float(share.low),
                "high": float(share.high),
                "stable": None if orbit is None else bool(orbit.stable),
                "largest_multiplier": np.nan if orbit is None else float(np.max(np.abs(orbit.multipliers))),
                "lyapunov": attractor.lyapunov,
                "points": json.dumps(attractor.points.tolist()),
                "note": attractor.note,
            }
        )
    if -1 in shares.index:
        share = shares.loc[-1]
        rows.append(
            {
                "attractor": -1,
                "name": "failed",
                "kind": "failed",
                "starts": int(share.starts),
                "fraction": float(share.fraction),
                "low": float(share.low),
                "high": float(share.high),
            }
        )
    return pd.DataFrame(rows, columns=ATTRACTOR_COLUMNS)


def _color(ident: int) -> str:
    return FAILED if ident < 0 else COLORS[ident % len(COLORS)]


def basins_figure(basins: Basins) -> Figure:
    """The slice coloured by attractor, a legend naming each with its share, and each
    attractor's own section points (projected on the slice's plane) drawn on top."""
    from matplotlib.colors import ListedColormap
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    grid, x, y = basins.grid, basins.x, basins.y
    idents = sorted(set(np.unique(grid).tolist()))
    colormap = ListedColormap([_color(i) for i in idents])
    codes = np.searchsorted(idents, grid)
    fig = Figure(figsize=(7.5, 6.0), layout="constrained")
    ax = fig.add_subplot()
    ax.pcolormesh(x.values, y.values, codes, cmap=colormap, vmin=-0.5, vmax=len(idents) - 0.5, shading="nearest")
    shares = basins.found.fractions().set_index("attractor")
    handles: list[Any] = []
    for attractor in basins.found.attractors:
        share = shares.loc[attractor.id]
        label = f"{attractor.name} — {share_text(share.fraction, share.low, share.high)}"
        marker = MARKERS[attractor.id % len(MARKERS)]
        if attractor.period:
            handles.append(
                Line2D([], [], ls="", marker=marker, ms=11, color=_color(attractor.id), mec="black", label=label)
            )
        else:  # its basin's colour; its points are the black dots
            handles.append(Patch(facecolor=_color(attractor.id), edgecolor="black", label=f"{label} (dots: its set)"))
        _draw_points(ax, attractor, x.name, y.name)
    if -1 in shares.index:
        handles.append(Patch(color=FAILED, label=f"failed — {shares.loc[-1].fraction:.1%}"))
    ax.set_xlabel(state_label(x.name))
    ax.set_ylabel(state_label(y.name))
    fixed = [
        f"{name} = {value:g} {unit_of(name)}"
        for name, value in zip(STATE, basins.found.case.initial.y, strict=True)
        if name not in (x.name, y.name)
    ]
    what = f"basins at t0 = {basins.found.case.initial.t0:g} s, {', '.join(fixed)}"
    ax.set_title(wrapped_title(basins.found.case, what), parse_math=False, fontsize=9)
    ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.1), fontsize=8, ncol=1, frameon=False)
    return fig


def unit_of(name: str) -> str:
    """The unit of a state component: ``m`` for a displacement, ``m/s`` for a velocity."""
    return "m" if name.startswith("x") else "m/s"


def state_label(name: str) -> str:
    """An axis label for a state component, with its unit: ``x2 (m)``."""
    return f"{name} ({unit_of(name)})"


def wrapped_title(case: Any, what: str) -> str:
    """The case (with what its overrides changed) and what the figure shows, wrapped to the
    figure's width: a long list of changed values is not cut off."""
    import textwrap

    return textwrap.fill(f"{figure_title(case)}: {what}", width=100)


def _draw_points(ax: Any, attractor: Attractor, xname: str, yname: str) -> None:
    """The attractor's section points projected on the slice's plane.  A periodic attractor's few
    points: black-edged markers of its colour, one shape per attractor, smaller for each later
    attractor so that coinciding points of two attractors both show; an aperiodic set's many
    points: small black dots that draw its shape."""
    points = attractor.points
    xs, ys = points[:, STATE.index(xname)], points[:, STATE.index(yname)]
    if not attractor.period:
        ax.scatter(xs, ys, s=2, marker=".", color="black", linewidths=0, alpha=0.6, zorder=4, rasterized=True)
        return
    ax.scatter(
        xs,
        ys,
        s=max(150 - 50 * attractor.id, 30),
        marker=MARKERS[attractor.id % len(MARKERS)],
        color=_color(attractor.id),
        edgecolors="black",
        linewidths=1.0,
        zorder=5 + attractor.id,
    )


def lyapunov_figure(spectrum: LyapunovSpectrum) -> Figure:
    """The running averages of the four exponents against the averaging time."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7.0, 4.2), layout="constrained")
    ax = fig.add_subplot()
    table = spectrum.convergence
    for k in range(1, 5):
        values = table[f"lambda{k}"].to_numpy()
        if np.isfinite(values).any():
            ax.plot(table.t, values, label=f"lambda{k} -> {values[-1]:.4g} 1/s")
        else:  # nothing to draw: said in the legend all the same
            ax.plot([], [], ls="none", label=f"lambda{k} = {values[-1]:.4g} 1/s throughout (not drawn)")
    ax.axhline(0.0, color="0.5", lw=0.8)
    ax.set_xscale("log")
    ax.set_xlabel("averaging time (s)")
    ax.set_ylabel("exponent (1/s)")
    title = textwrap.fill(f"Lyapunov exponents of {figure_title(spectrum.case)}", 90)
    ax.set_title(title, parse_math=False, fontsize=9)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return fig


def _save(fig: Figure, folder: Path, name: str) -> None:
    folder.mkdir(exist_ok=True)
    for suffix in (".png", ".svg"):
        with atomic_path(folder / f"{name}{suffix}") as temporary:
            fig.savefig(temporary, format=suffix[1:], dpi=110)


def _basins_blocks(basins: Basins, table: pd.DataFrame) -> list[mk.Block]:
    case, x, y = basins.found.case, basins.x, basins.y
    settings = basins.found.settings
    rows = tuple(
        (
            str(row.name),
            str(row.kind),
            f"{row.starts}",
            share_text(row.fraction, row.low, row.high),
            "" if row.kind != "periodic" or pd.isna(row.stable) else ("stable" if row.stable else "unstable"),
            "" if pd.isna(row.largest_multiplier) else f"{row.largest_multiplier:.4g}",
            "" if pd.isna(row.signature) else str(row.signature),
        )
        for row in table.itertuples(index=False)
    )
    blocks: list[mk.Block] = [
        mk.Heading(1, (f"{case.name}: basins of attraction",)),
        mk.Paragraph(
            (
                f"{x.count} x {y.count} starts at t0 = {case.initial.t0:g} s, {x.name} from {x.low:g} to {x.high:g} "
                f"and {y.name} from {y.low:g} to {y.high:g}; each run {settings.transient} forcing periods, then "
                f"{settings.record} recorded. {len(basins.found.attractors)} attractor(s) found.",
            )
        ),
    ]
    blocks += modified_blocks(case)
    blocks += [mk.Paragraph((f"Warning: {warning}.",)) for warning in basins.found.warnings]
    header = ("attractor", "kind", "starts", "share [95% interval]", "orbit", "largest |multiplier|", "switches")
    caption = "the basins; the markers are each attractor's own section points, projected on the slice's plane"
    note = (
        "The share is the fraction of the slice's starts that reach the attractor; the interval, Wilson's 95 % "
        "interval for the fraction of the whole slice, as estimated from that many starts (none for one start)."
    )
    blocks += [mk.Table(header, rows), mk.Paragraph((note,)), mk.Figure("basins", caption)]
    return blocks


def _write_folder(
    folder: Path,
    tables: dict[str, pd.DataFrame],
    figures: Sequence[tuple[str, Callable[[], Figure]]],
    blocks: list[mk.Block],
    title: str,
) -> list[str]:
    """The tables first, then the figures (a failure kept as a problem, the tables safe), then
    the report, without the figures that were not drawn; every file written atomically."""
    problems = []
    for name, frame in tables.items():
        with atomic_path(folder / f"{name}.parquet") as temporary:
            frame.to_parquet(temporary, index=False)
    drawn = set()
    for name, draw in figures:
        try:
            _save(draw(), folder / "figures", name)
            drawn.add(name)
        except Exception as exc:  # a figure's failure keeps the computed tables
            problems.append(f"figure {name}: {exc}")
    blocks = [block for block in blocks if not isinstance(block, mk.Figure) or block.name in drawn]
    for name, text in (
        ("report.md", mk.to_markdown(blocks)),
        ("report.html", mk.to_html(blocks, folder=folder, title=title)),
    ):
        with atomic_path(folder / name) as temporary:
            temporary.write_text(text, encoding="utf-8")
    return problems


def write_basins(basins: Basins, folder: Path, *, plots: bool = True) -> list[str]:
    """Write the tables, the figure and the report into the basins folder (each file atomically).
    Returns what could not be written (a figure that failed), the tables being written first."""
    table = attractor_table(basins)
    figure = [("basins", lambda: basins_figure(basins))] if plots else []
    title = f"{basins.found.case.name}: basins of attraction"
    tables = {"basins": basins.table(), "attractors": table}
    return _write_folder(folder, tables, figure, _basins_blocks(basins, table), title)


def write_lyapunov(spectrum: LyapunovSpectrum, folder: Path, *, plots: bool = True) -> list[str]:
    """``lyapunov.parquet`` (the convergence), ``lyapunov.json`` (the exponents), the figure."""
    problems = []
    with atomic_path(folder / "lyapunov.parquet") as temporary:
        spectrum.convergence.to_parquet(temporary, index=False)
    info = {
        "case": spectrum.case.name,
        "modified": list(spectrum.case.modified),
        "periods": spectrum.periods,
        "exponents": [float(v) if np.isfinite(v) else str(v) for v in spectrum.exponents],
        "start": spectrum.start.tolist(),
        "dimension": spectrum.dimension,
    }
    with atomic_path(folder / "lyapunov.json") as temporary:
        temporary.write_text(json.dumps(info, indent=2), encoding="utf-8")
    if plots:
        try:
            _save(lyapunov_figure(spectrum), folder / "figures", "lyapunov")
        except Exception as exc:  # a figure's failure keeps the computed tables
            problems.append(f"figure lyapunov: {exc}")
    return problems


def following_figure(over: AttractorsOver, coordinate: str, branches: list[tuple[int, Branch]]) -> Figure:
    """Top: each attractor's section points (``coordinate``) against the parameter, one colour per
    kept id, the periodic orbits' branches under them (solid where stable, dotted where not) and
    the located appearances and ends (dashed lines); bottom: each attractor's share of the fresh
    starts, with its 95 % interval."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(8.0, 7.0), layout="constrained")
    top, bottom = fig.subplots(2, 1, sharex=True, height_ratios=(3, 2))
    column = STATE.index(coordinate)
    table = over.table()
    signatures = table.drop_duplicates("id").set_index("id").signature
    for ident, branch in branches:  # each only where the orbit keeps its attractor's cycle of switches
        points = branch.points
        own = (points.signature == signatures.get(ident)).to_numpy(bool)
        stable = points.stable.to_numpy(bool)
        values, ys = points[over.param].to_numpy(float), points[coordinate].to_numpy(float)
        for where, style in ((own & stable, "-"), (own & ~stable, ":")):  # solid where stable, dotted where not
            xs, cut = np.where(where, values, np.nan), np.where(where, ys, np.nan)
            top.plot(xs, cut, color=_color(ident), lw=0.8, ls=style)
    for ident, rows in table.groupby("id"):
        color = _color(int(ident))
        for value, points in zip(rows[over.param], rows.points, strict=True):
            cloud = np.asarray(json.loads(points), dtype=float).reshape(-1, 4)
            top.scatter(np.full(len(cloud), value), cloud[:, column], s=14, color=color, zorder=4)
        label = f"A{int(ident)}: {rows.name.iloc[0]}"
        # a share is measured at each value, not between them: steps, with each value's interval
        bottom.step(rows[over.param], rows.fraction, where="mid", color=color, lw=1.2, label=label)
        bottom.errorbar(
            rows[over.param],
            rows.fraction,
            yerr=[rows.fraction - rows.low, rows.high - rows.fraction],
            color=color,
            ls="none",
            marker="o",
            ms=4,
            capsize=2,
        )
    start, stop = float(over.values[0]), float(over.values[-1])
    for end in over.ends:
        for ax in (top, bottom):
            ax.axvline(end.at, color=_color(end.id), ls="--", lw=0.8)
        label = f"A{end.id} {end.change(start, stop)} at {over.param} = {end.at:.7g}"
        bottom.plot([], [], color=_color(end.id), ls="--", lw=0.8, label=label)
    top.set_ylabel(f"{coordinate} at the section ({unit_of(coordinate)})")
    bottom.set_ylabel("share of the fresh starts")
    bottom.set_xlabel(labelled(over.param))
    bottom.ticklabel_format(useOffset=False)
    bottom.set_ylim(-0.05, 1.05)
    bottom.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.25), ncol=2, frameon=False)
    for ax in (top, bottom):
        ax.grid(alpha=0.3)
    top.set_title(f"{figure_title(over.case)}: attractors over {over.param}", parse_math=False, fontsize=9)
    return fig


def _following_blocks(over: AttractorsOver, table: pd.DataFrame) -> list[mk.Block]:
    case, param = over.case, over.param
    values = over.values
    blocks: list[mk.Block] = [
        mk.Heading(1, (f"{case.name}: attractors over {param}",)),
        mk.Paragraph(
            (
                f"{len(values)} values of {param} from {values[0]:.10g} to {values[-1]:.10g}, {over.fresh} fresh "
                f"start(s) at each, and a seed from each attractor of the value before. "
                f"{table['id'].nunique() if len(table) else 0} attractor(s) in all.",
            )
        ),
    ]
    blocks += modified_blocks(case)
    start, stop = float(values[0]), float(values[-1])
    ends = tuple(
        (f"A{e.id}", e.name, e.change(start, stop), f"{e.inside:.10g}", f"{e.outside:.10g}", e.becomes)
        for e in over.ends
    )
    if ends:
        change = f"as {param} goes from {start:.10g} to {stop:.10g}, it"
        header = ("attractor", "what", change, f"last {param} with it", f"first {param} without it", "its seed goes to")
        blocks += [mk.Heading(2, ("Where attractors appear and end",)), mk.Table(header, ends)]
    rows = tuple(
        (
            f"{getattr(row, param):.10g}",
            f"A{row.id}",
            str(row.name),
            share_text(row.fraction, row.low, row.high),
        )
        for row in table.itertuples(index=False)
    )
    blocks += [
        mk.Heading(2, ("Attractors at each value",)),
        mk.Table((param, "attractor", "what", "share [95% interval]"), rows),
        mk.Figure("attractors", "each attractor's section points, its share, and the branches of orbits"),
    ]
    return blocks


def write_following(
    over: AttractorsOver, folder: Path, *, coordinate: str, branches: list[tuple[int, Branch]], plots: bool = True
) -> list[str]:
    """``attractors.parquet``, ``ends.parquet``, the figure and the report, into ``folder``."""
    table = over.table()
    figure = [("attractors", lambda: following_figure(over, coordinate, branches))] if plots else []
    title = f"{over.case.name}: attractors over {over.param}"
    tables = {"attractors": table, "ends": over.ends_table()}
    return _write_folder(folder, tables, figure, _following_blocks(over, table), title)


#: Fig. 14's two lines through the plane: Q2 = 71 (the Omega sweep) and Omega = 1.6 (the Q2 sweep).
FIG_14_LINES = {"Q2": 71.0, "Omega": 1.6}


#: What an atlas figure can be coloured by: the column of the atlas's table, and how it is named.
ATLAS_MEASURES = {
    "regime": "regime of the first attractor",
    "period": "period of the first attractor (0: aperiodic)",
    "coexisting": "number of coexisting attractors",
    "lyapunov": "largest Lyapunov exponent of the first attractor (1/s)",
    "impact_velocity": "largest impact velocity over the attractors (m/s)",
}
#: Fig. 14's two lines, each in its own colour, marked by a tick on the frame.
FIG_14_COLORS = {"Omega": "tab:red", "Q2": "tab:purple"}


def atlas_figure(atlas: Atlas, by: str = "regime") -> Figure:
    """The plane coloured by one of :data:`ATLAS_MEASURES`: categories (regime, period, number of
    attractors) in a legend, the exponent and the impact velocity on a colour bar; points where
    several attractors coexist hatched; Fig. 14's lines marked on the frame (outside the data,
    each in its own colour), not drawn across it."""
    from matplotlib.figure import Figure

    if by not in ATLAS_MEASURES:
        raise InputError(f"by must be one of {', '.join(ATLAS_MEASURES)}, got {by!r}", field="by")
    fig = Figure(figsize=(8.0, 6.5), layout="constrained")
    ax = fig.add_subplot()
    handles = _atlas_values(fig, ax, atlas, by)
    codes, coexisting, _ = atlas.grid()
    if (codes < 0).any():
        from matplotlib.colors import ListedColormap
        from matplotlib.patches import Patch

        failed = np.ma.masked_greater_equal(codes, 0)
        ax.pcolormesh(atlas.x.values, atlas.y.values, failed, cmap=ListedColormap([FAILED]), shading="nearest")
        handles.append(Patch(color=FAILED, label="failed"))
    handles += _hatch_coexisting(ax, atlas, coexisting > 1)
    handles += _fig_14_marks(ax, atlas)
    ax.set_xlabel(labelled(atlas.x.name))
    ax.set_ylabel(labelled(atlas.y.name))
    ax.ticklabel_format(useOffset=False)
    title = f"{figure_title(atlas.case)}: {ATLAS_MEASURES[by]} over {atlas.x.name} and {atlas.y.name}"
    ax.set_title(textwrap.fill(title, 90), parse_math=False, fontsize=9)
    if handles:
        ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.1), fontsize=8, ncol=2, frameon=False)
    return fig


def _atlas_values(fig: Figure, ax: Any, atlas: Atlas, by: str) -> list[Any]:
    """The cells coloured by ``by``; the legend's entries for a category, none for a colour bar."""
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    x, y = atlas.x.values, atlas.y.values
    table = atlas.table[atlas.table.status == "ok"]
    if by in ("lyapunov", "impact_velocity"):
        frame = table if by == "impact_velocity" else table[table.attractor <= 0]
        values = np.full((atlas.y.count, atlas.x.count), np.nan)
        cells = frame.groupby(["row", "column"])[by].max()
        values[cells.index.get_level_values(0), cells.index.get_level_values(1)] = cells.to_numpy()
        finite = np.ma.masked_invalid(np.where(np.isfinite(values), values, np.nan))
        mesh = ax.pcolormesh(x, y, finite, cmap="viridis", shading="nearest")
        fig.colorbar(mesh, ax=ax, label=ATLAS_MEASURES[by])
        return []
    first = table[table.attractor <= 0].drop_duplicates(["row", "column"])
    labels = first.regime if by == "regime" else first[by].astype(int)
    categories = sorted(labels.unique().tolist())
    codes = np.full((atlas.y.count, atlas.x.count), -1)
    codes[first.row, first.column] = [categories.index(value) for value in labels]
    palette = [COLORS[k % len(COLORS)] for k in range(len(categories))]
    shown = np.ma.masked_less(codes, 0)
    ax.pcolormesh(x, y, shown, cmap=ListedColormap(palette), vmin=-0.5, vmax=len(categories) - 0.5, shading="nearest")
    name = {"regime": "", "period": "period ", "coexisting": "attractors: "}[by]
    return [Patch(color=color, label=f"{name}{value}") for color, value in zip(palette, categories, strict=True)]


def _hatch_coexisting(ax: Any, atlas: Atlas, several: np.ndarray) -> list[Any]:
    """Each cell where several attractors coexist hatched; its legend entry."""
    from matplotlib.patches import Patch, Rectangle

    x, y = atlas.x.values, atlas.y.values
    dx, dy = (x[1] - x[0], y[1] - y[0])
    for row, column in zip(*np.nonzero(several), strict=True):
        corner = (x[column] - dx / 2, y[row] - dy / 2)
        ax.add_patch(Rectangle(corner, dx, dy, fill=False, hatch="////", lw=0.0, edgecolor="black"))
    if not several.any():
        return []
    return [Patch(facecolor="white", edgecolor="black", hatch="////", label="several attractors coexist")]


def _fig_14_marks(ax: Any, atlas: Atlas) -> list[Any]:
    """Fig. 14's lines where they cross the window: a long tick on the frame's opposite side (the
    top for a value of x, the right for one of y), labelled, each line in its own colour, so that
    the data under them stays visible."""
    from matplotlib.lines import Line2D

    handles = []
    for name, value in FIG_14_LINES.items():
        color = FIG_14_COLORS[name]
        if name == atlas.x.name and atlas.x.low <= value <= atlas.x.high:
            side = ax.secondary_xaxis("top")
            side.set_xticks([value], labels=[f"Fig. 14: {name} = {value:g}"])
        elif name == atlas.y.name and atlas.y.low <= value <= atlas.y.high:
            side = ax.secondary_yaxis("right")
            side.set_yticks([value], labels=[f"Fig. 14:\n{name} = {value:g}"])
        else:
            continue
        side.tick_params(color=color, labelcolor=color, length=12, width=3, labelsize=8)
        label = f"Fig. 14's line {name} = {value:g} (the tick on the frame)"
        handles.append(Line2D([], [], color=color, lw=3, label=label))
    return handles


def _atlas_blocks(atlas: Atlas) -> list[mk.Block]:
    case, x, y, table = atlas.case, atlas.x, atlas.y, atlas.table
    first = table[table.attractor <= 0]
    counts = first.regime.value_counts()
    rows = tuple((str(regime), str(int(count)), f"{count / len(first):.1%}") for regime, count in counts.items())
    several = int((first.coexisting > 1).sum())
    blocks: list[mk.Block] = [
        mk.Heading(1, (f"{case.name}: regime atlas over {x.name} and {y.name}",)),
        mk.Paragraph(
            (
                f"{x.count} x {y.count} points, {x.name} from {x.low:g} to {x.high:g} and {y.name} from {y.low:g} to "
                f"{y.high:g}; at {several} of them several attractors coexist.",
            )
        ),
    ]
    blocks += modified_blocks(case)
    blocks += [mk.Table(("regime (first attractor)", "points", "share"), rows)]
    blocks += [
        mk.Figure(atlas_figure_name(by), f"the {what} over the plane; hatched where several attractors coexist")
        for by, what in ATLAS_MEASURES.items()
    ]
    return blocks


def atlas_figure_name(by: str) -> str:
    """The file name of the atlas's figure coloured by ``by``: ``atlas`` for the regimes,
    ``atlas-lyapunov`` and so on for the others."""
    return "atlas" if by == "regime" else f"atlas-{by.replace('_', '-')}"


def write_atlas(atlas: Atlas, folder: Path, *, plots: bool = True) -> list[str]:
    """``atlas.parquet`` (one row per attractor of each point), a figure for each of
    :data:`ATLAS_MEASURES` and the report."""
    measures = ATLAS_MEASURES if plots else {}
    figure = [(atlas_figure_name(by), functools.partial(atlas_figure, atlas, by)) for by in measures]
    title = f"{atlas.case.name}: regime atlas"
    return _write_folder(folder, {"atlas": atlas.table}, figure, _atlas_blocks(atlas), title)


#: Line styles of the curves drawn over one plane, in turn.
CURVE_STYLES = ("-", "--", "-.", ":")


def curve_figure(curves: Curve | Sequence[Curve], atlas: Atlas | None = None) -> Figure:
    """Bifurcation curves in their plane (one or several, each in its own style, named in the
    legend), over the atlas's regimes when one is given."""
    from matplotlib.figure import Figure

    several = [curves] if isinstance(curves, Curve) else list(curves)
    first = several[0]
    if atlas is not None:
        fig = atlas_figure(atlas)
        ax = fig.axes[0]
        legend = ax.get_legend()
        handles = list(legend.legend_handles) if legend is not None else []
    else:
        fig = Figure(figsize=(7.0, 5.5), layout="constrained")
        ax = fig.add_subplot()
        ax.set_xlabel(labelled(first.x))
        ax.set_ylabel(labelled(first.y))
        ax.grid(alpha=0.3)
        handles = []
    for k, curve in enumerate(several):
        (line,) = ax.plot(
            curve.points[curve.x],
            curve.points[curve.y],
            color="black",
            lw=1.6,
            ls=CURVE_STYLES[k % len(CURVE_STYLES)],
            marker=".",
            ms=4,
            label=f"{curve.kind} curve ({len(curve.points)} points)",
        )
        handles.append(line)
        if curve.inside_point is not None:
            _side_labels(ax, curve)
    ax.ticklabel_format(useOffset=False)
    kinds = " and ".join(dict.fromkeys(curve.kind for curve in several))
    title = f"{kinds} curve in {first.x} and {first.y}"
    if atlas is not None:
        title = f"{figure_title(atlas.case)}: {title}, over the regime of the first attractor"
    ax.set_title(textwrap.fill(title, 90), parse_math=False, fontsize=9)
    ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.1), fontsize=8, ncol=2, frameon=False)
    return fig


def _side_labels(ax: Any, curve: Curve) -> None:
    """The curve's two sides named beside its start: where its orbit exists, and where not (a
    tenth of the axes' span off the curve, along the normal toward ``inside_point``)."""
    assert curve.inside_point is not None
    spans = np.array([np.ptp(ax.get_xlim()), np.ptp(ax.get_ylim())])
    start = curve.points[[curve.x, curve.y]].to_numpy()
    inside = np.array(curve.inside_point)
    near = start[np.argmin(np.sum(((start - inside) / spans) ** 2, axis=1))]
    unit = (inside - near) / spans
    offset = 0.1 * spans * unit / max(float(np.linalg.norm(unit)), 1e-300)
    box = {"boxstyle": "round,pad=0.2", "facecolor": "white", "alpha": 0.85, "lw": 0}
    for where, text in ((near + offset, "its orbit exists"), (near - offset, "its orbit does not")):
        ax.annotate(text, tuple(where), fontsize=7, ha="center", va="center", bbox=box, zorder=7)


def read_atlas(folder: Path, case: Case | None = None) -> Atlas:
    """The atlas of a folder ``oscillator atlas`` wrote (its axes from atlas.json, its table from
    atlas.parquet; the folder's case.toml unless ``case`` is given), every file checked: a folder
    that holds none, or a damaged one, is refused naming it."""
    from oscillator.analysis.axes import Axis
    from oscillator.io.cases import load_case
    from oscillator.io.files import read_untrusted

    shown_folder = printable(str(folder))
    try:
        info = json.loads(read_untrusted(folder / "atlas.json", what="atlas file", field="folder", limit=1_000_000))
        identity = info["identity"]
        x, y = (Axis(**identity[name]) for name in ("x", "y"))
        table = pd.read_parquet(folder / "atlas.parquet")
        case = case if case is not None else load_case(folder / "case.toml")
    except (OSError, ValueError, KeyError, TypeError, OscillatorError) as error:
        raise InputError(f"{shown_folder} holds no finished atlas ({error})", field="folder") from None
    found = Atlas(case, x, y, table)
    try:
        found.grid()  # every point in its cell, or the table is damaged
    except (AttributeError, IndexError, KeyError, TypeError, ValueError) as error:
        raise InputError(f"{shown_folder}: its atlas.parquet is damaged ({error})", field="folder") from None
    return found


def read_curve(folder: Path) -> Curve:
    """The curve of a folder ``oscillator curve`` wrote (``curve.json``, ``curve.parquet``), every
    file checked: a folder that holds none, or a damaged one, is refused naming it."""
    from oscillator.io.files import read_untrusted

    shown_folder = printable(str(folder))
    try:
        info = json.loads(read_untrusted(folder / "curve.json", what="curve file", field="folder", limit=1_000_000))
        x, y, kind, inside = (str(info[key]) for key in ("x", "y", "kind", "inside"))
        ends = tuple(str(end) for end in info["ends"])
        points = pd.read_parquet(folder / "curve.parquet")[[x, y]].astype(float)
    except InputError as error:
        raise InputError(f"{shown_folder} holds no curve ({error})", field="folder") from None
    except (OSError, ValueError, KeyError, TypeError) as error:
        raise InputError(f"{shown_folder} holds no curve, or a damaged one ({error})", field="folder") from None
    if len(ends) != 2 or not len(points) or not np.isfinite(points.to_numpy()).all():
        raise InputError(f"{shown_folder}: its curve is damaged (its ends or points)", field="folder")
    side = info.get("inside_point")
    ok = isinstance(side, list) and len(side) == 2 and all(isinstance(v, (int, float)) for v in side)
    inside_point = (float(side[0]), float(side[1])) if ok and np.isfinite(side).all() else None
    return Curve(kind, x, y, points, (ends[0], ends[1]), (), inside, inside_point)


def write_curve(
    curve: Curve, folder: Path, *, atlas: Atlas | None = None, plots: bool = True, also: Sequence[Curve] = ()
) -> list[str]:
    """``curve.parquet``, ``curve.json`` (how it ended, its folds), the figure (with the curves
    ``also`` drawn beside it) and the report."""
    info = {
        "kind": curve.kind,
        "x": curve.x,
        "y": curve.y,
        "inside": curve.inside,
        "inside_point": None if curve.inside_point is None else list(curve.inside_point),
        "ends": list(curve.ends),
        "folds": [list(f) for f in curve.folds],
    }
    with atomic_path(folder / "curve.json") as temporary:
        temporary.write_text(json.dumps(info, indent=2), encoding="utf-8")
    rows = tuple((f"{row[0]:.10g}", f"{row[1]:.10g}") for row in curve.points[[curve.x, curve.y]].to_numpy())
    blocks: list[mk.Block] = [
        mk.Heading(1, (f"{curve.kind} curve in {curve.x} and {curve.y}",)),
        mk.Paragraph((f"The border of the orbit {curve.inside}; {len(curve.points)} points.",)),
        mk.Bullets(tuple((f"one end: {end}",) for end in curve.ends)),
        mk.Table((curve.x, curve.y), rows),
        mk.Figure("curve", "the curve" + (" over the atlas's regimes" if atlas is not None else "")),
    ]
    figure = [("curve", lambda: curve_figure([curve, *also], atlas))] if plots else []
    return _write_folder(folder, {"curve": curve.points}, figure, blocks, f"{curve.kind} curve")


def rebuild(folder: Path) -> str | None:
    """Rebuild the tables, figures and report of a finished basins, atlas or curve folder from
    what it keeps (for ``oscillator report``); what was rebuilt, or None for a folder of another
    kind.  The landings and rows are read back, never computed: an unfinished folder is refused
    (the command that made it resumes it)."""
    from oscillator.io.cases import load_case

    if (folder / "curve.json").exists():
        write_curve(read_curve(folder), folder)
        return "the curve (drawn without an atlas)"
    if (folder / "attractors.json").exists():
        raise InputError(
            f"{printable(str(folder))}: an attractors folder is rebuilt by running the command that made it again with "
            "the same --out: it reads its landings back and computes none",
            field="folder",
        )
    if (folder / "lyapunov.json").exists():
        raise InputError(
            f"{printable(str(folder))}: a Lyapunov folder keeps no state to redraw from; run the same lyapunov "
            "command with a new --out (it takes seconds)",
            field="folder",
        )
    if (folder / "basins.json").exists():
        _rebuild_basins(folder, _identity(folder / "basins.json"), load_case(folder / "case.toml"))
        return "the basins"
    if (folder / "atlas.json").exists():
        _rebuild_atlas(folder, _identity(folder / "atlas.json"), load_case(folder / "case.toml"))
        return "the atlas"
    return None


def _rebuild_basins(folder: Path, identity: dict[str, Any], case: Any) -> None:
    from oscillator.analysis.axes import Axis
    from oscillator.attractors.basins import basin_store, find_basins, grid_starts
    from oscillator.attractors.mapping import AttractorSettings

    try:
        x, y = (Axis(**identity[name]) for name in ("x", "y"))
        settings = AttractorSettings(**identity["settings"])
    except (KeyError, TypeError) as error:
        raise InputError(f"{printable(str(folder))}/basins.json is damaged ({error})", field="folder") from None
    store = basin_store(folder, case, x, y, settings)
    store.check()  # this very computation, or refused
    _finished(store, len(grid_starts(case, x, y)), "starts")
    write_basins(find_basins(case, x, y, store, settings=settings), folder)


def _rebuild_atlas(folder: Path, identity: dict[str, Any], case: Any) -> None:
    from oscillator.analysis.axes import Axis
    from oscillator.attractors.atlas import AtlasSettings, atlas_store, regime_atlas

    try:
        x, y = (Axis(**identity[name]) for name in ("x", "y"))
        settings = AtlasSettings(**identity["settings"])
    except (KeyError, TypeError) as error:
        raise InputError(f"{printable(str(folder))}/atlas.json is damaged ({error})", field="folder") from None
    store = atlas_store(folder, case, x, y, settings)
    store.check()  # this very computation, or refused
    _finished(store, y.count, "rows", batches=True)
    write_atlas(regime_atlas(case, x, y, settings=settings, store=store), folder)


def _identity(marker: Path) -> dict[str, Any]:
    """The identity a folder's marker file holds (checked as untrusted text)."""
    from oscillator.io.files import read_untrusted

    try:
        identity = json.loads(read_untrusted(marker, what="marker file", field="folder", limit=1_000_000))["identity"]
        if not isinstance(identity, dict):
            raise TypeError("not a table")
    except (ValueError, KeyError, TypeError, RecursionError) as error:
        raise InputError(f"{printable(str(marker))} is damaged ({error}); give a new folder", field="folder") from None
    return identity


def _finished(store: Any, total: int, what: str, *, batches: bool = False) -> None:
    """Refuse a folder whose computation has not finished: ``report`` reads back, never computes."""
    parts = sorted(store.parts.glob("batch-*.parquet" if batches else "*.parquet"))
    done = len(parts) if batches else sum(len(pd.read_parquet(part)) for part in parts)
    if done < total:
        raise InputError(
            f"{printable(str(store.folder))} is not finished ({done} of {total} {what}); run the command that made it "
            "again with the same --out to resume it",
            field="folder",
        )
