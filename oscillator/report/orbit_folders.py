"""A branch or an orbit on disk.

A branch folder is made like a run folder (:mod:`oscillator.report.runs`), in two steps, so that a
computed branch is never lost to a later step:

1. :func:`write_branch` writes ``branch.parquet``, ``bifurcations.parquet``, the sweep's points
   it is drawn over (``sweep_points.parquet``, a copy: nothing outside the folder is read
   again), ``case.toml`` and ``run.json`` (``"kind": "branch"``, the status and what is still
   ``"pending"``) into the claimed folder and renames it into place.
2. :func:`finish_branch` draws the figures and writes the report, each file atomically, and
   takes them off ``"pending"``; ``oscillator report DIR`` runs it again on a folder whose
   figures or report were interrupted.

An orbit's folder (:func:`save_orbit`) holds ``orbit.json`` and its run's tables; every file read
back is checked as untrusted.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from oscillator.errors import InputError, Reason
from oscillator.io.cases import Case, case_to_toml, load_case
from oscillator.io.files import FolderClaim, inner_folder, read_untrusted, replace_file
from oscillator.io.tables import kinds_problem
from oscillator.orbits.branch import BIFURCATION_KINDS, MULTIPLIERS, Branch, points_from_disk, points_on_disk
from oscillator.orbits.shooting import STATE, Orbit
from oscillator.report import markup as mk
from oscillator.report.orbits import branch_status, draw_branch, draw_multipliers, report_blocks
from oscillator.text import printable, shown

__all__ = [
    "BranchFolder",
    "checked_table",
    "finish_branch",
    "orbit_info",
    "orbit_of",
    "orbit_of_folder",
    "read_branch",
    "read_sweep_points",
    "save_branch",
    "save_orbit",
    "write_branch",
]


#: What :func:`finish_branch` makes after the tables are safe.
PENDING = ("figures", "report")


_MAX_RUN_JSON = 1 << 20


def write_branch(
    branch: Branch,
    case: Case,
    claim: FolderClaim,
    *,
    coordinate: str,
    sweep_points: pd.DataFrame | None,
    command: list[str],
) -> Path:
    """Write the tables, ``case.toml`` and ``run.json`` into the claimed folder and put it in place.

    Returns the folder's path.  On any failure the claim is abandoned (nothing is left behind)
    and the error raised.
    """
    from oscillator.report.runs import json_text, run_metadata

    temporary = claim.temporary
    try:
        points_on_disk(branch.points).to_parquet(temporary / "branch.parquet", index=False)
        branch.bifurcations.to_parquet(temporary / "bifurcations.parquet", index=False)
        if sweep_points is not None:
            sweep_points.to_parquet(temporary / "sweep_points.parquet", index=False)
        (temporary / "case.toml").write_text(case_to_toml(case), encoding="utf-8")
        info = {
            "kind": "branch",
            "case": case.name,
            "title": case.full_title,
            "modified": list(case.modified),
            "param": branch.param,
            "period": branch.period,
            "section": branch.section,
            "coordinate": coordinate,
            "complete": branch.complete,
            "status": branch_status(branch),
            "failure": branch.message or None,
            "reason": None if branch.reason is None else branch.reason.value,
            "pending": list(PENDING),
            **run_metadata(command),
        }
        (temporary / "run.json").write_text(json_text(info), encoding="utf-8")
        return claim.commit()
    except BaseException:
        claim.abandon()
        raise


@dataclass(frozen=True)
class BranchFolder:
    """A branch folder read back: the branch, the case, ``run.json`` and the sweep's points."""

    path: Path
    branch: Branch
    case: Case
    run: dict[str, Any]
    sweep_points: pd.DataFrame | None


#: How a damaged branch folder is made again.
_REMAKE = "continue the case again to remake the folder"
#: How a damaged sweep folder is made again.
_RESWEEP = "run the sweep again into a new folder"


def _damaged(path: Path, what: str, remake: str = _REMAKE) -> InputError:
    return InputError(f"{printable(str(path))} is damaged: {what}; {remake}", field=path.name)


def checked_table(
    path: Path, columns: dict[str, str], *, folder: str = "branch folder", remake: str = _REMAKE
) -> pd.DataFrame:
    """A Parquet table of a ``folder`` (its kind, for the messages) with these columns, of these
    kinds (``"number"``, ``"text"``, ``"flag"``); refused naming the file, what is wrong and
    ``remake`` (how to make it again)."""
    if not path.is_file():
        raise InputError(
            f"{printable(str(path.parent))} is not a complete {folder}: {path.name} is missing", field=path.name
        )
    try:
        frame = pd.read_parquet(path)
    except Exception as exc:  # pyarrow raises many types for a damaged file
        if isinstance(exc, MemoryError):
            raise
        raise _damaged(path, f"it cannot be read as a table ({type(exc).__name__})", remake) from exc
    problem = kinds_problem(frame, columns)
    if problem is not None:
        raise _damaged(path, problem, remake)
    return frame


def read_sweep_points(folder: Path, param: str, coordinate: str) -> pd.DataFrame:
    """A sweep folder's Poincaré points: ``param`` and ``coordinate``, both numbers, checked.

    Raises
    ------
    InputError
        Not a sweep folder, ``poincare.parquet`` missing or damaged, or not a sweep of ``param``.
    """
    folder = Path(folder)
    path = folder / "poincare.parquet"
    if not folder.is_dir():
        raise InputError(
            f"{printable(str(folder))} is not a folder; give a folder written by 'oscillator sweep'", field="over"
        )
    if not path.is_file():
        raise InputError(
            f"{printable(str(folder))} holds no finished sweep (no poincare.parquet); give a folder "
            "written by 'oscillator sweep'",
            field="over",
        )
    frame = checked_table(path, {}, folder="sweep folder", remake=_RESWEEP)
    if param not in frame.columns:
        raise InputError(f"the sweep in {printable(str(folder))} is not a sweep of {shown(param)}", field="over")
    frame = checked_table(path, {param: "number", coordinate: "number"}, folder="sweep folder", remake=_RESWEEP)
    return frame[[param, coordinate]].reset_index(drop=True)


def _run_info(folder: Path) -> dict[str, Any]:
    path = folder / "run.json"
    info = _json(path)
    if info.get("kind") != "branch":
        raise _damaged(path, "it does not describe a branch")
    checks = {"param": str, "coordinate": str, "period": int, "complete": bool, "pending": list}
    for key, kind in checks.items():
        if not isinstance(info.get(key), kind) or (kind is int and isinstance(info.get(key), bool)):
            raise _damaged(path, f"{key} is not {kind.__name__}")
    if info["coordinate"] not in STATE:
        raise _damaged(path, f"coordinate must be one of {', '.join(STATE)}")
    if not set(info["pending"]) <= set(PENDING):
        raise _damaged(path, f"pending must be a list of {', '.join(PENDING)}")
    section = info.get("section")
    if isinstance(section, bool) or not isinstance(section, (int, float)) or not math.isfinite(section):
        raise _damaged(path, "section is not a finite number")
    for key in ("failure", "case", "title"):
        if info.get(key) is not None and not isinstance(info[key], str):
            raise _damaged(path, f"{key} is not text")
    if info.get("reason") is not None and info["reason"] not in tuple(Reason):
        raise _damaged(path, f"reason must be null or one of {', '.join(Reason)}")
    modified = info.get("modified", [])
    if not isinstance(modified, list) or not all(isinstance(change, str) for change in modified):
        raise _damaged(path, "modified must be a list of texts")
    return info


def _json(path: Path) -> dict[str, Any]:
    import json

    text = read_untrusted(path, what="run file", field="run.json", limit=_MAX_RUN_JSON)
    try:
        info = json.loads(text)
    except (ValueError, RecursionError) as exc:
        raise _damaged(path, "it is not JSON") from exc
    if not isinstance(info, dict):
        raise _damaged(path, "it is not a JSON object")
    return info


def read_branch(folder: Path) -> BranchFolder:
    """Read a branch folder back (for ``oscillator report``), checking every file it reads."""
    folder = Path(folder)
    info = _run_info(folder)
    param = info["param"]
    moduli = {f"{name}_{part}": "number" for name in MULTIPLIERS for part in ("re", "im")}
    numbers = {param: "number", **dict.fromkeys(STATE, "number")}
    points = checked_table(
        folder / "branch.parquet", {**numbers, **moduli, "stable": "flag", "signature": "text", "piece": "number"}
    )
    rows = checked_table(
        folder / "bifurcations.parquet",
        {**numbers, "kind": "text", "jump": "number", "before": "text", "after": "text"},
    )
    if points.empty:
        raise _damaged(folder / "branch.parquet", "it has no points")
    if not rows["kind"].isin(BIFURCATION_KINDS).all():
        raise _damaged(folder / "bifurcations.parquet", f"kind must be one of {', '.join(BIFURCATION_KINDS)}")
    points = points_from_disk(points)
    sweep = None
    if (folder / "sweep_points.parquet").exists():
        sweep = checked_table(folder / "sweep_points.parquet", {param: "number", info["coordinate"]: "number"})
    case = load_case(folder / "case.toml")
    case = dataclasses.replace(case, name=info.get("case") or folder.name, modified=tuple(info.get("modified", ())))
    reason = None if info.get("reason") is None else Reason(info["reason"])
    if reason is None and info.get("status") == "interrupted":  # written before reasons were
        reason = Reason.INTERRUPTED
    branch = Branch(
        param,
        points,
        rows,
        float(info["section"]),
        info["period"],
        info["complete"],
        info.get("failure") or "",
        reason,
        case,
    )
    return BranchFolder(folder, branch, case, info, sweep)


def finish_branch(folder: Path) -> BranchFolder:
    """Draw the branch's figures and write its report, each atomically; ``run.json``'s
    ``"pending"`` says what is still to be made, so an interrupted finish is finished by calling
    this again.  A figure file that is missing or empty is drawn again."""
    from oscillator.report.runs import json_text

    found = read_branch(folder)
    info, figures = found.run, folder / "figures"
    names = ("branch", "multipliers")
    if "figures" in info["pending"] or any(not _drawn(figures / f"{name}.png") for name in names):
        inner_folder(figures)
        draw_branch(found.branch, figures / "branch.png", info["coordinate"], found.sweep_points)
        draw_multipliers(found.branch, figures / "multipliers.png")
        info["pending"] = [item for item in info["pending"] if item != "figures"]
        replace_file(folder / "run.json", json_text(info))
    blocks = report_blocks(found.branch, found.case)
    replace_file(folder / "report.md", mk.to_markdown(blocks))
    replace_file(folder / "report.html", mk.to_html(blocks, folder=folder, title=f"{found.case.name}: branch"))
    info["pending"] = []
    replace_file(folder / "run.json", json_text(info))
    return found


def save_branch(branch: Branch, folder: Path | str, *, coordinate: str) -> Path:
    """Write ``branch`` as a branch folder into ``folder`` (new), then its figures and report; if
    those fail, the tables stay, a warning says so, and the folder is returned all the same."""
    from oscillator.report.runs import claim_output, finish_or_warn

    if branch.case is None:
        raise InputError("this branch carries no case to save with it; build it with continue_orbit", field="case")
    claim = claim_output(Path(folder), f"{branch.case.name}-continue")
    path = write_branch(
        branch,
        branch.case,
        claim,
        coordinate=coordinate,
        sweep_points=None,
        command=["python", "oscillator.Branch.save"],
    )
    finish_or_warn(lambda: finish_branch(path), path)
    return path


def orbit_info(orbit: Orbit) -> dict[str, Any]:
    """What ``run.json`` holds of an orbit under ``"orbit"`` (complex numbers as ``[re, im]``)."""
    return {
        "section": orbit.section,
        "period": orbit.period,
        "state": [float(v) for v in orbit.state],
        "monodromy": np.asarray(orbit.monodromy, float).tolist(),
        "multipliers": [[float(mu.real), float(mu.imag)] for mu in orbit.multipliers],
        "stable": bool(orbit.stable),
        "verdict": orbit.verdict,
        "residual": orbit.residual,
        "iterations": orbit.iterations,
        "history": list(orbit.history),
        "resting": list(orbit.resting),
        "discontinuous": list(orbit.discontinuous),
        "note": orbit.note,
    }


def save_orbit(orbit: Orbit, folder: Path | str) -> Path:
    """Write ``orbit`` as the run folder of one return (:meth:`Orbit.one_period`), ``run.json``
    holding ``"kind": "orbit"`` and :func:`orbit_info`; then its figures and report."""
    from oscillator.hybrid.simulate import simulate
    from oscillator.io.files import check_new
    from oscillator.report.runs import claim_output, finish_or_warn, finish_run, write_run

    folder = Path(folder)
    check_new(folder)  # before the simulation: a taken name is refused at once
    result = simulate(orbit.one_period())
    claim = claim_output(folder, f"{orbit.case.name}-orbit")
    path = write_run(
        result, claim, command=["python", "oscillator.Orbit.save"], extra={"kind": "orbit", "orbit": orbit_info(orbit)}
    )
    finish_or_warn(lambda: finish_run(path), path)
    return path


def orbit_of_folder(path: Path, case: Case, events: pd.DataFrame, info: dict[str, Any]) -> Orbit:
    """The :class:`Orbit` a folder of :func:`save_orbit` holds (``info``: its ``run.json``),
    every field checked."""
    where = path / "run.json"
    return orbit_of(info.get("orbit"), case, events, lambda what: _damaged(where, what))


def orbit_of(data: object, case: Case, events: pd.DataFrame, damaged: Callable[[str], InputError]) -> Orbit:
    """The :class:`Orbit` that :func:`orbit_info` wrote as ``data`` (untrusted: every field
    checked, a bad one refused by ``damaged(what)``), with its one period's ``events``."""
    if not isinstance(data, dict):
        raise damaged("orbit is not a JSON object")

    def numbers(key: str, shape: tuple[int, ...]) -> np.ndarray:
        try:
            values = np.array(data.get(key), dtype=float)
        except (TypeError, ValueError):
            raise damaged(f"orbit.{key} is not numbers") from None
        if values.shape != shape or not np.all(np.isfinite(values)):
            raise damaged(f"orbit.{key} must be {' x '.join(map(str, shape))} finite numbers")
        return values

    period = data.get("period")
    if isinstance(period, bool) or not isinstance(period, int) or period < 1:
        raise damaged("orbit.period is not a whole number >= 1")
    resting, discontinuous, history = data.get("resting", []), data.get("discontinuous", []), data.get("history", [])
    if not (isinstance(resting, list) and all(m in (1, 2) and not isinstance(m, bool) for m in resting)):
        raise damaged("orbit.resting must be a list of masses, 1 or 2")
    if not (isinstance(discontinuous, list) and all(v in ("v1", "v2") for v in discontinuous)):
        raise damaged("orbit.discontinuous must be a list of v1, v2")
    if not isinstance(data.get("note", ""), str) or not isinstance(data.get("stable"), bool):
        raise damaged("orbit.note must be text and orbit.stable true or false")
    if not isinstance(history, list):
        raise damaged("orbit.history must be a list of numbers")
    pairs = numbers("multipliers", (4, 2))
    return Orbit(
        case=case,
        section=float(numbers("section", ())),
        state=numbers("state", (4,)),
        period=period,
        monodromy=numbers("monodromy", (4, 4)),
        multipliers=pairs[:, 0] + 1j * pairs[:, 1],
        stable=data["stable"],
        residual=float(numbers("residual", ())),
        iterations=int(numbers("iterations", ())),
        event_records=events,
        history=tuple(float(v) for v in numbers("history", (len(history),))),
        resting=tuple(resting),
        discontinuous=tuple(discontinuous),
        note=data.get("note", ""),
    )


def _drawn(path: Path) -> bool:
    try:
        return path.is_file() and path.stat().st_size > 0
    except OSError:
        return False
