"""Run folders: everything a run produced, written atomically, and read back.

A run folder holds ``events.csv`` and/or ``events.parquet`` (the columns of ``Result.events``),
``trajectory.parquet``, ``case.toml`` (the fully resolved case, to repeat the run exactly),
``run.json`` (versions, solver settings, wall time, counts, energy audit), ``figures/`` and
``report.md`` / ``report.html``.  It is written into a hidden temporary folder next to the
target and renamed into place at the end, so an interrupted or failed run leaves no
half-written folder.  A run that the solver or a guard stopped, or that was interrupted, is
written the same way from its partial result, with ``"status": "failed"`` or ``"interrupted"``
and the reason (``"failure"``) in ``run.json``.
"""

from __future__ import annotations

import dataclasses
import datetime as dt
import json
import platform
import sys
import tempfile
from collections.abc import Callable
from importlib import metadata
from pathlib import Path

import pandas as pd

from oscillator._errors import OscillatorError
from oscillator._files import atomic_folder
from oscillator.cases import Case, case_to_toml, load_case
from oscillator.events import Event
from oscillator.result import Result

__all__ = [
    "FORMATS",
    "RunFolder",
    "check_output_folder",
    "default_output_folder",
    "read_events_csv",
    "read_run",
    "write_run",
]

FORMATS = ("csv", "parquet", "both")
_PACKAGES = ("oscillator", "scikit-sundae", "numpy", "pandas", "pyarrow", "matplotlib", "typer")


@dataclasses.dataclass(frozen=True)
class RunFolder:
    """A run folder read back: the case, the tables and ``run.json``."""

    path: Path
    case: Case
    events: pd.DataFrame
    trajectory: pd.DataFrame
    run: dict


def default_output_folder(case_name: str, root: Path = Path("runs")) -> Path:
    """``runs/<case>-<YYYYmmdd-HHMMSS>``, with a counter if that exists already."""
    stamp = dt.datetime.now().strftime("%Y%m%d-%H%M%S")
    folder = root / f"{case_name}-{stamp}"
    n = 1
    while folder.exists():
        n += 1
        folder = root / f"{case_name}-{stamp}-{n}"
    return folder


def check_output_folder(folder: Path) -> None:
    """Refuse, before any work, a folder that exists or whose parent cannot be written."""
    if folder.exists():
        raise OscillatorError(
            f"--out {folder} exists already; give a new folder (runs are never overwritten)", field="--out"
        )
    parent = folder.parent if str(folder.parent) else Path(".")
    try:
        parent.mkdir(parents=True, exist_ok=True)
        probe = tempfile.NamedTemporaryFile(dir=parent, prefix=".oscillator-probe-")
        probe.close()
    except OSError as exc:
        raise OscillatorError(
            f"--out {folder}: cannot write in {parent} ({exc.strerror}); choose a writable folder",
            field="--out",
        ) from exc


def _versions() -> dict:
    versions = {"python": platform.python_version()}
    for name in _PACKAGES:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = None
    return versions


def run_info(result: Result, *, command: list[str] | None = None) -> dict:
    """What ``run.json`` holds."""
    case = result.case
    return {
        "case": case.name,
        "source": str(case.source) if case.source else None,
        "title": case.title,
        "complete": result.complete,
        "status": result.status,
        "failure": result.failure,
        "created": dt.datetime.now(dt.UTC).isoformat(timespec="seconds"),
        "command": command if command is not None else sys.argv,
        "versions": _versions(),
        "platform": platform.platform(),
        "solver": {
            "integrator": "CVODE (SUNDIALS, through scikit-sundae), Adams, root finding",
            **dataclasses.asdict(case.options),
            "max_step": case.options.max_step_fraction * case.parameters.period,
        },
        "t0": case.initial.t0,
        "t_end": case.t_end,
        "t_final": result.final_state[0],
        "final_state": dict(zip(("t", "x1", "v1", "x2", "v2"), result.final_state, strict=True)),
        "wall_time": result.stats["wall_time"],
        "counts": {k: v for k, v in result.stats.items() if k != "wall_time"},
        "energy": result.energy,
    }


def write_run(
    result: Result,
    folder: Path,
    *,
    formats: str = "both",
    extras: Callable[[Path, dict], None] | None = None,
    command: list[str] | None = None,
) -> Path:
    """Write a run folder atomically; ``extras(tmp, info)`` adds figures and reports inside.

    Raises
    ------
    OscillatorError
        When the folder exists or cannot be written; nothing is left behind.
    """
    if formats not in FORMATS:
        raise OscillatorError(f"--format must be one of {', '.join(FORMATS)}, got {formats!r}", field="--format")
    check_output_folder(folder)
    with atomic_folder(folder) as temporary:
        if formats in ("csv", "both"):
            result.events.to_csv(temporary / "events.csv", index=False)
        if formats in ("parquet", "both"):
            result.events.to_parquet(temporary / "events.parquet", index=False)
        result.trajectory.to_parquet(temporary / "trajectory.parquet", index=False)
        (temporary / "case.toml").write_text(case_to_toml(result.case), encoding="utf-8")
        info = run_info(result, command=command)
        if extras is not None:
            extras(temporary, info)
        (temporary / "run.json").write_text(json.dumps(info, indent=2, default=str) + "\n", encoding="utf-8")
    return folder


def read_run(folder: Path) -> RunFolder:
    """Read a run folder back (for ``oscillator report``)."""
    folder = Path(folder)
    if not (folder / "run.json").is_file():
        raise OscillatorError(
            f"{folder} is not a run folder (no run.json); give a folder written by 'oscillator run'", field="DIR"
        )
    run = json.loads((folder / "run.json").read_text(encoding="utf-8"))
    case = dataclasses.replace(load_case(folder / "case.toml"), name=run.get("case", folder.name))
    if (folder / "events.parquet").is_file():
        events = pd.read_parquet(folder / "events.parquet")
    else:
        events = read_events_csv(folder / "events.csv")
    trajectory = pd.read_parquet(folder / "trajectory.parquet")
    return RunFolder(folder, case, events, trajectory, run)


def read_events_csv(path: Path) -> pd.DataFrame:
    """``events.csv`` back as ``Result.events``: text columns as text, empty text as ``""``."""
    text = Event.text_columns()
    events = pd.read_csv(path, dtype=dict.fromkeys(text, str))
    return events.fillna(dict.fromkeys(text, ""))
