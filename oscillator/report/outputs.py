"""What the global analyses' folders share: a colour and a marker per attractor, axis labels with
units, figure titles, a figure saved atomically, and a folder's tables, figures and report
written in that order (a figure that fails keeps the tables)."""

from __future__ import annotations

import textwrap
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pandas as pd

from oscillator.errors import InputError, OscillatorError
from oscillator.io.files import atomic_path, inner_folder
from oscillator.model.chains import FrictionChain
from oscillator.model.parameters import labelled
from oscillator.model.system import ARTICLE
from oscillator.report import markup as mk
from oscillator.report.figures import figure_title, save_figure
from oscillator.text import printable

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

    from oscillator.io.cases import Case

__all__ = [
    "COLORS",
    "FAILED",
    "MARKERS",
    "color_of",
    "folder_case",
    "folder_system",
    "number_label",
    "plain_label",
    "quantity_label",
    "save_into",
    "state_label",
    "unit_of",
    "wrapped_title",
    "write_folder",
]


#: A colour per attractor (more attractors cycle through them), and the failed cells' grey.
COLORS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown", "tab:pink", "tab:olive")


FAILED = "0.6"


#: A marker per attractor for its own section points, so that coinciding ones stay apart.
MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*")


def color_of(ident: int) -> str:
    return FAILED if ident < 0 else COLORS[ident % len(COLORS)]


def unit_of(name: str) -> str:
    """The unit of a state component: ``m`` for a displacement (``x1``, ``x:<mass>``) or a
    slider's stretch (``z:<slider>``), ``m/s`` for a velocity."""
    return "m" if name.startswith(("x", "z")) else "m/s"


def number_label(system: Case | FrictionChain, name: str) -> str:
    """An axis label for a parameter with its unit: the article's, or a declared system's number's
    (as plain text)."""
    if isinstance(system, FrictionChain):
        unit = FrictionChain.unit(name)
        return plain_label(f"{name} ({unit})" if unit else name)
    return labelled(name)


def plain_label(text: str) -> str:
    """A name as plain text for matplotlib (no mathtext)."""
    return printable(text).replace("$", r"\$")


def state_label(name: str) -> str:
    """An axis label for a state component, with its unit: ``x2 (m)``."""
    return f"{name} ({unit_of(name)})"


def quantity_label(name: str, prefix: str = "") -> str:
    """An axis label with its unit for any quantity a figure draws: a parameter (``Omega
    (rad/s)``), a state component (``x2 (m)``) or a response measure's column (``impact_max_right
    (m/s)``, ``rest_m2 (fraction of the period)``); ``prefix`` before the name (``"worst "``)."""
    from oscillator.model.parameters import Parameters, labelled
    from oscillator.orbits.response import COLUMNS
    from oscillator.orbits.response import unit_of as measure_unit

    if name in Parameters.names():
        return prefix + labelled(name)
    if name in ARTICLE.state:
        return prefix + state_label(name)
    if name in COLUMNS:
        unit = measure_unit(name)
        return f"{prefix}{name} ({unit or 'fraction of the period'})"
    return prefix + name


def wrapped_title(case: Any, what: str) -> str:
    """The case (with what its overrides changed) and what the figure shows, wrapped to the
    figure's width: a long list of changed values is not cut off."""

    return textwrap.fill(f"{figure_title(case)}: {what}", width=100)


def save_into(fig: Figure, folder: Path, name: str) -> None:
    """Save a figure as PNG and SVG into ``folder`` (created), uncropped."""
    save_figure(fig, inner_folder(folder), name, tight=False)


def write_folder(
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
    try:
        if figures:
            inner_folder(folder / "figures")
    except OscillatorError as error:
        problems.append(f"figures not drawn: {error}")
        figures = ()
    for name, draw in figures:
        try:
            save_into(draw(), folder / "figures", name)
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


def folder_system(folder: Path, marker: str) -> Case | FrictionChain:
    """The system a global analysis's folder keeps: a declared system's ``system.toml`` (read as
    any system file: checked, its text untrusted), else the case (:func:`folder_case`)."""
    from oscillator.io.chains import load_system

    if not (folder / "case.toml").exists() and (folder / "system.toml").is_file():
        return load_system(folder / "system.toml")
    return folder_case(folder, marker)


def folder_case(folder: Path, marker: str, *, key: str = "case_name") -> Case:
    """The case a global analysis's folder keeps (``case.toml``), under the name its marker keeps
    at ``key`` (a case file holds no name); refused naming the folder where it cannot be read."""
    import dataclasses
    import json

    from oscillator.io.cases import load_case
    from oscillator.io.files import read_untrusted

    if not (folder / "case.toml").exists() and (folder / "system.toml").exists():
        raise InputError(
            f"{printable(str(folder))} holds a declared system's {marker.removesuffix('.json')} (system.toml), which "
            "is not read back yet: its tables and report are in it; to write them again, run the same command "
            "with --out naming it (it resumes, nothing computed twice)",
            field="folder",
        )
    try:
        case = load_case(folder / "case.toml")
    except OscillatorError as error:
        raise InputError(f"{printable(str(folder))}: its case.toml cannot be read ({error})", field="folder") from None
    try:
        info = json.loads(read_untrusted(folder / marker, what="marker file", field="folder", limit=1 << 20))
    except (OscillatorError, ValueError, RecursionError):
        return case
    name = info.get(key) if isinstance(info, dict) else None
    return dataclasses.replace(case, name=name) if isinstance(name, str) and name else case
