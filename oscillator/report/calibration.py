"""A calibration's folder: its tables, the figure of the data against the fitted model and of the
residuals, and the report (docs/calibration.md).

Every text that came from the measurements (a measure's or a variable's name) is drawn as plain
text and escaped in the report.
"""

from __future__ import annotations

import functools
import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from oscillator.report import markup as mk
from oscillator.report.outputs import number_label, plain_label

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from oscillator.calibrating.fit import Calibration

__all__ = ["calibration_blocks", "calibration_figure", "summary", "write_calibration"]


def _group(table: pd.DataFrame) -> str:
    """The column that names what each row measured: a measure, a variable or an event kind."""
    return next(c for c in ("measure", "variable", "kind") if c in table.columns)


def _residual_panel(ax: Axes, found: Calibration, group: str) -> None:
    table, x = found.residuals, found.over
    for k, name in enumerate(dict.fromkeys(table[group])):
        rows = table[table[group] == name].sort_values(x)
        ax.plot(rows[x], rows.residual / rows.sigma, "o", ms=4, color=f"C{k % 10}", label=plain_label(str(name)))
    band = 2.0 * (found.uncertainty.scale if math.isfinite(found.uncertainty.scale) else 1.0)
    ax.axhspan(-band, band, color="0.92", zorder=0, label="two standard deviations")
    ax.axhline(0.0, color="0.4", lw=0.8)
    ax.set_ylabel("residual / sigma")
    ax.grid(alpha=0.3)


#: At most this many measures or variables get a panel of their own (all are in the residuals).
PANELS = 8


def calibration_figure(found: Calibration) -> Figure:
    """The measurements (with their standard deviations) against the fitted model, one panel per
    measure or variable (each on its own scale), and below the residuals in standard deviations
    with a band of two; for event times, the residuals alone."""
    from matplotlib.figure import Figure

    table, x, group = found.residuals, found.over, _group(found.residuals)
    names = [] if group == "kind" else list(dict.fromkeys(table[group]))[:PANELS]
    fig = Figure(figsize=(9, 2.0 * len(names) + 3.0), layout="constrained")
    axes = fig.subplots(len(names) + 1, 1, sharex=True, squeeze=False)[:, 0]
    for k, (ax, name) in enumerate(zip(axes, names, strict=False)):
        rows = table[table[group] == name].sort_values(x)
        color, label = f"C{k % 10}", plain_label(str(name))
        ax.errorbar(rows[x], rows.value, yerr=rows.sigma, fmt="o", ms=4, color=color, label="measured")
        shown = "fitted, at the measured times" if x == "t" else "fitted"
        ax.plot(rows[x], rows.fitted, "-" if x == "t" else "x-", lw=1, color="0.2", label=shown)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="best")
    _residual_panel(axes[-1], found, group)
    axes[-1].legend(fontsize=7, loc="best", ncols=2)
    axes[-1].set_xlabel("t (s)" if x == "t" else number_label(found.system, x))
    fitted = ", ".join(f"{n} = {v:.6g}" for n, v in found.estimate.items())
    fig.suptitle(plain_label(f"{_title(found)}: {fitted}"), fontsize=10)
    return fig


def _title(found: Calibration) -> str:
    system = found.system
    return str(getattr(system, "name", None) or getattr(system, "title", None) or "system")


def calibration_blocks(found: Calibration, plots: bool) -> list[mk.Block]:
    """The report: what was fitted to what, the estimate with its intervals, the warnings, the
    correlations, the starts, the crossings and notes, the figure."""
    level = f"{100 * found.uncertainty.level:g} %"
    blocks: list[mk.Block] = [mk.Heading(1, (f"{_title(found)}: calibration",))]
    what = {"measure": "steady responses", "variable": "a time series", "kind": "event times"}[_group(found.residuals)]
    blocks.append(
        mk.Paragraph(
            (
                f"{', '.join(found.params)} fitted to {len(found.residuals)} measurements of {what} "
                f"by least squares ({found.loss} loss): {found.message}",
            )
        )
    )
    header = ("parameter", "range", "start", "estimate", "standard error", f"{level} interval")
    rows = tuple(
        (
            name,
            f"{r.low:g} to {r.high:g}",
            f"{r.start:.6g}",
            f"{r.estimate:.8g}",
            f"{r.stderr:.3g}",
            f"{r.ci_low:.6g} to {r.ci_high:.6g}",
        )
        for name, r in found.table.iterrows()
    )
    blocks += [mk.Heading(2, ("The estimate",)), mk.Table(header, rows)]
    scale = found.uncertainty.scale
    blocks.append(
        mk.Paragraph(
            (
                f"The residuals' scale is {scale:.4g} (1 where the measurements gave sigma); "
                f"{found.evaluations} evaluations of the model, {found.runs} simulations in all.",
            )
        )
    )
    if found.warnings:
        blocks += [mk.Heading(2, ("What the data cannot determine",)), mk.Bullets(tuple((w,) for w in found.warnings))]
    names = list(found.params)
    correlation = tuple((n, *(f"{found.correlation.at[n, m]:.3f}" for m in names)) for n in names)
    blocks += [mk.Heading(2, ("Correlations",)), mk.Table(("", *names), correlation)]
    if len(found.starts) > 1:
        starts = tuple(
            (*(f"{r[n]:.6g}" for n in names), f"{r.cost:.6g}", str(r.status)) for _, r in found.starts.iterrows()
        )
        blocks += [mk.Heading(2, ("Starts",)), mk.Table((*names, "cost", "status"), starts)]
    over = found.over
    notes = [
        f"step {int(c.evaluation)}{_where(over, c[over])}: the switching sequence changed "
        f"({int(c.switches_before)} to {int(c.switches_after)} switches)"
        for _, c in found.crossings.iterrows()
    ] + list(found.notes)
    if notes:
        blocks += [
            mk.Heading(2, ("Where the fit crossed a boundary of the motion",)),
            mk.Bullets(tuple((n,) for n in notes[:20])),
        ]
    if plots:
        blocks.append(mk.Figure("calibration", "the measurements against the fitted model, and the residuals"))
    return blocks


def summary(found: Calibration) -> dict[str, object]:
    """What ``calibration.json`` keeps of a finished calibration beside its identity: the estimate,
    its standard errors and level, the warnings, the cost, the counts and SciPy's verdict."""
    return {
        "estimate": {n: float(v) for n, v in found.estimate.items()},
        "stderr": {n: _number(v) for n, v in found.table.stderr.items()},
        "level": found.uncertainty.level,
        "warnings": list(found.warnings),
        "cost": found.cost,
        "evaluations": found.evaluations,
        "runs": found.runs,
        "message": found.message,
        "success": found.success,
        "loss": found.loss,
    }


def write_calibration(found: Calibration, folder: Path, *, plots: bool = True) -> list[str]:
    """``estimate.csv`` and ``.parquet`` (the table), ``residuals.csv`` and ``.parquet``,
    ``starts.parquet``, ``correlation.parquet``, the figure and the report; what could not be
    drawn (the tables stay). The summary (:func:`summary`) is the folder's ``calibration.json``
    (:class:`~oscillator.calibrating.store.CalibrationStore`)."""
    from oscillator.io.files import atomic_path
    from oscillator.report.outputs import write_folder

    estimate = found.table.rename_axis("parameter").reset_index()
    for name, frame in (("estimate", estimate), ("residuals", found.residuals)):
        with atomic_path(folder / f"{name}.csv") as temporary:
            frame.to_csv(temporary, index=False)
    tables = {"estimate": estimate, "residuals": found.residuals, "starts": found.starts}
    tables["correlation"] = found.correlation.rename_axis("parameter").reset_index()
    figures = [("calibration", functools.partial(calibration_figure, found))] if plots else []
    return write_folder(folder, tables, figures, calibration_blocks(found, plots), f"{_title(found)}: calibration")


def _where(over: str, at: float) -> str:
    """`` at Omega = 0.6`` (a steady response's point) or `` at t = 11.525 s`` (the first event
    that changed); nothing where unknown."""
    if not math.isfinite(at):
        return ""
    return f" at t = {at:.6g} s" if over == "t" else f" at {over} = {at:g}"


def _number(value: float) -> float | None:
    """A float for JSON: None for an infinite or undefined standard error."""
    return float(value) if np.isfinite(value) else None
