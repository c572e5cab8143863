"""Basins, the attractors over a parameter and Lyapunov spectra written out: tables, figures, a
report (text escaped).

A basins folder holds ``basins.parquet`` (one row per cell: the two axes' values, the
attractor, the run's status), ``attractors.parquet`` (one row per attractor: its name, kind,
period, cycle of switches, share of the starts with a confidence interval, stability and
largest multiplier, Lyapunov exponent, section points), ``figures/basins.png`` (and ``.svg``),
``report.md`` and ``report.html``, beside ``basins.json``, ``case.toml`` and ``parts/``.
"""

from __future__ import annotations

import json
import textwrap
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from oscillator.analysis.axes import STATE
from oscillator.attractors.basins import Basins
from oscillator.attractors.chain_attractors import ChainBasins
from oscillator.attractors.finding import share_text
from oscillator.attractors.following import AttractorsOver
from oscillator.attractors.grouping import Attractor
from oscillator.attractors.lyapunov import LyapunovSpectrum
from oscillator.io.cases import Case, case_to_toml
from oscillator.io.chains import chain_to_toml
from oscillator.io.files import atomic_path
from oscillator.model.chain_fields import state_of
from oscillator.model.chains import FrictionChain
from oscillator.orbits.response import COLUMNS
from oscillator.report import markup as mk
from oscillator.report.figures import figure_title
from oscillator.report.global_folders import write_found
from oscillator.report.orbits import modified_blocks
from oscillator.report.outputs import (
    FAILED,
    MARKERS,
    color_of,
    number_label,
    plain_label,
    save_into,
    state_label,
    unit_of,
    write_folder,
)
from oscillator.text import printable

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

    from oscillator.orbits.branch import Branch

__all__ = [
    "attractor_table",
    "basins_blocks",
    "basins_figure",
    "following_blocks",
    "following_figure",
    "lyapunov_figure",
    "name_of",
    "write_basins",
    "write_following",
    "write_lyapunov",
]


#: The columns of ``attractors.parquet`` (the same when every start failed and there is no attractor).
ATTRACTOR_COLUMNS = [
    *(
        "attractor name kind period signature rests_m1 rests_m2 contacts rest_time_m1 rest_time_m2 starts fraction low "
        "high stable largest_multiplier lyapunov"
    ).split(),
    *COLUMNS,
    "points",
    "note",
]


def attractor_table(basins: Basins) -> pd.DataFrame:
    """One row per attractor (and one for failed starts, if any): what it is and its share."""
    rows = []
    for attractor, row in attractor_rows(basins.found.attractors, basins.found.fractions()):
        masses = {"rests_m1": attractor.rests[0], "rests_m2": attractor.rests[1], "contacts": attractor.contacts}
        masses |= {"rest_time_m1": attractor.rest_time[0], "rest_time_m2": attractor.rest_time[1]}
        rows.append(row | masses | attractor.response_columns())
    return pd.DataFrame(rows + failed_rows(basins.found.fractions()), columns=ATTRACTOR_COLUMNS)


def attractor_rows(attractors: Sequence[Attractor], fractions: pd.DataFrame) -> list[tuple[Attractor, dict[str, Any]]]:
    """Each attractor with the columns every attractor table has: ``attractor, name, kind,
    period, signature, starts, fraction, low, high, stable, largest_multiplier, lyapunov,
    points`` (JSON) and ``note`` (its share from ``fractions``)."""
    shares = fractions.set_index("attractor")
    found = []
    for attractor in attractors:
        share, orbit = shares.loc[attractor.id], attractor.orbit
        largest = np.nan if orbit is None else float(np.max(np.abs(orbit.multipliers), initial=0.0))
        row = {"attractor": attractor.id, "name": attractor.name, "kind": attractor.kind, "period": attractor.period}
        row |= {"signature": attractor.signature, "starts": int(share.starts), "fraction": float(share.fraction)}
        row |= {"low": float(share.low), "high": float(share.high)}
        row |= {"stable": None if orbit is None else bool(orbit.stable), "largest_multiplier": largest}
        row |= {"lyapunov": attractor.lyapunov, "points": json.dumps(attractor.points.tolist()), "note": attractor.note}
        found.append((attractor, row))
    return found


def failed_rows(fractions: pd.DataFrame) -> list[dict[str, Any]]:
    """The row of the starts that failed (none if none did)."""
    shares = fractions.set_index("attractor")
    if -1 not in shares.index:
        return []
    share = shares.loc[-1]
    row = {"attractor": -1, "name": "failed", "kind": "failed", "starts": int(share.starts)}
    return [row | {"fraction": float(share.fraction), "low": float(share.low), "high": float(share.high)}]


def basins_figure(basins: Basins | ChainBasins) -> Figure:
    """The slice coloured by attractor, a legend naming each with its share, and each
    attractor's own section points (projected on the slice's plane) drawn on top (a case's or a
    declared system's)."""
    from matplotlib.colors import ListedColormap
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    grid, x, y = basins.grid, basins.x, basins.y
    state, start, t0, title = _slice_of(basins)
    idents = sorted(set(np.unique(grid).tolist()))
    colormap = ListedColormap([color_of(i) for i in idents])
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
                Line2D([], [], ls="", marker=marker, ms=11, color=color_of(attractor.id), mec="black", label=label)
            )
        else:  # its basin's colour; its points are the black dots
            handles.append(Patch(facecolor=color_of(attractor.id), edgecolor="black", label=f"{label} (dots: its set)"))
        _draw_points(ax, attractor, state.index(x.name), state.index(y.name))
    if -1 in shares.index:
        handles.append(Patch(color=FAILED, label=f"failed — {shares.loc[-1].fraction:.1%}"))
    ax.set_xlabel(state_label(x.name), parse_math=False)  # a declared system's names are its file's text
    ax.set_ylabel(state_label(y.name), parse_math=False)
    fixed = [f"{name} = {value:g} {unit_of(name)}" for name, value in zip(state, start, strict=True)]
    kept = [f for f, n in zip(fixed, state, strict=True) if n not in (x.name, y.name)]
    what = ", ".join([f"basins at t0 = {t0:g} s", *kept])
    ax.set_title(textwrap.fill(f"{title}: {what}", width=100), parse_math=False, fontsize=9)
    legend = ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.1), fontsize=8, frameon=False)
    for text in legend.get_texts():  # the attractors' names carry a declared system's mass names
        text.set_parse_math(False)
    return fig


def _slice_of(basins: Basins | ChainBasins) -> tuple[tuple[str, ...], np.ndarray, float, str]:
    """The slice's state names, the start it varies two of, its section time and its title."""
    if isinstance(basins, ChainBasins):
        chain = basins.found.chain
        return chain.system.state, state_of(chain), chain.t0, title_of(chain)
    case = basins.found.case
    return STATE, np.asarray(case.initial.y), case.initial.t0, title_of(case)


def name_of(system: Case | FrictionChain) -> str:
    """The case's name, or the declared system's title (as written: escape it where it is shown)."""
    return system.name if isinstance(system, Case) else (system.title or "friction chain")


def title_of(system: Case | FrictionChain) -> str:
    """A figure's title for the case (what its overrides changed) or the declared system (its
    title, as plain text)."""
    if isinstance(system, FrictionChain):
        return printable(system.title or "friction chain")
    return figure_title(system)


def _draw_points(ax: Any, attractor: Attractor, i: int, j: int) -> None:
    """The attractor's section points projected on the slice's plane.  A periodic attractor's few
    points: black-edged markers of its colour, one shape per attractor, smaller for each later
    attractor so that coinciding points of two attractors both show; an aperiodic set's many
    points: small black dots that draw its shape."""
    points = attractor.points
    xs, ys = points[:, i], points[:, j]
    if not attractor.period:
        ax.scatter(xs, ys, s=2, marker=".", color="black", linewidths=0, alpha=0.6, zorder=4, rasterized=True)
        return
    ax.scatter(
        xs,
        ys,
        s=max(150 - 50 * attractor.id, 30),
        marker=MARKERS[attractor.id % len(MARKERS)],
        color=color_of(attractor.id),
        edgecolors="black",
        linewidths=1.0,
        zorder=5 + attractor.id,
    )


def lyapunov_figure(spectrum: LyapunovSpectrum) -> Figure:
    """The running averages of the exponents against the averaging time."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7.0, 4.2), layout="constrained")
    ax = fig.add_subplot()
    table = spectrum.convergence
    for k in range(1, len(spectrum.exponents) + 1):
        values = table[f"lambda{k}"].to_numpy()
        if np.isfinite(values).any():
            ax.plot(table.t, values, label=f"lambda{k} -> {values[-1]:.4g} 1/s")
        else:  # nothing to draw: said in the legend all the same
            ax.plot([], [], ls="none", label=f"lambda{k} = {values[-1]:.4g} 1/s throughout (not drawn)")
    ax.axhline(0.0, color="0.5", lw=0.8)
    ax.set_xscale("log")
    ax.set_xlabel("averaging time (s)")
    ax.set_ylabel("exponent (1/s)")
    title = textwrap.fill(f"Lyapunov exponents of {title_of(spectrum.case)}", 90)
    ax.set_title(title, parse_math=False, fontsize=9)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return fig


def basins_blocks(basins: Basins, table: pd.DataFrame) -> list[mk.Block]:
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


def write_basins(basins: Basins, folder: Path, *, plots: bool = True) -> list[str]:
    """Write the tables, the figure and the report into the basins folder (each file atomically).
    Returns what could not be written (a figure that failed), the tables being written first."""
    table = attractor_table(basins)
    figure = [("basins", lambda: basins_figure(basins))] if plots else []
    title = f"{basins.found.case.name}: basins of attraction"
    tables = {"basins": basins.table(), "attractors": table}
    write_found(folder, [basins.found])
    return write_folder(folder, tables, figure, basins_blocks(basins, table), title)


def write_lyapunov(spectrum: LyapunovSpectrum, folder: Path, *, plots: bool = True) -> list[str]:
    """``lyapunov.parquet`` (the convergence), ``lyapunov.json`` (the exponents), the figure."""
    problems = []
    with atomic_path(folder / "lyapunov.parquet") as temporary:
        spectrum.convergence.to_parquet(temporary, index=False)
    system = spectrum.case
    if isinstance(system, FrictionChain):  # a declared system: its own file beside the spectrum
        name, modified, source, text = system.title, [], "system.toml", chain_to_toml(system)
    else:
        name, modified, source, text = system.name, list(system.modified), "case.toml", case_to_toml(system)
    info = {
        "case": name,
        "modified": modified,
        "periods": spectrum.periods,
        "exponents": [float(v) if np.isfinite(v) else str(v) for v in spectrum.exponents],
        "start": spectrum.start.tolist(),
        "dimension": spectrum.dimension,
    }
    with atomic_path(folder / "lyapunov.json") as temporary:
        temporary.write_text(json.dumps(info, indent=2), encoding="utf-8")
    if not (folder / source).exists():
        with atomic_path(folder / source) as temporary:
            temporary.write_text(text, encoding="utf-8")
    if plots:
        try:
            save_into(lyapunov_figure(spectrum), folder / "figures", "lyapunov")
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
    state = over.case.system.state
    column = state.index(coordinate)
    table = over.table()
    signatures = table.drop_duplicates("id").set_index("id").signature
    for ident, branch in branches:  # each only where the orbit keeps its attractor's cycle of switches
        points = branch.points  # a chain's branch keeps no cycles of switches: drawn whole
        own = (points.signature == signatures.get(ident)).to_numpy(bool) if "signature" in points else True
        stable = points.stable.to_numpy(bool)
        values, ys = points[over.param].to_numpy(float), points[coordinate].to_numpy(float)
        for where, style in ((own & stable, "-"), (own & ~stable, ":")):  # solid where stable, dotted where not
            xs, cut = np.where(where, values, np.nan), np.where(where, ys, np.nan)
            top.plot(xs, cut, color=color_of(ident), lw=0.8, ls=style)
    for ident, rows in table.groupby("id"):
        color = color_of(int(ident))
        for value, points in zip(rows[over.param], rows.points, strict=True):
            cloud = np.asarray(json.loads(points), dtype=float).reshape(-1, len(state))
            top.scatter(np.full(len(cloud), value), cloud[:, column], s=14, color=color, zorder=4)
        label = plain_label(f"A{int(ident)}: {rows.name.iloc[0]}")
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
            ax.axvline(end.at, color=color_of(end.id), ls="--", lw=0.8)
        label = plain_label(f"A{end.id} {end.change(start, stop)} at {over.param} = {end.at:.7g}")
        bottom.plot([], [], color=color_of(end.id), ls="--", lw=0.8, label=label)
    top.set_ylabel(plain_label(f"{coordinate} at the section ({unit_of(coordinate)})"))
    bottom.set_ylabel("share of the fresh starts")
    bottom.set_xlabel(number_label(over.case, over.param))
    bottom.ticklabel_format(useOffset=False)
    bottom.set_ylim(-0.05, 1.05)
    bottom.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.25), ncol=2, frameon=False)
    for ax in (top, bottom):
        ax.grid(alpha=0.3)
    top.set_title(f"{title_of(over.case)}: attractors over {over.param}", parse_math=False, fontsize=9)
    return fig


def following_blocks(over: AttractorsOver, table: pd.DataFrame) -> list[mk.Block]:
    case, param = over.case, over.param
    values = over.values
    blocks: list[mk.Block] = [
        mk.Heading(1, (f"{name_of(case)}: attractors over {param}",)),
        mk.Paragraph(
            (
                f"{len(values)} values of {param} from {values[0]:.10g} to {values[-1]:.10g}, {over.fresh} fresh "
                f"start(s) at each, and a seed from each attractor of the value before. "
                f"{table['id'].nunique() if len(table) else 0} attractor(s) in all.",
            )
        ),
    ]
    blocks += modified_blocks(case) if isinstance(case, Case) else []
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
    """``attractors.parquet``, ``ends.parquet``, the figure and the report, into ``folder``; the
    attractors kept for :func:`oscillator.read_run` too (the article's case: ``found.json``)."""
    table = over.table()
    figure = [("attractors", lambda: following_figure(over, coordinate, branches))] if plots else []
    title = f"{title_of(over.case)}: attractors over {over.param}"
    tables = {"attractors": table, "ends": over.ends_table()}
    if not isinstance(over.case, FrictionChain):
        write_found(folder, over.found, [{"ids": sorted(ids.items()), "fresh": over.fresh} for ids in over.ids])
    return write_folder(folder, tables, figure, following_blocks(over, table), title)
