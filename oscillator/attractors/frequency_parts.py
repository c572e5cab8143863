"""A frequency response's resumable folder (``frc.json``): its parts, written as they finish and
read back only as the task's that asked for them.

Each part is a table (:class:`~oscillator.analysis.store.TableFolder`) with its task's key in its
metadata and what it must hold (:class:`~oscillator.analysis.store.Expected`): a seed's branches
(``seed-KKKK``: the seed's index and value), the branches born at a period doubling
(``doubling-BBBB-RRR``: the branch, the doubling's row and value), a branch's measures
(``measures-BBBB``: one row per point of the branch, at the branch's own parameter values) and a
sweep (``sweep-up``, ``sweep-down``: one row per value, the sweep's own).  A part that holds
another task's result, another number of rows, values outside the span, columns of another kind
or metadata that does not read is refused by name, never merged.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from oscillator.analysis.store import Expected, TableFolder, identity
from oscillator.attractors.mapping import STATE, AttractorSettings, check_settings
from oscillator.errors import Reason
from oscillator.io.cases import Case
from oscillator.orbits.branch import MULTIPLIERS, Bifurcation, Branch, point_columns, points_from_disk, points_on_disk
from oscillator.orbits.response import COLUMNS as RESPONSE_COLUMNS
from oscillator.orbits.shooting import orbit_case

__all__ = [
    "FrequencyStore",
    "branch_part_columns",
    "branches_from_disk",
    "branches_on_disk",
    "branches_problem",
    "frequency_store",
    "measures_part",
    "no_points",
    "sweep_columns",
    "sweep_part",
]

#: How far a branch's points may lie beyond the span, relative to its width (rounding).
_SLACK = 1e-9


class FrequencyStore(TableFolder):
    """The resumable folder of a frequency response (``frc.json``): one part per seed (its
    branches), per period doubling (the branches born there), per branch (its measures) and per
    sweep (module docstring)."""

    #: 2: each part keyed by its task, every sweep row with every measure's column; 3: the impulses
    #: and force_rms among the measures (a folder of an earlier format is refused, not read as damaged);
    #: 4: force_above and a_above among them.
    FORMAT = 4

    def __init__(self, folder: Path, identity: dict[str, Any], *, name: str = "") -> None:
        super().__init__(folder, "frc.json", identity, name=name)


def frequency_store(
    folder: Path,
    case: Case,
    param: str,
    span: tuple[float, float],
    *,
    period: int = 1,
    seeds: int = 5,
    states: np.ndarray | None = None,
    sweep: int = 41,
    settings: AttractorSettings | None = None,
    max_points: int = 3000,
) -> FrequencyStore:
    """The resumable folder of this frequency response (:class:`FrequencyStore`)."""
    pieces = {"param": param, "span": list(span), "period": period, "seeds": seeds, "sweep": sweep}
    pieces |= {"states": states, "settings": check_settings(settings), "max_points": max_points}
    return FrequencyStore(folder, identity(case, **pieces), name=case.name)


def no_points(param: str) -> pd.DataFrame:
    """The points table of a frequency response without a branch: its columns, no row."""
    columns = ["branch", "period", *point_columns(param), *RESPONSE_COLUMNS]
    return pd.DataFrame({name: pd.Series(dtype=object if name == "signature" else float) for name in columns})


def branch_part_columns(param: str) -> dict[str, str]:
    """The kinds of the columns of a part of branches (:func:`branches_on_disk`)."""
    numbers = [param, *STATE, *(f"{name}_{part}" for name in MULTIPLIERS for part in ("re", "im"))]
    numbers += ["piece", "iterations", "branch"]
    return dict.fromkeys(numbers, "number") | {"stable": "flag", "signature": "text"}


def branches_on_disk(param: str, branches: list[Branch]) -> tuple[pd.DataFrame, list[dict[str, Any]]]:
    """Branches as one table (points, ``branch`` their index among these) and the rest of each
    (section, period, ending, bifurcations) as the part's metadata."""
    frames = [points_on_disk(branch.points).assign(branch=k) for k, branch in enumerate(branches)]
    meta = [
        {
            "section": branch.section,
            "period": branch.period,
            "complete": branch.complete,
            "message": branch.message,
            "reason": None if branch.reason is None else branch.reason.value,
            "bifurcations": branch.bifurcations.to_dict("records"),
        }
        for branch in branches
    ]
    empty = pd.DataFrame({name: pd.Series(dtype=_DTYPE[kind]) for name, kind in branch_part_columns(param).items()})
    return pd.concat(frames, ignore_index=True) if frames else empty, meta


_DTYPE = {"number": float, "flag": bool, "text": object}
_BIFURCATION_COLUMNS = ("kind", *STATE, "jump", "before", "after")


def branches_problem(param: str, span: tuple[float, float], frame: pd.DataFrame, meta: Any) -> str:
    """What is wrong with a part of branches (``""``: nothing): each branch of the metadata with
    at least two points in the table, its points within the span, its section, period, ending
    and bifurcations of their kinds."""
    low, high = span
    slack = _SLACK * (high - low)
    if not isinstance(meta, list):
        return "its metadata holds no branches"
    numbers = frame[[c for c, kind in branch_part_columns(param).items() if kind == "number"]].to_numpy(float)
    if not np.isfinite(numbers).all():
        return "a number of its points is not finite"
    if len(frame) and not ((frame[param] >= low - slack) & (frame[param] <= high + slack)).all():
        return f"a point's {param} lies outside the span [{low:g}, {high:g}]"
    counts = frame["branch"].value_counts()
    if set(counts.index) != set(range(len(meta))) or (counts < 2).any():
        return "its points are not those of the branches its metadata holds, two or more each"
    for info in meta:
        why = _branch_info_problem(param, info)
        if why:
            return why
    return ""


def _branch_info_problem(param: str, info: Any) -> str:
    if not isinstance(info, dict) or set(info) != {
        "section",
        "period",
        "complete",
        "message",
        "reason",
        "bifurcations",
    }:
        return "a branch's metadata is not a branch's"
    section, period = info["section"], info["period"]
    if not (isinstance(section, int | float) and math.isfinite(section)) or not isinstance(period, int) or period < 1:
        return "a branch's section or period is not a number"
    if not isinstance(info["complete"], bool) or not isinstance(info["message"], str):
        return "a branch's ending is not what it was"
    if info["reason"] is not None and info["reason"] not in {reason.value for reason in Reason}:
        return "a branch ended for a reason there is none of"
    rows = info["bifurcations"]
    kinds = {kind.value for kind in Bifurcation}
    if not isinstance(rows, list) or not all(
        isinstance(row, dict) and set(row) == {param, *_BIFURCATION_COLUMNS} and row["kind"] in kinds for row in rows
    ):
        return "a branch's bifurcations are not of the kinds there are"
    return ""


def branches_from_disk(case: Case, param: str, frame: pd.DataFrame, meta: list[dict[str, Any]]) -> list[Branch]:
    """:func:`branches_on_disk` read back, from a part :func:`branches_problem` passed."""
    branches = []
    for k, info in enumerate(meta):
        rows = frame[frame["branch"] == k].drop(columns="branch").reset_index(drop=True)
        bifurcations = pd.DataFrame(info["bifurcations"], columns=[param, *_BIFURCATION_COLUMNS])
        reason = None if info["reason"] is None else Reason(info["reason"])
        points = points_from_disk(rows)
        ending = info["complete"], info["message"], reason
        # the case continue_orbit gave the branch (its tolerances tightened): its measures, the same
        at = orbit_case(case, {param: float(points[param].iloc[0])})
        branches.append(Branch(param, points, bifurcations, float(info["section"]), info["period"], *ending, at))
    return branches


def measures_part(index: int, branch: Branch) -> Expected:
    """What the part of the measures of branch ``index`` must hold: one row per point, at the
    branch's own parameter values and stability, every measure a number."""
    points = branch.points
    columns = dict.fromkeys([branch.param, "piece", *RESPONSE_COLUMNS], "number") | {"stable": "flag"}
    equal = {branch.param: points[branch.param].to_numpy(float), "stable": points["stable"].to_numpy(bool)}
    return Expected({"branch": index, "points": len(points)}, columns, len(points), equal)


def sweep_columns(param: str) -> dict[str, str]:
    """The kinds of a sweep's columns (:func:`~oscillator.attractors.responding.sweep`)."""
    columns = dict.fromkeys([param, "period", *STATE, *RESPONSE_COLUMNS], "number")
    return columns | {"direction": "text", "signature": "text", "jump": "flag"}


def sweep_part(param: str, direction: str, values: np.ndarray) -> Expected:
    """What the part of the sweep ``direction`` over ``values`` must hold: one row per value, in
    order, with its direction, period (0 or more), signature, jump and every measure."""
    columns = sweep_columns(param)
    equal = {param: np.asarray(values, dtype=float), "direction": np.full(len(values), direction, dtype=object)}

    def check(frame: pd.DataFrame, meta: Any) -> str:
        periods = frame["period"].to_numpy(float)
        return "" if ((periods >= 0) & (periods == np.round(periods))).all() else "a period is not a whole number"

    key = {"direction": direction, "values": [float(v) for v in values]}
    return Expected(key, columns, len(values), equal, check)
