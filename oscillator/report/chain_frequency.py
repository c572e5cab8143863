"""A friction chain's frequency sweeps (``oscillator frc FILE``), its branches (``oscillator
continue FILE``) and its designs (``oscillator design FILE``): their folders and figures.

::

    sweeps.csv / sweeps.parquet   one row per value and direction (up, down): the orbit's status,
                                  stability, largest multiplier, measures and state
    branches.csv / .parquet       with --seeds: one row per point of every period-1 branch
                                  (``branch``, the number, ``stable``, ``largest``, measures, state)
    bifurcations.csv / .parquet   with --seeds: each branch's folds and changes of stability
    system.toml                   the system as swept
    run.json                      the parameter, its span, the values, the failed ones
    figures/frequency.png, .svg   each mass's largest displacement up and down the band (unstable
                                  orbits hollow) over the branches (solid where stable, dotted where
                                  not, folds marked), and each friction element's and slider's stuck
                                  share

A branch's folder holds ``branch.parquet``/``.csv`` (its points), ``bifurcations.parquet``/``.csv``,
``system.toml``, ``run.json`` and ``figures/branch.png``; a design's ``history.parquet``/``.csv``,
``system.toml`` (at the best value), ``run.json`` and ``figures/design.png``.

The tables and ``run.json`` are written whole, then the folder put in place; the figure after (its
failure keeps the tables).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from oscillator.errors import InputError
from oscillator.io.chains import chain_to_toml
from oscillator.io.files import FolderClaim
from oscillator.model.chains import FrictionChain
from oscillator.orbits.chain_response import measure_unit
from oscillator.report.outputs import number_label, plain_label
from oscillator.report.runs import json_text, run_metadata
from oscillator.text import printable

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

    from oscillator.attractors.chain_frequency import ChainFrequencyResponse
    from oscillator.designing.chain_design import ChainDesign
    from oscillator.orbits.chain_branch import ChainBranch

__all__ = [
    "branch_figure",
    "design_figure",
    "sweep_figure",
    "write_chain_branch",
    "write_chain_design",
    "write_chain_sweeps",
]

#: How each direction is drawn: line style and marker.
_STYLE = {"up": ("-", "o"), "down": ("--", "s")}


def write_chain_sweeps(
    table: pd.DataFrame,
    chain: FrictionChain,
    param: str,
    claim: FolderClaim,
    *,
    formats: str = "both",
    command: list[str] | None = None,
    response: ChainFrequencyResponse | None = None,
    noise: tuple[pd.DataFrame, pd.DataFrame] | None = None,
) -> Path:
    """Write the sweeps' table (and the ``response``'s branches and bifurcations, and ``noise``'s
    levels and spectra: :func:`~oscillator.orbits.chain_noise.sweep_noise`), ``system.toml`` and
    ``run.json`` and put the folder in place; on any failure nothing is left behind.  The
    folder's path."""
    temporary = claim.temporary
    tables = {"sweeps": table}
    if response is not None:
        tables |= {"branches": response.table(), "bifurcations": response.bifurcations()}
    if noise is not None:
        tables |= {"noise": noise[0], "spectra": noise[1]}
    try:
        for name, frame in tables.items():
            if formats in ("csv", "both"):
                frame.to_csv(temporary / f"{name}.csv", index=False)
            if formats in ("parquet", "both"):
                frame.to_parquet(temporary / f"{name}.parquet", index=False)
        (temporary / "system.toml").write_text(chain_to_toml(chain), encoding="utf-8")
        values = table[table.direction == "up"][param]
        info: dict[str, Any] = {
            "kind": "system-frc",
            "title": chain.title,
            "param": param,
            "span": [float(values.min()), float(values.max())],
            "values": len(values),
            "failed": int((table.status == "failed").sum()),
            "branches": None if response is None else len(response.branches),
            **run_metadata(command),
        }
        (temporary / "run.json").write_text(json_text(info), encoding="utf-8")
        return claim.commit()
    except BaseException:
        claim.abandon()
        raise


def sweep_figure(
    table: pd.DataFrame,
    chain: FrictionChain,
    param: str,
    response: ChainFrequencyResponse | None = None,
    measure: str | None = None,
) -> Figure:
    """Each mass's ``x_max`` (or ``measure``, one panel) against ``param`` up and down the band
    (unstable orbits hollow, failed values left out) over the ``response``'s branches, and, where
    the chain has friction elements or sliders, their stuck shares."""
    from matplotlib.figure import Figure

    if measure is not None and measure not in table:
        raise InputError(f"no measure named {printable(measure)} in the sweeps", field="measure")
    system = chain.system
    drawn = [f"x_max:{mass}" for mass in system.masses] if measure is None else [measure]
    held = [e.name for e in chain.elements if e.type in ("friction", "jenkins")] if measure is None else []
    panels = len(drawn) + (1 if held else 0)
    fig = Figure(figsize=(9, 2.6 * panels + 0.6), layout="constrained")
    axes = fig.subplots(panels, 1, sharex=True, squeeze=False)[:, 0]
    for ax, column in zip(axes, drawn, strict=False):
        if response is not None:
            _draw_branches(ax, response, column)
        for direction, rows in table[table.status != "failed"].groupby("direction", sort=False):
            line, marker = _STYLE[str(direction)]
            ax.plot(rows[param], rows[column], line, color="tab:blue", lw=1, label=f"sweep {direction}")
            unstable = rows[~rows.stable.astype(bool)]
            ax.plot(rows[param], rows[column], marker, color="tab:blue", ms=4, ls="none")
            ax.plot(unstable[param], unstable[column], marker, mfc="white", color="tab:red", ms=6, ls="none")
        unit = measure_unit(column)
        ax.set_ylabel(plain_label(f"{column} ({unit})" if unit else column))
        ax.legend(fontsize=8, loc="upper right")
    if held:
        ax = axes[-1]
        for name in held:
            rows = table[(table.status != "failed") & (table.direction == "up")]
            ax.plot(rows[param], rows[f"stuck:{name}"], "-o", ms=3, lw=1, label=plain_label(name))
        ax.set_ylim(-0.05, 1.05)
        ax.set_ylabel("stuck share of the period")
        ax.set_title("friction elements and sliders (sweep up)", loc="left", fontsize=9)
        ax.legend(fontsize=8, loc="upper right")
    axes[-1].set_xlabel(number_label(chain, param))
    what = "branches and sweeps" if response is not None else "sweeps"
    fig.suptitle(f"{plain_label(chain.title or 'friction chain')}: {what} over {plain_label(param)}", fontsize=10)
    return fig


def _draw_branches(ax: Any, response: ChainFrequencyResponse, column: str) -> None:
    """Each branch's ``column``: black, solid where stable, dotted where not; its folds marked."""
    param = response.param
    for k, branch in enumerate(response.branches):
        points = branch.points
        values, ys = points[param].to_numpy(float), points[column].to_numpy(float)
        stable = points.stable.to_numpy(bool)
        unstable = ~stable
        unstable[1:] |= unstable[:-1].copy()  # the dotted stretch joined to the solid one after it
        for where, style, label in ((stable, "-", "stable branch"), (unstable, ":", "unstable branch")):
            ax.plot(values, np.where(where, ys, np.nan), style, color="black", lw=1.2, label=label if k == 0 else None)
        for j, lam in enumerate(branch.folds[param]):
            y = ys[int(np.argmin(np.abs(values - lam)))]
            ax.plot([lam], [y], "x", color="black", ms=8, mew=1.5, label=None if k or j else "folds", zorder=3)


def finish_chain_sweeps(
    folder: Path,
    table: pd.DataFrame,
    chain: FrictionChain,
    param: str,
    response: ChainFrequencyResponse | None = None,
    spectra: pd.DataFrame | None = None,
) -> None:
    """The folder's figures (PNG and SVG), each file written whole: the sweeps, and the stable
    orbits' ``spectra`` where measured."""
    from oscillator.report.figures import save_figure
    from oscillator.report.noise import SPECTRA_FIGURE, chain_spectra_figure

    figures = folder / "figures"
    figures.mkdir(exist_ok=True)
    save_figure(sweep_figure(table, chain, param, response), figures, "frequency")
    if spectra is not None:
        save_figure(chain_spectra_figure(spectra, chain, param), figures, SPECTRA_FIGURE)


def design_figure(design: ChainDesign, sweeps: Mapping[float, pd.DataFrame] | None = None) -> Figure:
    """A system's design (:class:`~oscillator.designing.chain_design.ChainDesign`): the worst of
    its objective over the band against the number varied, each value judged a point, the best
    a star; and, given ``sweeps`` (the varied number's value -> a sweep over the band:
    :func:`~oscillator.orbits.chain_response.frequency_sweep`), the objective along the band at
    each, the worst's place marked."""
    from matplotlib.figure import Figure

    worst, name = design.worst, design.vary
    fig = Figure(figsize=(10 if sweeps else 6, 3.8), layout="constrained")
    axes = fig.subplots(1, 2 if sweeps else 1, squeeze=False)[0]
    history = design.history.sort_values(name)
    ax = axes[0]
    ax.plot(history[name], history.worst, "-o", color="tab:blue", ms=4, lw=1, label="values judged")
    ax.plot([design.value], [worst.value], "*", color="tab:red", ms=14, label=f"best: {design.value:.4g}")
    ax.set_xlabel(plain_label(name))
    ax.set_ylabel(f"worst {plain_label(worst.measure)} over the band")
    ax.set_title(f"the worst over the band against {plain_label(name)}", loc="left", fontsize=9)
    ax.legend(fontsize=8)
    if sweeps:
        ax = axes[1]
        param = next(c for c in next(iter(sweeps.values())).columns if c not in ("status",))
        for value, table in sorted(sweeps.items()):
            rows = table[table.status != "failed"]
            best = abs(value - design.value) <= 1e-9 * max(1.0, abs(design.value))
            ax.plot(
                rows[param], rows[worst.measure], "-", lw=2 if best else 1, label=f"{plain_label(name)} = {value:.4g}"
            )
        ax.plot([worst.at], [worst.value], "*", color="tab:red", ms=12)
        ax.set_xlabel(plain_label(param))
        ax.set_ylabel(plain_label(worst.measure))
        ax.set_title("along the band", loc="left", fontsize=9)
        ax.legend(fontsize=8)
    fig.suptitle(f"{plain_label(design.chain.title or 'friction chain')}: {plain_label(design.summary)}", fontsize=9)
    return fig


def write_chain_design(
    design: ChainDesign, claim: FolderClaim, *, band: tuple[str, float, float], command: list[str] | None = None
) -> Path:
    """Write a system's design: ``history.parquet`` and ``.csv`` (every value judged),
    ``system.toml`` (the machine at the best value), ``run.json`` (the problem, the best value,
    its worst, where, and its derivative) and put the folder in place; on any failure nothing is
    left behind.  The folder's path."""
    temporary = claim.temporary
    try:
        design.history.to_csv(temporary / "history.csv", index=False)
        design.history.to_parquet(temporary / "history.parquet", index=False)
        (temporary / "system.toml").write_text(chain_to_toml(design.chain), encoding="utf-8")
        worst = design.worst
        info: dict[str, Any] = {
            "kind": "system-design",
            "title": design.chain.title,
            "vary": design.vary,
            "over": list(band),
            "objective": worst.measure,
            "best": design.value,
            "worst": worst.value,
            "at": worst.at,
            "gradient": worst.gradient,
            "judged": len(design.history),
            **run_metadata(command),
        }
        (temporary / "run.json").write_text(json_text(info), encoding="utf-8")
        return claim.commit()
    except BaseException:
        claim.abandon()
        raise


def branch_figure(branch: ChainBranch) -> Figure:
    """A chain's branch (:class:`~oscillator.orbits.chain_branch.ChainBranch`): each mass's
    largest displacement against the number along the branch, stable parts solid, unstable
    dashed red, each fold and change of stability marked."""
    from matplotlib.figure import Figure

    chain, param, points = branch.chain, branch.param, branch.points
    masses = chain.system.masses
    fig = Figure(figsize=(8, 2.6 * len(masses) + 0.6), layout="constrained")
    axes = fig.subplots(len(masses), 1, sharex=True, squeeze=False)[:, 0]
    stable = points.stable.to_numpy(bool)
    for ax, mass in zip(axes, masses, strict=True):
        x, y = points[param].to_numpy(float), points[f"x_max:{mass}"].to_numpy(float)
        ax.plot(x, np.where(stable, y, np.nan), "-", color="tab:blue", lw=1.5, label="stable")
        ax.plot(x, np.where(~stable, y, np.nan), "--", color="tab:red", lw=1.2, label="unstable")
        for _, row in branch.bifurcations.iterrows():
            k = int(row.point)
            ax.plot([row[param]], [y[k]], "o", mfc="white", color="black", ms=6)
            ax.annotate(
                plain_label(str(row.kind)), (row[param], y[k]), fontsize=7, xytext=(4, 4), textcoords="offset points"
            )
        ax.set_ylabel(f"x_max of {plain_label(str(mass))} (m)")
        ax.legend(fontsize=8, loc="upper left")
    axes[-1].set_xlabel(plain_label(param))
    fig.suptitle(f"{plain_label(chain.title or 'friction chain')}: the branch over {plain_label(param)}", fontsize=10)
    return fig


def write_chain_branch(branch: ChainBranch, claim: FolderClaim, *, command: list[str] | None = None) -> Path:
    """Write a chain's branch: ``branch.parquet`` and ``.csv`` (its points), ``bifurcations.parquet``
    and ``.csv``, ``system.toml`` and ``run.json`` (the number, the span reached, why it ended),
    and put the folder in place; on any failure nothing is left behind.  The folder's path."""
    temporary = claim.temporary
    try:
        for name, table in (("branch", branch.points), ("bifurcations", branch.bifurcations)):
            table.to_csv(temporary / f"{name}.csv", index=False)
            table.to_parquet(temporary / f"{name}.parquet", index=False)
        (temporary / "system.toml").write_text(chain_to_toml(branch.chain), encoding="utf-8")
        values = branch.points[branch.param]
        info: dict[str, Any] = {
            "kind": "system-branch",
            "title": branch.chain.title,
            "param": branch.param,
            "reached": [float(values.min()), float(values.max())],
            "points": len(branch.points),
            "ended": branch.ended,
            **run_metadata(command),
        }
        (temporary / "run.json").write_text(json_text(info), encoding="utf-8")
        return claim.commit()
    except BaseException:
        claim.abandon()
        raise
