"""The frequency response's figure, in the vibration engineers' style: a response measure against
the parameter, one panel per mass; each branch stable solid and unstable dashed; its folds and its
sliding, grazing and period-doubling points marked as on the branch figures; the slow sweeps'
values (up and down) with an arrow at each jump; the values where the sweeps' motion sticks or is
in contact shaded."""

from __future__ import annotations

import functools
from typing import TYPE_CHECKING

import numpy as np

from oscillator.errors import InputError
from oscillator.orbits.branch import Bifurcation
from oscillator.orbits.response import CONTACT_MEASURES, ENERGY_MEASURES, MASS_MEASURES, UNITS, above_note
from oscillator.report import markup as mk
from oscillator.report.orbits import bifurcation_style, modified_blocks
from oscillator.report.outputs import color_of, quantity_label, wrapped_title

if TYPE_CHECKING:  # pragma: no cover
    from collections.abc import Iterator
    from pathlib import Path

    import pandas as pd
    from matplotlib.artist import Artist
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from oscillator.attractors.frequency import FrequencyResponse

__all__ = [
    "MEASURES",
    "RESPONSE",
    "figure_measures",
    "frequency_blocks",
    "frequency_figure",
    "read_frequency",
    "stability_runs",
    "write_frequency",
]

#: What the sweeps' values are shaded by: the columns any of which is positive, the colour, the label.
_CONTACT = (("onsets_right", "onsets_left"), "tab:blue", "contact")
_STICKS = {
    mass: ((f"rest_m{mass}",), colour, f"m{mass} sticks") for mass, colour in ((1, "tab:orange"), (2, "tab:red"))
}
#: The panels of a measure of each kind: ``(column suffix, what it is of, what is shaded)``.
PANELS = {
    **dict.fromkeys(MASS_MEASURES, (("_m1", "m1", (_STICKS[1], _CONTACT)), ("_m2", "m2", (_STICKS[2], _CONTACT)))),
    **dict.fromkeys(
        CONTACT_MEASURES,
        (
            ("_right", "the right stop", ((("onsets_right",), "tab:purple", "contact with the right stop"),)),
            (
                "_left",
                "the contact between the masses",
                ((("onsets_left",), "tab:green", "contact between the masses"),),
            ),
        ),
    ),
}
#: Every measure the figure draws.
MEASURES = (*MASS_MEASURES, *CONTACT_MEASURES, *(f"energy_{name}" for name in ENERGY_MEASURES))


def frequency_figure(found: FrequencyResponse, measure: str = "x_pp") -> Figure:
    """``measure`` against the parameter (module docstring): a mass measure (``x_pp``,
    ``x_max``, ``x_rms``, ``v_peak``, ``a_rms``, ...) in one panel per mass, a contact measure
    (``impact_max``, ``force_peak``, ``onsets``, ...) in one panel per contact, an energy
    (``energy_friction``, ...) in one panel."""
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    if measure not in MEASURES:
        raise InputError(f"measure must be one of {', '.join(MEASURES)}, got {measure!r}", field="measure")
    panels = PANELS.get(measure, (("", "", (_CONTACT,)),))
    fig = Figure(figsize=(8.0, 3.5 * len(panels)), layout="constrained")
    axes = np.atleast_1d(fig.subplots(len(panels), 1, sharex=True, squeeze=False)[:, 0])
    for (suffix, of, shades), ax in zip(panels, axes, strict=True):
        column = f"{measure}{suffix}"
        _shade(ax, found, shades)
        _branches(ax, found, column)
        _sweeps(ax, found, column)
        unit = UNITS[measure.removeprefix("energy_")] or "fraction of the period"
        unit += above_note(measure, found.cutoff)
        label = f"{measure} of {of}" if of else measure
        ax.set_ylabel(f"{label}{' ' if len(label) + len(unit) < 48 else chr(10)}({unit})", fontsize=9)
        ax.grid(alpha=0.3)
        ax.ticklabel_format(useOffset=False)
    axes[-1].set_xlabel(quantity_label(found.param))
    count = len(found.branches)
    axes[0].set_title(
        wrapped_title(found.case, f"frequency response over {found.param}: {count} branch{'es' if count != 1 else ''}"),
        parse_math=False,
        fontsize=9,
    )
    unique: dict[str, Artist] = {
        "stable orbits (each branch its colour)": Line2D([], [], color="0.2", ls="-", lw=1.4),
        "unstable orbits": Line2D([], [], color="0.2", ls="--", lw=1.4),
    }
    for ax in axes:
        handles, labels = ax.get_legend_handles_labels()
        unique |= {label: handle for label, handle in zip(labels, handles, strict=True) if label not in unique}
    fig.legend(
        list(unique.values()), list(unique.keys()), loc="outside lower center", ncol=4, fontsize=8, frameon=False
    )
    return fig


def stability_runs(piece: pd.DataFrame) -> Iterator[tuple[pd.DataFrame, bool]]:
    """A branch piece's runs of equal stability (its ``stable`` column), each with whether it is
    stable; each run reaches the next point, so that a curve has no gap where stability changes."""
    stable = piece.stable.to_numpy(bool)
    cuts = np.flatnonzero(stable[1:] != stable[:-1]) + 1
    for run in np.split(np.arange(len(piece)), cuts):
        yield piece.iloc[run[0] : run[-1] + 2], bool(stable[run[0]])


def _branches(ax: Axes, found: FrequencyResponse, column: str) -> None:
    """Each branch: runs of equal stability along each piece, solid or dashed; its bifurcations."""
    points = found.points
    for k, branch in enumerate(found.branches):
        mine = points[points.branch == k]
        for _, piece in mine.groupby("piece", sort=False):
            for span, solid in stability_runs(piece):
                ax.plot(span[found.param], span[column], color=color_of(k), ls="-" if solid else "--", lw=1.4)
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
        ax.plot(*at, **bifurcation_style(kind), label=label)


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


def _shade(ax: Axes, found: FrequencyResponse, shades: tuple[tuple[tuple[str, ...], str, str], ...]) -> None:
    """The sweep values where the motion has what ``shades`` name (a mass resting, a contact)."""
    sweeps = found.sweeps
    if sweeps.empty:
        return
    values = np.sort(sweeps[found.param].unique())
    step = float(np.min(np.diff(values))) if len(values) > 1 else 0.0
    for columns, color, label in shades:
        mask = sweeps[[c for c in columns if c in sweeps]].fillna(0).sum(axis=1) > 0
        for value in np.unique(sweeps[found.param][mask]):
            ax.axvspan(value - step / 2, value + step / 2, color=color, alpha=0.12, lw=0, label=label)


def frequency_figure_name(measure: str) -> str:
    """The file name of the figure of ``measure``: ``frequency-x-pp`` for ``x_pp``."""
    return f"frequency-{measure.replace('_', '-')}"


def figure_measures(found: FrequencyResponse, measure: str) -> list[str]:
    """The measures ``oscillator frc`` draws: ``measure``, and the largest impact velocity where
    any orbit or sweep value has a contact."""
    frames = (found.points, found.sweeps)
    contacts = any((f[c].fillna(0) > 0).any() for f in frames for c in ("onsets_right", "onsets_left") if c in f)
    return list(dict.fromkeys([measure, *(["impact_max"] if contacts else [])]))


def frequency_blocks(found: FrequencyResponse, measures: list[str]) -> list[mk.Block]:
    """The report: what was found (branches, points, stable share, folds and other bifurcations,
    the sweeps' jumps), then the figures."""
    points, param = found.points, found.param
    low, high = float(found.sweeps[param].min()), float(found.sweeps[param].max())
    stable = float(points.stable.mean()) if len(points) else 0.0
    count = len(found.branches)
    summary = (
        f"{count} branch{'es' if count != 1 else ''} of periodic orbits over {param} from {low:g} to {high:g}, "
        f"{len(points)} points, {stable:.0%} of them stable. The slow sweep up jumps at "
        f"{_values(found.jumps('up'))}; the slow sweep down at {_values(found.jumps('down'))}."
    )
    if not found.branches:
        summary = f"{found.nothing_found()[0].upper()}{found.nothing_found()[1:]}."
    blocks: list[mk.Block] = [mk.Heading(1, (f"{found.case.name}: frequency response over {param}",))]
    blocks += [mk.Paragraph((summary,))]
    blocks += modified_blocks(found.case)
    rows = found.bifurcations
    if len(rows):
        blocks += [mk.Heading(2, ("Bifurcations along the branches",))]
        table = tuple(
            (str(int(r.branch)), f"{float(r[param]):.8g}", str(r.kind).replace("_", " ")) for _, r in rows.iterrows()
        )
        blocks += [mk.Table(("branch", param, "kind"), table)]
    if found.branches:
        blocks += [mk.Heading(2, ("Branches",))]
        header = ("branch", "period", f"{param} from", "to", "points", "stable", "ended")
        blocks += [mk.Table(header, _branch_rows(found))]
    blocks += [mk.Figure(frequency_figure_name(m), f"{m} against {param}") for m in measures]
    return blocks


def _values(values: list[float]) -> str:
    return ", ".join(f"{value:g}" for value in values) if values else "no value"


def _branch_rows(found: FrequencyResponse) -> tuple[tuple[str, ...], ...]:
    rows = []
    for k, branch in enumerate(found.branches):
        values = branch.points[found.param].to_numpy(float)
        ended = "at the span's end" if branch.complete else branch.message
        share = f"{branch.points.stable.mean():.0%}"
        rows.append(
            (str(k), str(branch.period), f"{values[0]:.8g}", f"{values[-1]:.8g}", str(len(values)), share, ended)
        )
    return tuple(rows)


#: The file that keeps what the tables do not: the branches' sections, endings and bifurcations,
#: and the measure drawn (so that ``oscillator report`` draws it again).
RESPONSE = "response.json"
#: How a frequency-response folder that cannot be read is made again.
_REMAKE = "run the oscillator frc command that made it again with the same --out"
_ANEW = "run the oscillator frc command that made it again with a new --out"


def write_frequency(
    found: FrequencyResponse,
    folder: Path,
    measure: str = "x_pp",
    *,
    plots: bool = True,
    noise: tuple[pd.DataFrame, pd.DataFrame] | None = None,
) -> list[str]:
    """``points.parquet`` (every branch point with its measures; the multipliers as real and
    imaginary parts), ``bifurcations.parquet``, ``sweeps.parquet``, ``response.json`` (what
    :func:`read_frequency` needs besides), the figures of :func:`figure_measures` and the report;
    with ``noise`` (:meth:`~oscillator.FrequencyResponse.noise_tables`: given, or kept in the
    folder from before) ``noise.parquet``, ``spectra.parquet`` and their figure; what could not be
    drawn (the tables stay)."""
    import json

    from oscillator.attractors.frequency_parts import branches_on_disk
    from oscillator.io.files import atomic_path
    from oscillator.orbits.branch import points_on_disk
    from oscillator.report.noise import SPECTRA_FIGURE, spectra_response_figure
    from oscillator.report.outputs import write_folder

    measures = figure_measures(found, measure)
    figures = (
        [(frequency_figure_name(m), functools.partial(frequency_figure, found, m)) for m in measures] if plots else []
    )
    tables = {"points": points_on_disk(found.points), "bifurcations": found.bifurcations, "sweeps": found.sweeps}
    noise = noise if noise is not None else kept_noise(folder)
    if noise is not None:
        tables |= {"noise": noise[0], "spectra": noise[1]}
        figures += [(SPECTRA_FIGURE, functools.partial(spectra_response_figure, found, noise[1]))] if plots else []
    _, branches = branches_on_disk(found.param, list(found.branches))
    with atomic_path(folder / RESPONSE) as temporary:  # NaN kept as JSON's NaN, as the parts keep it
        info = {"measure": measure, "branches": branches, "cutoff": found.cutoff}
        temporary.write_text(json.dumps(info, indent=1), encoding="utf-8")
    title = f"{found.case.name}: frequency response"
    blocks = frequency_blocks(found, measures if plots else []) + noise_blocks(found, noise, plots)
    return write_folder(folder, tables, figures, blocks, title)


def kept_noise(folder: Path) -> tuple[pd.DataFrame, pd.DataFrame] | None:
    """The noise tables an earlier ``oscillator frc --noise`` wrote into ``folder``, if both are
    there and readable (a report written again keeps them)."""
    import pandas as pd

    try:
        return pd.read_parquet(folder / "noise.parquet"), pd.read_parquet(folder / "spectra.parquet")
    except (OSError, ValueError):
        return None


def noise_blocks(
    found: FrequencyResponse, noise: tuple[pd.DataFrame, pd.DataFrame] | None, plots: bool
) -> list[mk.Block]:
    """The report's noise section: where the tables are, the loudest stable point, the figure."""
    if noise is None:
        return []
    from oscillator.report.noise import SPECTRA_FIGURE

    table, spectra = noise
    harmonics = int(spectra.harmonic.max()) if len(spectra) else 0
    text = (
        f"The noise measures of every branch point (noise.parquet: impacts, impulses, impact power, levels; "
        f"docs/noise.md) and their spectra, {harmonics} harmonics of each return (spectra.parquet)."
    )
    blocks: list[mk.Block] = [mk.Heading(2, ("Noise",)), mk.Paragraph((text,))]
    stable = table[table.stable.astype(bool)] if len(table) else table
    if len(stable) and "impact_power_left" in stable:
        loudest = stable.loc[(stable.impact_power_left + stable.impact_power_right).idxmax()]
        power = float(loudest.impact_power_left + loudest.impact_power_right)
        where = f"{found.param} = {float(loudest[found.param]):.6g} (branch {int(loudest.branch)})"
        blocks += [mk.Paragraph((f"The largest impact power of a stable point: {power:.4g} W at {where}.",))]
    if plots:
        blocks += [mk.Figure(SPECTRA_FIGURE, f"the stable orbits' spectra against {found.param}")]
    return blocks


def read_frequency(folder: Path) -> tuple[FrequencyResponse, str]:
    """The frequency response a folder holds (``oscillator frc``'s, finished, or a
    :meth:`~oscillator.FrequencyResponse.save`'s) and the measure its figures drew; every file
    checked, nothing computed.

    Raises
    ------
    InputError
        A file missing (an unfinished folder: the command resumes it) or damaged, named.
    """
    import json

    from oscillator.attractors.frequency import FrequencyResponse
    from oscillator.attractors.frequency_parts import (
        branch_part_columns,
        branches_from_disk,
        branches_problem,
        sweep_columns,
    )
    from oscillator.io.files import read_untrusted
    from oscillator.orbits.branch import points_from_disk
    from oscillator.orbits.response import COLUMNS as RESPONSE_COLUMNS
    from oscillator.report.orbit_folders import checked_table
    from oscillator.report.outputs import folder_case
    from oscillator.text import printable

    param, (low, high), period = _identity_of(folder)
    case = folder_case(folder, "frc.json")
    where = folder / RESPONSE
    if not where.is_file():
        raise InputError(
            f"{printable(str(folder))} is not a finished frequency response: {RESPONSE} is missing; {_REMAKE}",
            field=RESPONSE,
        )
    try:
        info = json.loads(read_untrusted(where, what="frequency-response file", field=RESPONSE, limit=64 << 20))
        measure, meta = info["measure"], info["branches"]
        cutoff = float(info["cutoff"]) if "cutoff" in info else 0.0  # a folder of before the cut-off: 0 Hz
    except (ValueError, KeyError, TypeError, RecursionError) as error:
        raise InputError(f"{printable(str(where))} is damaged ({error}); {_REMAKE}", field=RESPONSE) from None
    if measure not in MEASURES:
        raise InputError(f"{printable(str(where))} is damaged (its measure is none of ours); {_REMAKE}", field=RESPONSE)
    parts = branch_part_columns(param)
    kinds = {"period": "number", **parts, **dict.fromkeys(RESPONSE_COLUMNS, "number")}
    table = checked_table(folder / "points.parquet", kinds, folder="frequency-response folder", remake=_REMAKE)
    branch_table = table[[column for column in table.columns if column in parts]]  # in the order written
    why = branches_problem(param, (low, high), branch_table, meta)
    if why:
        raise InputError(
            f"{printable(str(folder))}: points.parquet and {RESPONSE} disagree ({why}); {_REMAKE}", field=RESPONSE
        )
    branches = branches_from_disk(case, param, branch_table, meta)
    sweeps = checked_table(
        folder / "sweeps.parquet", sweep_columns(param), folder="frequency-response folder", remake=_REMAKE
    )
    if not sweeps["direction"].isin(("up", "down")).all():
        raise InputError(f"{printable(str(folder))}/sweeps.parquet is damaged (a direction); {_REMAKE}", field="folder")
    found = FrequencyResponse(param, tuple(branches), points_from_disk(table), sweeps, case, period, cutoff)
    return found, measure


def _identity_of(folder: Path) -> tuple[str, tuple[float, float], int]:
    """The parameter, the span and the period a frequency-response folder's ``frc.json`` holds."""
    from oscillator.model.parameters import Parameters
    from oscillator.report.global_results import marker_identity
    from oscillator.text import printable

    def damaged(why: str) -> InputError:
        return InputError(f"{printable(str(folder))}/frc.json is damaged ({why}); {_REMAKE}", field="folder")

    from oscillator.attractors.frequency_parts import FrequencyStore

    known = marker_identity(folder / "frc.json", FrequencyStore.FORMAT, _ANEW)
    try:
        param = Parameters.check_name(known.get("param"), "folder")
        low, high = (float(value) for value in known["span"])
    except (KeyError, TypeError, ValueError, InputError) as error:
        raise damaged(f"its parameter or span: {error}") from None
    period = known.get("period", 1)
    if isinstance(period, bool) or not isinstance(period, int) or period < 1:
        raise damaged("its period is not a whole number of forcing periods")
    return param, (low, high), period
