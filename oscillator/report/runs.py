"""Run folders: everything a run produced, written atomically, read back and finished.

A run folder holds ``events.csv`` and/or ``events.parquet`` (the columns of ``Result.events``),
``trajectory.parquet``, ``case.toml`` (the fully resolved case, to repeat the run exactly),
``run.json`` (versions, solver settings, wall time, counts, energy audit), ``figures/`` and
``report.md`` / ``report.html``.

It is made in two steps, so that a finished computation is never lost to a later step:

1. :func:`write_run` writes the tables, ``case.toml`` and ``run.json`` into the folder claimed
   before the run (:func:`claim_output`) and renames it into place.  ``run.json`` lists what is
   still to be made under ``"pending"`` (``figures``, ``report``).
2. :func:`finish_run` draws the figures and writes the report, each file atomically, and takes
   them off ``"pending"``.  ``oscillator report DIR`` runs this step again: it finishes a folder
   whose figures or report were interrupted, and redraws missing figures.

A run that the solver or a guard stopped, or that was interrupted, is written the same way from
its partial result, with ``"status": "failed"`` or ``"interrupted"`` and the reason
(``"failure"``) in ``run.json``.  Everything read back is checked (:func:`read_run_folder`): a damaged
file is named in the error, never a traceback.
"""

from __future__ import annotations

import dataclasses
import datetime as dt
import json
import math
import os
import platform
import stat
import sys
from collections.abc import Callable
from importlib import metadata
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pandas as pd

from oscillator.engines import describe
from oscillator.errors import InputError, Reason
from oscillator.io.cases import Case, case_to_toml, load_case
from oscillator.io.files import FolderClaim, FolderTaken, claim_folder, default_name, read_untrusted, replace_file
from oscillator.io.tables import check_events, check_trajectory
from oscillator.model.events import Event
from oscillator.model.parameters import is_finite_number, is_number
from oscillator.text import printable

if TYPE_CHECKING:  # pragma: no cover
    from oscillator.hybrid.result import Result

__all__ = [
    "FORMATS",
    "PENDING",
    "RunFolder",
    "claim_output",
    "finish_or_warn",
    "finish_run",
    "folder_kind",
    "is_chain_folder",
    "read_events_csv",
    "read_run_folder",
    "result_of",
    "run_metadata",
    "save_result",
    "write_run",
]

FORMATS = ("csv", "parquet", "both")
#: What :func:`finish_run` makes after the tables are safe, in order.
PENDING = ("figures", "report")
_PACKAGES = ("oscillator", "scikit-sundae", "numpy", "pandas", "pyarrow", "matplotlib", "typer")
_STATUSES = ("complete", "failed", "interrupted")
#: The largest ``run.json`` read back (bytes); ours are about 2 kB.
_MAX_RUN_JSON = 1 << 20


@dataclasses.dataclass(frozen=True)
class RunFolder:
    """A run folder read back: the case, the tables and ``run.json``."""

    path: Path
    case: Case
    events: pd.DataFrame
    trajectory: pd.DataFrame
    run: dict[str, Any]


def claim_output(folder: Path | None, case_name: str, *, root: Path = Path("runs")) -> FolderClaim:
    """Claim the output folder before a run: ``folder``, or ``runs/<case>-<YYYYmmdd-HHMMSS>`` (the
    case's name made safe as a folder name: :func:`~oscillator.io.files.default_name`).

    A default name taken by another run (a folder, or one being written now) gets the first free
    suffix ``-2``, ``-3``, ...; an explicit ``folder`` that is taken is refused
    (:func:`oscillator.io.files.claim_folder`).
    """
    if folder is not None:
        return claim_folder(folder)
    stamp = dt.datetime.now().strftime("%Y%m%d-%H%M%S")
    name = default_name(case_name)
    for n in range(1, 10_000):
        try:
            return claim_folder(root / (f"{name}-{stamp}" if n == 1 else f"{name}-{stamp}-{n}"))
        except FolderTaken:
            continue
    raise InputError(f"no free folder name under {root} for {case_name}; give a folder", field="folder")


def _versions() -> dict[str, Any]:
    versions: dict[str, str | None] = {"python": platform.python_version()}
    for name in _PACKAGES:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = None
    return versions


def run_metadata(command: list[str] | None = None) -> dict[str, Any]:
    """When, how and with what a folder was made: ``created``, ``command``, ``versions``, ``platform``."""
    return {
        "created": dt.datetime.now(dt.UTC).isoformat(timespec="seconds"),
        "command": command if command is not None else sys.argv,
        "versions": _versions(),
        "platform": platform.platform(),
    }


def run_info(result: Result, *, command: list[str] | None = None, pending: tuple[str, ...] = PENDING) -> dict[str, Any]:
    """What ``run.json`` holds."""
    case = result.case
    info: dict[str, Any] = {
        "case": case.name,
        "source": str(case.source) if case.source else None,
        "title": case.full_title,
        "modified": list(case.modified),
        "complete": result.success,
        "status": str(result.status),
        "failure": result.message or None,
        "reason": None if result.reason is None else result.reason.value,
        "pending": list(pending),
        **run_metadata(command),
        "solver": {
            "integrator": describe(result.stats.engine).method,
            "engine": result.stats.engine,
            **dataclasses.asdict(case.options),
            "max_step": case.options.max_step_fraction * case.parameters.period,
        },
        "t0": case.initial.t0,
        "t_end": case.t_end,
        "t_final": result.final_state[0],
        "final_state": dict(zip(("t", *case.system.state), result.final_state, strict=True)),
        "wall_time": result.stats.wall_time,
        "counts": {k: v for k, v in result.stats.as_dict().items() if k not in ("wall_time", "engine")},
        "energy": result.energy.as_dict(),
    }
    if case.expected:
        from oscillator.analysis.reproduction import compare

        table = compare(case, result.events)
        ok = int((table.within_article & table.within_reference).sum())
        info["check"] = {"expected": len(table), "within_tolerance": ok}
    return info


def _plain(value: Any) -> Any:
    """``value`` as strict JSON: non-finite floats become ``null``, NumPy scalars Python ones."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if hasattr(value, "item") and not isinstance(value, (str, bytes)):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def json_text(info: dict[str, Any]) -> str:
    """Strict JSON (no ``NaN`` or ``Infinity``, which JSON does not have)."""
    return json.dumps(_plain(info), indent=2, default=str, allow_nan=False) + "\n"


def write_tables(events: pd.DataFrame, trajectory: pd.DataFrame, folder: Path, formats: str) -> None:
    """A run's event table (as CSV, Parquet or both: ``formats``) and its trajectory (Parquet)."""
    if formats in ("csv", "both"):
        events.to_csv(folder / "events.csv", index=False)
    if formats in ("parquet", "both"):
        events.to_parquet(folder / "events.parquet", index=False)
    trajectory.to_parquet(folder / "trajectory.parquet", index=False)


def write_run(
    result: Result,
    claim: FolderClaim,
    *,
    formats: str = "both",
    command: list[str] | None = None,
    pending: tuple[str, ...] = PENDING,
    extra: dict[str, Any] | None = None,
) -> Path:
    """Write the tables, ``case.toml`` and ``run.json`` into the claimed folder and put it in place.

    ``extra`` is added to ``run.json`` (an orbit's ``"kind"`` and ``"orbit"``).  Returns the
    folder's path (see :meth:`FolderClaim.commit`).  On any failure the claim is abandoned:
    nothing is left behind.
    """
    if formats not in FORMATS:
        raise InputError(f"formats must be one of {', '.join(FORMATS)}, got {formats!r}", field="formats")
    temporary = claim.temporary
    try:
        write_tables(result.events, result.trajectory, temporary, formats)
        (temporary / "case.toml").write_text(case_to_toml(result.case), encoding="utf-8")
        info = {**run_info(result, command=command, pending=pending), **(extra or {})}
        (temporary / "run.json").write_text(json_text(info), encoding="utf-8")
        return claim.commit()
    except BaseException:
        claim.abandon()
        raise


# --------------------------------------------------------------------------- reading back


def _damaged(path: Path, what: str) -> InputError:
    return InputError(
        f"{printable(str(path))} is damaged: {what}; run the case again to remake the folder", field=path.name
    )


def _regular(path: Path) -> bool:
    try:
        return stat.S_ISREG(os.stat(path).st_mode)
    except OSError:
        return False


def _require(folder: Path, name: str) -> Path:
    path = folder / name
    if not _regular(path):
        what = "is not a regular file" if os.path.lexists(path) else "is missing"
        raise InputError(
            f"{printable(str(folder))} is not a complete run folder: {name} {what}; give a folder written by "
            f"'oscillator run' (or run the case again)",
            field=name,
        )
    return path


# --------------------------------------------------------------------------- run.json, checked by one table
#
# Each field run_info writes that a reader relies on, with what it must be.  A check returns what
# is wrong (or "" when the value is right); a field that is absent is not checked here (readers
# give it a default).  tests/test_hostile.py damages each field in turn.


def _text(value: Any) -> str:
    return "" if value is None or isinstance(value, str) else "is not text"


def _finite(value: Any) -> str:
    return "" if is_finite_number(value) else "is not a finite number"


def _object(value: Any) -> str:
    return "" if value is None or isinstance(value, dict) else "is not a JSON object"


def _one_of(choices: tuple[str, ...], *, null: bool = False) -> Callable[[Any], str]:
    def check(value: Any) -> str:
        if (null and value is None) or (isinstance(value, str) and value in choices):
            return ""
        return f"must be {'null or ' if null else ''}one of {', '.join(choices)}"

    return check


def _values(check: Callable[[Any], bool], what: str) -> Callable[[Any], str]:
    """A JSON object whose every value passes ``check``."""

    def checked(value: Any) -> str:
        if value is None:
            return ""
        if not isinstance(value, dict):
            return "is not a JSON object"
        wrong = next((key for key, item in value.items() if not check(item)), None)
        return "" if wrong is None else f".{wrong} is not {what}"

    return checked


def _items(check: Callable[[Any], bool], what: str) -> Callable[[Any], str]:
    """A JSON list whose every item passes ``check``."""
    return lambda value: "" if isinstance(value, list) and all(check(item) for item in value) else f"must be {what}"


def _figures(value: Any) -> str:
    if not isinstance(value, (dict, type(None))):
        return "is not a JSON object"
    return "" if isinstance((value or {}).get("label", ""), str) else ".label is not text"


#: What each field of ``run.json`` must be (:func:`run_info` writes them).
RUN_JSON: dict[str, Callable[[Any], str]] = {
    "status": _one_of(_STATUSES),
    "reason": _one_of(tuple(Reason), null=True),
    **dict.fromkeys(("t_final", "wall_time", "t0", "t_end"), _finite),
    **dict.fromkeys(("versions", "solver", "check"), _object),
    "figures": _figures,
    "energy": _values(lambda v: v is None or is_number(v), "a number"),
    "counts": _values(lambda v: isinstance(v, int) and not isinstance(v, bool), "a whole number"),
    "pending": _items(lambda v: v in PENDING, f"a list of {', '.join(PENDING)}"),
    **dict.fromkeys(("failure", "case", "title"), _text),
    "modified": _items(lambda v: isinstance(v, str), "a list of texts"),
}


def _check_run_info(data: Any, path: Path) -> dict[str, Any]:
    """``run.json``'s content, with the fields the report reads checked (:data:`RUN_JSON`)."""
    if not isinstance(data, dict):
        raise _damaged(path, "it is not a JSON object")
    for key, check in RUN_JSON.items():
        wrong = check(data[key]) if key in data else ""
        if wrong:  # "is not ...", "must be ..." or ".field is not ..."
            raise _damaged(path, f"{key}{wrong}" if wrong.startswith(".") else f"{key} {wrong}")
    return data


def _read_table(path: Path, reader: Callable[[Path], pd.DataFrame]) -> pd.DataFrame:
    try:
        return reader(path)
    except Exception as exc:  # pyarrow and pandas raise many types for a damaged file
        if isinstance(exc, MemoryError):
            raise
        raise _damaged(path, f"it cannot be read as a table ({type(exc).__name__})") from exc


def read_run_folder(folder: Path) -> RunFolder:
    """Read a run folder back (for ``oscillator report``), checking every file it reads.

    Raises
    ------
    OscillatorError
        Not a run folder, a file missing, or a file damaged (named in the message).
    """
    folder = Path(folder)
    if not folder.is_dir() or not (folder / "run.json").exists():
        raise InputError(
            f"{printable(str(folder))} is not a run folder (no run.json); give a folder written by 'oscillator run'",
            field="folder",
        )
    info_path = _require(folder, "run.json")
    text = read_untrusted(info_path, what="run file", field="run.json", limit=_MAX_RUN_JSON)
    try:
        data = json.loads(text)
    except (ValueError, RecursionError) as exc:
        raise _damaged(info_path, "it is not JSON") from exc
    info = _check_run_info(data, info_path)
    case = dataclasses.replace(
        load_case(_require(folder, "case.toml")),
        name=info.get("case") or folder.name,
        modified=tuple(info.get("modified", ())),
    )
    if _regular(folder / "events.parquet"):
        events = _read_table(folder / "events.parquet", pd.read_parquet)
        source = folder / "events.parquet"
    else:
        source = _require(folder, "events.csv")
        events = _read_table(source, read_events_csv)
    events = check_events(events, printable(str(source)))
    trajectory_path = _require(folder, "trajectory.parquet")
    trajectory = check_trajectory(_read_table(trajectory_path, pd.read_parquet), printable(str(trajectory_path)))
    return RunFolder(folder, case, events, trajectory, info)


def result_of(run: RunFolder) -> Result:
    """The :class:`~oscillator.hybrid.result.Result` a run folder holds: its case and tables,
    its status and failure, the energy audit and the solver's counts from ``run.json`` (a value
    the file lacks reads as NaN, a count as 0)."""
    from oscillator.hybrid.result import EnergyAudit, Result, SolverStats, Status, records_of

    info = run.run

    def number(value: Any) -> float:
        return float(value) if is_number(value) else math.nan

    energy = info.get("energy") or {}
    audit = EnergyAudit(**{name.name: number(energy.get(name.name)) for name in dataclasses.fields(EnergyAudit)})
    counts = info.get("counts") or {}
    stats = SolverStats(
        engine=str((info.get("solver") or {}).get("engine", "unknown")),
        wall_time=number(info.get("wall_time")),
        **{f.name: int(counts.get(f.name, 0)) for f in dataclasses.fields(SolverStats) if f.type in ("int", int)},
    )
    given = info.get("final_state")
    final: dict[str, Any] = given if isinstance(given, dict) else {}
    if not final and len(run.trajectory):
        final = run.trajectory.iloc[-1].to_dict()
    state = tuple(number(final.get(name)) for name in ("t", *run.case.system.state))
    return Result(
        run.case,
        audit,
        stats,
        state,
        Status(info.get("status", "complete")),
        info.get("failure") or "",
        None if info.get("reason") is None else Reason(info["reason"]),
        _records=records_of(run.events, run.trajectory),
    )


def save_result(
    result: Result, folder: Path | str, *, formats: str = "both", figures: bool = True, report: bool = True
) -> Path:
    """Write ``result`` as a run folder (as ``oscillator run`` does) into ``folder``, a new one.

    The tables, ``case.toml`` and ``run.json`` are written first; then the figures and the
    report.  If those fail, the folder keeps the tables (``run.json`` lists them as
    ``"pending"``; ``oscillator report`` makes them), a warning says so, and the folder is
    returned all the same.
    """
    if formats not in FORMATS:
        raise InputError(f"formats must be one of {', '.join(FORMATS)}, got {formats!r}", field="formats")
    folder = Path(folder)
    pending = tuple(step for step, wanted in (("figures", figures), ("report", report)) if wanted)
    path = write_run(
        result,
        claim_output(folder, result.case.name),
        formats=formats,
        command=["python", "oscillator.Result.save"],
        pending=pending,
    )
    if pending:
        finish_or_warn(lambda: finish_run(path, figures=figures, report=report), path)
    return path


def finish_or_warn(finish: Callable[[], object], folder: Path) -> None:
    """Make a saved folder's figures and report (``finish``); if that fails, warn and go on:
    the tables are written, and ``oscillator report`` makes the rest later."""
    import warnings

    try:
        finish()
    except Exception as error:  # a later step failed: what was computed is safe
        warnings.warn(
            f"the figures or report of {folder} could not be made ({type(error).__name__}: {error}); "
            f"the tables are written; `oscillator report {folder}` makes them",
            stacklevel=4,
        )


def read_events_csv(path: Path) -> pd.DataFrame:
    """``events.csv`` back as ``Result.events``: text columns as text, empty text as ``""``."""
    text = Event.text_columns()
    events = pd.read_csv(path, dtype=dict.fromkeys(text, str))
    return events.fillna(dict.fromkeys(text, ""))


# --------------------------------------------------------------------------- finishing


def _update(folder: Path, info: dict[str, Any], *, done: str | None = None, **changes: Any) -> None:
    """Rewrite ``run.json`` with ``changes``, and with ``done`` taken off ``"pending"``."""
    info.update(changes)
    if done is not None:
        info["pending"] = [item for item in info.get("pending", []) if item != done]
    replace_file(folder / "run.json", json_text(info))


def is_chain_folder(folder: Path) -> bool:
    """Whether ``folder`` is a friction chain's run folder (its ``system.toml`` and ``run.json``)."""
    return (folder / "system.toml").is_file() and (folder / "run.json").is_file()


def folder_kind(folder: Path) -> str:
    """``"branch"`` for a folder that ``oscillator continue`` wrote (its ``run.json`` says
    ``"kind": "branch"``), else ``"run"`` (also when ``run.json`` cannot be read: the run
    folder's reader then names what is wrong)."""
    try:
        text = read_untrusted(Path(folder) / "run.json", what="run file", field="run.json", limit=_MAX_RUN_JSON)
        data = json.loads(text)
    except (OSError, ValueError, RecursionError):  # InputError is a ValueError
        return "run"
    return "branch" if isinstance(data, dict) and data.get("kind") == "branch" else "run"


def finish_run(
    folder: Path,
    *,
    figures: bool = True,
    report: bool = True,
    window: tuple[float, float] | None = None,
    run: RunFolder | None = None,
) -> RunFolder:
    """Draw the run's missing figures (``figures``) and write its report (``report``).

    The figures show the whole run, or the last forcing periods of a long one; ``window``
    redraws them all for that time window (``run.json``'s ``"figures"`` records which).  Each
    file is written atomically, and ``run.json``'s ``"pending"`` says what is still to be made,
    so an interrupted finish is finished by calling this again.  ``run`` is the folder as
    :func:`read_run_folder` read it, if the caller has it already.
    """
    run = read_run_folder(folder) if run is None else run  # checked before the drawing libraries are loaded
    from oscillator.analysis.reproduction import compare
    from oscillator.report.figures import figure_title, figure_window, missing_figures, write_figures
    from oscillator.report.transitions import available_figures, report_document, write_report

    case, info = run.case, run.run
    t_final = info.get("t_final", case.t_end)
    chosen = figure_window(case.initial.t0, t_final, case.parameters.period, window)
    if (window is not None or (figures and missing_figures(folder / "figures"))) and not run.trajectory.empty:
        start = (case.initial.t0, *case.initial.y)
        write_figures(
            run.trajectory,
            run.events,
            case.parameters,
            start,
            folder / "figures",
            title=figure_title(case),
            window=chosen,
        )
        _update(folder, info, figures={"window": [chosen.start, chosen.stop], "label": chosen.label})
    if figures and "figures" in info.get("pending", []):
        _update(folder, info, done="figures")
    if report:
        comparison = compare(case, run.events) if case.expected else None
        blocks = report_document(case, run.events, info, comparison=comparison, figures=available_figures(folder))
        write_report(folder, blocks)
        if "report" in info.get("pending", []):
            _update(folder, info, done="report")
    return run
