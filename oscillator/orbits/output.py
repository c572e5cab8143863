"""A branch on disk: its tables, its figures (Fig. 14 with the unstable parts) and a report."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import numpy as np
import pandas as pd

from oscillator.io.cases import Case
from oscillator.io.files import FolderClaim, replace_file
from oscillator.orbits.continuation import Branch
from oscillator.report import markup as mk

__all__ = ["draw_branch", "draw_multipliers", "write_branch"]

_MARKERS = {"sliding_onset": "v", "sliding_vanish": "^", "grazing": "s", "fold": "o", "period_doubling": "D",
            "torus": "*"}  # fmt: skip


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
    return [(float(rows[param].iloc[k]), float(rows[param].iloc[k + 1])) for k in range(len(rows) - 1)
            if rows.after.iloc[k] == "" and rows.before.iloc[k + 1] == ""]  # fmt: skip


def _label_values(ax, rows: pd.DataFrame, param: str, coordinate: str, span: float) -> None:
    """Each bifurcation's parameter beside its marker; labels of close values stacked, not overlaid."""
    decimals = min(10, max(0, math.ceil(-math.log10(span)) + 5)) if span > 0 else 7
    level, last = 0, -math.inf
    for value, y in sorted(zip(rows[param], rows[coordinate], strict=True)):
        level = level + 1 if value - last < 0.12 * span else 0
        last = value
        offset = (5, 6 + 9 * level)
        ax.annotate(f"{value:.{decimals}f}", (value, y), textcoords="offset points", xytext=offset, fontsize=7)


def draw_branch(branch: Branch, path: Path, coordinate: str, sweep_points: pd.DataFrame | None = None) -> None:
    """``coordinate`` at t0 against the parameter: stable solid, unstable dashed, bifurcations marked."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    param, points = branch.param, branch.points
    fig, ax = plt.subplots(figsize=(7, 4.5), dpi=150)
    if sweep_points is not None and len(sweep_points):
        ax.plot(sweep_points[param], sweep_points[coordinate], "o", color="k", ms=2.5, zorder=3,
                label="sweep (Poincaré points)")  # fmt: skip
    stable = points.stable.to_numpy(bool)
    labelled = set()
    for piece in _pieces(points):
        for part in _runs(stable, piece):
            is_stable = bool(stable[part.start])
            label = "stable" if is_stable else "unstable"
            ax.plot(points[param].iloc[part], points[coordinate].iloc[part], "-" if is_stable else "--",
                    color="C0", lw=1.5, label=None if label in labelled else label)  # fmt: skip
            labelled.add(label)
    for k, (lo, hi) in enumerate(_gaps(branch)):
        ax.axvspan(lo, hi, color="0.85", zorder=0, label=None if k else f"no period-{branch.period} orbit")
    for kind, rows in branch.bifurcations.groupby("kind"):
        ax.plot(rows[param], rows[coordinate], _MARKERS.get(str(kind), "x"), color="C3", ms=7, mfc="none",
                label=str(kind).replace("_", " "))  # fmt: skip
    _label_values(ax, branch.bifurcations, param, coordinate, span=float(np.ptp(points[param])))
    ax.ticklabel_format(useOffset=False)
    ax.xaxis.set_major_locator(MaxNLocator(6))
    ax.set_xlabel(param)
    ax.set_ylabel(f"{coordinate} at t0 + kT")
    ax.set_title(f"period-{branch.period} orbit continued in {param}")
    ax.legend(fontsize=8, loc="best")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def draw_multipliers(branch: Branch, path: Path) -> None:
    """The multipliers' moduli against the parameter, with the unit circle's radius."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    param, points = branch.param, branch.points
    fig, ax = plt.subplots(figsize=(7, 3.5), dpi=150)
    floor = 1e-16  # a multiplier of 0 (a resting mass's constrained velocity) is drawn here
    for k in range(1, 5):
        moduli = points[f"mu{k}"].clip(lower=floor)
        for j, piece in enumerate(_pieces(points)):
            ax.semilogy(points[param].iloc[piece], moduli.iloc[piece], "-", lw=1.2, color=f"C{k - 1}",
                        label=None if j else f"|mu{k}|")  # fmt: skip
    ax.axhline(1.0, color="k", lw=0.8, ls=":")
    for value in branch.bifurcations[param]:
        ax.axvline(value, color="C3", lw=0.6, ls="--")
    ax.ticklabel_format(axis="x", useOffset=False)
    ax.xaxis.set_major_locator(MaxNLocator(6))
    ax.set_xlabel(param)
    ax.set_ylabel("modulus of multiplier")
    ax.set_ylim(floor / 10, None)
    ax.text(0.99, 0.02, "0 is drawn at 1e-16", transform=ax.transAxes, ha="right", fontsize=7, color="0.4")
    ax.legend(fontsize=8, ncol=4, loc="center left")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def report_blocks(branch: Branch, case: Case) -> list[mk.Block]:
    """The report: what was continued, the bifurcations, the figures (all text escaped)."""
    param = branch.param
    lo, hi = branch.points[param].min(), branch.points[param].max()
    blocks: list[mk.Block] = [
        mk.Heading(1, (f"{case.name}: period-{branch.period} orbit continued in {param}",)),
        mk.Paragraph((f"{len(branch.points)} points from {param} = {lo:.10g} to {hi:.10g}; section t0 = "
                      f"{branch.t0:g} s. ", "Complete." if branch.complete else f"Ended early: {branch.message}.")),
    ]  # fmt: skip
    if case.modified:
        blocks.append(mk.Paragraph(("Changed from the case as written: ", ", ".join(case.modified), ".")))
    none = f"(no period-{branch.period} orbit)"
    rows = tuple(
        (f"{getattr(row, param):.10g}", str(row.kind), f"{row.x1:.6g}", f"{row.v1:.6g}", f"{row.x2:.6g}",
         f"{row.v2:.6g}", "-" if math.isnan(row.jump) else f"{row.jump:.2e}", str(row.before) or none,
         str(row.after) or none)
        for row in branch.bifurcations.itertuples(index=False)
    )  # fmt: skip
    blocks.append(mk.Heading(2, ("Bifurcations",)))
    if rows:
        blocks.append(mk.Table((param, "kind", "x1", "v1", "x2", "v2", "jump", "events before", "events after"), rows))
    else:
        blocks.append(mk.Paragraph(("None in the range.",)))
    for lo, hi in _gaps(branch):
        blocks.append(mk.Paragraph((f"No period-{branch.period} orbit on this branch for {param} between {lo:.10g} "
                                    f"and {hi:.10g}: simulate there, or look for an orbit of another period "
                                    "(--period).",)))  # fmt: skip
    stable = branch.points.stable
    blocks.append(mk.Paragraph((f"{int(stable.sum())} stable and {int((~stable).sum())} unstable points.",)))
    blocks += [mk.Figure("branch", "the branch"), mk.Figure("multipliers", "the multipliers' moduli")]
    return blocks


def write_branch(
    branch: Branch, case: Case, claim: FolderClaim, *, coordinate: str, sweep_points: pd.DataFrame | None
) -> tuple[Path, str]:
    """Write the tables, then the figures and the report; ``(folder, problem)`` with ``problem``
    empty unless a figure or the report failed (the tables are kept either way)."""
    branch.points.to_parquet(claim.temporary / "branch.parquet", index=False)
    branch.bifurcations.to_parquet(claim.temporary / "bifurcations.parquet", index=False)
    folder = claim.commit()
    try:
        (folder / "figures").mkdir(exist_ok=True)
        draw_branch(branch, folder / "figures" / "branch.png", coordinate, sweep_points)
        draw_multipliers(branch, folder / "figures" / "multipliers.png")
        blocks = report_blocks(branch, case)
        replace_file(folder / "report.md", mk.to_markdown(blocks))
        replace_file(folder / "report.html", mk.to_html(blocks, folder=folder, title=f"{case.name}: branch"))
    except (OSError, ValueError, RuntimeError) as failure:
        return folder, f"the figures or the report could not be written ({failure})"
    return folder, ""
