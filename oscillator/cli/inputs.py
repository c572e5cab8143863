"""The command line's inputs: a case with its ``--set`` overrides, ``--sample`` and sweep settings,
and a figure's file."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from oscillator.errors import InputError
from oscillator.io.cases import Case, check_setting, load_case, resolve_case
from oscillator.io.expressions import parse_value
from oscillator.model.parameters import SolverOptions, SweepSettings, is_finite_number
from oscillator.text import printable, shown

if TYPE_CHECKING:  # pragma: no cover
    import numpy as np
    import pandas as pd
    from matplotlib.figure import Figure

__all__ = [
    "case_from",
    "check_engine",
    "figure_file",
    "output_file",
    "overrides",
    "refuse_taken",
    "sample_grid",
    "sweep_settings",
    "table_file",
    "write_figure",
    "write_table",
]

#: What a figure's file may be.
FIGURE_SUFFIXES = (".png", ".svg", ".pdf")
#: What a table's file may be.
TABLE_SUFFIXES = (".csv", ".parquet")


def output_file(target: Path, option: str, suffixes: tuple[str, ...] = FIGURE_SUFFIXES) -> Path:
    """``target`` if a file can be written there as ``option`` names it: a name with one of
    ``suffixes``, writable as given, not a link, in a folder that exists (checked before anything
    is computed)."""
    from oscillator.io.files import check_name, refuse_link

    if target.suffix.lower() not in suffixes:
        kinds = ", ".join(suffixes[:-1]) + f" or {suffixes[-1]}"
        raise InputError(f"{option} must end in {kinds}, got {printable(str(target))}", field=option)
    check_name(target, option=option)
    refuse_link(target, option=option)
    if not target.absolute().parent.is_dir():
        raise InputError(
            f"{option} {printable(str(target))}: its folder does not exist; create it or give another", field=option
        )
    return target


def figure_file(target: Path, option: str) -> Path:
    """``target`` if a figure can be written there (:func:`output_file`: ``.png``, ``.svg``, ``.pdf``)."""
    return output_file(target, option, FIGURE_SUFFIXES)


def table_file(target: Path, option: str) -> Path:
    """``target`` if a table can be written there (:func:`output_file`: ``.csv``, ``.parquet``)."""
    return output_file(target, option, TABLE_SUFFIXES)


def write_figure(fig: Figure, target: Path) -> None:
    """``fig`` written to ``target`` (:func:`figure_file`) atomically: the whole file or none."""
    from oscillator.io.files import atomic_path

    with atomic_path(target) as temporary:
        fig.savefig(temporary, format=target.suffix[1:].lower(), dpi=120, bbox_inches="tight")


def write_table(frame: pd.DataFrame, target: Path) -> None:
    """``frame`` written to ``target`` (:func:`table_file`) atomically, as CSV or Parquet by its name."""
    from oscillator.io.files import atomic_path

    with atomic_path(target) as temporary:
        if target.suffix.lower() == ".csv":
            frame.to_csv(temporary, index=False)
        else:
            frame.to_parquet(temporary, index=False)


def check_engine(engine: str | None, among: tuple[str, ...] | None = None) -> None:
    """Refuse an ``--engine`` that is not an engine (or not one of the command's, ``among``)
    before anything is created."""
    from oscillator.engines import check_engine as checked

    if engine is not None:
        checked(engine, among=among, field="--engine")


INTEGER_OPTIONS = {f.name for f in SolverOptions.__dataclass_fields__.values() if f.type in ("int", int)}


def overrides(assignments: list[str]) -> dict[str, Any]:
    """``NAME=VALUE`` strings to overrides, values as numbers or expressions of pi."""
    values = {}
    for item in assignments:
        name, sep, text = item.partition("=")
        name = name.strip()
        if not sep or not name:
            raise InputError(f"--set {shown(item)}: write NAME=VALUE, e.g. --set Omega=1.7", field="--set")
        check_setting(name)
        value = parse_value(text.strip(), field=f"--set {printable(name)}")
        if name in INTEGER_OPTIONS:
            if not isinstance(value, (int, float)) or not math.isfinite(value) or not float(value).is_integer():
                raise InputError(f"--set {printable(name)}={shown(text)}: {name} is a whole number", field=name)
            value = int(value)
        values[name] = value
    return values


def case_from(
    case: str, t_end: float | None = None, assignments: list[str] | None = None, keep_events_from: float | None = None
) -> Case:
    from oscillator.io.chains import system_path

    if system_path(case) is not None:
        raise InputError(
            f"{printable(case)} is a system file (a declared machine); this command takes the article's cases. The "
            f"commands that take a system file: {', '.join(SYSTEM_COMMANDS)} (docs/systems.md)",
            field="case",
        )
    return resolve_case(load_case(case), t_end=t_end, keep_events_from=keep_events_from, **overrides(assignments or []))


#: The commands that take a system file where they take a case.
SYSTEM_COMMANDS = (
    "run",
    "show",
    "check",
    "orbit",
    "continue",
    "frc",
    "design",
    "attractors",
    "atlas",
    "curve",
    "sweep",
    "locate",
    "basins",
    "lyapunov",
    "explore",
)


def refuse_taken(assignments: list[str] | None, taken: Mapping[str, str]) -> None:
    """Refuse ``--set NAME=...`` of a parameter or start value that another option gives (the
    swept or continued parameter, a varied one, an axis: ``taken`` maps it to that option): the
    value set would be ignored.  Only the names are read here: the article's case and a declared
    system check their own (``Omega``, ``wall.at``)."""
    for item in assignments or []:
        name = item.partition("=")[0].strip()
        if name in taken:
            raise InputError(
                f"--set {printable(name)}=...: {printable(name)} is given by {taken[name]}, which would override it; "
                f"give its values with {taken[name]} only",
                field="--set",
            )


def sample_grid(case: Case, sample: float | None) -> np.ndarray | None:
    """The grid of ``--sample DT``: every DT seconds from t0, and t_end."""
    if sample is None:
        return None
    import numpy as np

    if not (is_finite_number(sample) and sample > 0):
        raise InputError(f"--sample must be a positive time step in s, got {sample!r}", field="--sample")
    rows = (case.t_end - case.initial.t0) / sample
    if rows > case.options.max_trajectory_rows:
        raise InputError(
            f"--sample {sample:g} gives {rows:.3g} rows, more than max_trajectory_rows = "
            f"{case.options.max_trajectory_rows}; give a longer step",
            field="--sample",
        )
    grid = case.initial.t0 + sample * np.arange(math.floor(rows) + 1)
    return np.unique(np.append(grid[grid < case.t_end], case.t_end))


def sweep_settings(
    c: Case,
    param: str | None,
    start: float | None,
    stop: float | None,
    steps: int | None,
    transient: int | None,
    record: int | None,
    both_ways: bool = False,
) -> SweepSettings:
    """The case's ``[sweep]`` table with the command line's changes (``--both-ways`` sets it)."""
    base = c.sweep
    if base is None and (param is None or start is None or stop is None):
        raise InputError(
            f"case {shown(c.name)} has no [sweep] table; give --param NAME --from A --to B", field="--param"
        )
    changes = {
        k: v
        for k, v in dict(
            param=param,
            start=start,
            stop=stop,
            steps=steps,
            transient=transient,
            record=record,
            both_ways=both_ways or None,
        ).items()
        if v is not None
    }
    if base is None:
        return SweepSettings(**changes)  # type: ignore[arg-type]  # the values' types by name, checked there
    return dataclasses.replace(base, **changes)  # type: ignore[arg-type]
