"""The Pareto front of two objectives, by the epsilon-constraint method (docs/design.md).

With two objectives ``f1`` and ``f2`` (each a worst case over the band and every attractor), a
design on the front is one that no other beats in both.  Each point is found as a single-objective
design: minimise ``f1`` subject to ``f2 <= eps`` (and the problem's own constraints), refined with
the exact sensitivities and checked from fresh starts like any design
(:func:`~oscillator.designing.optimise.design`), for ``eps`` spread between the smallest ``f2`` of
the global search's feasible candidates and the ``f2`` of the design that minimises ``f1`` alone.
The candidates themselves are the front's first sketch: the front keeps every design, refined or
candidate, that no other beats.  Where the front crosses a regime boundary (a contact beginning:
the gradient of the first objective is zero on the side without it), a refinement cannot cross
it, and the candidates fill that stretch.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np
import pandas as pd

from oscillator.designing.judging import Judged
from oscillator.designing.problem import Constraint, Problem

__all__ = ["FRONT_COLUMNS", "non_dominated", "pareto_front"]

#: The columns of a front's table after the design's parameters.
FRONT_COLUMNS = ("eps", "objective", "second", "refined", "violation", "runs")


def non_dominated(points: np.ndarray) -> np.ndarray:
    """Which rows of ``points`` (n x 2, both minimised) no other row beats in both (ties kept once)."""
    keep = np.ones(len(points), dtype=bool)
    for k, point in enumerate(points):
        others = np.delete(points, k, axis=0)
        beaten = np.any(np.all(others <= point, axis=1) & np.any(others < point, axis=1))
        duplicate = np.any(np.all(points[:k] == point, axis=1))
        keep[k] = not beaten and not duplicate
    return keep


def pareto_front(
    problem: Problem,
    judged: list[Judged],
    first: Judged,
    refined: Callable[[Problem, Judged], Judged],
    count: int,
) -> pd.DataFrame:
    """The front (module docstring): ``count`` levels of the second objective, from the smallest
    among the feasible candidates ``judged`` to that of ``first`` (the design minimising the first
    objective alone, the front's last point); ``refined(subproblem, start)`` refines and checks
    one point.  One row per point on the front, by increasing second objective: the refined
    designs and the candidates no refined design beats (``refined`` False)."""
    (second,) = problem.also
    feasible = [j for j in judged if j.feasible]
    rows = [_row(problem, j, np.nan, refined=False) for j in feasible] + [_row(problem, first, np.nan)]
    if feasible and count > 1:
        low, high = min(j.worst[second] for j in feasible), first.worst[second]
        for eps in np.linspace(low, high, count)[:-1]:
            bound = Constraint(second, float(eps))
            sub = dataclasses.replace(problem, constraints=(*problem.constraints, bound), also=())
            starts = [Judged.of(sub, j.design, list(j.seen), 0, "survey") for j in judged]
            start = min(starts, key=Judged.key)
            if start.feasible:
                point = refined(sub, start)
                rows.append(
                    _row(problem, Judged.of(problem, point.design, list(point.seen), point.runs, point.how), eps)
                )
    table = pd.DataFrame(rows)
    table = table[table.violation == 0]
    table = table[non_dominated(table[["objective", "second"]].to_numpy(float))]
    return table.sort_values("second").reset_index(drop=True)


def _row(problem: Problem, judged: Judged, eps: float, *, refined: bool = True) -> dict[str, object]:
    (second,) = problem.also
    row: dict[str, object] = dict(problem.design(judged.design))
    row |= {"eps": eps, "objective": judged.objective, "second": judged.worst[second], "refined": refined}
    return row | {"violation": judged.violation, "runs": judged.runs}
