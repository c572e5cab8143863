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

import concurrent.futures as cf
import dataclasses
import json
import math
import multiprocessing
import os
import time
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from oscillator._errors import OscillatorError
from oscillator._files import atomic_folder, atomic_path, replace_file
from oscillator.cases import Case, case_to_toml
from oscillator.parameters import SweepSettings
from oscillator.simulation import resolve_case, simulate

__all__ = [
    "TABLES",
    "Location",
    "PointTables",
    "SweepOutcome",
    "detect_period",
    "locate",
    "read_sweep",
    "run_point",
    "run_sweep",
    "sliding_ranges",
]

#: The tables a sweep writes, one Parquet file each.
TABLES = ("switches", "poincare", "summary")
_INDICATORS = {"sliding": "sliding", "period": "period", "grazing": "switches_per_period"}


def _columns(param: str) -> dict[str, dict[str, str]]:
    """Column names and dtypes of each table; the swept parameter comes first."""
    return {
        "switches": {param: "float64", "index": "int64", "t": "float64", "phase": "float64", "kind": "str",
                     "boundary": "str", "from_domain": "int64", "to_domain": "int64", "x": "float64",
                     "v": "float64"},
        "poincare": {param: "float64", "index": "int64", "n": "int64", "t": "float64", "x1": "float64",
                     "v1": "float64", "x2": "float64", "v2": "float64"},
        "summary": {param: "float64", "index": "int64", "status": "str", "message": "str", "period": "int64",
                    "periodic": "bool", "sliding": "bool", "sliding_periods": "int64",
                    "rest_time_per_period": "float64", "switches_per_period": "float64",
                    "crossings_per_period": "float64", "grazings_per_period": "float64", "wall_time": "float64"},
    }  # fmt: skip


def _frame(rows: list[dict] | dict, columns: dict[str, str]) -> pd.DataFrame:
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


def _rest_time(events: pd.DataFrame, mass: int, domain_at_start: int, start: float, stop: float) -> tuple:
    """Total rest time of ``mass`` in ``[start, stop]`` and the rest intervals."""
    intervals, resting_since = [], start if domain_at_start == 0 else None
    for row in events[(events.mass == mass) & (events.from_domain != events.to_domain)].itertuples():
        if not start <= row.t <= stop:
            continue
        if row.to_domain == 0 and resting_since is None:
            resting_since = row.t
        elif row.to_domain != 0 and resting_since is not None:
            intervals.append((resting_since, row.t))
            resting_since = None
    if resting_since is not None:
        intervals.append((resting_since, stop))
    return sum(b - a for a, b in intervals), intervals


def run_point(case: Case, settings: SweepSettings, index: int, value: float) -> PointTables:
    """Simulate one parameter value and tabulate what the sweep keeps of it.

    A value the model refuses (e.g. ``Omega <= 0``) or a solver failure gives a summary row
    with ``status = "failed"`` and the message, and no other rows.
    """
    param, mass = settings.param, settings.mass
    columns = _columns(param)
    started = time.perf_counter()
    try:
        point = resolve_case(case, **{param: value})
        period = point.parameters.period
        t0 = point.initial.t0
        grid = t0 + period * np.arange(settings.transient, settings.transient + settings.record + 1)
        result = simulate(point, t_end=float(grid[-1]), t_eval=grid, keep_events_from=float(grid[0]))
    except OscillatorError as error:
        summary = {param: value, "index": index, "status": "failed", "message": str(error), "period": 0,
                   "periodic": False, "sliding": False, "sliding_periods": 0, "rest_time_per_period": math.nan,
                   "switches_per_period": math.nan, "crossings_per_period": math.nan,
                   "grazings_per_period": math.nan, "wall_time": time.perf_counter() - started}  # fmt: skip
        empty = [_frame([], columns["switches"]), _frame([], columns["poincare"])]
        return PointTables(index, value, *empty, _frame(summary, columns["summary"]))

    start, stop = float(grid[0]), float(grid[-1])
    events = result.events
    window = events[(events.mass == mass) & (events.t >= start) & (events.t <= stop)]
    omega = point.parameters.Omega
    switches = _frame(
        [
            {param: value, "index": index, "t": row.t, "phase": math.fmod(omega * row.t, 2 * math.pi),
             "kind": row.kind, "boundary": row.boundary, "from_domain": row.from_domain,
             "to_domain": row.to_domain, "x": getattr(row, f"x{mass}"), "v": getattr(row, f"v{mass}")}
            for row in window.itertuples()
        ],
        columns["switches"],
    )  # fmt: skip
    trajectory = result.trajectory
    poincare = _frame(
        [
            {param: value, "index": index, "n": settings.transient + k, "t": row.t, "x1": row.x1, "v1": row.v1,
             "x2": row.x2, "v2": row.v2}
            for k, row in enumerate(trajectory.itertuples())
        ],
        columns["poincare"],
    )  # fmt: skip
    points = poincare[["x1", "v1", "x2", "v2"]].to_numpy()
    n = detect_period(points, settings.period_tolerance, settings.max_period)
    domain_at_start = int(trajectory[f"domain{mass}"].iloc[0])
    rest, intervals = _rest_time(events, mass, domain_at_start, start, stop)
    periods_with_rest: set[int] = set()
    for a, b in intervals:  # a rest spanning several periods counts in each of them
        first = min(int((a - start) // period), settings.record - 1)
        last = min(math.ceil((b - start) / period), settings.record)
        periods_with_rest.update(range(first, max(last, first + 1)))
    crossings = window[window.kind.isin(["passable", "sliding_onset"])]
    grazings = window[window.kind == "grazing"]  # reports: they switch nothing
    summary = {param: value, "index": index, "status": "ok", "message": "", "period": n, "periodic": n > 0,
               "sliding": rest > 0, "sliding_periods": len(periods_with_rest),
               "rest_time_per_period": rest / settings.record,
               "switches_per_period": (len(window) - len(grazings)) / settings.record,
               "crossings_per_period": len(crossings) / settings.record,
               "grazings_per_period": len(grazings) / settings.record,
               "wall_time": time.perf_counter() - started}  # fmt: skip
    return PointTables(index, value, switches, poincare, _frame(summary, columns["summary"]))


def sliding_ranges(summary: pd.DataFrame, param: str) -> list[tuple[float, float]]:
    """The ranges ``(first, last)`` of consecutive swept values at which the mass slides."""
    ok = summary[summary.status == "ok"].sort_values(param)
    ranges: list[tuple[float, float]] = []
    start = previous = None
    for value, flag in zip(ok[param], ok.sliding, strict=True):
        if flag and start is None:
            start = value
        if not flag and start is not None:
            ranges.append((start, previous))
            start = None
        previous = value
    if start is not None:
        ranges.append((start, previous))
    return ranges


# --------------------------------------------------------------------------- storage


class _Store:
    """A sweep folder: its identity, the finished points, and the consolidated tables."""

    def __init__(self, folder: Path, case: Case, settings: SweepSettings) -> None:
        self.folder = folder
        self.parts = folder / "parts"
        self.identity = {"case": case_to_toml(case), "settings": dataclasses.asdict(settings)}
        self.settings = settings

    def open(self) -> None:
        """Create the folder, or check that it holds this very sweep (to resume it)."""
        marker = self.folder / "sweep.json"
        if marker.is_file():
            stored = json.loads(marker.read_text(encoding="utf-8"))
            if stored.get("identity") != self.identity:
                raise OscillatorError(
                    f"--out {self.folder} holds a different sweep (another case or settings); give a new "
                    f"folder, or the same case and settings to resume it",
                    field="--out",
                )
            return
        if self.folder.exists() and any(self.folder.iterdir()):
            raise OscillatorError(
                f"--out {self.folder} exists and is not a sweep folder; give a new folder", field="--out"
            )
        try:  # the new folder appears whole (parts/, case.toml, sweep.json) or not at all
            with atomic_folder(self.folder) as temporary:
                (temporary / "parts").mkdir()
                (temporary / "case.toml").write_text(self.identity["case"], encoding="utf-8")
                (temporary / "sweep.json").write_text(self._status("running", done=0), encoding="utf-8")
        except OSError as exc:
            raise OscillatorError(
                f"--out {self.folder}: cannot create it ({exc.strerror}); choose a writable folder", field="--out"
            ) from exc

    def _status(self, status: str, **extra) -> str:
        info = {"identity": self.identity, "status": status, "param": self.settings.param,
                "points": self.settings.steps, **extra}  # fmt: skip
        return json.dumps(info, indent=2, default=str)

    def write_status(self, status: str, **extra) -> None:
        replace_file(self.folder / "sweep.json", self._status(status, **extra))

    def done(self) -> set[int]:
        return {int(p.name.split(".")[0]) for p in self.parts.glob("*.summary.parquet")}

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
        raise OscillatorError(f"{folder} holds no finished sweep (no {missing[0]}.parquet)", field="DIR")
    return {name: pd.read_parquet(folder / f"{name}.parquet") for name in TABLES}


# --------------------------------------------------------------------------- execution


def _points_serial(case, settings, tasks) -> Iterator[PointTables]:
    for index, value in tasks:
        yield run_point(case, settings, index, value)


def _points_pool(case, settings, tasks, workers: int) -> Iterator[PointTables]:
    """A local process pool; at most ``4 workers`` points in flight, so memory stays flat."""
    context = multiprocessing.get_context("spawn")
    pending = iter(tasks)
    with cf.ProcessPoolExecutor(max_workers=workers, mp_context=context) as pool:
        running = set()

        def fill() -> None:
            for index, value in pending:
                running.add(pool.submit(run_point, case, settings, index, value))
                if len(running) >= 4 * workers:
                    return

        fill()
        while running:
            finished, _ = cf.wait(running, return_when=cf.FIRST_COMPLETED)
            for future in finished:
                running.discard(future)
                yield future.result()
            fill()


def _points_dask(case, settings, tasks, scheduler: str) -> Iterator[PointTables]:
    try:
        from distributed import Client, as_completed
    except ImportError as exc:
        raise OscillatorError(
            "--scheduler needs Dask: pip install 'oscillator[dask]' (dask.distributed)", field="--scheduler"
        ) from exc
    try:
        client = Client(scheduler, timeout="10s")
    except OSError as exc:
        raise OscillatorError(
            f"--scheduler {scheduler}: cannot reach the Dask scheduler ({exc}); check the address", field="--scheduler"
        ) from exc
    try:
        case_on_cluster = client.scatter(case, broadcast=True)
        futures = [client.submit(run_point, case_on_cluster, settings, i, v, pure=False) for i, v in tasks]
        for future in as_completed(futures):
            yield future.result()
            future.release()
    finally:
        client.close()


@dataclasses.dataclass(frozen=True)
class SweepOutcome:
    """Where a sweep was written and how it went."""

    folder: Path
    points: int
    computed: int
    resumed: int
    failed: int
    wall_time: float


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
        Local processes (default: every core); 1 runs in this process.
    scheduler : str, optional
        ``tcp://HOST:PORT`` of a Dask scheduler: the points run on that cluster instead.
    progress : callable, optional
        Called as ``progress(done, total)`` after every stored point.
    """
    started = time.perf_counter()
    store = _Store(Path(folder), case, settings)
    store.open()
    values = settings.values
    done = store.done()
    tasks = [(i, v) for i, v in enumerate(values) if i not in done]
    if progress is not None:
        progress(len(done), len(values))
    if scheduler:
        points: Iterable[PointTables] = _points_dask(case, settings, tasks, scheduler)
    else:
        workers = workers or os.cpu_count() or 1
        points = _points_serial(case, settings, tasks) if workers == 1 or len(tasks) <= 1 else _points_pool(
            case, settings, tasks, workers
        )  # fmt: skip
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
    return SweepOutcome(store.folder, len(values), computed, len(done), failed, wall)


# --------------------------------------------------------------------------- locate


@dataclasses.dataclass(frozen=True)
class Location:
    """Where a summary indicator changes between two parameter values, and the evidence."""

    param: str
    what: str
    lower: float
    upper: float
    iterations: int
    below: pd.DataFrame
    above: pd.DataFrame
    evidence_below: pd.DataFrame
    evidence_above: pd.DataFrame

    @property
    def value(self) -> float:
        """The located parameter: the middle of the final bracket."""
        return 0.5 * (self.lower + self.upper)

    @property
    def width(self) -> float:
        return self.upper - self.lower


def locate(
    case: Case, settings: SweepSettings, what: str, between: tuple[float, float], *, tolerance: float = 1e-8
) -> Location:
    """Bisect ``[a, b]`` until the bracket is narrower than ``tolerance``.

    ``what`` is ``sliding`` (whether the mass rests), ``period`` (the period-n found) or
    ``grazing`` (switches of the mass per period: at a grazing bifurcation a pair of crossings
    appears or disappears).  The indicator must differ at ``a`` and ``b``.
    """
    if what not in _INDICATORS:
        raise OscillatorError(f"--what must be one of {', '.join(_INDICATORS)}, got {what!r}", field="--what")
    column = _INDICATORS[what]
    a, b = float(min(between)), float(max(between))
    if not b > a:
        raise OscillatorError(f"--between needs two different values, got {between}", field="--between")

    def evaluate(value: float) -> PointTables:
        point = run_point(case, settings, 0, value)
        row = point.summary.iloc[0]
        if row.status != "ok":
            raise OscillatorError(f"{settings.param} = {value!r}: {row.message}", field=settings.param)
        return point

    low, high = evaluate(a), evaluate(b)
    if low.summary[column].iloc[0] == high.summary[column].iloc[0]:
        raise OscillatorError(
            f"{what} is the same at {settings.param} = {a!r} and {b!r} ({column} = {low.summary[column].iloc[0]}); "
            f"give two values on either side of a change (see the sweep's summary table)",
            field="--between",
        )
    iterations = 0
    while b - a > tolerance:
        middle = evaluate(0.5 * (a + b))
        iterations += 1
        if middle.summary[column].iloc[0] == low.summary[column].iloc[0]:
            a, low = middle.value, middle
        else:
            b, high = middle.value, middle
    return Location(settings.param, what, a, b, iterations, low.summary, high.summary, low.switches, high.switches)
