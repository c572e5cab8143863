"""Maximal runs of one state in a sequence: rest intervals, domain intervals, sliding ranges.

One helper for what the sweep (rest time per period, sliding ranges), the report (time in each
domain) and the figures (rest shading) each ask of a sequence of states.
"""

from __future__ import annotations

from collections.abc import Hashable, Mapping, Sequence
from typing import TYPE_CHECKING, TypeVar

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd

__all__ = ["rest_intervals", "runs", "spans"]

S = TypeVar("S", bound=Hashable)


def runs(states: Sequence[S]) -> list[tuple[S, int, int]]:
    """The maximal runs of equal consecutive states: ``(state, first index, index after the last)``.

    >>> runs([False, True, True, False])
    [(False, 0, 1), (True, 1, 3), (False, 3, 4)]
    """
    found: list[tuple[S, int, int]] = []
    start = 0
    for i in range(1, len(states) + 1):
        if i == len(states) or states[i] != states[start]:
            found.append((states[start], start, i))
            start = i
    return found


def spans(times: Sequence[float], states: Sequence[S], end: float) -> list[tuple[S, float, float]]:
    """The intervals of a piecewise-constant state: ``states[i]`` holds from ``times[i]`` until the
    next change, the last one until ``end``.  ``(state, from, to)`` in order.

    >>> spans([0.0, 1.0, 2.0, 3.0], ["a", "b", "b", "a"], 5.0)
    [('a', 0.0, 1.0), ('b', 1.0, 3.0), ('a', 3.0, 5.0)]
    """
    return [(state, times[i], times[j] if j < len(times) else end) for state, i, j in runs(states)]


def rest_intervals(
    events: pd.DataFrame | Mapping[str, np.ndarray], mass: int, resting_at_start: bool, start: float, stop: float
) -> list[tuple[float, float]]:
    """The intervals of ``[start, stop]`` in which ``mass`` rests, from its events (a table, or
    arrays by name, with ``t, mass, from_domain, to_domain``): a rest begins at an event into
    domain 0 and ends at one out of it; ``resting_at_start`` says whether it rests at ``start``.
    Exact where a sampled trajectory is not: a rest shorter than the sampling step is found all
    the same."""
    t = np.asarray(events["t"], dtype=float)
    into = np.asarray(events["to_domain"])
    switches = (np.asarray(events["mass"]) == mass) & (np.asarray(events["from_domain"]) != into)
    switches &= (t >= start) & (t <= stop)
    times = [start, *t[switches].tolist()]
    resting = [resting_at_start, *(into[switches] == 0).tolist()]
    return [(a, b) for rests, a, b in spans(times, resting, stop) if rests and b > a]
