"""A folder's picture for the explorer, and what a click on it computes.

``oscillator explore FOLDER`` opens an atlas (a plane of two parameters, each cell coloured by the
regime of its attractors) or the basins of a slice of starts (each cell coloured by the attractor
its start reaches).  A click on a cell asks :func:`~oscillator.find_attractors` for the
attractor(s) there: at an atlas cell, from the case's start and from each attractor the folder
holds at that cell; at a basins cell, from the cell's start.  The folder's own values are read
once, checked (:func:`~oscillator.report.global_results.read_global`), and nothing else is read.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from oscillator.analysis.axes import STATE
from oscillator.attractors.atlas import Atlas
from oscillator.attractors.basins import Basins
from oscillator.attractors.finding import Attractors, find_attractors
from oscillator.errors import InputError
from oscillator.io.cases import Case, resolve_case
from oscillator.text import printable

__all__ = ["Picture", "picture_of"]


@dataclass(frozen=True, eq=False)
class Picture:
    """A folder's picture: one point per cell, with its label, and what a click there asks.

    Attributes
    ----------
    kind : str
        ``"atlas"`` or ``"basins"``.
    case : Case
        The folder's case.
    x, y : str
        The axes' names (parameters for an atlas, start coordinates for basins).
    points : DataFrame
        ``x, y, label``: one row per cell, in the folder's order.
    width, height : float
        A cell's size along each axis.
    source : Atlas or Basins
        What the folder holds.
    """

    kind: str
    case: Case
    x: str
    y: str
    points: pd.DataFrame
    width: float
    height: float
    source: Any

    def nearest(self, x: float, y: float) -> int:
        """The cell nearest ``(x, y)``, measured in cells."""
        dx = (self.points.x.to_numpy() - x) / (self.width or 1.0)
        dy = (self.points.y.to_numpy() - y) / (self.height or 1.0)
        return int(np.argmin(dx * dx + dy * dy))

    def starts_at(self, index: int) -> tuple[Case, np.ndarray]:
        """The case at cell ``index`` and the starts a click there runs from."""
        row = self.points.iloc[index]
        if self.kind == "atlas":
            case = resolve_case(self.case, **{self.x: float(row.x), self.y: float(row.y)})
            table = self.source.table
            held = table[(table[self.x] == row.x) & (table[self.y] == row.y) & (table.status == "ok")]
            starts = [np.array(case.initial.y, dtype=float), *held[list(STATE)].to_numpy(float)]
            return case, np.unique(np.array(starts), axis=0)
        start = np.array(self.case.initial.y, dtype=float)
        start[STATE.index(self.x)], start[STATE.index(self.y)] = float(row.x), float(row.y)
        return self.case, start[None, :]

    def attractors_at(self, index: int) -> Attractors:
        """What :func:`~oscillator.find_attractors` finds from the starts of cell ``index``."""
        case, starts = self.starts_at(index)
        settings = self.source.found.settings if self.kind == "basins" else None
        return find_attractors(case, states=starts, settings=settings)

    def label_at(self, index: int) -> str:
        row = self.points.iloc[index]
        return f"{self.x} = {row.x:.6g}, {self.y} = {row.y:.6g}: {row.label}"


def _step(values: np.ndarray) -> float:
    unique = np.unique(values)
    return float(np.min(np.diff(unique))) if len(unique) > 1 else 1.0


def _atlas(atlas: Atlas) -> Picture:
    x, y = atlas.x.name, atlas.y.name
    table = atlas.table
    first = table[table.attractor <= 0].drop_duplicates(["row", "column"])
    counts = table.groupby(["row", "column"]).size()
    labels = [
        f"{regime}" + (f" (+{n - 1} more)" if n > 1 else "")
        for regime, n in zip(first.regime, counts.loc[list(zip(first.row, first.column, strict=True))], strict=True)
    ]
    points = pd.DataFrame({"x": first[x].to_numpy(float), "y": first[y].to_numpy(float), "label": labels})
    return Picture("atlas", atlas.case, x, y, points, _step(points.x), _step(points.y), atlas)


def _basins(basins: Basins) -> Picture:
    x, y = basins.x.name, basins.y.name
    labels = basins.found.labels
    names = {a.id: a.name for a in basins.found.attractors}
    text = [names.get(int(k), "failed") for k in labels.attractor]
    points = pd.DataFrame({"x": labels[x].to_numpy(float), "y": labels[y].to_numpy(float), "label": text})
    return Picture("basins", basins.found.case, x, y, points, _step(points.x), _step(points.y), basins)


def picture_of(folder: str | Path) -> Picture:
    """The picture of an atlas or basins folder (read and checked once).

    Raises
    ------
    InputError
        Not a readable folder, a damaged file in it, or a folder of another kind (named).
    """
    from oscillator.report.global_results import global_kind, read_global

    path = Path(folder)
    if not path.is_dir() or global_kind(path) is None:
        raise InputError(
            f"{printable(str(folder))} is not a folder of oscillator atlas or basins; give one, or a case",
            field="case",
        )
    found = read_global(path)
    if isinstance(found, Atlas):
        return _atlas(found)
    if isinstance(found, Basins):
        return _basins(found)
    raise InputError(
        f"{printable(str(folder))} holds a {type(found).__name__}, not an atlas or basins; the explorer opens a case "
        "or one of those",
        field="case",
    )
