"""Seeding: the starts a point of a global continuation takes from the attractors already found.

A seeding rule turns the attractors of the points that seed a point (nearest first) into
starts, each with its origin ``(point, attractor)`` so that the matcher can tell where a seed
went.  :class:`LastPoints` seeds every attractor (the attractors over a parameter);
:class:`OnePerRegime` one per regime of several neighbours (the atlas, where three points of the
row before seed each point).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from oscillator.attractors.grouping import Attractor, regime_of

__all__ = ["LastPoints", "OnePerRegime", "Seed", "Seeding"]

#: A seed: its state ``(x1, v1, x2, v2)`` and its origin ``(point, attractor id there)``.
Seed = tuple[np.ndarray, tuple[int, int]]


class Seeding(Protocol):
    def __call__(self, sources: Sequence[tuple[int, Sequence[Attractor]]]) -> list[Seed]:
        """The seeds from ``(point, its attractors)`` of the points that seed this one, nearest first."""
        ...


@dataclass(frozen=True)
class LastPoints:
    """One seed per attractor of every source: its last section point."""

    def __call__(self, sources: Sequence[tuple[int, Sequence[Attractor]]]) -> list[Seed]:
        return [(a.points[-1], (point, a.id)) for point, attractors in sources for a in attractors]


@dataclass(frozen=True)
class OnePerRegime:
    """One seed per regime (:func:`~oscillator.attractors.grouping.regime_of`): the last section
    point of the first attractor with it, the sources taken nearest first."""

    def __call__(self, sources: Sequence[tuple[int, Sequence[Attractor]]]) -> list[Seed]:
        seeds: dict[str, Seed] = {}
        for point, attractors in sources:
            for a in attractors:
                seeds.setdefault(regime_of(a), (a.points[-1], (point, a.id)))
        return list(seeds.values())
