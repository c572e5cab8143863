"""The attractors the global analyses found, kept whole in their folders and read back.

A basins or attractors-over-a-parameter folder holds, beside its tables for people, what makes
the result again without computing anything: ``found.json`` (each set of attractors: its
settings, warnings and attractors, each with its orbit as :func:`~oscillator.report.orbit_folders.orbit_info`
writes it, and what the analysis adds: kept ids, the fresh starts' count),
``labels.parquet`` (where every start went, a ``set`` column numbering the sets) and
``orbit-events.parquet`` (each refined orbit's events over one period, with ``set`` and
``attractor``).  Every file is read as untrusted: a missing or damaged one is refused naming it.
"""

from __future__ import annotations

import dataclasses
import json
import numbers
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from oscillator.analysis.axes import STATE
from oscillator.attractors.finding import Attractors
from oscillator.attractors.grouping import Attractor
from oscillator.attractors.mapping import AttractorSettings
from oscillator.errors import InputError
from oscillator.io.cases import Case
from oscillator.io.files import atomic_path, read_untrusted
from oscillator.orbits.shooting import Orbit
from oscillator.report.orbit_folders import orbit_info, orbit_of
from oscillator.text import printable

__all__ = ["FOUND", "read_found", "write_found"]

#: The files that keep the attractors.
FOUND, LABELS, EVENTS = "found.json", "labels.parquet", "orbit-events.parquet"
#: The largest ``found.json`` read (bytes).
MAX_FOUND = 256 << 20
LABEL_COLUMNS = ["index", *STATE, "attractor", "status", "reason", "message", "period"]


def _record(attractor: Attractor) -> dict[str, Any]:
    fields = {f.name: getattr(attractor, f.name) for f in dataclasses.fields(attractor) if f.name != "orbit"}
    fields["points"] = np.asarray(attractor.points, dtype=float).tolist()
    fields["orbit"] = orbit_info(attractor.orbit) if isinstance(attractor.orbit, Orbit) else None
    return fields


def write_found(folder: Path, sets: Sequence[Attractors], extras: Sequence[dict[str, Any]] | None = None) -> None:
    """``found.json``, ``labels.parquet`` and ``orbit-events.parquet`` of these sets (each file
    atomically); ``extras``: what each set's record adds (kept ids)."""
    records, labels, events = [], [], []
    for k, found in enumerate(sets):
        record: dict[str, Any] = {"settings": dataclasses.asdict(found.settings), "warnings": list(found.warnings)}
        record["attractors"] = [_record(a) for a in found.attractors]
        records.append({**record, **(extras[k] if extras else {})})
        labels.append(found.labels.assign(set=k))
        events += [a.orbit.events.assign(set=k, attractor=a.id) for a in found.attractors if a.orbit is not None]
    with atomic_path(folder / FOUND) as temporary:
        temporary.write_text(json.dumps({"sets": records}, indent=1), encoding="utf-8")
    for name, frames in ((LABELS, labels), (EVENTS, events)):
        frame = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame({"set": [], "attractor": []})
        with atomic_path(folder / name) as temporary:
            frame.to_parquet(temporary, index=False)


def _damaged(path: Path, what: str) -> InputError:
    return InputError(f"{printable(str(path))} is damaged: {what}; compute it again into a new folder", field="folder")


def _table(path: Path) -> pd.DataFrame:
    if not path.is_file() or path.is_symlink():
        raise InputError(
            f"{printable(str(path.parent))} holds no saved attractors: {path.name} is missing", field="folder"
        )
    try:
        return pd.read_parquet(path)
    except Exception as exc:  # pyarrow raises many types for a damaged file
        if isinstance(exc, MemoryError):
            raise
        raise _damaged(path, "it cannot be read as a table") from exc


def _number(value: object) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def _pair(value: object) -> tuple[float, float] | None:
    ok = isinstance(value, list) and len(value) == 2 and all(_number(v) for v in value)
    return (float(value[0]), float(value[1])) if ok else None  # type: ignore[index]


def _attractor(data: object, case: Case, events: pd.DataFrame, damaged: Callable[[str], InputError]) -> Attractor:
    """An attractor's record checked field by field."""
    if not isinstance(data, dict):
        raise damaged("an attractor is not a JSON object")
    whole = {name: data.get(name) for name in ("id", "period", "starts")}
    if not all(isinstance(v, int) and not isinstance(v, bool) and v >= 0 for v in whole.values()):
        raise damaged("an attractor's id, period or starts is not a whole number")
    try:
        points = np.array(data.get("points"), dtype=float)
    except (TypeError, ValueError):
        points = np.empty((0, 0))
    if points.ndim != 2 or points.shape[1:] != (4,) or not len(points) or not np.isfinite(points).all():
        raise damaged(f"attractor {whole['id']}'s points are not rows of four finite numbers")
    rests, rest_time = _pair(data.get("rests")), _pair(data.get("rest_time"))
    floats = [data.get(name) for name in ("contacts", "lyapunov", "forcing_period")]
    measures = data.get("measures", {})
    texts = [data.get(name) for name in ("signature", "note")]
    if (
        rests is None
        or rest_time is None
        or not all(_number(v) for v in floats)
        or not all(isinstance(t, str) for t in texts)
    ):
        raise damaged(f"attractor {whole['id']}'s rests, contacts, exponent or texts are not what they should be")
    if not (isinstance(measures, dict) and all(isinstance(k, str) and _number(v) for k, v in measures.items())):
        raise damaged(f"attractor {whole['id']}'s measures are not numbers by name")
    orbit = data.get("orbit")
    contacts, largest, forcing = (float(v) for v in floats)  # type: ignore[arg-type]
    return Attractor(
        int(whole["id"]),  # type: ignore[arg-type]
        int(whole["period"]),  # type: ignore[arg-type]
        points,
        str(texts[0]),
        rests,
        contacts,
        int(whole["starts"]),  # type: ignore[arg-type]
        orbit=None if orbit is None else orbit_of(orbit, case, events, damaged),
        lyapunov=largest,
        note=str(texts[1]),
        forcing_period=forcing,
        rest_time=rest_time,
        measures={k: float(v) for k, v in measures.items()},
    )


def read_found(folder: Path, cases: Sequence[Case]) -> tuple[list[Attractors], list[dict[str, Any]]]:
    """The sets of attractors :func:`write_found` kept (set ``k`` in ``cases[k]``), and each
    set's whole record (for what an analysis added to it)."""
    where = folder / FOUND
    text = read_untrusted(where, what="attractors file", field="folder", limit=MAX_FOUND)
    try:
        records = json.loads(text)["sets"]
    except (ValueError, KeyError, TypeError, RecursionError) as exc:
        raise _damaged(where, "it is not the JSON of a set of attractors") from exc
    if not isinstance(records, list) or len(records) != len(cases):
        raise _damaged(where, f"it does not hold {len(cases)} sets of attractors")
    labels, events = _table(folder / LABELS), _table(folder / EVENTS)
    missing = [name for name in [*LABEL_COLUMNS, "set"] if name not in labels.columns]
    if missing or not {"set", "attractor"} <= set(events.columns):
        raise _damaged(folder / LABELS, f"it has no column {', '.join(missing) or 'set'}")
    return [
        _set(record, k, case, labels, events, where)
        for k, (record, case) in enumerate(zip(records, cases, strict=True))
    ], records


def _set(record: object, k: int, case: Case, labels: pd.DataFrame, events: pd.DataFrame, where: Path) -> Attractors:
    def damaged(what: str) -> InputError:
        return _damaged(where, f"set {k}: {what}")

    if not isinstance(record, dict) or not isinstance(record.get("attractors"), list):
        raise damaged("no list of attractors")
    try:
        settings = AttractorSettings(**record["settings"])
    except (KeyError, TypeError, InputError) as exc:
        raise damaged("its settings are not an AttractorSettings") from exc
    warnings = record.get("warnings", [])
    if not (isinstance(warnings, list) and all(isinstance(w, str) for w in warnings)):
        raise damaged("its warnings are not texts")
    mine = events[events["set"] == k]
    attractors = tuple(_attractor(data, case, _events_of(mine, data), damaged) for data in record["attractors"])
    frame = labels[labels["set"] == k][LABEL_COLUMNS].reset_index(drop=True)
    if (
        sorted(a.id for a in attractors) != list(range(len(attractors)))
        or not frame.attractor.isin([-1, *range(len(attractors))]).all()
    ):
        raise damaged("its attractors are not numbered 0, 1, ... or a start's attractor is not one of them")
    return Attractors(case, settings, attractors, frame, tuple(warnings))


def _events_of(events: pd.DataFrame, data: object) -> pd.DataFrame:
    ident = data.get("id") if isinstance(data, dict) else None
    return events[events["attractor"] == ident].drop(columns=["set", "attractor"]).reset_index(drop=True)
