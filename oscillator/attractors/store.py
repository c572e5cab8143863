"""A folder that keeps landings as they finish, so that a global analysis resumes.

The folder holds a marker file (``basins.json``, ``attractors.json``, ``atlas.json``) with the
computation's identity (:func:`identity`: the case as TOML and the settings), ``case.toml``, and
``parts/``: each batch of landings one Parquet file written atomically (a temporary name, then a
rename), so a killed run leaves only whole parts.  Running the same computation into the folder
again reads the parts and computes only what is missing; another computation is refused before
anything is written.  The basins keep batches of starts of one grid; a global continuation
(:mod:`~oscillator.attractors.continuing`) one part per batch of points, each landing with its
point.
"""

from __future__ import annotations

import dataclasses
import json
import os
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pyarrow.parquet as pq

from oscillator.attractors.mapping import STATE, Landing
from oscillator.errors import InputError
from oscillator.io.files import atomic_folder, atomic_path, check_name, read_untrusted, replace_file
from oscillator.text import printable

__all__ = ["LandingStore", "identity"]

_MAX_JSON = 1_000_000
#: The layout and meaning of the parts; a folder of another format is refused (format 2: a contact
#: between the masses is counted once, not once per mass; the rest time of each mass is kept;
#: format 3: an atlas keeps landings, not tables, and the parts of a continuation are batches).
FORMAT = 3


def landing_row(landing: Landing) -> dict[str, Any]:
    """A landing as one row of a part (its section points flattened)."""
    return {
        "index": landing.index,
        **dict(zip(STATE, landing.start, strict=True)),
        "status": landing.status,
        "reason": landing.reason,
        "message": landing.message,
        "period": landing.period,
        "signature": landing.signature,
        "rests1": landing.rests[0],
        "rests2": landing.rests[1],
        "contacts": landing.contacts,
        "wall_time": landing.wall_time,
        "rest_time1": landing.rest_time[0],
        "rest_time2": landing.rest_time[1],
        "points": landing.points.ravel().tolist(),
    }


def landing_of(row: Any) -> Landing:
    """:func:`landing_row` read back."""
    return Landing(
        int(row.index),
        (float(row.x1), float(row.v1), float(row.x2), float(row.v2)),
        str(row.status),
        str(row.reason),
        str(row.message),
        int(row.period),
        np.asarray(row.points, dtype=float).reshape(-1, 4),
        str(row.signature),
        (float(row.rests1), float(row.rests2)),
        float(row.contacts),
        float(row.wall_time),
        (float(row.rest_time1), float(row.rest_time2)),
    )


def identity(case: Any, **pieces: Any) -> dict[str, Any]:
    """A computation's identity, as its folder's marker keeps it: the case as TOML and each piece
    (an axis, the settings: dataclasses, or plain values), so that two computations are the same
    exactly when their identities are equal."""
    from oscillator.io.cases import case_to_toml

    return {"case": case_to_toml(case), **{name: _plain_value(value) for name, value in pieces.items()}}


def _plain_value(value: Any) -> Any:
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return dataclasses.asdict(value)
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, list):
        return [_plain_value(item) for item in value]
    return value


def _foreign(landing: Landing, starts: np.ndarray, seen: set[int]) -> str:
    """Why a stored landing is not one of this computation's (empty if it is)."""
    if not 0 <= landing.index < len(starts) or landing.index in seen:
        return f"start {landing.index} is not one of its starts or is there twice"
    if not np.array_equal(np.asarray(landing.start), starts[landing.index]):
        return f"start {landing.index} is not the start of that number"
    if landing.status not in ("ok", "failed") or (landing.status == "ok" and not np.isfinite(landing.points).all()):
        return f"start {landing.index} has no status or section points that are not numbers"
    if landing.status == "ok" and (landing.period < 0 or len(landing.points) < max(landing.period, 1)):
        return f"start {landing.index} has fewer section points than its period"
    return ""


class LandingStore:
    """A resumable folder of landings; ``marker`` names its identity file (``basins.json``)."""

    def __init__(self, folder: Path, marker: str, identity: dict[str, Any]) -> None:
        self.folder = Path(folder)
        self.parts = self.folder / "parts"
        self.marker = marker
        self.what = marker.removesuffix(".json")
        self.identity = identity
        self.resuming = False
        #: What was read back from earlier runs: landings, and the batches of points they came in.
        self.reused = {"landings": 0, "batches": 0}

    def check(self) -> None:
        """Refuse, before anything is created, a folder that cannot hold this computation: a new
        name must be writable; an existing folder must hold this very computation (it resumes)."""
        text = printable(str(self.folder))
        check_name(self.folder, option="folder")
        if not os.path.lexists(self.folder):
            return
        if not self.folder.is_dir():
            raise InputError(f"folder {text} exists and is not a folder; give a new folder", field="folder")
        marker = self.folder / self.marker
        if not os.path.lexists(marker):
            if any(self.folder.iterdir()):
                raise InputError(
                    f"folder {text} exists and is not a {self.what} folder; give a new folder", field="folder"
                )
            return
        raw = read_untrusted(marker, what=f"{self.what} file", field=self.marker, limit=_MAX_JSON)
        try:
            stored = json.loads(raw)
        except (ValueError, RecursionError) as exc:
            raise InputError(
                f"{text}/{self.marker} is damaged: it is not JSON; give a new folder", field="folder"
            ) from exc
        if not isinstance(stored, dict) or stored.get("identity") != self.identity:
            raise InputError(
                f"folder {text} holds another {self.what} computation (another case or settings); give a new "
                "folder, or the same case and settings to resume it",
                field="folder",
            )
        if stored.get("format") != FORMAT:
            raise InputError(
                f"folder {text} was written by another version of oscillator (its parts count contacts "
                "differently); give a new folder",
                field="folder",
            )
        if self.parts.is_symlink() or not self.parts.is_dir():
            raise InputError(
                f"{text} is damaged: its parts/ is missing or is a link; give a new folder", field="folder"
            )
        self.resuming = True

    def open(self) -> None:
        """Create the folder (appearing whole), unless resuming."""
        if self.resuming:
            return
        try:
            with atomic_folder(self.folder) as temporary:
                (temporary / "parts").mkdir()
                (temporary / "case.toml").write_text(str(self.identity["case"]), encoding="utf-8")
                (temporary / self.marker).write_text(self._status("running"), encoding="utf-8")
        except OSError as exc:
            raise InputError(
                f"folder {printable(str(self.folder))}: cannot create it ({exc.strerror}); choose a writable folder",
                field="folder",
            ) from exc
        self.resuming = True

    def _status(self, status: str, **extra: Any) -> str:
        marker = {"identity": self.identity, "format": FORMAT, "status": status, **extra}
        return json.dumps(marker, indent=2, default=str)

    def write_status(self, status: str, **extra: Any) -> None:
        replace_file(self.folder / self.marker, self._status(status, **extra))

    def read(self, starts: np.ndarray, prefix: str = "") -> list[Landing]:
        """The landings of the parts whose names start with ``prefix``, each checked against
        ``starts`` (the computation's starts, by index): a damaged part, or one holding a start
        that is not this computation's or one already read, is refused with its name."""
        found: list[Landing] = []
        seen: set[int] = set()
        for part in sorted(self.parts.glob(f"{prefix}*.parquet")):
            self._plain(part)
            try:
                frame = pq.read_table(part).to_pandas()
                landings = [landing_of(row) for row in frame.itertuples(index=False)]
            except Exception as exc:  # pyarrow raises many types for a damaged file
                if isinstance(exc, MemoryError):
                    raise
                raise self._damaged(part, "it cannot be read") from exc
            for landing in landings:
                why = _foreign(landing, starts, seen)
                if why:
                    raise self._damaged(part, why)
                seen.add(landing.index)
            found += landings
        self.reused["landings"] += len(found)
        return found

    def _plain(self, part: Path) -> None:
        """Refuse a part that is a link or not a file: a resume folder is untrusted, and nothing
        is read or written through a link in it."""
        if part.is_symlink() or not part.is_file():
            raise InputError(
                f"{printable(str(part))} is a link or not a file; a {self.what} folder holds plain files only: give "
                "a new folder",
                field="folder",
            )

    @staticmethod
    def _damaged(part: Path, why: str) -> InputError:
        return InputError(
            f"{printable(str(part))} is damaged ({why}); delete it and run the same command to compute its starts "
            "again",
            field="folder",
        )

    def write_batch(self, landings: dict[int, list[Landing]], name: str) -> None:
        """One part holding the landings of a batch of points (``point -> its landings``)."""
        rows = [{"point": point, **landing_row(item)} for point, items in landings.items() for item in items]
        with atomic_path(self.parts / f"{name}.parquet") as temporary:
            pd.DataFrame(rows).to_parquet(temporary, index=False)

    def read_batch(self, name: str, starts: dict[int, np.ndarray]) -> dict[int, list[Landing]] | None:
        """The landings of the batch part ``name`` by point, each point's checked against its
        ``starts`` (all there, each once); None if there is no such part."""
        part = self.parts / f"{name}.parquet"
        if not os.path.lexists(part):
            return None
        self._plain(part)
        try:
            frame = pq.read_table(part).to_pandas()
            landings = [(int(row.point), landing_of(row)) for row in frame.itertuples(index=False)]
        except Exception as exc:  # pyarrow raises many types for a damaged file
            if isinstance(exc, MemoryError):
                raise
            raise self._damaged(part, "it cannot be read") from exc
        found: dict[int, list[Landing]] = {point: [] for point in starts}
        seen: dict[int, set[int]] = {point: set() for point in starts}
        for point, landing in landings:
            why = f"point {point} is not one of its batch" if point not in starts else ""
            why = why or _foreign(landing, starts[point], seen[point])
            if why:
                raise self._damaged(part, why)
            seen[point].add(landing.index)
            found[point].append(landing)
        if any(len(seen[point]) != len(starts[point]) for point in starts):
            raise self._damaged(part, "a start of its batch is missing")
        self.reused["landings"] += len(landings)
        self.reused["batches"] += 1
        return found

    def write(self, landings: list[Landing], name: str | None = None) -> None:
        """A part of these landings, named ``name`` (by default after its first start's index)."""
        if not landings:
            return
        if name is None:
            name = f"{min(item.index for item in landings):08d}-{len(landings):04d}"
        with atomic_path(self.parts / f"{name}.parquet") as temporary:
            pd.DataFrame([landing_row(item) for item in landings]).to_parquet(temporary, index=False)
