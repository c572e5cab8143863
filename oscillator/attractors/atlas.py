"""The regime atlas: what the machine does at every point of a plane of two parameters.

At each point ``(x, y)`` of a grid the attractors are found (:func:`~oscillator.attractors.finding.land`
and :func:`~oscillator.attractors.finding.group`) from a few starts: the case's own start (a
*fresh* start, with the longer transient) and *seeds*: the attractors found at the three
nearest points of the row before, one per regime (their last section points, with a short
transient, since they start close to an attractor).  Rows are computed in order, the points of a row in parallel:
each point depends only on the row before, so the atlas is the same for any number of workers.

For each attractor of a point the atlas keeps its period, rest intervals of each mass and
contact onsets per forcing period, the largest impact velocity at a contact onset, and its
largest Lyapunov exponent: for a periodic orbit ``log |mu_1| / (n T)`` from the monodromy of
one return at its cycle (the derivative through every switch, :func:`~oscillator.orbits.shooting.period_map`),
for an aperiodic set the QR average of :func:`~oscillator.attractors.lyapunov.lyapunov`.  Its
*regime* is a label built from these (``P1``, ``P1 m2 rests``, ``P2 contact``, ``chaotic``, ...),
and a point where several attractors coexist keeps each, with their number.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from oscillator.analysis.execution import Pool, check_runner, run_tasks
from oscillator.attractors.finding import Attractor, AttractorSettings, group, land, largest_exponent
from oscillator.attractors.lyapunov import lyapunov
from oscillator.errors import InputError, OscillatorError
from oscillator.io.cases import Case, resolve_case
from oscillator.model.parameters import Parameters
from oscillator.orbits.shooting import check_count, period_map
from oscillator.presenting import presenter
from oscillator.text import printable, shown

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

__all__ = [
    "Atlas",
    "AtlasAxis",
    "AtlasSettings",
    "atlas_identity",
    "atlas_point",
    "atlas_row",
    "fresh_starts",
    "regime_of",
    "run_atlas",
]

#: The most points along one axis of the atlas.
MAX_POINTS = 2000
#: ``lambda_1 T`` above which an aperiodic attractor is chaotic.
CHAOTIC = 0.01
COLUMNS = {
    "row": "int64",
    "column": "int64",
    "attractor": "int64",
    "coexisting": "int64",
    "regime": "str",
    "period": "int64",
    "rests_m1": "float64",
    "rests_m2": "float64",
    "contacts": "float64",
    "impact_velocity": "float64",
    "lyapunov": "float64",
    "starts": "int64",
    "status": "str",
    "message": "str",
    "x1": "float64",
    "v1": "float64",
    "x2": "float64",
    "v2": "float64",
}


@dataclass(frozen=True)
class AtlasAxis:
    """One axis of the plane: a parameter and ``count`` values from ``low`` to ``high``."""

    name: str
    low: float
    high: float
    count: int

    def __post_init__(self) -> None:
        if self.name not in Parameters.names():
            raise InputError(
                f"axis {shown(self.name)} is not a parameter; give one of {', '.join(Parameters.names())}",
                field="axis",
            )
        if not (math.isfinite(self.low) and math.isfinite(self.high) and self.low < self.high):
            raise InputError(
                f"axis {self.name}: from {self.low!r} to {self.high!r} is not a range; give the lower end first",
                field="axis",
            )
        check_count(self.count, f"axis {self.name}: its count", 2, MAX_POINTS)

    @property
    def values(self) -> np.ndarray:
        return np.linspace(self.low, self.high, self.count)


@dataclass(frozen=True)
class AtlasSettings:
    """How each point is computed.

    Attributes
    ----------
    fresh_transient : int
        Forcing periods before recording, for the case's own start.
    seed_transient : int
        The same for a seed from the row before (it starts near an attractor).
    record : int
        Forcing periods recorded (the longest period found is ``record - 1``).
    lyapunov_periods : int
        Periods averaged for an aperiodic attractor's largest exponent.
    starts : int
        Fresh starts at every point (1 to 1000): the case's start, and ``starts - 1`` more
        (:func:`fresh_starts`), so that coexisting attractors are found at a point without a
        seed that reaches them.
    """

    fresh_transient: int = 40
    seed_transient: int = 16
    record: int = 10
    lyapunov_periods: int = 100
    starts: int = 1

    def __post_init__(self) -> None:
        for name, least in (("fresh_transient", 1), ("seed_transient", 1), ("record", 2), ("lyapunov_periods", 1)):
            check_count(getattr(self, name), name, least, 1_000_000)
        check_count(self.starts, "starts", 1, 1000)

    def landing(self, transient: int) -> AttractorSettings:
        return AttractorSettings(
            transient=transient, record=self.record, max_period=self.record - 1, lyapunov_periods=0
        )


def fresh_starts(case: Case, count: int) -> np.ndarray:
    """``count`` starts ``(x1, v1, x2, v2)``: the case's own start first, then the points of a
    Halton sequence (unscrambled: the same starts every time) in the box centred on it whose
    half-width in every component is ``max(1, max |start|)`` (in m and m/s)."""
    from scipy.stats import qmc

    start = np.array(case.initial.y, dtype=float)
    if count == 1:
        return start[None, :]
    width = max(1.0, float(np.max(np.abs(start))))
    unit = qmc.Halton(d=4, scramble=False).random(count)[1:]  # the first point is the box's corner
    return np.vstack([start, start - width + 2.0 * width * unit])


def regime_of(
    period: int,
    rests: tuple[float, float],
    contacts: float,
    largest: float,
    forcing: float,
    rest_time: tuple[float, float] = (0.0, 0.0),
) -> str:
    """The regime's label: ``P<n>`` (or ``chaotic``, ``quasi-periodic``, ``aperiodic``), then
    ``m1 rests`` / ``m2 rests`` (rest intervals, or at rest throughout) and ``contact`` when they
    happen."""
    if period:
        label = f"P{period}"
    elif math.isfinite(largest) and largest * forcing > CHAOTIC:
        label = "chaotic"
    elif math.isfinite(largest) and largest * forcing > -CHAOTIC:
        label = "quasi-periodic"
    else:
        label = "aperiodic"
    resting = zip((1, 2), rests, rest_time, strict=True)
    parts = [label] + [f"m{mass} rests" for mass, rate, share in resting if rate or share > 0]
    if contacts:
        parts.append("contact")
    return " ".join(parts)


def _largest_exponent(case: Case, attractor: Attractor, settings: AtlasSettings) -> float:
    """``log |mu_1| / (n T)`` at a periodic attractor's cycle (one return's monodromy), or the QR
    average for an aperiodic one; NaN where it cannot be computed (the run fails there)."""
    period = case.parameters.period
    try:
        if attractor.period:
            image = period_map(case, case.initial.t0, attractor.points[-1], attractor.period, derivative=True)
            assert image.monodromy is not None
            return largest_exponent(np.linalg.eigvals(image.monodromy), attractor.period * period)
        spectrum = lyapunov(case, guess=attractor.points[-1], transient=0, periods=settings.lyapunov_periods)
        return spectrum.largest
    except OscillatorError:
        return math.nan


def _impact_velocity(case: Case, start: np.ndarray, periods: int) -> float:
    """The largest relative velocity at a contact onset over ``periods`` forcing periods from ``start``."""
    from oscillator.hybrid.simulate import simulate
    from oscillator.model.events import EventKind

    begin = dict(zip(("x1", "v1", "x2", "v2"), (float(v) for v in start), strict=True))
    run = resolve_case(case, **begin)
    result = simulate(run, t_end=run.initial.t0 + periods * run.parameters.period, record_trajectory=False)
    events = result.events
    onsets = events[events.kind.isin(EventKind.values_where(lambda kind: kind.contact_starts))]
    if onsets.empty:
        return 0.0
    left = onsets.kind.map(lambda kind: EventKind(kind).contact == "left")
    speed = np.where(left, np.abs(onsets.v1 - onsets.v2), np.abs(onsets.v1))
    return float(np.max(speed))


def atlas_point(
    case: Case,
    settings: AtlasSettings,
    x: AtlasAxis,
    y: AtlasAxis,
    row: int,
    column: int,
    seeds: Sequence[Sequence[float]],
) -> pd.DataFrame:
    """The attractors at one point of the plane (a pure function): one row each, or one row with
    ``status = "failed"`` when every start failed."""
    try:
        point = resolve_case(case, **{x.name: float(x.values[column]), y.name: float(y.values[row])})
    except OscillatorError as error:
        return _failed(row, column, str(error))
    fresh = settings.landing(settings.fresh_transient)
    landings = [land(point, fresh, k, tuple(start)) for k, start in enumerate(fresh_starts(point, settings.starts))]
    seed_settings = settings.landing(settings.seed_transient)
    landings += [land(point, seed_settings, len(landings) + k, tuple(seed)) for k, seed in enumerate(seeds)]
    found, _ = group(landings, seed_settings)
    if not found:
        return _failed(row, column, next((item.message for item in landings if item.message), "every start failed"))
    forcing = point.parameters.period
    rows = []
    for attractor in found:
        largest = _largest_exponent(point, attractor, settings)
        impact = _impact_velocity(point, attractor.points[-1], max(attractor.period, 1)) if attractor.contacts else 0.0
        rows.append(
            {
                "row": row,
                "column": column,
                "attractor": attractor.id,
                "coexisting": len(found),
                "regime": regime_of(
                    attractor.period, attractor.rests, attractor.contacts, largest, forcing, attractor.rest_time
                ),
                "period": attractor.period,
                "rests_m1": attractor.rests[0],
                "rests_m2": attractor.rests[1],
                "contacts": attractor.contacts,
                "impact_velocity": impact,
                "lyapunov": largest,
                "starts": attractor.starts,
                "status": "ok",
                "message": "",
                **dict(zip(("x1", "v1", "x2", "v2"), (float(v) for v in attractor.points[-1]), strict=True)),
            }
        )
    return pd.DataFrame(rows).astype(COLUMNS)


def _failed(row: int, column: int, message: str) -> pd.DataFrame:
    values: dict[str, Any] = {name: (math.nan if kind == "float64" else 0) for name, kind in COLUMNS.items()}
    values.update(row=row, column=column, attractor=-1, regime="failed", status="failed", message=message)
    return pd.DataFrame([values]).astype(COLUMNS)


def seeds_for(previous: pd.DataFrame | None, column: int) -> list[tuple[float, ...]]:
    """The seeds of a point: the attractors of the three nearest points of the row before, one per
    regime (the nearest point's), in a fixed order."""
    if previous is None or previous.empty:
        return []
    near = previous[((previous.column - column).abs() <= 1) & (previous.status == "ok")].copy()
    near["distance"] = (near.column - column).abs()
    near = near.sort_values(["distance", "column", "attractor"], kind="stable").drop_duplicates("regime")
    return [tuple(float(v) for v in state) for state in near[["x1", "v1", "x2", "v2"]].to_numpy()]


def atlas_row(
    case: Case,
    settings: AtlasSettings,
    x: AtlasAxis,
    y: AtlasAxis,
    row: int,
    previous: pd.DataFrame | None,
    *,
    workers: int = 1,
    client: Any = None,
    pool: Pool | None = None,
    progress: Callable[[int], None] | None = None,
) -> pd.DataFrame:
    """Every point of one row, seeded from ``previous`` (the row before's table), in parallel (on
    ``pool`` when given: one pool for all the rows)."""
    tasks = [(row, column, seeds_for(previous, column)) for column in range(x.count)]
    parts = []
    shared = (case, settings, x, y)
    for part in run_tasks(atlas_point, tasks, shared=shared, workers=workers, client=client, pool=pool):
        parts.append(part)
        if progress is not None:
            progress(len(parts))
    table = pd.concat(parts, ignore_index=True)
    return table.sort_values(["column", "attractor"], kind="stable").reset_index(drop=True)


def atlas_identity(case: Case, x: AtlasAxis, y: AtlasAxis, settings: AtlasSettings) -> dict[str, Any]:
    from oscillator.io.cases import case_to_toml

    return {
        "case": case_to_toml(case),
        "x": dataclasses.asdict(x),
        "y": dataclasses.asdict(y),
        "settings": dataclasses.asdict(settings),
    }


@dataclass(frozen=True)
class Atlas:
    """The atlas of a plane: ``table`` has one row per attractor of each point (``row``,
    ``column`` and the two parameters' values first)."""

    case: Case
    x: AtlasAxis
    y: AtlasAxis
    table: pd.DataFrame

    def plot(self, by: str = "regime") -> Figure:
        """The plane coloured by ``by``: ``regime``, ``period``, ``coexisting``, ``lyapunov`` or
        ``impact_velocity`` (as ``oscillator atlas`` draws it)."""
        return presenter().plot_global(self, by=by)

    def grid(self) -> tuple[np.ndarray, np.ndarray, list[str]]:
        """``(codes, coexisting, regimes)``: at each point the code of its regime (the regime of
        its first attractor; an index into ``regimes``, sorted) and how many attractors coexist,
        both ``(y.count, x.count)``."""
        first = self.table[self.table.attractor <= 0].drop_duplicates(["row", "column"])
        regimes = sorted(first.regime.unique())
        codes = np.full((self.y.count, self.x.count), -1)
        coexisting = np.zeros((self.y.count, self.x.count), dtype=int)
        codes[first.row, first.column] = [regimes.index(r) for r in first.regime]
        coexisting[first.row, first.column] = first.coexisting
        return codes, coexisting, regimes


def run_atlas(
    case: Case,
    x: AtlasAxis,
    y: AtlasAxis,
    *,
    settings: AtlasSettings | None = None,
    store: Any = None,
    workers: int = 1,
    client: Any = None,
    progress: Callable[[int, int], None] | None = None,
) -> Atlas:
    """The atlas, row by row (each row's points in parallel, seeded from the row before); with a
    ``store`` (:class:`~oscillator.attractors.store.LandingStore`), each row kept as it finishes
    and the rows already there read back (a run that resumes)."""
    settings = settings or AtlasSettings()
    workers = check_runner(workers, client, progress)
    if x.name == y.name:
        raise InputError(f"both axes are {x.name}; give two different parameters", field="axis")
    with contextlib.ExitStack() as stack:
        pool = stack.enter_context(Pool(workers)) if client is None and workers > 1 else None
        rows = _rows(case, x, y, settings, store, client, pool, progress)
    frame = pd.concat(rows, ignore_index=True)
    frame.insert(2, x.name, x.values[frame.column.to_numpy()])
    frame.insert(3, y.name, y.values[frame.row.to_numpy()])
    return Atlas(case, x, y, frame)


def _checked_row(table: pd.DataFrame, row: int, count: int, part: Any) -> pd.DataFrame:
    """A stored row of the atlas, checked: every column there with its type, the row's number,
    each of its ``count`` points once or more and no other; else refused naming the part."""
    why = ""
    missing = [name for name in COLUMNS if name not in table.columns]
    if missing:
        why = f"no column {', '.join(missing)}"
    else:
        kinds = {"int64": pd.api.types.is_integer_dtype, "float64": pd.api.types.is_numeric_dtype}
        wrong = [
            name for name, dtype in COLUMNS.items() if not kinds.get(dtype, pd.api.types.is_string_dtype)(table[name])
        ]
        if wrong:
            why = f"column {', '.join(wrong)} of the wrong type"
        else:
            table = table[list(COLUMNS)].astype(COLUMNS)
    if not why and (not (table["row"] == row).all() or set(table["column"]) != set(range(count)) or not len(table)):
        why = f"its rows are not row {row}'s points 0 to {count - 1}"
    if not why and not table.status.isin(["ok", "failed"]).all():
        why = "a status that is neither ok nor failed"
    elif not why and not np.isfinite(table.loc[table.status == "ok", ["x1", "v1", "x2", "v2"]].to_numpy()).all():
        why = "a state that is not a number"
    if why:
        raise InputError(
            f"{printable(str(part))} is damaged ({why}); delete it and run the same command to compute that row again",
            field="folder",
        )
    return table


def _rows(
    case: Case,
    x: AtlasAxis,
    y: AtlasAxis,
    settings: AtlasSettings,
    store: Any,
    client: Any,
    pool: Pool | None,
    progress: Callable[[int, int], None] | None,
) -> list[pd.DataFrame]:
    rows: list[pd.DataFrame] = []
    previous: pd.DataFrame | None = None
    total = x.count * y.count
    for row in range(y.count):
        table = store.read_table(f"row-{row:05d}") if store is not None else None
        if table is not None:
            table = _checked_row(table, row, x.count, store.parts / f"row-{row:05d}.parquet")
        if table is None:

            def step(count: int, done: int = row * x.count) -> None:
                if progress is not None:
                    progress(done + count, total)

            table = atlas_row(case, settings, x, y, row, previous, client=client, pool=pool, progress=step)
            if store is not None:
                store.write_table(table, f"row-{row:05d}")
        elif progress is not None:
            progress((row + 1) * x.count, total)
        rows.append(table)
        previous = table
    return rows
