"""The global analyses' results saved whole and read back: what ``save`` writes and
:func:`oscillator.read_run` reads, for basins, the attractors over a parameter, an atlas, a
curve and a Lyapunov spectrum.

Each folder is the one the analysis's command writes (its marker file names its kind:
``basins.json``, ``attractors.json``, ``atlas.json``, ``curve.json``, ``lyapunov.json``), so that
``read_run`` reads a command's folder and a saved one alike; nothing is computed on reading.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from oscillator.analysis.axes import STATE, Axis
from oscillator.analysis.store import identity
from oscillator.attractors.atlas import Atlas
from oscillator.attractors.basins import Basins
from oscillator.attractors.following import AttractorsOver, End
from oscillator.attractors.lyapunov import LyapunovSpectrum
from oscillator.attractors.store import FORMAT
from oscillator.errors import InputError, OscillatorError
from oscillator.io.cases import resolve_case
from oscillator.io.files import atomic_path, claim_folder, read_untrusted
from oscillator.model.parameters import Parameters
from oscillator.orbits.curves import Curve
from oscillator.report.attractors import write_basins, write_following, write_lyapunov
from oscillator.report.global_folders import read_found
from oscillator.report.outputs import folder_case
from oscillator.report.plane import read_atlas, read_curve, write_atlas, write_curve
from oscillator.text import printable

__all__ = ["GLOBAL_MARKERS", "global_kind", "marker_identity", "read_global", "save_global"]

#: Each global folder's marker file and the kind it names.
GLOBAL_MARKERS = {
    "basins.json": "basins",
    "attractors.json": "attractors",
    "atlas.json": "atlas",
    "curve.json": "curve",
    "lyapunov.json": "lyapunov",
}
Global = Basins | AttractorsOver | Atlas | Curve | LyapunovSpectrum


def global_kind(folder: Path) -> str | None:
    """The kind of global result a folder holds (by its marker file), or None."""
    return next((kind for marker, kind in GLOBAL_MARKERS.items() if (folder / marker).is_file()), None)


def marker_identity(marker: Path) -> dict[str, Any]:
    """The identity a folder's marker file holds (checked as untrusted text)."""
    try:
        identity = json.loads(read_untrusted(marker, what="marker file", field="folder", limit=1_000_000))["identity"]
        if not isinstance(identity, dict):
            raise TypeError("not a table")
    except (ValueError, KeyError, TypeError, RecursionError) as error:
        raise InputError(f"{printable(str(marker))} is damaged ({error}); give a new folder", field="folder") from None
    return identity


def read_global(folder: Path) -> Global:
    """The result a global analysis's folder holds (its command's, or its ``save``'s)."""
    kind = global_kind(folder)
    if kind == "atlas":
        return read_atlas(folder)
    if kind == "curve":
        return read_curve(folder)
    if kind == "basins":
        return read_basins(folder)
    if kind == "attractors":
        return read_following(folder)
    if kind == "lyapunov":
        return read_lyapunov(folder)
    raise InputError(f"{printable(str(folder))} holds no result of a global analysis", field="folder")


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
    if exponents.shape != (4,) or start.shape != (4,) or np.isnan(exponents).any() or not np.isfinite(start).all():
        raise InputError(f"{printable(str(where))} is damaged: its exponents or start", field="folder")
    return LyapunovSpectrum(folder_case(folder, "lyapunov.json", key="case"), exponents, periods, start, convergence)


def _marker(folder: Path, marker_name: str, known: dict[str, Any], name: str) -> None:
    """The marker file (the identity, status ``saved``) and ``case.toml``."""
    marker = json.dumps({"identity": known, "format": FORMAT, "case_name": name, "status": "saved"}, indent=2)
    for file, text in ((marker_name, marker), ("case.toml", str(known["case"]))):
        with atomic_path(folder / file) as temporary:
            temporary.write_text(text, encoding="utf-8")


def _write(found: Global, folder: Path) -> list[str]:
    """The result's folder written into ``folder`` (empty): its marker, case and outputs."""
    if isinstance(found, Basins):
        known = identity(found.found.case, x=found.x, y=found.y, settings=found.found.settings)
        _marker(folder, "basins.json", known, found.found.case.name)
        return write_basins(found, folder)
    if isinstance(found, AttractorsOver):
        fresh = found.found[0].labels[list(STATE)].to_numpy()[: found.fresh]
        settings = found.found[0].settings
        known = identity(found.case, param=found.param, values=found.values, states=fresh, settings=settings)
        _marker(folder, "attractors.json", known, found.case.name)
        return write_following(found, folder, coordinate="x2", branches=[])
    if isinstance(found, Atlas):
        _marker(folder, "atlas.json", identity(found.case, x=found.x, y=found.y), found.case.name)
        return write_atlas(found, folder)
    if isinstance(found, Curve):
        return write_curve(found, folder)
    return write_lyapunov(found, folder)


def save_global(found: Global, folder: str | Path) -> Path:
    """Write ``found`` into ``folder`` (new; it appears whole) as its command writes it;
    :func:`oscillator.read_run` reads it back.  A figure that fails is said in a warning (the
    tables are written)."""
    import warnings

    claim = claim_folder(Path(folder))
    try:
        problems = _write(found, claim.temporary)
        written = claim.commit()
    except BaseException:
        claim.abandon()
        raise
    for problem in problems:
        warnings.warn(f"{written}: {problem}; the tables are written", stacklevel=3)
    return written
