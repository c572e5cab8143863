"""Judging a design: its worst case over the band and over every attractor (docs/design.md).

Two ways, one for each stage of :func:`~oscillator.designing.optimise.design`:

* :func:`survey` (global): at each band value, :func:`~oscillator.find_attractors` from
  ``starts`` fresh starts (:func:`~oscillator.attractors.atlas.fresh_starts`); every attractor's
  response measures.  An attractor without them (aperiodic, or a periodic one Newton could not
  refine) counts as the worst: the design is not judged good on what it cannot measure.
* :func:`follow` (local): the attractors a survey found, each continued by Newton to a nearby
  design (:func:`~oscillator.find_orbit` from its section point), with the exact derivatives of
  their measures in the design's parameters (:func:`~oscillator.sensitivities`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from oscillator.analysis.store import Expected
from oscillator.attractors.mapping import AttractorSettings
from oscillator.designing.problem import Problem
from oscillator.hybrid.counting import runs
from oscillator.model.system import ARTICLE

_STATE = ARTICLE.state

__all__ = [
    "Judged",
    "Seen",
    "follow",
    "seen_columns",
    "seen_from_table",
    "seen_table",
    "survey",
    "survey_part",
    "survey_task",
]


@dataclass(frozen=True)
class Seen:
    """One attractor at one band value: the band value, the attractor's period and section point
    (for Newton to continue it), its measures (``nan`` where unmeasured) and, when followed, their
    derivatives in the design's parameters.  A band value where every start failed is one ``Seen``
    too, of period 0, unmeasured (the worst: a design is not judged good where it cannot be run),
    ``failure`` saying why."""

    band: float
    period: int
    state: np.ndarray = field(repr=False)
    measures: Mapping[str, float] = field(repr=False)
    gradients: Mapping[str, np.ndarray] = field(default_factory=dict, repr=False)
    failure: str = ""

    def value(self, measure: str) -> float:
        value = self.measures.get(measure, math.nan)
        return math.inf if not math.isfinite(value) else float(value)


def seen_table(seen: list[Seen], **extra: str) -> pd.DataFrame:
    """``seen`` as a table: ``band, period, x1, v1, x2, v2``, every response measure (``nan``
    where unmeasured) and ``failure``, one row per attractor (a design store's part); ``extra``
    columns after them, each one value for every row."""
    from oscillator.orbits.response import COLUMNS

    rows = [
        {"band": s.band, "period": s.period, **dict(zip(_STATE, s.state, strict=True))}
        | {name: float(s.measures.get(name, math.nan)) for name in COLUMNS}
        | {"failure": s.failure}
        | extra
        for s in seen
    ]
    return pd.DataFrame(rows, columns=["band", "period", *_STATE, *COLUMNS, "failure", *extra])


def seen_columns() -> dict[str, str]:
    """The kinds of :func:`seen_table`'s columns (a design store's part, a design folder's
    attractors)."""
    from oscillator.orbits.response import COLUMNS

    return dict.fromkeys(["band", "period", *_STATE, *COLUMNS], "number") | {"failure": "text"}


def survey_part(candidate: int, band: int, design: np.ndarray, value: float) -> Expected:
    """What the part of candidate ``candidate``'s survey at band value number ``band`` must hold
    (a design store's part): :func:`seen_table`'s columns, one row or more, all at ``value``,
    whole periods, and the runs it took in its metadata."""
    columns = seen_columns()

    def check(frame: pd.DataFrame, meta: Any) -> str:
        periods = frame["period"].to_numpy(float)
        if not len(frame) or not (frame["band"] == value).all():
            return f"its rows are not at the band value {value:g}"
        if not ((periods >= 0) & (periods == np.round(periods))).all():
            return "a period is not a whole number"
        runs = meta.get("runs") if isinstance(meta, dict) else None
        return "" if isinstance(runs, int) and runs >= 0 else "its metadata holds no count of runs"

    key = {"candidate": candidate, "band": band, "design": [float(v) for v in design], "value": float(value)}
    return Expected(key, columns, check=check)


def seen_from_table(table: pd.DataFrame) -> list[Seen]:
    """:func:`seen_table` read back."""
    measures = [column for column in table.columns if column not in ("band", "period", *_STATE, "failure")]
    return [
        Seen(
            float(row["band"]),
            int(row["period"]),
            row[list(_STATE)].to_numpy(float),
            row[measures].astype(float).to_dict(),
            failure=str(row["failure"]),
        )
        for _, row in table.iterrows()
    ]


@dataclass(frozen=True)
class Judged:
    """A design and what was seen of it: ``objective`` (the worst value over ``seen``),
    ``violation`` (0 when every constraint holds on every attractor), ``runs`` (simulations),
    ``worst`` (the worst value of every measure judged)."""

    design: np.ndarray
    seen: tuple[Seen, ...]
    objective: float
    violation: float
    runs: int
    how: str
    worst: Mapping[str, float] = field(default_factory=dict)

    @classmethod
    def of(cls, problem: Problem, design: np.ndarray, seen: list[Seen], runs: int, how: str) -> Judged:
        worst = {measure: max((s.value(measure) for s in seen), default=math.inf) for measure in problem.measures}
        design = np.array(design, dtype=float)
        return cls(design, tuple(seen), worst[problem.objective], problem.violation(worst), runs, how, worst)

    @property
    def feasible(self) -> bool:
        return self.violation == 0.0

    def key(self) -> tuple[float, float]:
        """Better designs sort first: feasible before not, then the smaller worst objective."""
        return (self.violation, self.objective)

    def active(self, measure: str) -> Seen:
        """The attractor (and band value) where ``measure`` is worst."""
        return max(self.seen, key=lambda s: s.value(measure))


def survey_task(
    problem: Problem, settings: AttractorSettings, design: tuple[float, ...], band: float
) -> tuple[list[Seen], int]:
    """The attractors at one band value of one design, and the runs it took (a worker's task)."""
    from oscillator.attractors.atlas import fresh_starts
    from oscillator.attractors.finding import find_attractors
    from oscillator.io.cases import resolve_case

    before = runs()
    case = resolve_case(problem.case, **problem.design(design), **{problem.over[0]: float(band)})
    found = find_attractors(case, states=fresh_starts(case, problem.starts), settings=settings)
    seen = [
        Seen(float(band), attractor.period, np.array(attractor.points[0], dtype=float), dict(attractor.measures))
        for attractor in found.attractors
    ]
    if not seen:  # every start failed: the worst case, and why
        messages = found.labels["message"].astype(str)
        why = messages.mode().iloc[0] if len(messages) else "no start was run"
        seen = [Seen(float(band), 0, np.full(len(_STATE), math.nan), {}, failure=why)]
    return seen, runs() - before


def survey(problem: Problem, settings: AttractorSettings, design: np.ndarray) -> Judged:
    """:func:`survey_task` at every band value, in this process."""
    seen, total = [], 0
    for band in problem.band_values():
        found, cost = survey_task(problem, settings, tuple(design), float(band))
        seen += found
        total += cost
    return Judged.of(problem, design, seen, total, "survey")


def follow(
    problem: Problem, judged: Judged, design: np.ndarray, *, gradients: bool = True, cutoff: float = 0.0
) -> Judged:
    """``judged``'s attractors continued to ``design`` by Newton, each with the derivatives of the
    objective's and the constraints' measures in the design's parameters (``gradients``; else
    only their values, :meth:`~oscillator.Orbit.response`; ``force_above`` and ``a_above`` above
    ``cutoff`` Hz).  An attractor that Newton loses (it ended at a fold or a boundary of its
    regime) raises the library's error."""
    from oscillator.orbits.shooting import find_orbit

    before = runs()
    measures = set(problem.measures)
    seen = []
    for s in judged.seen:
        if not math.isfinite(min(s.value(m) for m in measures)):
            seen.append(s)  # unmeasured: it stays the worst
            continue
        overrides: dict[str, Any] = problem.design(design) | {problem.over[0]: s.band}
        orbit = find_orbit(problem.case, guess=s.state, period=s.period, **overrides)
        if not gradients:
            seen.append(Seen(s.band, s.period, orbit.state, orbit.response(cutoff).columns()))
            continue
        table = orbit.sensitivities(problem.names).above(cutoff)
        values = table["value"].to_dict()
        slopes = {m: table.loc[m, [f"d/d{n}" for n in problem.names]].to_numpy(float) for m in measures}
        seen.append(Seen(s.band, s.period, orbit.state, values, slopes))
    return Judged.of(problem, design, seen, runs() - before, "followed")
