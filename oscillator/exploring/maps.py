"""A folder's picture for the explorer, and what a click on it computes.

``oscillator explore FOLDER`` opens the folder an analysis wrote, drawn as its command draws it:

- an **atlas** (a plane of two parameters, each cell coloured by the regime of its attractors);
- **basins** (a slice of starts, each cell coloured by the attractor its start reaches);
- a **sweep** (its bifurcation diagram: the Poincaré points of the swept mass against the
  parameter, coloured by the period the sweep recorded);
- a **frequency response** (``oscillator frc``: every branch point's peak-to-peak amplitude of
  each mass against the parameter, stable and unstable apart).

A click on a cell or a point is a :class:`Site`: the case there, the starts that
:func:`~oscillator.find_attractors` runs from (the case's start and what the folder holds there:
an atlas cell's attractors, a sweep value's end state, a branch point's orbit; a basins cell's own
start), and what the folder says of it.  The folder's own files are read once, checked, and nothing
else is read.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
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
from oscillator.model.parameters import Parameters
from oscillator.model.system import System
from oscillator.text import printable

__all__ = ["Picture", "Site", "picture_of"]

#: The folders the explorer opens, by the kind their marker file names.
KINDS = ("atlas", "basins", "sweep", "frc")
#: How far from an unstable branch point the starts of a click there are, relative to its state.
NUDGE = 1e-3
#: What each folder's points are, in the explorer's words.
WHAT = {"atlas": "atlas", "basins": "basins", "sweep": "sweep", "frc": "frequency response"}


@dataclass(frozen=True, eq=False)
class Site:
    """What a click on one cell or point asks, and what the folder holds there.

    Attributes
    ----------
    case : Case
        The case there (the folder's, with the cell's or point's parameter values).
    starts : ndarray of shape (N, 4)
        The starts :func:`~oscillator.find_attractors` runs from, at the case's ``t0``.
    held : str
        What the folder says of the site (plain text; empty if nothing beyond its label).
    state : ndarray of shape (4,), optional
        The start put on the explorer's controls (a branch point's orbit); the first attractor
        found when None.
    """

    case: Case
    starts: np.ndarray
    held: str = ""
    state: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class Picture:
    """A folder's picture: one point per cell (or per point drawn), with its label, and what a
    click there asks.

    Attributes
    ----------
    kind : str
        One of :data:`KINDS`.
    case : Case
        The folder's case.
    x, y : str
        The axes' names.
    points : DataFrame
        ``x, y, label, at``: one row per cell or point drawn, in the folder's order; ``at`` is the
        site (a row of ``source``) a click there asks for.
    width, height : float
        A cell's size along each axis; 0 for a picture of points.
    source : Any
        What the folder holds: an :class:`~oscillator.Atlas`, a :class:`~oscillator.Basins`, a
        sweep's summary or a frequency response's branch points (one row per site).
    site_of : callable
        ``site_of(picture, at)``: the :class:`Site` of a row of ``source``.
    marks : DataFrame
        ``x, y, label``: points marked on the picture (a frequency response's bifurcations).
    """

    kind: str
    case: Case
    x: str
    y: str
    points: pd.DataFrame
    width: float
    height: float
    source: Any
    site_of: Callable[[Picture, int], Site]
    marks: pd.DataFrame = field(default_factory=lambda: pd.DataFrame({"x": [], "y": [], "label": []}))

    @property
    def cells(self) -> bool:
        """Whether the picture is of cells (an atlas, basins), not of points."""
        return self.width > 0

    @property
    def frame(self) -> tuple[float, float, float, float]:
        """The cells' extent, ``(left, right, bottom, top)`` (the points' for a picture of points)."""
        xs, ys = self.points.x.to_numpy(float), self.points.y.to_numpy(float)
        drawn = np.isfinite(xs) & np.isfinite(ys)
        half_x, half_y = self.width / 2, self.height / 2
        return (
            float(xs[drawn].min()) - half_x,
            float(xs[drawn].max()) + half_x,
            float(ys[drawn].min()) - half_y,
            float(ys[drawn].max()) + half_y,
        )

    def inside(self, x: float, y: float) -> bool:
        """Whether ``(x, y)`` is on the picture's cells (any point, for a picture of points)."""
        if not self.cells:
            return True
        left, right, bottom, top = self.frame
        return left <= x <= right and bottom <= y <= top

    def nearest(self, x: float, y: float) -> int:
        """The cell or point nearest ``(x, y)``, measured in cells (in the axes' spans for points);
        points whose coordinates are not numbers are not drawn, and not picked."""
        xs, ys = self.points.x.to_numpy(float), self.points.y.to_numpy(float)
        width = self.width or float(np.nanmax(xs) - np.nanmin(xs)) or 1.0
        height = self.height or float(np.nanmax(ys) - np.nanmin(ys)) or 1.0
        dx, dy = (xs - x) / width, (ys - y) / height
        distance = dx * dx + dy * dy
        distance[~np.isfinite(distance)] = np.inf  # a point not drawn (a measure not a number) is not picked
        return int(np.argmin(distance))

    def site(self, index: int) -> Site:
        """What a click on point ``index`` asks, and what the folder holds there."""
        return self.site_of(self, int(self.points.at[index, "at"]))

    def starts_at(self, index: int) -> tuple[Case, np.ndarray]:
        """The case at point ``index`` and the starts a click there runs from."""
        site = self.site(index)
        return site.case, site.starts

    def attractors(self, site: Site) -> Attractors:
        """What :func:`~oscillator.find_attractors` finds from the starts of ``site`` (with the
        folder's settings for basins, the defaults elsewhere)."""
        settings = self.source.found.settings if self.kind == "basins" else None
        return find_attractors(site.case, states=site.starts, settings=settings)

    def label_at(self, index: int) -> str:
        row = self.points.iloc[index]
        return f"{self.x} = {row.x:.6g}, {self.y} = {row.y:.6g}: {row.label}"


def _step(values: np.ndarray) -> float:
    unique = np.unique(values)
    return float(np.min(np.diff(unique))) if len(unique) > 1 else 1.0


def _starts(case: Case, *held: np.ndarray) -> np.ndarray:
    """The case's start and the finite states held, each once."""
    starts = [np.array(case.initial.y, dtype=float), *(s for s in held if np.isfinite(s).all())]
    return np.unique(np.array(starts), axis=0)


# -- atlas and basins ---------------------------------------------------------------------------
def _atlas(atlas: Atlas) -> Picture:
    if not isinstance(atlas.case, Case):  # a declared system's atlas folder is not read back yet
        raise InputError("the explorer shows the article's atlases; a system's atlas is in its folder", field="folder")
    x, y = atlas.x.name, atlas.y.name
    table = atlas.table
    first = table[table.attractor <= 0].drop_duplicates(["row", "column"])
    counts = table.groupby(["row", "column"]).size()
    labels = [
        f"{regime}" + (f" (+{n - 1} more)" if n > 1 else "")
        for regime, n in zip(first.regime, counts.loc[list(zip(first.row, first.column, strict=True))], strict=True)
    ]
    points = pd.DataFrame({"x": first[x].to_numpy(float), "y": first[y].to_numpy(float), "label": labels})
    points["at"] = np.arange(len(points))
    return Picture("atlas", atlas.case, x, y, points, _step(points.x), _step(points.y), atlas, _atlas_site)


def _atlas_site(picture: Picture, at: int) -> Site:
    row = picture.points.iloc[at]
    case = resolve_case(picture.case, **{picture.x: float(row.x), picture.y: float(row.y)})
    table = picture.source.table
    held = table[(table[picture.x] == row.x) & (table[picture.y] == row.y) & (table.status == "ok")]
    return Site(case, _starts(case, *held[list(STATE)].to_numpy(float)))


def _basins(basins: Basins) -> Picture:
    x, y = basins.x.name, basins.y.name
    labels = basins.found.labels
    names = {a.id: a.name for a in basins.found.attractors}
    text = [names.get(int(k), "failed") for k in labels.attractor]
    points = pd.DataFrame({"x": labels[x].to_numpy(float), "y": labels[y].to_numpy(float), "label": text})
    points["at"] = np.arange(len(points))
    case = basins.found.case
    return Picture("basins", case, x, y, points, _step(points.x), _step(points.y), basins, _basins_site)


def _basins_site(picture: Picture, at: int) -> Site:
    row = picture.points.iloc[at]
    start = np.array(picture.case.initial.y, dtype=float)
    start[STATE.index(picture.x)], start[STATE.index(picture.y)] = float(row.x), float(row.y)
    return Site(picture.case, start[None, :])


# -- sweep and frequency response ---------------------------------------------------------------
def _identity(folder: Path, marker: str) -> tuple[dict[str, Any], Case]:
    """A folder's identity (its marker file's) and its case, or refused naming the folder."""
    from oscillator.report.global_results import marker_identity
    from oscillator.report.outputs import folder_case

    return marker_identity(folder / marker), folder_case(folder, marker)


def _parameter(name: object, folder: Path, marker: str) -> str:
    """The parameter a folder's marker names, or refused naming the marker (a damaged folder)."""
    return Parameters.check_name(name, "case", label=f"{printable(str(folder / marker))} is damaged: its parameter")


def _sweep(folder: Path) -> Picture:
    from oscillator.report.orbit_folders import checked_table

    identity, case = _identity(folder, "sweep.json")
    settings = identity.get("settings")
    settings = settings if isinstance(settings, dict) else {}
    param = _parameter(settings.get("param"), folder, "sweep.json")
    mass = settings.get("mass")
    coordinate = case.system.position(mass if mass in case.system.masses and not isinstance(mass, bool) else 2)
    columns = {param: "number", "index": "number", "status": "text", "period": "number", "direction": "text"}
    columns |= {f"end_{name}": "number" for name in STATE}
    read = partial(checked_table, folder="sweep folder", remake="run the sweep again into a new folder")
    summary = read(folder / "summary.parquet", columns).reset_index(drop=True)
    poincare = read(folder / "poincare.parquet", {param: "number", "index": "number", coordinate: "number"})
    rows = {int(index): k for k, index in enumerate(summary["index"])}  # a both-ways sweep's values twice
    at = np.array([rows.get(int(index), -1) for index in poincare["index"]], dtype=int)
    keep = at >= 0
    points = pd.DataFrame(
        {
            "x": poincare[param].to_numpy(float)[keep],
            "y": poincare[coordinate].to_numpy(float)[keep],
            "label": [_sweep_label(summary.iloc[k]) for k in at[keep]],
            "at": at[keep],
        }
    )
    source = summary.assign(both_ways=bool(settings.get("both_ways")))
    return Picture("sweep", case, param, coordinate, points, 0.0, 0.0, source, _sweep_site)


def _sweep_label(row: pd.Series) -> str:
    if row.status != "ok":
        return "failed"
    return f"period-{int(row.period)}" if row.period > 0 else "no period found"


def _sweep_site(picture: Picture, at: int) -> Site:
    row = picture.source.iloc[at]
    case = resolve_case(picture.case, **{picture.x: float(row[picture.x])})
    end = row[[f"end_{name}" for name in STATE]].to_numpy(float)
    state = ", ".join(f"{v:.6g}" for v in end)
    sweep = f"the sweep {row.direction}" if row.both_ways else "the sweep"
    return Site(case, _starts(case, end), f"{sweep} recorded {_sweep_label(row)}, ending at ({state})")


def _frc(folder: Path) -> Picture:
    from oscillator.orbits.branch import MULTIPLIERS, points_from_disk
    from oscillator.report.orbit_folders import checked_table

    identity, case = _identity(folder, "frc.json")
    system = case.system
    param = _parameter(identity.get("param"), folder, "frc.json")
    columns = {param: "number", "branch": "number", "period": "number", "stable": "flag"}
    columns |= dict.fromkeys((*system.state, *(f"x_pp{system.suffix(m)}" for m in system.masses)), "number")
    columns |= {f"{name}_{part}": "number" for name in MULTIPLIERS for part in ("re", "im")}
    table = checked_table(
        folder / "points.parquet", columns, folder="frequency-response folder", remake="run oscillator frc again"
    )
    branch = points_from_disk(table).reset_index(drop=True)
    stable = np.where(branch.stable.to_numpy(bool), "stable", "unstable")
    points = pd.concat(
        [
            pd.DataFrame(
                {
                    "x": branch[param].to_numpy(float),
                    "y": branch[f"x_pp{system.suffix(mass)}"].to_numpy(float),
                    "label": [f"{system.label(mass)} {kind}" for kind in stable],
                    "at": np.arange(len(branch)),
                }
            )
            for mass in system.masses
        ],
        ignore_index=True,
    )
    return Picture(
        "frc", case, param, "x_pp", points, 0.0, 0.0, branch, _frc_site, _frc_marks(folder, param, branch, system)
    )


def _frc_marks(folder: Path, param: str, branch: pd.DataFrame, system: System) -> pd.DataFrame:
    """The frequency response's bifurcations, each at the ``x_pp`` of every mass of ``system`` at
    its branch's point nearest it (none where the folder keeps no bifurcation table)."""
    from oscillator.orbits.branch import BIFURCATION_KINDS
    from oscillator.report.orbit_folders import checked_table

    path = folder / "bifurcations.parquet"
    if not path.is_file():
        return pd.DataFrame({"x": [], "y": [], "label": []})
    rows = checked_table(
        path,
        {"branch": "number", param: "number", "kind": "text"},
        folder="frequency-response folder",
        remake="run oscillator frc again",
    )
    marks = []
    for row in rows.itertuples(index=False):
        mine = branch[branch.branch == row.branch]
        if row.kind not in BIFURCATION_KINDS or mine.empty:
            continue
        value = float(getattr(row, param))
        nearest = mine.iloc[int(np.argmin(np.abs(mine[param].to_numpy(float) - value)))]
        marks += [
            (value, float(nearest[f"x_pp{system.suffix(mass)}"]), str(row.kind).replace("_", " "))
            for mass in system.masses
        ]
    return pd.DataFrame(marks, columns=["x", "y", "label"])


def _frc_site(picture: Picture, at: int) -> Site:
    from oscillator.orbits.branch import MULTIPLIERS

    row = picture.source.iloc[at]
    case = resolve_case(picture.case, **{picture.x: float(row[picture.x])})
    state = row[list(STATE)].to_numpy(float)
    moduli = ", ".join(f"{abs(complex(row[name])):.4g}" for name in MULTIPLIERS)
    held = (
        f"branch {int(row.branch)}: {'a stable' if row.stable else 'an unstable'} period-{int(row.period)} orbit "
        f"through ({', '.join(f'{v:.6g}' for v in state)}); |multipliers| {moduli}; "
        f"x_pp_m1 = {row.x_pp_m1:.5g}, x_pp_m2 = {row.x_pp_m2:.5g}"
    )
    if row.stable:
        return Site(case, _starts(case, state), held, state)
    # a start on an unstable orbit stays on it as long as a run takes to settle: started on either
    # side of it instead, the motion leaves it for the attractors between which it lies
    nudge = NUDGE * (1.0 + np.abs(state))
    held += f"; find_attractors starts on either side of it ({NUDGE:g} relative)"
    return Site(case, _starts(case, state + nudge, state - nudge), held, state)


#: The pictures of the analyses' folders the explorer opens (:mod:`oscillator.report.kinds`
#: names a folder's kind; a frequency response's picture reads its points table only).
_PICTURES: dict[str, Callable[[Any], Picture]] = {"atlas": _atlas, "basins": _basins}


def picture_of(folder: str | Path) -> Picture:
    """The picture of an atlas, basins, sweep or frequency-response folder (read and checked once).

    Raises
    ------
    InputError
        Not a readable folder, a damaged file in it, a folder of another kind (named), or one with
        no point to show.
    """
    picture = _read(Path(folder))
    finite = np.isfinite(picture.points.x.to_numpy(float)) & np.isfinite(picture.points.y.to_numpy(float))
    if not finite.any():
        raise InputError(
            f"{printable(str(folder))} holds no point to show (its {WHAT[picture.kind]} has no finite value); "
            "compute it again, or give another folder",
            field="case",
        )
    return picture


def _read(path: Path) -> Picture:
    from oscillator.report.kinds import folder_kind

    if path.is_dir() and (path / "sweep.json").is_file():
        return _sweep(path)
    kind = folder_kind(path) if path.is_dir() else None
    if kind is None:
        raise InputError(
            f"{printable(str(path))} is not a folder of an oscillator atlas, basins, sweep or frequency response; "
            "give one, or a case",
            field="case",
        )
    if kind.name == "frc":
        return _frc(path)
    if kind.name not in _PICTURES:
        raise InputError(
            f"{printable(str(path))} holds {kind.what}, not an atlas, basins, sweep or frequency response; the "
            "explorer opens a case or one of those",
            field="case",
        )
    return _PICTURES[kind.name](kind.at("read")(path))
