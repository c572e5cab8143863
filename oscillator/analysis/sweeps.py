"""Parameter sweeps (sliding bifurcation diagrams, Sec. 7) and locating where a summary changes.

A sweep runs one simulation per value of a parameter: a transient of forcing periods, then a
recorded window.  For each value it keeps, after the transient,

* every switching point of the chosen mass (``switches``): the value, ``t``, the phase
  ``Omega t mod 2 pi``, kind, boundary, domains, ``x`` and ``v`` of that mass;
* the Poincaré points ``(x1, v1, x2, v2)`` at ``t0 + n T`` (``poincare``);
* a summary row (``summary``): period-n found (Poincaré points repeating within a tolerance)
  or 0, whether the mass rests (``sliding``) and in how many periods, rest time per period,
  switches per period (events that change a domain or a contact; grazing reports, which
  switch nothing, are counted apart), and whether the point ran at all.

Every table carries the swept parameter as a column named after it (e.g. ``Omega``).

Points are computed by :func:`run_point` (a pure function, so the same rows come out serially,
in a process pool or on a Dask cluster) and stored by the parent process as they finish: each
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

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from oscillator.analysis.execution import check_workers, connect, run_tasks
from oscillator.analysis.intervals import rest_intervals, runs
from oscillator.analysis.store import ResumableFolder, identity
from oscillator.errors import InputError, OscillatorError, Reason, SimulationFailed
from oscillator.io.cases import Case, resolve_case, section_times
from oscillator.io.files import atomic_path, lock_name
from oscillator.model.events import EventKind
from oscillator.model.parameters import SweepSettings
from oscillator.text import printable

__all__ = [
    "TABLES",
    "PointTables",
    "Sweep",
    "SweepOutcome",
    "detect_period",
    "open_sweep",
    "read_sweep",
    "run_point",
    "run_sweep",
    "sliding_ranges",
]

#: The values a sweep runs: ``(index, value)``.
Tasks = list[tuple[int, float]]

#: The tables a sweep writes, one Parquet file each.
TABLES = ("switches", "poincare", "summary")


@dataclasses.dataclass(frozen=True)
class PointSummary:
    """One row of ``summary.parquet``, after the swept parameter's own column.

    The defaults are those of a value that failed (``status = "failed"`` and the message).
    """

    index: int  #: the value's place in the sweep, from 0
    status: str = "ok"  #: ``ok`` or ``failed``
    message: str = ""  #: why it failed, else empty
    period: int = 0  #: period-n of the Poincaré points, 0 if none within ``max_period``
    periodic: bool = False
    sliding: bool = False  #: the mass rests on its velocity boundary
    sliding_periods: int = 0  #: recorded periods with a rest in them
    rest_time_per_period: float = math.nan
    switches_per_period: float = math.nan
    crossings_per_period: float = math.nan
    grazings_per_period: float = math.nan
    wall_time: float = math.nan  #: seconds spent on the value
    direction: str = "up"  #: ``up`` or ``down``: the way the sweep went when it ran the value
    #: The state the value's run ended in (NaN if it failed): where a both-ways sweep's next value starts.
    end_x1: float = math.nan
    end_v1: float = math.nan
    end_x2: float = math.nan
    end_v2: float = math.nan
    reason: str = ""  #: why it failed, for a program (:class:`~oscillator.errors.Reason`), else empty

    def row(self, param: str, value: float) -> dict[str, Any]:
        return {param: value, **dataclasses.asdict(self)}


_DTYPES = {"int": "int64", "float": "float64", "bool": "bool", "str": "str"}


def _columns(param: str) -> dict[str, dict[str, str]]:
    """Column names and dtypes of each table; the swept parameter comes first."""
    return {
        "switches": {
            param: "float64",
            "index": "int64",
            "t": "float64",
            "phase": "float64",
            "kind": "str",
            "boundary": "str",
            "from_domain": "int64",
            "to_domain": "int64",
            "x": "float64",
            "v": "float64",
        },
        "poincare": {
            param: "float64",
            "index": "int64",
            "n": "int64",
            "t": "float64",
            "x1": "float64",
            "v1": "float64",
            "x2": "float64",
            "v2": "float64",
        },
        "summary": {param: "float64", **{f.name: _DTYPES[str(f.type)] for f in dataclasses.fields(PointSummary)}},
    }


def _frame(rows: list[dict[str, Any]] | dict[str, Any], columns: dict[str, str]) -> pd.DataFrame:
    frame = pd.DataFrame(rows if isinstance(rows, list) else [rows], columns=list(columns))
    return frame.astype(columns)


@dataclasses.dataclass(frozen=True)
class PointTables:
    """The rows one parameter value contributes to each table."""

    index: int
    value: float
    switches: pd.DataFrame
    poincare: pd.DataFrame
    summary: pd.DataFrame

    def table(self, name: str) -> pd.DataFrame:
        return getattr(self, name)


def detect_period(points: np.ndarray, tolerance: float, max_period: int) -> int:
    """The smallest ``n <= max_period`` with ``P_(k+n) = P_k`` for every recorded ``k``, else 0.

    ``points`` are the Poincaré points in order, one row each; two points are equal when their
    distance is at most ``tolerance (1 + |P|)``.
    """
    scale = tolerance * (1.0 + np.max(np.abs(points))) if points.size else tolerance
    for n in range(1, min(max_period, len(points) - 1) + 1):
        if np.max(np.linalg.norm(points[n:] - points[:-n], axis=1)) <= scale:
            return n
    return 0


def _rest_time(
    events: pd.DataFrame, mass: int, domain_at_start: int, start: float, stop: float
) -> tuple[float, list[tuple[float, float]]]:
    """Total rest time of ``mass`` in ``[start, stop]`` and the rest intervals."""
    intervals = rest_intervals(events, mass, domain_at_start == 0, start, stop)
    return sum(b - a for a, b in intervals), intervals


def _point_case(
    case: Case, settings: SweepSettings, value: float, from_state: tuple[float, ...] | None = None
) -> tuple[Case, np.ndarray]:
    """The case of one swept value (from ``from_state``, ``(x1, v1, x2, v2)`` at ``t0``, if given),
    and its Poincaré times: one at the start of each recorded period (the run ends with the
    last period)."""
    param = settings.param
    begin = {} if from_state is None else dict(zip(("x1", "v1", "x2", "v2"), from_state, strict=True))
    point = resolve_case(case, **{param: value}, **begin)
    return point, section_times(point, settings.transient, settings.transient + settings.record)


def _periods_with_rest(intervals: list[tuple[float, float]], start: float, period: float, record: int) -> int:
    """How many of the ``record`` periods from ``start`` hold a rest (a rest spanning several
    periods counts in each of them)."""
    periods: set[int] = set()
    for a, b in intervals:
        first = min(int((a - start) // period), record - 1)
        last = min(math.ceil((b - start) / period), record)
        periods.update(range(first, max(last, first + 1)))
    return len(periods)


def run_point(
    case: Case,
    settings: SweepSettings,
    index: int,
    value: float,
    *,
    from_state: tuple[float, ...] | None = None,
    direction: str = "up",
) -> PointTables:
    """Simulate one parameter value and tabulate what the sweep keeps of it.

    The run starts from the case's start, or from ``from_state`` (``x1, v1, x2, v2`` at ``t0``:
    a both-ways sweep's previous end).  A value the model refuses (``Omega <= 0``) or a solver
    failure gives a summary row with ``status = "failed"`` and the message, and no other rows.
    """
    from oscillator.hybrid.recording import SaveAt
    from oscillator.hybrid.simulate import simulate  # here: a sweep's settings are checked before it loads

    param, mass = settings.param, settings.mass
    columns = _columns(param)
    started = time.perf_counter()
    try:
        point, marks = _point_case(case, settings, value, from_state)
        result = simulate(point, t_end=float(marks[-1]), save=SaveAt(ts=marks[:-1], events_from=float(marks[0])))
    except OscillatorError as error:
        reason = error.reason if isinstance(error, SimulationFailed) else Reason.REFUSED
        failed = PointSummary(
            index,
            "failed",
            str(error),
            wall_time=time.perf_counter() - started,
            direction=direction,
            reason=reason.value,
        )
        empty = _frame([], columns["switches"]), _frame([], columns["poincare"])
        return PointTables(index, value, *empty, _frame(failed.row(param, value), columns["summary"]))

    start, stop = float(marks[0]), float(marks[-1])
    events = result.events
    window = events[(events.mass == mass) & (events.t >= start) & (events.t <= stop)]
    switches = _switch_rows(window, param, value, index, mass, point.parameters.Omega, columns["switches"])
    trajectory = result.trajectory
    poincare = _poincare_rows(trajectory, param, value, index, settings.transient, columns["poincare"])
    n = detect_period(poincare[["x1", "v1", "x2", "v2"]].to_numpy(), settings.period_tolerance, settings.max_period)
    rest, intervals = _rest_time(events, mass, int(trajectory[f"domain{mass}"].iloc[0]), start, stop)
    crossings = window[window.kind.isin(EventKind.values_where(lambda kind: kind.reaches_velocity_boundary))]
    grazings = window[~window.kind.isin(EventKind.values_where(lambda kind: kind.switches))]  # reports only
    record = settings.record
    summary = PointSummary(
        index,
        period=n,
        periodic=n > 0,
        sliding=rest > 0,
        sliding_periods=_periods_with_rest(intervals, start, point.parameters.period, record),
        rest_time_per_period=rest / record,
        switches_per_period=(len(window) - len(grazings)) / record,
        crossings_per_period=len(crossings) / record,
        grazings_per_period=len(grazings) / record,
        wall_time=time.perf_counter() - started,
        direction=direction,
        end_x1=result.final_state[1],
        end_v1=result.final_state[2],
        end_x2=result.final_state[3],
        end_v2=result.final_state[4],
    ).row(param, value)
    return PointTables(index, value, switches, poincare, _frame(summary, columns["summary"]))


def _switch_rows(
    window: pd.DataFrame, param: str, value: float, index: int, mass: int, omega: float, columns: dict[str, str]
) -> pd.DataFrame:
    """``switches.parquet``'s rows of one value: the swept mass's events in the recorded window."""
    rows = [
        {
            param: value,
            "index": index,
            "t": row.t,
            "phase": math.fmod(omega * row.t, 2 * math.pi),
            "kind": row.kind,
            "boundary": row.boundary,
            "from_domain": row.from_domain,
            "to_domain": row.to_domain,
            "x": getattr(row, f"x{mass}"),
            "v": getattr(row, f"v{mass}"),
        }
        for row in window.itertuples()
    ]
    return _frame(rows, columns)


def _poincare_rows(
    trajectory: pd.DataFrame, param: str, value: float, index: int, transient: int, columns: dict[str, str]
) -> pd.DataFrame:
    """``poincare.parquet``'s rows of one value: the state once a period after the transient."""
    rows = [
        {
            param: value,
            "index": index,
            "n": transient + k,
            "t": row.t,
            "x1": row.x1,
            "v1": row.v1,
            "x2": row.x2,
            "v2": row.v2,
        }
        for k, row in enumerate(trajectory.itertuples())
    ]
    return _frame(rows, columns)


def sliding_ranges(summary: pd.DataFrame, param: str, direction: str | None = None) -> list[tuple[float, float]]:
    """The ranges ``(first, last)`` of consecutive swept values at which the mass slides (of
    the values run going ``direction``, if given: a both-ways sweep has each value twice)."""
    if direction is not None and "direction" in summary.columns:
        summary = summary[summary.direction == direction]
    ok = summary[summary.status == "ok"].sort_values(param)
    values = ok[param].tolist()
    return [(values[i], values[j - 1]) for slides, i, j in runs(ok.sliding.tolist()) if slides]


# --------------------------------------------------------------------------- storage


class _Store(ResumableFolder):
    """A sweep folder: its identity, the finished points, and the consolidated tables."""

    def __init__(self, folder: Path, case: Case, settings: SweepSettings) -> None:
        super().__init__(folder, "sweep.json", identity(case, settings=settings))
        self.settings = settings

    def check_parts(self) -> None:
        """Every part named ``NNNNNN.TABLE.parquet``, a plain file whose footer reads."""
        for part in sorted(self.parts.glob("*.parquet")):
            try:
                index, name, _ = part.name.split(".")
                int(index)
                if name not in TABLES or not stat.S_ISREG(os.stat(part).st_mode):
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

    def end_state(self, index: int) -> tuple[float, ...] | None:
        """The state a stored point ended in, or None (no such point, or it failed)."""
        path = self.parts / f"{index:06d}.summary.parquet"
        if not path.is_file():
            return None
        row = pd.read_parquet(path).iloc[0]
        state = tuple(float(row.get(f"end_{name}", math.nan)) for name in ("x1", "v1", "x2", "v2"))
        return state if all(math.isfinite(v) for v in state) else None

    def write_point(self, point: PointTables) -> None:
        for name in TABLES:  # the summary last: it marks the point done
            with atomic_path(self.parts / f"{point.index:06d}.{name}.parquet") as temporary:
                point.table(name).to_parquet(temporary, index=False)

    def consolidate(self) -> None:
        """Stream the parts, in parameter order, into one Parquet file per table."""
        for name in TABLES:
            with atomic_path(self.folder / f"{name}.parquet") as temporary:
                writer = None
                try:
                    for part in sorted(self.parts.glob(f"*.{name}.parquet")):
                        table = pq.read_table(part)
                        if writer is None:
                            writer = pq.ParquetWriter(temporary, table.schema)
                        writer.write_table(table.cast(writer.schema))
                    if writer is None:
                        columns = _columns(self.settings.param)[name]
                        pq.write_table(pa.Table.from_pandas(_frame([], columns), preserve_index=False), temporary)
                finally:
                    if writer is not None:
                        writer.close()


def read_sweep(folder: Path) -> dict[str, pd.DataFrame]:
    """The consolidated tables of a finished sweep folder."""
    folder = Path(folder)
    missing = [name for name in TABLES if not (folder / f"{name}.parquet").is_file()]
    if missing:
        raise InputError(f"{folder} holds no finished sweep (no {missing[0]}.parquet)", field="folder")
    return {name: pd.read_parquet(folder / f"{name}.parquet") for name in TABLES}


# --------------------------------------------------------------------------- execution


def _points_following(case: Case, settings: SweepSettings, tasks: Tasks, store: _Store) -> Iterator[PointTables]:
    """A both-ways sweep: each point from the state the point before it ended in (read from
    its stored summary when resuming), the first from the case's start; after a failed point,
    from the case's start again."""
    directions = dict(enumerate(direction for direction, _ in settings.points))
    ends: dict[int, tuple[float, ...] | None] = {}
    for index, value in tasks:
        start = None
        if index > 0:
            if index - 1 not in ends:
                ends[index - 1] = store.end_state(index - 1)
            start = ends[index - 1]
        point = run_point(case, settings, index, value, from_state=start, direction=directions[index])
        row = point.summary.iloc[0]
        state = tuple(float(row[f"end_{name}"]) for name in ("x1", "v1", "x2", "v2"))
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
        self, case: Case, settings: SweepSettings, store: _Store, workers: int, client: Any, lock: Any
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
                    run_point,
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
            _point_case(case, settings, value)
        except InputError as error:
            raise InputError(f"{name} = {value!r} is not a valid {settings.param}: {error}", field=name) from None


def open_sweep(
    case: Case,
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
    case: Case,
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
    case : Case
        The base case; its start and parameters except the swept one are used for every value.
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
