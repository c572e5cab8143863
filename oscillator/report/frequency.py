"""The frequency response's figure, in the vibration engineers' style: a response measure against
the parameter, one panel per mass; each branch stable solid and unstable dashed; its folds and its
sliding, grazing and period-doubling points marked as on the branch figures; the slow sweeps'
values (up and down) with an arrow at each jump; the values where the sweeps' motion sticks or is
in contact shaded."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from oscillator.errors import InputError
from oscillator.orbits.branch import Bifurcation
from oscillator.orbits.response import MASS_MEASURES
from oscillator.report.orbits import BIFURCATION_MARKERS
from oscillator.report.outputs import color_of, wrapped_title

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd
    from matplotlib.artist import Artist
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from oscillator.attractors.frequency import FrequencyResponse

__all__ = ["frequency_figure"]

#: The units of the mass measures.
UNITS = {"x_max": "m", "x_min": "m", "x_pp": "m", "x_rms": "m", "v_peak": "m/s", "a_rms": "m/s²", "rest": ""}


def frequency_figure(found: FrequencyResponse, measure: str = "x_pp") -> Figure:
    """``measure`` (one of the mass measures: ``x_pp``, ``x_max``, ``x_rms``, ``v_peak``,
    ``a_rms``, ...) of each mass against the parameter (module docstring)."""
    from matplotlib.figure import Figure

    if measure not in MASS_MEASURES:
        raise InputError(f"measure must be one of {', '.join(MASS_MEASURES)}, got {measure!r}", field="measure")
    fig = Figure(figsize=(8.0, 7.0), layout="constrained")
    axes = fig.subplots(2, 1, sharex=True)
    for mass, ax in zip((1, 2), axes, strict=True):
        column = f"{measure}_m{mass}"
        _shade(ax, found, mass)
        _branches(ax, found, column)
        _sweeps(ax, found, column)
        unit = UNITS[measure]
        ax.set_ylabel(f"{measure} of m{mass}" + (f" ({unit})" if unit else ""))
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel(found.param)
    count = len(found.branches)
    axes[0].set_title(
        wrapped_title(found.case, f"frequency response over {found.param}: {count} branch{'es' if count != 1 else ''}"),
        parse_math=False,
        fontsize=9,
    )
    unique: dict[str, Artist] = {}
    for ax in axes:
        handles, labels = ax.get_legend_handles_labels()
        unique |= {label: handle for label, handle in zip(labels, handles, strict=True) if label not in unique}
    fig.legend(
        list(unique.values()), list(unique.keys()), loc="outside lower center", ncol=4, fontsize=8, frameon=False
    )
    return fig


def _branches(ax: Axes, found: FrequencyResponse, column: str) -> None:
    """Each branch: runs of equal stability along each piece, solid or dashed; its bifurcations."""
    points = found.points
    for k, branch in enumerate(found.branches):
        mine = points[points.branch == k]
        for _, piece in mine.groupby("piece", sort=False):
            stable = piece.stable.to_numpy(bool)
            cuts = np.flatnonzero(stable[1:] != stable[:-1]) + 1
            for run in np.split(np.arange(len(piece)), cuts):
                # each run reaches the next point, so that the curve has no gap where stability changes
                span = piece.iloc[run[0] : run[-1] + 2]
                solid = bool(stable[run[0]])
                ax.plot(
                    span[found.param],
                    span[column],
                    color=color_of(k),
                    ls="-" if solid else "--",
                    lw=1.4,
                    label="stable orbits" if solid else "unstable orbits",
                )
        _bifurcations(ax, found.param, branch.bifurcations, mine, column)


def _bifurcations(ax: Axes, param: str, bifurcations: pd.DataFrame, points: pd.DataFrame, column: str) -> None:
    """Each located bifurcation, at the measure of the branch point nearest it."""
    if bifurcations.empty or points.empty:
        return
    values = points[param].to_numpy(float)
    for _, row in bifurcations.iterrows():
        kind = Bifurcation(row["kind"])
        nearest = int(np.argmin(np.abs(values - float(row[param]))))
        at = (float(row[param]), float(points[column].iloc[nearest]))
        label = str(kind).replace("_", " ")
        ax.plot(*at, BIFURCATION_MARKERS[kind], color="C3", mfc="none", ms=7, label=label)


def _sweeps(ax: Axes, found: FrequencyResponse, column: str) -> None:
    """The sweeps' values, up and down, and an arrow at each jump."""
    sweeps = found.sweeps
    if column not in sweeps:
        return
    for direction, marker, offset in (("up", "^", "0.35"), ("down", "v", "0.55")):
        rows = sweeps[sweeps.direction == direction]
        ax.plot(
            rows[found.param], rows[column], marker=marker, ls="none", ms=3.5, color=offset, label=f"sweep {direction}"
        )
        values, measures, jumps = rows[found.param].to_numpy(), rows[column].to_numpy(), rows.jump.to_numpy(bool)
        for k in np.flatnonzero(jumps):
            if k and np.isfinite(measures[k - 1]) and np.isfinite(measures[k]):
                ax.annotate(
                    "",
                    xy=(values[k], measures[k]),
                    xytext=(values[k - 1], measures[k - 1]),
                    arrowprops={"arrowstyle": "->", "color": offset, "lw": 1.2},
                )


def _shade(ax: Axes, found: FrequencyResponse, mass: int) -> None:
    """The values where the sweeps' motion has this mass resting, or a contact, shaded."""
    sweeps = found.sweeps
    if sweeps.empty or f"rest_m{mass}" not in sweeps:
        return
    values = np.sort(sweeps[found.param].unique())
    step = float(np.min(np.diff(values))) if len(values) > 1 else 0.0
    contact = sweeps[[c for c in ("onsets_right", "onsets_left") if c in sweeps]].fillna(0).sum(axis=1) > 0
    for mask, color, label in (
        (sweeps[f"rest_m{mass}"].fillna(0) > 0, "tab:orange", f"m{mass} sticks"),
        (contact, "tab:blue", "contact"),
    ):
        for value in np.unique(sweeps[found.param][mask]):
            ax.axvspan(value - step / 2, value + step / 2, color=color, alpha=0.12, lw=0, label=label)
