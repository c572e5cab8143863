"""A branch on disk: its tables, its figures (Fig. 14 with the unstable parts) and a report."""

from __future__ import annotations

import itertools
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


def _runs(stable: np.ndarray) -> list[slice]:
    """Slices of consecutive points with the same stability (each overlapping the next by one)."""
    edges = [0, *(np.flatnonzero(np.diff(stable.astype(int))) + 1).tolist(), len(stable)]
    return [slice(a, min(b + 1, len(stable))) for a, b in itertools.pairwise(edges)]


def draw_branch(branch: Branch, path: Path, coordinate: str, sweep_points: pd.DataFrame | None = None) -> None:
    """``coordinate`` at t0 against the parameter: stable solid, unstable dashed, bifurcations marked."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    param, points = branch.param, branch.points
    fig, ax = plt.subplots(figsize=(7, 4.5), dpi=150)
    if sweep_points is not None and len(sweep_points):
        ax.plot(sweep_points[param], sweep_points[coordinate], "o", color="k", ms=2.5, zorder=3,
                label="sweep (Poincaré points)")  # fmt: skip
    stable = points.stable.to_numpy(bool)
    for k, part in enumerate(_runs(stable)):
        is_stable = bool(stable[part.start])
        ax.plot(points[param].iloc[part], points[coordinate].iloc[part], "-" if is_stable else "--", color="C0",
                lw=1.5, label=None if k > 1 else ("stable" if is_stable else "unstable"))  # fmt: skip
    for kind, rows in branch.bifurcations.groupby("kind"):
        ax.plot(rows[param], rows[coordinate], _MARKERS.get(str(kind), "x"), color="C3", ms=7, mfc="none",
                label=str(kind).replace("_", " "))  # fmt: skip
        for value, y in zip(rows[param], rows[coordinate], strict=True):
            ax.annotate(f"{value:.7g}", (value, y), textcoords="offset points", xytext=(4, 6), fontsize=7)
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

    param, points = branch.param, branch.points
    fig, ax = plt.subplots(figsize=(7, 3.5), dpi=150)
    floor = 1e-16  # a multiplier of 0 (a resting mass's constrained velocity) is drawn here
    for k in range(1, 5):
        moduli = points[f"mu{k}"].clip(lower=floor)
        ax.semilogy(points[param], moduli, "-", lw=1.2, label=f"|mu{k}|")
    ax.axhline(1.0, color="k", lw=0.8, ls=":")
    for value in branch.bifurcations[param]:
        ax.axvline(value, color="C3", lw=0.6, ls="--")
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
    rows = tuple(
        (f"{getattr(row, param):.10g}", str(row.kind), f"{row.x1:.6g}", f"{row.v1:.6g}", f"{row.x2:.6g}",
         f"{row.v2:.6g}", f"{row.jump:.2e}", str(row.before), str(row.after))
        for row in branch.bifurcations.itertuples(index=False)
    )  # fmt: skip
    blocks.append(mk.Heading(2, ("Bifurcations",)))
    if rows:
        blocks.append(mk.Table((param, "kind", "x1", "v1", "x2", "v2", "jump", "events before", "events after"), rows))
    else:
        blocks.append(mk.Paragraph(("None in the range.",)))
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
