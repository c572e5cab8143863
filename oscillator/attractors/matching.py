"""The matcher: which attractor of a point continues which of the point before.

An attractor found at a point continues one of the point it is matched to when that one's seed
landed on it with the same period and cycle of switches (the evidence of the flow itself: the
first such seed wins); an attractor whose seed was not run here (the atlas seeds one per regime)
is matched by distance: to the nearest attractor with the same period and cycle of switches (the
largest distance between their cycles' section points, in the best rotation), or for aperiodic
sets of the same kind, between their centres.  Any other attractor is new.  Attractors.jl's
``MatchBySSSetDistance`` with the seeds' evidence first.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from oscillator.attractors.grouping import Attractor, cycle_distance, order_key

__all__ = ["Matcher", "NearestSame", "renumbered"]


#: A matcher: ``matcher(previous, here, landed, next_id) -> (ids, next_id)``: each attractor of
#: ``here`` (by its id) -> its kept id.  ``previous``: the attractors of the points matched to, each
#: with its kept id; ``landed``: kept id -> the attractor of ``here`` its seed reached (or -1), for
#: those seeded here.
Matcher = Callable[
    [Sequence[tuple[Attractor, int]], Sequence[Attractor], dict[int, int], int], tuple[dict[int, int], int]
]


def _distance(a: Attractor, b: Attractor) -> float:
    """How far apart two attractors of the same kind are, relative to their size; inf for two
    of different periods, cycles of switches or kinds."""
    if (a.period, a.signature) != (b.period, b.signature) or (not a.period and a.kind != b.kind):
        return np.inf
    scale = 1.0 + max(float(np.max(np.abs(a.points))), float(np.max(np.abs(b.points))))
    if a.period:
        return cycle_distance(a.points, b.points) / scale
    return float(np.linalg.norm(np.mean(a.points, axis=0) - np.mean(b.points, axis=0))) / scale


@dataclass(frozen=True)
class NearestSame:
    """The seeds' evidence first, then (``by_distance``) the nearest attractor of the same kind
    within ``within`` (relative distance) for the attractors not seeded here."""

    by_distance: bool = True
    within: float = np.inf

    def __call__(
        self,
        previous: Sequence[tuple[Attractor, int]],
        here: Sequence[Attractor],
        landed: dict[int, int],
        next_id: int,
    ) -> tuple[dict[int, int], int]:
        ids: dict[int, int] = {}
        by_id = {a.id: a for a in here}
        for attractor, kept in previous:
            local = landed.get(kept, -1)
            if local < 0 or local in ids or kept in ids.values():
                continue
            if (by_id[local].period, by_id[local].signature) == (attractor.period, attractor.signature):
                ids[local] = kept
        if self.by_distance:
            unseeded = [(a, kept) for a, kept in previous if kept not in landed and kept not in ids.values()]
            pairs = sorted((_distance(a, b), kept, b.id) for a, kept in unseeded for b in here if b.id not in ids)
            for distance, kept, local in pairs:
                if distance < np.inf and distance <= self.within and local not in ids and kept not in ids.values():
                    ids[local] = kept
        for attractor in here:
            if attractor.id not in ids:
                ids[attractor.id] = next_id
                next_id += 1
        return ids, next_id


def renumbered(found: Sequence[Sequence[Attractor]], ids: Sequence[dict[int, int]]) -> list[dict[int, int]]:
    """The kept ids renumbered by :func:`~oscillator.attractors.grouping.order_key` of each one's
    first attractor, so that ``A0`` names the same orbit in every analysis wherever they meet
    it, whichever point met it first."""
    first: dict[int, Attractor] = {}
    for here, local in zip(found, ids, strict=True):
        for attractor in here:
            first.setdefault(local[attractor.id], attractor)
    order = {kept: new for new, kept in enumerate(sorted(first, key=lambda kept: order_key(first[kept])))}
    return [{k: order[kept] for k, kept in local.items()} for local in ids]
