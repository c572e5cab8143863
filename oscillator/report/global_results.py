"""The global analyses' results read back from their folders: basins, the attractors over a
parameter and a Lyapunov spectrum (:mod:`oscillator.report.kinds` registers them with the
others); a command's folder and a saved one alike, nothing computed on reading."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from oscillator.analysis.axes import Axis
from oscillator.attractors.basins import Basins
from oscillator.attractors.following import AttractorsOver, End
from oscillator.attractors.lyapunov import LyapunovSpectrum
from oscillator.errors import InputError, OscillatorError
from oscillator.io.cases import resolve_case
from oscillator.io.chains import load_system
from oscillator.io.files import read_untrusted
from oscillator.model.parameters import Parameters
from oscillator.report.global_folders import read_found
from oscillator.report.outputs import folder_case
from oscillator.text import printable

__all__ = ["marker_identity", "read_basins", "read_following", "read_lyapunov"]


def marker_identity(marker: Path, form: int | None = None, remake: str = "give a new folder") -> dict[str, Any]:
    """The identity a folder's marker file holds (checked as untrusted text); ``form``: the format
    its store writes today (:attr:`~oscillator.analysis.store.TableFolder.FORMAT`), another one
    refused as another version's, with ``remake`` as the fix."""
    try:
        stored = json.loads(read_untrusted(marker, what="marker file", field="folder", limit=1_000_000))
        identity = stored["identity"]
        if not isinstance(identity, dict):
            raise TypeError("not a table")
    except (ValueError, KeyError, TypeError, RecursionError) as error:
        raise InputError(f"{printable(str(marker))} is damaged ({error}); give a new folder", field="folder") from None
    if form is not None and stored.get("format") != form:
        raise InputError(
            f"{printable(str(marker.parent))} was written by another version of oscillator (its tables hold other "
            f"measures); {remake}",
            field="folder",
        )
    return identity


def read_basins(folder: Path) -> Basins:
    """The basins a folder holds (``basins.json``'s axes, ``found.json``'s attractors)."""
    known = marker_identity(folder / "basins.json")
    case = folder_case(folder, "basins.json")
    try:
        x, y = (Axis(**known[name]) for name in ("x", "y"))
    except (KeyError, TypeError, InputError) as error:
        raise InputError(f"{printable(str(folder))}/basins.json is damaged ({error})", field="folder") from None
    (found,), _ = read_found(folder, [case])
    if len(found.labels) != x.count * y.count:
        raise InputError(f"{printable(str(folder))}: its labels are not one per cell of its slice", field="folder")
    return Basins(found, x, y)


def read_following(folder: Path) -> AttractorsOver:
    """The attractors over a parameter a folder holds (``attractors.json``'s values,
    ``found.json``'s attractors and kept ids, ``ends.parquet``'s ends)."""
    known = marker_identity(folder / "attractors.json")
    case = folder_case(folder, "attractors.json")
    try:
        param = Parameters.check_name(known["param"], "folder")
        values = np.array(known["values"], dtype=float)
        cases = [resolve_case(case, **{param: float(v)}) for v in values]
    except (KeyError, TypeError, ValueError, OscillatorError) as error:
        raise InputError(f"{printable(str(folder))}/attractors.json is damaged ({error})", field="folder") from None
    found, records = read_found(folder, cases)
    try:
        ids = [{int(a): int(b) for a, b in record["ids"]} for record in records]
        fresh = int(records[0]["fresh"])
        ends = pd.read_parquet(folder / "ends.parquet")
        kept = tuple(
            End(int(e.id), str(e.name), float(e.inside), float(e.outside), str(e.becomes)) for e in ends.itertuples()
        )
    except Exception as error:  # a damaged table: pyarrow raises many types
        if isinstance(error, MemoryError):
            raise
        raise InputError(
            f"{printable(str(folder))}: its kept ids or ends.parquet are damaged ({error})", field="folder"
        ) from None
    if any(set(local) != {a.id for a in here.attractors} for local, here in zip(ids, found, strict=True)):
        raise InputError(f"{printable(str(folder))}/found.json: a kept id is missing", field="folder")
    return AttractorsOver(case, param, values, tuple(found), tuple(ids), fresh, kept)


def read_lyapunov(folder: Path) -> LyapunovSpectrum:
    """The Lyapunov spectrum a folder holds (``lyapunov.json``, ``lyapunov.parquet``)."""
    where = folder / "lyapunov.json"
    try:
        info = json.loads(read_untrusted(where, what="Lyapunov file", field="folder", limit=1_000_000))
        exponents = np.array([float(v) for v in info["exponents"]])
        start, periods = np.array(info["start"], dtype=float), int(info["periods"])
        convergence = pd.read_parquet(folder / "lyapunov.parquet")
    except Exception as error:  # a damaged file: JSON, numbers, pyarrow raise many types
        if isinstance(error, MemoryError):
            raise
        raise InputError(
            f"{printable(str(folder))} holds no Lyapunov spectrum, or a damaged one ({error})", field="folder"
        ) from None
    declared = folder / "system.toml"  # a declared system's spectrum (the folder's own file)
    system = load_system(declared) if declared.is_file() else folder_case(folder, "lyapunov.json", key="case")
    size = system.system.size
    if (
        exponents.shape != (size,)
        or start.shape != (size,)
        or np.isnan(exponents).any()
        or not np.isfinite(start).all()
    ):
        raise InputError(f"{printable(str(where))} is damaged: its exponents or start", field="folder")
    return LyapunovSpectrum(system, exponents, periods, start, convergence)
