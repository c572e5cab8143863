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

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, Literal

import numpy as np
import pandas as pd
import pyarrow.parquet as pq

from oscillator.analysis.store import ResumableFolder
from oscillator.attractors.mapping import STATE, Landing
from oscillator.errors import InputError, Reason
from oscillator.io.cases import Case
from oscillator.io.files import atomic_path
from oscillator.model.chains import FrictionChain

__all__ = ["LandingStore"]


_MAX_JSON = 1_000_000
#: The layout and meaning of the parts; a folder of another format is refused (format 2: a contact
#: between the masses is counted once, not once per mass; the rest time of each mass is kept;
#: format 3: an atlas keeps landings, not tables, and the parts of a continuation are batches;
#: format 4: a landing keeps the periods its transient ran, ended where the motion settled).
FORMAT = 4


def landing_row(landing: Landing, state: Sequence[str] = STATE) -> dict[str, Any]:
    """A landing as one row of a part (its section points flattened; its start in the ``state``
    columns, each mass's rests in ``rests1``, ``rests2``, ... and ``rest_time1``, ...)."""
    return {
        "index": landing.index,
        **dict(zip(state, landing.start, strict=True)),
        "status": landing.status,
        "reason": "" if landing.reason is None else landing.reason.value,
        "message": landing.message,
        "period": landing.period,
        "signature": landing.signature,
        **{f"rests{k}": value for k, value in enumerate(landing.rests, start=1)},
        "contacts": landing.contacts,
        "wall_time": landing.wall_time,
        **{f"rest_time{k}": value for k, value in enumerate(landing.rest_time, start=1)},
        "transient": landing.transient,
        "points": landing.points.ravel().tolist(),
    }


def landing_of(row: Mapping[str, Any], state: Sequence[str] = STATE, masses: int = 2) -> Landing:
    """:func:`landing_row` read back (a row of a part, by column)."""
    return Landing(
        int(row["index"]),
        tuple(float(row[name]) for name in state),
        _status(str(row["status"])),
        _reason(str(row["reason"])),
        str(row["message"]),
        int(row["period"]),
        np.asarray(row["points"], dtype=float).reshape(-1, len(state)),
        str(row["signature"]),
        tuple(float(row[f"rests{k}"]) for k in range(1, masses + 1)),
        float(row["contacts"]),
        float(row["wall_time"]),
        tuple(float(row[f"rest_time{k}"]) for k in range(1, masses + 1)),
        int(row["transient"]),
    )


def _status(text: str) -> Literal["ok", "failed"]:
    """A stored status; another text is a damaged part (``ValueError``)."""
    if text not in ("ok", "failed"):
        raise ValueError(f"status {text!r}")
    return "ok" if text == "ok" else "failed"


def _reason(text: str) -> Reason | None:
    """A stored reason (empty: none); one that is no :class:`~oscillator.errors.Reason` is a
    damaged part (``ValueError``)."""
    return Reason(text) if text else None


def _foreign(landing: Landing, starts: np.ndarray, seen: set[int]) -> str:
    """Why a stored landing is not one of this computation's (empty if it is)."""
    if not 0 <= landing.index < len(starts) or landing.index in seen:
        return f"start {landing.index} is not one of its starts or is there twice"
    if not np.array_equal(np.asarray(landing.start), starts[landing.index]):
        return f"start {landing.index} is not the start of that number"
    if landing.ok and not np.isfinite(landing.points).all():
        return f"start {landing.index} has section points that are not numbers"
    if landing.ok and (landing.period < 0 or len(landing.points) < max(landing.period, 1)):
        return f"start {landing.index} has fewer section points than its period"
    return ""


class LandingStore(ResumableFolder):
    """A resumable folder of landings; ``marker`` names its identity file (``basins.json``)."""

    FORMAT = FORMAT

    def __init__(
        self,
        folder: Path,
        marker: str,
        identity: dict[str, Any],
        *,
        name: str = "",
        state: Sequence[str] = STATE,
        masses: int = 2,
    ) -> None:
        super().__init__(folder, marker, identity, name=name)
        #: The system's state (the starts' columns) and its number of masses (a friction chain's own).
        self.state, self.masses = tuple(state), masses
        #: What was read back from earlier runs: landings, and the batches of points they came in.
        self.reused = {"landings": 0, "batches": 0}

    @classmethod
    def of(cls, folder: Path, marker: str, identity: dict[str, Any], system: Case | FrictionChain) -> LandingStore:
        """The folder of a computation on the article's ``system`` (a case: its name) or on a
        declared one (its title, its state and its masses)."""
        if isinstance(system, FrictionChain):
            state, masses = system.system.state, len(system.masses)
            return cls(folder, marker, identity, name=system.title, state=state, masses=masses)
        return cls(folder, marker, identity, name=system.name)

    def _damaged(self, part: Path, why: str) -> InputError:
        return self.damaged(part, why, "delete it and run the same command to compute its starts again")

    def read(self, starts: np.ndarray, prefix: str = "") -> list[Landing]:
        """The landings of the parts whose names start with ``prefix``, each checked against
        ``starts`` (the computation's starts, by index): a damaged part, or one holding a start
        that is not this computation's or one already read, is refused with its name."""
        found: list[Landing] = []
        seen: set[int] = set()
        for part in sorted(self.parts.glob(f"{prefix}*.parquet")):
            self.plain(part)
            try:
                frame = pq.read_table(part).to_pandas()
                landings = [landing_of(row, self.state, self.masses) for row in frame.to_dict("records")]
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

    def write_batch(self, landings: dict[int, list[Landing]], name: str) -> None:
        """One part holding the landings of a batch of points (``point -> its landings``)."""
        rows = [
            {"point": point, **landing_row(item, self.state)} for point, items in landings.items() for item in items
        ]
        with atomic_path(self.parts / f"{name}.parquet") as temporary:
            pd.DataFrame(rows).to_parquet(temporary, index=False)

    def holds(self, name: str) -> bool:
        """Whether the batch part ``name`` is there (:meth:`read_batch` reads and checks it)."""
        return os.path.lexists(self.parts / f"{name}.parquet")

    def read_batch(self, name: str, starts: dict[int, np.ndarray]) -> dict[int, list[Landing]] | None:
        """The landings of the batch part ``name`` by point, each point's checked against its
        ``starts`` (all there, each once); None if there is no such part."""
        part = self.parts / f"{name}.parquet"
        if not os.path.lexists(part):
            return None
        self.plain(part)
        try:
            frame = pq.read_table(part).to_pandas()
            landings = [
                (int(row["point"]), landing_of(row, self.state, self.masses)) for row in frame.to_dict("records")
            ]
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
            pd.DataFrame([landing_row(item, self.state) for item in landings]).to_parquet(temporary, index=False)
