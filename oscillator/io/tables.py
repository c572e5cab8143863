"""The two tables of a run, ``events`` and ``trajectory``: their columns, and their check.

A run's tables are built here from the supervisor's records, and checked here when they are
read back from a run folder (which may have been edited or damaged): a table that passes
:func:`check_events` / :func:`check_trajectory` can be reported and drawn without surprise.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd

from oscillator.errors import InputError
from oscillator.model.events import COLUMN, Event, EventKind, decode_column
from oscillator.model.phase_space import Mode, system_state
from oscillator.model.system import ARTICLE
from oscillator.text import shown

__all__ = [
    "EVENT_DTYPES",
    "TRAJECTORY_COLUMNS",
    "check_events",
    "check_trajectory",
    "events_frame",
    "kinds_problem",
    "trajectory_frame",
]

TRAJECTORY_COLUMNS = ("t", *ARTICLE.state, "domain1", "domain2", "system_state")
_DOMAINS = {1: set(range(9)), 2: {0, 1, 2, 5, 6}}
_STATES = {
    system_state(left, right, r1, r2)
    for left in (False, True)
    for right in (False, True)
    for r1 in (False, True)
    for r2 in (False, True)
}


def kinds_problem(frame: pd.DataFrame, columns: Mapping[str, str]) -> str | None:
    """What is wrong with ``frame`` against ``columns`` (a name -> its kind: ``"number"``, not a
    flag; ``"flag"``, a bool; ``"text"``, a string in every row), said as a clause (``"it has no
    column 'x1'"``); None if nothing is.  The one check of a table read back from a folder."""
    types = pd.api.types
    for name, kind in columns.items():
        if name not in frame.columns:
            return f"it has no column {shown(name)}"
        column = frame[name]
        fits = {
            "number": types.is_numeric_dtype(column) and not types.is_bool_dtype(column),
            "flag": types.is_bool_dtype(column),
            "text": all(isinstance(value, str) for value in column),
        }[kind]
        if not fits:
            return f"its column {shown(name)} is not {kind}s"
    return None


#: The dtype of each column of ``Result.events``, from the types of :class:`Event`'s fields
#: (an empty table has them too).
EVENT_DTYPES = {f.name: {"float": "float64", "int": "int64"}.get(str(f.type), "str") for f in dataclasses.fields(Event)}


def events_frame(rows: np.ndarray) -> pd.DataFrame:
    """``Result.events`` from event rows (:data:`oscillator.model.events.COLUMN`): one row per
    event and mass, columns :meth:`Event.columns`, each in its dtype.

    Built column by column from the array: the numbers as they are, the codes read as text
    (a sweep builds thousands of these tables).
    """
    rows = np.asarray(rows, dtype=float).reshape(-1, len(COLUMN))
    masses = rows[:, COLUMN["mass"]]
    data = {}
    for name in Event.columns():
        dtype = EVENT_DTYPES[name]
        values = rows[:, COLUMN[name]]
        if dtype == "str":
            data[name] = pd.array(decode_column(name, values, masses), dtype="str")
        else:
            data[name] = values.astype(dtype)
    return pd.DataFrame(data, columns=list(Event.columns()))


def trajectory_frame(chunks: Sequence[tuple[np.ndarray, Mode]]) -> pd.DataFrame:
    """``Result.trajectory``: ``t, x1, v1, x2, v2, domain1, domain2, system_state``, from the
    rows ``(t, x1, v1, x2, v2)`` in pieces, each piece's rows in one mode."""
    rows = np.concatenate([rows for rows, _ in chunks]) if chunks else np.empty((0, 5))
    counts = [len(rows) for rows, _ in chunks]
    modes = [mode for _, mode in chunks]
    return pd.DataFrame(
        {
            "t": rows[:, 0],
            "x1": rows[:, 1],
            "v1": rows[:, 2],
            "x2": rows[:, 3],
            "v2": rows[:, 4],
            "domain1": np.repeat(np.array([m.domain1 for m in modes], dtype=int), counts),
            "domain2": np.repeat(np.array([m.domain2 for m in modes], dtype=int), counts),
            "system_state": np.repeat(np.array([m.system_state for m in modes], dtype=object), counts).tolist(),
        },
        columns=list(TRAJECTORY_COLUMNS),
    )


def _damaged(source: str, what: str) -> InputError:
    return InputError(f"{source} is damaged: {what}; run the case again to remake the folder", field=source)


def _check_columns(frame: pd.DataFrame, source: str, columns: Sequence[str], text: Sequence[str]) -> None:
    missing = [c for c in columns if c not in frame.columns]
    if missing:
        raise _damaged(source, f"it lacks the column {missing[0]!r}")
    for column in columns:
        values = frame[column]
        if column in text:
            if not values.map(lambda v: isinstance(v, str)).all():
                raise _damaged(source, f"column {column!r} must hold text")
        elif not pd.api.types.is_numeric_dtype(values) or pd.api.types.is_bool_dtype(values):
            raise _damaged(source, f"column {column!r} must hold numbers")


def _check_domains(frame: pd.DataFrame, source: str, columns: dict[str, int]) -> None:
    for column, mass in columns.items():
        values = frame[column].to_numpy()
        if not np.isin(values, sorted(_DOMAINS[mass])).all():
            raise _damaged(source, f"column {column!r} holds a domain that mass {mass} does not have")


def check_events(frame: pd.DataFrame, source: str) -> pd.DataFrame:
    """The events table read back from ``source``, checked; ints where the schema has ints.

    A table written before events had a ``branch`` column (version 0.1) gets an empty one.
    """
    if "branch" not in frame.columns and "equation" in frame.columns:
        frame = frame.assign(branch="")
        frame = frame[[c for c in Event.columns() if c in frame.columns]]
    _check_columns(frame, source, Event.columns(), Event.text_columns())
    if not frame["mass"].isin([1, 2]).all():
        raise _damaged(source, "column 'mass' must hold 1 or 2")
    if not frame["kind"].isin([k.value for k in EventKind]).all():
        raise _damaged(source, "column 'kind' holds an unknown event kind")
    for mass in (1, 2):
        rows = frame[frame["mass"] == mass]
        _check_domains(rows, source, {"from_domain": mass, "to_domain": mass})
    if not frame["state_from"].isin(_STATES | {""}).all() or not frame["state_to"].isin(_STATES | {""}).all():
        raise _damaged(source, "a system state is not one of I-a ... IV-d")
    times = frame["t"].to_numpy(dtype=float)
    if not np.isfinite(times).all():
        raise _damaged(source, "column 't' must hold finite times")
    if np.any(np.diff(times) < 0):
        raise _damaged(source, "column 't' must hold times in order")
    return frame.astype({"mass": int, "from_domain": int, "to_domain": int})


def check_trajectory(frame: pd.DataFrame, source: str) -> pd.DataFrame:
    """The trajectory table read back from ``source``, checked; ints where the schema has ints."""
    _check_columns(frame, source, TRAJECTORY_COLUMNS, ("system_state",))
    _check_domains(frame, source, {"domain1": 1, "domain2": 2})
    if not frame["system_state"].isin(_STATES).all():
        raise _damaged(source, "a system state is not one of I-a ... IV-d")
    if not np.isfinite(frame["t"].to_numpy(dtype=float)).all():
        raise _damaged(source, "column 't' must hold finite times")
    return frame.astype({"domain1": int, "domain2": int})
