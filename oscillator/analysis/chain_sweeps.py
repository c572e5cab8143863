"""One value of a declared system's sweep (issue 52): :func:`run_chain_point`, a pure function as
:func:`~oscillator.analysis.sweep_points.run_point` is for the article's system, and the tables
it gives, each with the swept number as a column named after it (``Omega``, ``wall.at``):

* every event after the transient (``switches``): ``t``, the phase ``Omega t mod 2 pi``, the
  element, its mass, what happened (``kind``), its modes before and after, ``G0`` and ``G1``
  (docs/systems.md, "Events");
* the Poincaré points at ``t0 + n T``: the system's state by its names (``poincare``);
* a summary row (``summary``): period-n found (Poincaré points repeating within a tolerance) or 0,
  switches, closings and stickings per recorded period, for each friction element and slider the
  fraction of the recorded time it holds (``stuck:<element>``) and for each stop and contact its
  closings per period (``closings:<element>``), the state the run ended in (``end:<name>``: where
  a both-ways sweep's next value starts), and whether the value ran at all.

The sweep itself (resumable folders, workers, Dask, both ways) is :mod:`oscillator.analysis.sweeps`'s,
for either system.
"""

from __future__ import annotations

import dataclasses
import math
import time
from typing import Any

import numpy as np
import pandas as pd

from oscillator.analysis.periods import detect_period
from oscillator.analysis.sweep_points import PointTables, frame_of
from oscillator.errors import InputError, OscillatorError
from oscillator.hybrid.chain_run import ChainResult, rows_at, simulate_chain, stuck_spans
from oscillator.model.chain_rules import ChainEventKind
from oscillator.model.chains import FrictionChain
from oscillator.model.parameters import SweepSettings
from oscillator.text import printable

__all__ = ["ChainSweepSettings", "chain_sweep_columns", "check_chain_sweep", "run_chain_point"]

#: Forcing periods a transient runs at once (each piece's trajectory is let go before the next).
PIECE = 50
_CLOSES = [ChainEventKind.STOP_CLOSES.value, ChainEventKind.CONTACT_CLOSES.value]
_STICKS = [ChainEventKind.STICKS.value, ChainEventKind.SLIDER_STICKS.value]
_HOLDING = ("friction", "jenkins")
_CLOSING = ("stop", "contact")


@dataclasses.dataclass(frozen=True, slots=True)
class ChainSweepSettings(SweepSettings):
    """A declared system's sweep: :class:`~oscillator.model.parameters.SweepSettings` with the swept
    number named as the system names it (checked against the system by
    :func:`check_chain_sweep`); ``mass`` is not used (every element's switches are kept)."""

    def check_param(self) -> None:
        if not isinstance(self.param, str) or not self.param:
            raise InputError(f"sweep.param must be a number of the system, got {self.param!r}", field="param")


def check_chain_sweep(chain: FrictionChain, settings: SweepSettings) -> None:
    """The swept number one of the chain's, and every value a valid one (the field named)."""
    if not all(math.isfinite(value) for value in settings.values):
        raise InputError("stop: the values leave floating point; give a range of physical size", field="stop")
    for name in ("start", "stop"):
        value = getattr(settings, name)
        try:
            chain.with_values({settings.param: value})
        except InputError as error:
            raise InputError(
                f"{name} = {value!r} is not a valid {printable(settings.param)}: {error}", field=name
            ) from None


def chain_sweep_columns(chain: FrictionChain, param: str) -> dict[str, dict[str, str]]:
    """Column names and dtypes of each table; the swept number comes first."""
    state = chain.system.state
    summary = {
        param: "float64",
        "index": "int64",
        "status": "str",
        "message": "str",
        "period": "int64",
        "periodic": "bool",
        "switches_per_period": "float64",
        "closings_per_period": "float64",
        "sticks_per_period": "float64",
        **{f"stuck:{e.name}": "float64" for e in chain.elements if e.type in _HOLDING},
        **{f"closings:{e.name}": "float64" for e in chain.elements if e.type in _CLOSING},
        "wall_time": "float64",
        "direction": "str",
        **{f"end:{name}": "float64" for name in state},
        "reason": "str",
    }
    switches = {param: "float64", "index": "int64", "t": "float64", "phase": "float64", "element": "str"}
    switches |= {"mass": "str", "kind": "str", "mode_before": "int64", "mode_after": "int64"}
    switches |= {"G0": "float64", "G1": "float64"}
    poincare = {param: "float64", "index": "int64", "n": "int64", "t": "float64", **dict.fromkeys(state, "float64")}
    return {"switches": switches, "poincare": poincare, "summary": summary}


def run_chain_point(
    chain: FrictionChain,
    settings: SweepSettings,
    index: int,
    value: float,
    from_state: tuple[float, ...] | None = None,
    direction: str = "up",
) -> PointTables:
    """Run the sweep's value ``value`` of ``chain``: ``settings.transient`` forcing periods from the
    chain's start (or ``from_state``), then ``settings.record`` recorded; its tables.  A run that
    fails gives a summary row saying why (``status = "failed"``) and no other rows."""
    started = time.perf_counter()
    columns = chain_sweep_columns(chain, settings.param)
    base = {settings.param: value, "index": index, "direction": direction}
    try:
        point = chain.with_values({settings.param: value})
        state = _after_transient(point, settings.transient, from_state)
        marks = point.t0 + point.period * np.arange(settings.record + 1)
        run = simulate_chain(point, float(marks[-1]), at=marks, start_state=state)
    except OscillatorError as error:
        failed = dict.fromkeys(columns["summary"], math.nan) | base | {"status": "failed", "message": str(error)}
        failed |= {"period": 0, "periodic": False, "reason": str(getattr(error, "reason", "") or "")}
        failed["wall_time"] = time.perf_counter() - started
        empty = {name: frame_of([], columns[name]) for name in ("switches", "poincare")}
        return PointTables(index, value, empty["switches"], empty["poincare"], frame_of(failed, columns["summary"]))
    poincare = _poincare(run, marks, settings.param, value, index)
    sections = poincare[list(chain.system.state)].to_numpy(float)
    period = detect_period(sections, settings.period_tolerance, settings.max_period)
    summary = base | {"status": "ok", "message": "", "period": period, "periodic": period > 0, "reason": ""}
    summary |= _counts(run, point, settings.record) | {"wall_time": time.perf_counter() - started}
    summary |= {f"end:{name}": float(v) for name, v in zip(chain.system.state, run.y_end, strict=False)}
    events = run.events.assign(**{settings.param: value, "index": index})
    events["phase"] = np.mod(point.Omega * events.t.to_numpy(float), 2 * math.pi)
    switches, sections = (
        table[list(columns[name])].astype(columns[name]).reset_index(drop=True)
        for name, table in (("switches", events), ("poincare", poincare))
    )
    return PointTables(index, value, switches, sections, frame_of(summary, columns["summary"]))


def _after_transient(chain: FrictionChain, periods: int, state: tuple[float, ...] | None) -> np.ndarray | None:
    """The state after ``periods`` forcing periods from the chain's start (or ``state``), run in
    pieces of :data:`PIECE` periods; ``state`` itself for none."""
    y = None if state is None else np.asarray(state, dtype=float)
    done = 0
    while done < periods:
        n = min(PIECE, periods - done)
        piece = dataclasses.replace(chain, t0=chain.t0 + done * chain.period, t_end=None)
        y = np.asarray(simulate_chain(piece, piece.t0 + n * chain.period, start_state=y).y_end, dtype=float)
        y = y[: chain.system.size]
        done += n
    return y


def _poincare(run: ChainResult, marks: np.ndarray, param: str, value: float, index: int) -> pd.DataFrame:
    """The state at each of ``marks`` (the run stops there exactly), the last row at a time with
    events there."""
    names = list(run.chain.system.state)
    rows = run.trajectory.drop_duplicates("t", keep="last").set_index("t")
    at = rows.iloc[rows_at(rows.index.to_numpy(float), marks, run.chain.period)]
    table = pd.DataFrame({"n": np.arange(len(marks)), "t": marks})
    for name in names:
        table[name] = at[name].to_numpy(float)
    return table.assign(**{param: value, "index": index})


def _counts(run: ChainResult, chain: FrictionChain, record: int) -> dict[str, Any]:
    """Switches, closings and stickings per recorded period; each holding element's fraction of
    the time held, each stop's and contact's closings per period."""
    events, span = run.events, record * chain.period
    switching = events[events.mode_before != events.mode_after]
    counts: dict[str, Any] = {
        "switches_per_period": len(switching) / record,
        "closings_per_period": int(events.kind.isin(_CLOSES).sum()) / record,
        "sticks_per_period": int(events.kind.isin(_STICKS).sum()) / record,
    }
    for element in chain.elements:
        if element.type in _HOLDING:
            held = sum(b - a for a, b in stuck_spans(run, element.name, chain.t0, span))
            counts[f"stuck:{element.name}"] = held / span
        elif element.type in _CLOSING:
            closings = int(((events.element == element.name) & events.kind.isin(_CLOSES)).sum())
            counts[f"closings:{element.name}"] = closings / record
    return counts
