"""What the global analyses' folders share: a colour and a marker per attractor, axis labels with
units, figure titles, a figure saved atomically, and a folder's tables, figures and report
written in that order (a figure that fails keeps the tables)."""

from __future__ import annotations

import textwrap
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pandas as pd

from oscillator.io.files import atomic_path
from oscillator.report import markup as mk
from oscillator.report.figures import figure_title, save_figure

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

__all__ = [
    "COLORS",
    "FAILED",
    "MARKERS",
    "color_of",
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
    """The unit of a state component: ``m`` for a displacement, ``m/s`` for a velocity."""
    return "m" if name.startswith("x") else "m/s"


def state_label(name: str) -> str:
    """An axis label for a state component, with its unit: ``x2 (m)``."""
    return f"{name} ({unit_of(name)})"


def wrapped_title(case: Any, what: str) -> str:
    """The case (with what its overrides changed) and what the figure shows, wrapped to the
    figure's width: a long list of changed values is not cut off."""

    return textwrap.fill(f"{figure_title(case)}: {what}", width=100)


def save_into(fig: Figure, folder: Path, name: str) -> None:
    """Save a figure as PNG and SVG into ``folder`` (created), uncropped."""
    folder.mkdir(exist_ok=True)
    save_figure(fig, folder, name, tight=False)


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
