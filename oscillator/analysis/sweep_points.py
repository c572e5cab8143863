"""One value of a sweep: :func:`run_point` (a pure function: the same rows come out serially,
in a process pool or on a Dask cluster) and the tables it gives, each with the swept parameter as
a column named after it:

* every switching point of the chosen mass after the transient (``switches``): the value,
  ``t``, the phase ``Omega t mod 2 pi``, kind, boundary, domains, ``x`` and ``v`` of that mass;
* the Poincaré points ``(x1, v1, x2, v2)`` at ``t0 + n T`` (``poincare``);
* a summary row (``summary``): period-n found (Poincaré points repeating within a tolerance)
  or 0, whether the mass rests (``sliding``) and in how many periods, rest time per period,
  switches per period (events that change a domain or a contact; grazing reports, which
  switch nothing, are counted apart), and whether the point ran at all.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np
import pandas as pd

from oscillator.analysis.intervals import rest_intervals, runs
from oscillator.analysis.periods import detect_period
from oscillator.errors import OscillatorError, Reason, SimulationFailed
from oscillator.io.cases import Case, resolve_case, section_times
from oscillator.model.events import EventKind
from oscillator.model.parameters import SweepSettings

__all__ = [
    "TABLES",
    "PointSummary",
    "PointTables",
    "Tasks",
    "frame_of",
    "point_case",
    "point_function",
    "run_point",
    "sliding_ranges",
    "table_columns",
]


#: The values a sweep runs: ``(index, value)``.
Tasks = list[tuple[int, float]]


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


def table_columns(param: str) -> dict[str, dict[str, str]]:
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


def frame_of(rows: list[dict[str, Any]] | dict[str, Any], columns: dict[str, str]) -> pd.DataFrame:
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


def _rest_time(
    events: pd.DataFrame, mass: int, domain_at_start: int, start: float, stop: float
) -> tuple[float, list[tuple[float, float]]]:
    """Total rest time of ``mass`` in ``[start, stop]`` and the rest intervals."""
    intervals = rest_intervals(events, mass, domain_at_start == 0, start, stop)
    return sum(b - a for a, b in intervals), intervals


def point_case(
    case: Case, settings: SweepSettings, value: float, from_state: tuple[float, ...] | None = None
) -> tuple[Case, np.ndarray]:
    """The case of one swept value (from ``from_state``, ``(x1, v1, x2, v2)`` at ``t0``, if given),
    and its Poincaré times: one at the start of each recorded period (the run ends with the
    last period)."""
    param = settings.param
    begin = {} if from_state is None else dict(zip(case.system.state, from_state, strict=True))
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
    columns = table_columns(param)
    started = time.perf_counter()
    try:
        point, marks = point_case(case, settings, value, from_state)
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
        empty = frame_of([], columns["switches"]), frame_of([], columns["poincare"])
        return PointTables(index, value, *empty, frame_of(failed.row(param, value), columns["summary"]))

    start, stop = float(marks[0]), float(marks[-1])
    events = result.events
    window = events[(events.mass == mass) & (events.t >= start) & (events.t <= stop)]
    switches = _switch_rows(window, param, value, index, mass, point.parameters.Omega, columns["switches"])
    trajectory = result.trajectory
    poincare = _poincare_rows(trajectory, param, value, index, settings.transient, columns["poincare"])
    n = detect_period(poincare[list(point.system.state)].to_numpy(), settings.period_tolerance, settings.max_period)
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
    return PointTables(index, value, switches, poincare, frame_of(summary, columns["summary"]))


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
    return frame_of(rows, columns)


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
    return frame_of(rows, columns)


def sliding_ranges(summary: pd.DataFrame, param: str, direction: str | None = None) -> list[tuple[float, float]]:
    """The ranges ``(first, last)`` of consecutive swept values at which the mass slides (of
    the values run going ``direction``, if given: a both-ways sweep has each value twice)."""
    if direction is not None and "direction" in summary.columns:
        summary = summary[summary.direction == direction]
    ok = summary[summary.status == "ok"].sort_values(param)
    values = ok[param].tolist()
    return [(values[i], values[j - 1]) for slides, i, j in runs(ok.sliding.tolist()) if slides]


#: The tables a sweep writes, one Parquet file each.
TABLES = ("switches", "poincare", "summary")


_DTYPES = {"int": "int64", "float": "float64", "bool": "bool", "str": "str"}


def point_function(subject: Any) -> Callable[..., PointTables]:
    """The function that runs one value of a sweep of ``subject``: :func:`run_point` for the
    article's case, :func:`~oscillator.analysis.chain_sweeps.run_chain_point` for a declared
    system."""
    from oscillator.model.chains import FrictionChain

    if isinstance(subject, FrictionChain):
        from oscillator.analysis.chain_sweeps import run_chain_point

        return run_chain_point
    return run_point
