"""Parameter sweeps (sliding bifurcation diagrams, Sec. 7): run, resumed and read back.

A sweep runs one simulation per value of a parameter: a transient of forcing periods, then a
recorded window; :mod:`oscillator.analysis.sweep_points` computes a value and the tables it
gives (switching points, Poincaré points, a summary row), each with the swept parameter as a
column named after it (e.g. ``Omega``).  A declared system's sweep (issue 52) runs
:func:`~oscillator.analysis.chain_sweeps.run_chain_point` instead, into the same kind of folder.

Points are computed by :func:`~oscillator.analysis.sweep_points.run_point` (a pure function, so
the same rows come out serially, in a process pool or on a Dask cluster) and stored by the parent
process as they finish: each
point as small Parquet parts written atomically, its summary part last.  A summary part marks
the point done, so running the same sweep into the same folder again resumes it, with no point
lost or duplicated, also after the process was killed.  At the end the parts are streamed into
one Parquet file per table (memory stays flat in the number of points).
"""

from __future__ import annotations

import dataclasses
import math
import os
import stat
import time
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import Any

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from oscillator.analysis.axes import STATE
from oscillator.analysis.execution import check_workers, connect, run_tasks
from oscillator.analysis.store import Expected, TableFolder, identity
from oscillator.analysis.sweep_points import (
    TABLES,
    PointTables,
    Tasks,
    frame_of,
    point_case,
    point_function,
    table_columns,
)
from oscillator.errors import InputError, OscillatorError
from oscillator.io.cases import Case
from oscillator.io.files import atomic_path, lock_name
from oscillator.model.chains import FrictionChain
from oscillator.model.parameters import SweepSettings
from oscillator.text import printable

__all__ = ["Sweep", "SweepOutcome", "open_sweep", "read_sweep", "run_sweep"]


# --------------------------------------------------------------------------- storage


class _Store(TableFolder):
    """A sweep folder: its identity, the finished points, and the consolidated tables.  Each
    point's three parts hold its key (the point, the table, the value, the direction) and are read
    back only as that point's (:meth:`expected`)."""

    FORMAT = 2  # 2: each point's parts keyed by the point

    def __init__(self, folder: Path, subject: Case | FrictionChain, settings: SweepSettings) -> None:
        if isinstance(subject, FrictionChain):
            from oscillator.analysis.chain_sweeps import chain_sweep_columns

            name = subject.title or "system"
            self.columns = chain_sweep_columns(subject, settings.param)
            self.ends = tuple(f"end:{state}" for state in subject.system.state)
        else:
            name = subject.name
            self.columns = table_columns(settings.param)
            self.ends = tuple(f"end_{state}" for state in STATE)
        super().__init__(folder, "sweep.json", identity(subject, settings=settings), name=name)
        self.settings = settings

    def check_parts(self) -> None:
        """Every part named ``NNNNNN.TABLE.parquet`` for a point of this sweep, a plain file whose
        footer reads."""
        for part in sorted(self.parts.glob("*.parquet")):
            try:
                index, name, _ = part.name.split(".")
                if name not in TABLES or not 0 <= int(index) < len(self.settings.points):
                    raise ValueError(name)
                if not stat.S_ISREG(os.lstat(part).st_mode):
                    raise ValueError(name)
                pq.read_metadata(part)
            except Exception as exc:  # pyarrow raises many types for a damaged file
                if isinstance(exc, MemoryError):
                    raise
                raise self.damaged(
                    part,
                    "it is not a part of this sweep",
                    "delete it, and run the same command to compute that point again",
                ) from exc

    def described(self) -> dict[str, Any]:
        return {"param": self.settings.param, "points": len(self.settings.points)}

    def done(self) -> set[int]:
        return {int(p.name.split(".")[0]) for p in self.parts.glob("*.summary.parquet")}

    def expected(self, index: int, name: str) -> Expected:
        """What point ``index``'s part of table ``name`` must hold: its key, its columns' kinds,
        every row at its value and its index (the summary one row)."""
        direction, value = self.settings.points[index]
        param = self.settings.param
        kinds = {column: _KINDS[dtype] for column, dtype in self.columns[name].items()}

        def check(frame: pd.DataFrame, meta: Any) -> str:
            if not ((frame[param] == value) & (frame["index"] == index)).all():
                return f"its rows are not point {index}'s ({param} = {value:g})"
            return ""

        key = {"point": index, "table": name, "value": float(value), "direction": direction}
        return Expected(key, kinds, 1 if name == "summary" else None, check=check)

    def end_state(self, index: int) -> tuple[float, ...] | None:
        """The state a stored point ended in, or None (no such point, or it failed)."""
        part = self.read(f"{index:06d}.summary", self.expected(index, "summary"))
        if part is None:
            return None
        row = part[0].iloc[0]
        state = tuple(float(row.get(name, math.nan)) for name in self.ends)
        return state if all(math.isfinite(v) for v in state) else None

    def write_point(self, point: PointTables) -> None:
        for name in TABLES:  # the summary last: it marks the point done
            key = self.expected(point.index, name).key
            self.write(f"{point.index:06d}.{name}", point.table(name), key=key)

    def consolidate(self) -> None:
        """Stream the parts, in parameter order, each checked as its point's, into one Parquet
        file per table."""
        for name in TABLES:
            columns = self.columns[name]
            schema = pa.Table.from_pandas(frame_of([], columns), preserve_index=False).schema
            with (
                atomic_path(self.folder / f"{name}.parquet") as temporary,
                pq.ParquetWriter(temporary, schema) as writer,
            ):
                for part in sorted(self.parts.glob(f"*.{name}.parquet")):
                    index = int(part.name.split(".")[0])
                    stored = self.read(f"{index:06d}.{name}", self.expected(index, name))
                    assert stored is not None  # the part was just listed
                    frame = stored[0].astype(columns)
                    writer.write_table(pa.Table.from_pandas(frame, schema=schema, preserve_index=False))


#: The kinds of :func:`~oscillator.analysis.sweep_points.table_columns`' dtypes.
_KINDS = {"float64": "number", "int64": "number", "bool": "flag", "str": "text"}


def read_sweep(folder: Path) -> dict[str, pd.DataFrame]:
    """The consolidated tables of a finished sweep folder."""
    folder = Path(folder)
    missing = [name for name in TABLES if not (folder / f"{name}.parquet").is_file()]
    if missing:
        raise InputError(f"{folder} holds no finished sweep (no {missing[0]}.parquet)", field="folder")
    return {name: pd.read_parquet(folder / f"{name}.parquet") for name in TABLES}


# --------------------------------------------------------------------------- execution


def _points_following(
    case: Case | FrictionChain, settings: SweepSettings, tasks: Tasks, store: _Store
) -> Iterator[PointTables]:
    """A both-ways sweep: each point from the state the point before it ended in (read from
    its stored summary when resuming), the first from the case's start; after a failed point,
    from the case's start again."""
    point_of = point_function(case)
    directions = dict(enumerate(direction for direction, _ in settings.points))
    ends: dict[int, tuple[float, ...] | None] = {}
    for index, value in tasks:
        start = None
        if index > 0:
            if index - 1 not in ends:
                ends[index - 1] = store.end_state(index - 1)
            start = ends[index - 1]
        point = point_of(case, settings, index, value, from_state=start, direction=directions[index])
        row = point.summary.iloc[0]
        state = tuple(float(row[name]) for name in store.ends)
        ends[index] = state if all(math.isfinite(v) for v in state) else None
        yield point


@dataclasses.dataclass(frozen=True)
class SweepOutcome:
    """Where a sweep was written and how it went."""

    folder: Path
    points: int
    computed: int
    resumed: int
    failed: int
    wall_time: float


class Sweep:
    """A sweep checked and ready to run: :func:`open_sweep` makes it, :meth:`run` runs it.

    Everything that can be refused (the settings, the folder, the workers, the scheduler) is
    refused by :func:`open_sweep` before anything is created; what :meth:`run` raises comes
    after work started, and every point finished by then is kept in the folder.
    """

    def __init__(
        self, case: Case | FrictionChain, settings: SweepSettings, store: _Store, workers: int, client: Any, lock: Any
    ) -> None:
        self.case, self.settings, self._store, self.workers = case, settings, store, workers
        self._client, self._lock = client, lock

    @property
    def folder(self) -> Path:
        return self._store.folder

    def close(self) -> None:
        """Let go of the folder's lock and the Dask client, if any (:meth:`run` does it)."""
        if self._client is not None:
            self._client.close()
            self._client = None
        self._lock.release()

    def run(self, progress: Callable[[int, int], None] | None = None) -> SweepOutcome:
        """Compute the points not yet done, store each as it finishes, and consolidate the tables.

        ``progress(done, total)`` is called after every stored point.
        """
        started = time.perf_counter()
        store, settings = self._store, self.settings
        try:
            store.open(done=0)
            values = [value for _, value in settings.points]
            done = store.done()
            tasks = [(i, v) for i, v in enumerate(values) if i not in done]
            if progress is not None:
                progress(len(done), len(values))
            if settings.both_ways:  # each point starts where the one before it ended: one after another
                points: Iterable[PointTables] = _points_following(self.case, settings, tasks, store)
            else:  # one way: every point from the case's start, in any order, anywhere
                points = run_tasks(
                    point_function(self.case),
                    tasks,
                    shared=(self.case, settings),
                    keywords={"direction": settings.points[0][0]},
                    workers=self.workers,
                    client=self._client,
                )
            computed = 0
            for point in points:
                store.write_point(point)
                computed += 1
                if progress is not None:
                    progress(len(done) + computed, len(values))
            store.consolidate()
            summary = pd.read_parquet(store.folder / "summary.parquet")
            failed = int((summary.status != "ok").sum())
            wall = time.perf_counter() - started
            store.write_status("complete", done=len(values), failed=failed, wall_time_last_run=wall)
        except OSError as exc:
            where = printable(str(exc.filename)) if exc.filename else printable(str(store.folder))
            raise OscillatorError(
                f"cannot write {where} ({exc.strerror or exc}); the points finished so far are kept: free the space "
                f"or fix the folder, and run the same command to resume",
                field="folder",
            ) from exc
        finally:
            self.close()
        return SweepOutcome(store.folder, len(values), computed, len(done), failed, wall)


def _check_values(case: Case, settings: SweepSettings) -> None:
    """Every swept value finite, and both ends valid values of the parameter (the constraints
    on a parameter are intervals: ``m1 > 0``, ``mu_s >= mu_k``, magnitudes; so the values
    between are valid too)."""
    if not all(math.isfinite(value) for value in settings.values):
        raise InputError(
            f"stop: the values from {settings.start!r} to {settings.stop!r} leave floating point; "
            "give a range of physical size",
            field="stop",
        )
    for name in ("start", "stop"):
        value = getattr(settings, name)
        try:
            point_case(case, settings, value)
        except InputError as error:
            raise InputError(f"{name} = {value!r} is not a valid {settings.param}: {error}", field=name) from None


def open_sweep(
    case: Case | FrictionChain,
    settings: SweepSettings,
    folder: Path,
    *,
    workers: int | None = None,
    scheduler: str | None = None,
) -> Sweep:
    """Check a sweep before anything is created: the folder, the workers, the scheduler.

    Parameters are those of :func:`run_sweep`.

    Raises
    ------
    OscillatorError
        A folder that cannot hold this sweep (a file, another sweep, a damaged sweep), a
        number of workers out of range, or a scheduler that is not an address or cannot be
        reached.
    """
    if isinstance(case, FrictionChain):
        from oscillator.analysis.chain_sweeps import check_chain_sweep

        check_chain_sweep(case, settings)
    else:
        _check_values(case, settings)
    store = _Store(Path(folder), case, settings)
    store.check()
    workers = check_workers(workers)
    client = connect(scheduler) if scheduler else None
    try:
        lock = lock_name(
            store.folder,
            busy=f"folder {printable(str(store.folder))} is being swept by another "
            f"process now; wait for it, or give another folder",
        )
    except OscillatorError:
        if client is not None:
            client.close()
        raise
    return Sweep(case, settings, store, workers, client, lock)


def run_sweep(
    case: Case | FrictionChain,
    settings: SweepSettings,
    folder: Path,
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> SweepOutcome:
    """Run (or resume) a sweep into ``folder``.

    Parameters
    ----------
    case : Case or FrictionChain
        The base case; its start and parameters except the swept one are used for every value.
        A declared system (issue 52) with :class:`~oscillator.analysis.chain_sweeps.
        ChainSweepSettings`: its tables are :func:`~oscillator.analysis.chain_sweeps.
        chain_sweep_columns`'.
    settings : SweepSettings
    folder : Path
        Created if new; if it holds the same sweep, the points already finished are kept.
    workers : int, optional
        Local processes (default: every core; at most 4 per core); 1 runs in this process.
    scheduler : str, optional
        ``tcp://HOST:PORT`` of a Dask scheduler: the points run on that cluster instead.
    progress : callable, optional
        Called as ``progress(done, total)`` after every stored point.
    """
    return open_sweep(case, settings, folder, workers=workers, scheduler=scheduler).run(progress)
