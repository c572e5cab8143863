"""The parameter plane written out: the atlas (coloured by any of its measures, Fig. 14's lines
marked) and the bifurcation curves traced across it; their folders written and read back, every
file read checked."""

from __future__ import annotations

import functools
import hashlib
import json
import re
import textwrap
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from oscillator.attractors.atlas import Atlas
from oscillator.errors import InputError, OscillatorError
from oscillator.io.cases import Case
from oscillator.io.files import atomic_path
from oscillator.model.chains import FrictionChain
from oscillator.model.parameters import labelled
from oscillator.orbits.curves import Curve
from oscillator.report import markup as mk
from oscillator.report.attractors import name_of, title_of
from oscillator.report.orbits import modified_blocks
from oscillator.report.outputs import COLORS, FAILED, folder_system, number_label, plain_label, write_folder
from oscillator.text import printable

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure


__all__ = [
    "ATLAS_MEASURES",
    "atlas_blocks",
    "atlas_figure",
    "atlas_measures",
    "curve_blocks",
    "curve_figure",
    "read_atlas",
    "read_curve",
    "write_atlas",
    "write_curve",
]


#: What an atlas figure can be coloured by: the column of the atlas's table, and how it is named.
ATLAS_MEASURES = {
    "regime": "regime of the first attractor",
    "period": "period of the first attractor (0: aperiodic)",
    "coexisting": "number of coexisting attractors",
    "lyapunov": "largest Lyapunov exponent of the first attractor (1/s)",
    "impact_velocity": "largest impact velocity over the attractors (m/s)",
}


def atlas_measures(atlas: Atlas) -> dict[str, str]:
    """What this atlas can be coloured by, and how each is named: :data:`ATLAS_MEASURES` that its
    table has (a chain's has no fixed impact velocity) and the response measures it was computed
    with (their largest value over a point's attractors)."""
    from oscillator.orbits.chain_response import measure_unit
    from oscillator.orbits.response import above_note, unit_of

    unit = measure_unit if isinstance(atlas.case, FrictionChain) else unit_of
    units = {name: f" ({unit(name)}{above_note(name, atlas.cutoff)})" if unit(name) else "" for name in atlas.measures}
    fixed = {by: what for by, what in ATLAS_MEASURES.items() if by in atlas.table}
    return fixed | {name: f"largest {name} over the attractors{units[name]}" for name in atlas.measures}


def atlas_figure(atlas: Atlas, by: str = "regime") -> Figure:
    """The plane coloured by one of :data:`ATLAS_MEASURES`: categories (regime, period, number of
    attractors) in a legend, the exponent and the impact velocity on a colour bar; points where
    several attractors coexist hatched; Fig. 14's lines marked on the frame (outside the data,
    each in its own colour), not drawn across it."""
    from matplotlib.figure import Figure

    named = atlas_measures(atlas)
    if by not in named:
        raise InputError(f"by must be one of {', '.join(named)}, got {by!r}", field="by")
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
    handles += _fig_14_marks(ax, atlas) if isinstance(atlas.case, Case) else []  # the article's figure
    ax.set_xlabel(number_label(atlas.case, atlas.x.name))
    ax.set_ylabel(number_label(atlas.case, atlas.y.name))
    ax.ticklabel_format(useOffset=False)
    title = f"{title_of(atlas.case)}: {named[by]} over {atlas.x.name} and {atlas.y.name}"
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
    if by == "lyapunov" or by in ("impact_velocity", *atlas.measures):
        frame = table[table.attractor <= 0] if by == "lyapunov" else table
        values = np.full((atlas.y.count, atlas.x.count), np.nan)
        cells = frame.groupby(["row", "column"])[by].max()
        values[cells.index.get_level_values(0), cells.index.get_level_values(1)] = cells.to_numpy()
        finite = np.ma.masked_invalid(np.where(np.isfinite(values), values, np.nan))
        mesh = ax.pcolormesh(x, y, finite, cmap="viridis", shading="nearest")
        fig.colorbar(mesh, ax=ax, label=plain_label(atlas_measures(atlas)[by]))
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
    return [
        Patch(color=color, label=plain_label(f"{name}{value}"))
        for color, value in zip(palette, categories, strict=True)
    ]


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


def atlas_blocks(atlas: Atlas) -> list[mk.Block]:
    case, x, y, table = atlas.case, atlas.x, atlas.y, atlas.table
    first = table[table.attractor <= 0]
    counts = first.regime.value_counts()
    rows = tuple((str(regime), str(int(count)), f"{count / len(first):.1%}") for regime, count in counts.items())
    several = int((first.coexisting > 1).sum())
    blocks: list[mk.Block] = [
        mk.Heading(1, (f"{name_of(case)}: regime atlas over {x.name} and {y.name}",)),
        mk.Paragraph(
            (
                f"{x.count} x {y.count} points, {x.name} from {x.low:g} to {x.high:g} and {y.name} from {y.low:g} to "
                f"{y.high:g}; at {several} of them several attractors coexist.",
            )
        ),
    ]
    blocks += modified_blocks(case) if isinstance(case, Case) else []
    blocks += [mk.Table(("regime (first attractor)", "points", "share"), rows)]
    blocks += [
        mk.Figure(atlas_figure_name(by), f"the {what} over the plane; hatched where several attractors coexist")
        for by, what in atlas_measures(atlas).items()
    ]
    return blocks


def atlas_figure_name(by: str) -> str:
    """The file name of the atlas's figure coloured by ``by``: ``atlas`` for the regimes,
    ``atlas-lyapunov`` and so on for the others (``x_max:blade``: ``atlas-x-max-blade``; a name
    with other characters than ``a-z0-9_:`` gets 8 hex digits of its hash, so that two names never
    share a file)."""
    if by == "regime":
        return "atlas"
    slug = re.sub(r"[^a-z0-9]+", "-", by.lower()).strip("-")
    if not re.fullmatch(r"[a-z0-9_:]+", by) or not slug:
        slug = f"{slug}-{hashlib.sha256(by.encode('utf-8')).hexdigest()[:8]}".lstrip("-")
    return f"atlas-{slug}"


def write_atlas(atlas: Atlas, folder: Path, *, plots: bool = True) -> list[str]:
    """``atlas.parquet`` (one row per attractor of each point), a figure for each of
    :func:`atlas_measures` and the report."""
    measures = atlas_measures(atlas) if plots else {}
    figure = [(atlas_figure_name(by), functools.partial(atlas_figure, atlas, by)) for by in measures]
    title = f"{name_of(atlas.case)}: regime atlas"
    return write_folder(folder, {"atlas": atlas.table}, figure, atlas_blocks(atlas), title)


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
        xlabel, ylabel = (labelled(first.x), labelled(first.y)) if first.labels is None else first.labels
        ax.set_xlabel(plain_label(xlabel))
        ax.set_ylabel(plain_label(ylabel))
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
    title = f"{kinds} curve in {printable(first.x)} and {printable(first.y)}"
    if atlas is not None:
        title = f"{title_of(atlas.case)}: {title}, over the regime of the first attractor"
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


def read_atlas(folder: Path, case: Case | FrictionChain | None = None) -> Atlas:
    """The atlas of a folder ``oscillator atlas`` wrote (its axes from atlas.json, its table from
    atlas.parquet; the folder's case.toml or a declared system's system.toml unless ``case`` is
    given), every file checked: a folder that holds none, or a damaged one, is refused naming it."""
    from oscillator.analysis.axes import Axis
    from oscillator.io.files import read_untrusted

    shown_folder = printable(str(folder))
    try:
        info = json.loads(read_untrusted(folder / "atlas.json", what="atlas file", field="folder", limit=1_000_000))
        identity = info["identity"]
        x, y = (Axis(**identity[name]) for name in ("x", "y"))
        held = identity["settings"] if "settings" in identity else identity  # computed, or saved (Atlas.save)
        cutoff = float(held["cutoff"]) if "cutoff" in held else 0.0  # an atlas of before the cut-off: 0 Hz
        table = pd.read_parquet(folder / "atlas.parquet")
        case = case if case is not None else folder_system(folder, "atlas.json")
    except (OSError, ValueError, KeyError, TypeError, OscillatorError) as error:
        raise InputError(f"{shown_folder} holds no finished atlas ({error})", field="folder") from None
    found = Atlas(case, x, y, table, cutoff)
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
    given = info.get("labels")
    named = isinstance(given, list) and len(given) == 2 and all(isinstance(label, str) for label in given)
    labels = (str(given[0]), str(given[1])) if named else None
    return Curve(kind, x, y, points, (ends[0], ends[1]), (), inside, inside_point, labels)


def curve_blocks(curve: Curve) -> list[mk.Block]:
    """The curve told: its kind and plane, its sides, its ends and its points."""
    rows = tuple((f"{row[0]:.10g}", f"{row[1]:.10g}") for row in curve.points[[curve.x, curve.y]].to_numpy())
    return [
        mk.Heading(1, (f"{curve.kind} curve in {curve.x} and {curve.y}",)),
        mk.Paragraph(
            (f"The border of the orbit whose cycle of switches is: {curve.inside}; {len(curve.points)} points.",)
        ),
        mk.Bullets(tuple((f"one end: {end}",) for end in curve.ends)),
        mk.Table((curve.x, curve.y), rows),
    ]


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
        "labels": None if curve.labels is None else list(curve.labels),
    }
    with atomic_path(folder / "curve.json") as temporary:
        temporary.write_text(json.dumps(info, indent=2), encoding="utf-8")
    caption = "the curve" + (" over the atlas's regimes" if atlas is not None else "")
    blocks = [*curve_blocks(curve), mk.Figure("curve", caption)]
    figure = [("curve", lambda: curve_figure([curve, *also], atlas))] if plots else []
    return write_folder(folder, {"curve": curve.points}, figure, blocks, f"{curve.kind} curve")


#: Fig. 14's two lines through the plane: Q2 = 71 (the Omega sweep) and Omega = 1.6 (the Q2 sweep).
FIG_14_LINES = {"Q2": 71.0, "Omega": 1.6}


#: Fig. 14's two lines, each in its own colour, marked by a tick on the frame.
FIG_14_COLORS = {"Omega": "tab:red", "Q2": "tab:purple"}
