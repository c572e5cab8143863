"""A resumable folder: what a long computation keeps as it goes, so that running it again resumes.

The folder holds a marker file (``sweep.json``, ``basins.json``, ``atlas.json``, ...) with the
computation's :func:`identity` (the case as TOML and its settings) and status, ``case.toml``, and
``parts/``: what is finished, one file per part written atomically (a temporary name, then a
rename), so that a killed run leaves only whole parts.  Running the same computation into the
folder again resumes it; another computation, or a folder of something else, is refused before
anything is written.  The sweeps (:mod:`~oscillator.analysis.sweeps`) and the global analyses
(:class:`~oscillator.attractors.store.LandingStore`) keep their parts in one of these.
"""

from __future__ import annotations

import dataclasses
import json
import os
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from oscillator.errors import InputError
from oscillator.io.files import atomic_folder, check_name, read_untrusted, refuse_link, replace_file
from oscillator.text import printable

__all__ = ["Expected", "ResumableFolder", "TableFolder", "identity"]

#: The largest marker file read.
MAX_MARKER = 1 << 20


def identity(case: Any, **pieces: Any) -> dict[str, Any]:
    """A computation's identity, as its folder's marker keeps it: the case as TOML (a friction
    chain's system file, under ``system``) and each piece (an axis, the settings: dataclasses;
    arrays; plain values), so that two computations are the same exactly when their identities
    are equal."""
    from oscillator.io.cases import case_to_toml
    from oscillator.io.chains import chain_to_toml
    from oscillator.model.chains import FrictionChain

    system = {"system": chain_to_toml(case)} if isinstance(case, FrictionChain) else {"case": case_to_toml(case)}
    return {**system, **{name: _plain(value) for name, value in pieces.items()}}


def _plain(value: Any) -> Any:
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return dataclasses.asdict(value)
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (list, tuple)):
        return [_plain(item) for item in value]
    return value


class ResumableFolder:
    """A computation's resumable folder; ``marker`` names its marker file (``sweep.json``)."""

    #: The layout and meaning of the parts, kept in the marker; a folder of another is refused.
    FORMAT: ClassVar[int | None] = None

    def __init__(self, folder: Path, marker: str, identity: dict[str, Any], *, name: str = "") -> None:
        self.folder = Path(folder)
        #: The case's name, kept in the marker beside the identity (a case file holds no name).
        self.name = name
        self.parts = self.folder / "parts"
        self.marker = marker
        self.what = marker.removesuffix(".json")
        self.identity = identity
        self.resuming = False

    def check(self) -> None:
        """Refuse, before anything is created, a folder that cannot hold this computation: a new
        name must be writable; an existing folder must hold this very computation (it resumes)."""
        text = printable(str(self.folder))
        check_name(self.folder, option="folder")
        refuse_link(self.folder)
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
        self._check_marker(marker, text)
        if self.parts.is_symlink() or not self.parts.is_dir():
            raise self.damaged(self.folder, "its parts/ is missing or is a link", "give a new folder")
        self.check_parts()
        self.resuming = True

    def _check_marker(self, marker: Path, text: str) -> None:
        raw = read_untrusted(marker, what=f"{self.what} file", field=self.marker, limit=MAX_MARKER)
        try:
            stored = json.loads(raw)
        except (ValueError, RecursionError) as exc:
            raise self.damaged(marker, "it is not JSON", "give a new folder") from exc
        if not isinstance(stored, dict) or "identity" not in stored:
            raise self.damaged(marker, f"it holds no {self.what} identity", "give a new folder")
        if stored["identity"] != self.identity:
            raise InputError(
                f"folder {text} holds another {self.what} computation (another case or settings); give a new "
                "folder, or the same case and settings to resume it",
                field="folder",
            )
        if self.FORMAT is not None and stored.get("format") != self.FORMAT:
            raise InputError(
                f"folder {text} was written by another version of oscillator (its parts mean something else); "
                "give a new folder",
                field="folder",
            )

    def check_parts(self) -> None:
        """Refuse parts that are not this computation's (a subclass's own checks; none here)."""

    def open(self, **extra: Any) -> None:
        """Create the folder (appearing whole: parts/, case.toml or a declared system's
        system.toml, the marker), unless resuming."""
        if self.resuming:
            return
        source = "case" if "case" in self.identity else "system"
        try:
            with atomic_folder(self.folder) as temporary:
                (temporary / "parts").mkdir()
                (temporary / f"{source}.toml").write_text(str(self.identity[source]), encoding="utf-8")
                (temporary / self.marker).write_text(self._status("running", **extra), encoding="utf-8")
        except OSError as exc:
            raise InputError(
                f"folder {printable(str(self.folder))}: cannot create it ({exc.strerror}); choose a writable folder",
                field="folder",
            ) from exc
        self.resuming = True

    def described(self) -> dict[str, Any]:
        """What the marker says of the computation besides its identity (a subclass's; none here)."""
        return {}

    def _status(self, status: str, **extra: Any) -> str:
        kept: dict[str, Any] = {"format": self.FORMAT} if self.FORMAT is not None else {}
        if self.name:
            kept["case_name"] = self.name
        marker = {"identity": self.identity, **kept, "status": status, **self.described(), **extra}
        return json.dumps(marker, indent=2, default=str)

    def write_status(self, status: str, **extra: Any) -> None:
        replace_file(self.folder / self.marker, self._status(status, **extra))

    def plain(self, part: Path) -> None:
        """Refuse a part that is a link or not a file: a resume folder is untrusted, and nothing
        is read or written through a link in it."""
        if part.is_symlink() or not part.is_file():
            raise InputError(
                f"{printable(str(part))} is a link or not a file; a {self.what} folder holds plain files only: give "
                "a new folder",
                field="folder",
            )

    @staticmethod
    def damaged(
        path: Path, why: str, fix: str = "delete it and run the same command to compute it again"
    ) -> InputError:
        """The refusal of a damaged part or marker, naming it, why and the fix."""
        return InputError(f"{printable(str(path))} is damaged ({why}); {fix}", field="folder")


@dataclasses.dataclass(frozen=True)
class Expected:
    """What a stored part must hold to be read back: what it is of (``key``, a JSON value: the
    task that made it, kept in the part's metadata), its columns' kinds (``"number"``, ``"flag"``,
    ``"text"``), and, where the task says, its row count, the exact values of some columns
    (``equal``: a sweep's parameter values, a branch's points) and a further ``check`` of the
    table and its metadata (a clause saying what is wrong, or ``""``)."""

    key: Any
    columns: Mapping[str, str] = dataclasses.field(default_factory=dict)
    rows: int | None = None
    equal: Mapping[str, Sequence[Any] | np.ndarray] = dataclasses.field(default_factory=dict)
    check: Callable[[Any, Any], str] | None = None

    def problem(self, key: Any, frame: Any, meta: Any) -> str:
        """What is wrong with a part holding ``key``, ``frame`` and ``meta`` (``""``: nothing)."""
        from oscillator.io.tables import kinds_problem

        if key != json.loads(json.dumps(self.key)):
            return f"it holds another task's result ({_said(key)}, where {_said(self.key)} belongs)"
        why = kinds_problem(frame, self.columns)
        if why is not None:
            return why
        if self.rows is not None and len(frame) != self.rows:
            return f"it has {len(frame)} rows, where its task has {self.rows}"
        for name, values in self.equal.items():
            if name not in frame.columns:
                return f"it has no column {name!r}"
            if len(frame) != len(values) or not np.array_equal(frame[name].to_numpy(), np.asarray(values)):
                return f"its column {name!r} is not its task's values"
        return self.check(frame, meta) if self.check is not None else ""


def _said(key: Any) -> str:
    return printable(json.dumps(key))[:200]


class TableFolder(ResumableFolder):
    """A resumable folder whose parts are tables: each a Parquet file with what it is of (its
    task's key) and a JSON value (a part's settings or summary) in its metadata, written atomically
    and read back only as its task's (:class:`Expected`), else refused by name.  :attr:`reused`
    counts the parts read back."""

    _META = b"oscillator"

    def __init__(self, folder: Path, marker: str, identity: dict[str, Any], *, name: str = "") -> None:
        super().__init__(folder, marker, identity, name=name)
        #: The parts read back from earlier runs.
        self.reused = 0

    def write(self, name: str, frame: Any, meta: Any = None, *, key: Any) -> None:
        """The part ``name``: ``frame`` (a DataFrame), with ``key`` and ``meta`` (JSON) in its
        metadata."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        from oscillator.io.files import atomic_path

        table = pa.Table.from_pandas(frame, preserve_index=False)
        kept = json.dumps({"key": key, "meta": meta})
        table = table.replace_schema_metadata({**(table.schema.metadata or {}), self._META: kept})
        with atomic_path(self.parts / f"{name}.parquet") as temporary:
            pq.write_table(table, temporary)

    def read(self, name: str, expected: Expected) -> tuple[Any, Any] | None:
        """The part ``name`` (a DataFrame) and its metadata, or None if there is none; a part that
        cannot be read or does not hold what ``expected`` says is refused with its name."""
        import pyarrow.parquet as pq

        path = self.parts / f"{name}.parquet"
        if not path.exists() and not path.is_symlink():
            return None
        self.plain(path)
        try:
            table = pq.read_table(path)
            kept = json.loads((table.schema.metadata or {})[self._META])
            key, meta = kept["key"], kept["meta"]
            frame = table.to_pandas()
        except Exception as exc:  # pyarrow raises many types for a damaged file
            if isinstance(exc, MemoryError):
                raise
            raise self.damaged(path, "it cannot be read") from exc
        why = expected.problem(key, frame, meta)
        if why:
            raise self.damaged(path, why)
        self.reused += 1
        return frame, meta
