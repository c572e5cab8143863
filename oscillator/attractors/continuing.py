"""Global continuation: the attractors at many parameter points, found and followed by one loop.

Attractors.jl's ``AttractorSeedContinueMatch`` for this class of systems, in which "there is no
difference between single or multi parameter global continuation": the attractors over a list of
values (:mod:`~oscillator.attractors.following`) and over a plane (:mod:`~oscillator.attractors.atlas`)
are the same loop over :class:`Point` s, composed of swappable pieces:

* the **mapper**: :func:`~oscillator.attractors.mapping.land` (a declared system's
  :func:`~oscillator.attractors.chain_attractors.land_chain`) with the settings of a
  :class:`Mapper` (a fresh start's, a seed's);
* the **grouper**: :func:`~oscillator.attractors.grouping.group`;
* the **describer**: what each attractor is told by (:class:`~oscillator.attractors.finding.Refined`:
  Newton's orbit and multipliers; :class:`~oscillator.attractors.features.Measured`: the exponent
  from one monodromy and the measures; a chain's :class:`~oscillator.attractors.chain_attractors.ChainRefined`);
* the **seeding** rule (:mod:`~oscillator.attractors.seeding`): the starts a point takes from the
  attractors of the points that seed it;
* the **matcher** (:mod:`~oscillator.attractors.matching`): which attractor continues which,
  from the seeds' evidence and the distance between attractors of the same kind;
* the **executor** (:class:`~oscillator.analysis.execution.Executor`) and the **store**
  (:class:`~oscillator.attractors.store.LandingStore`).

Points run in *batches*: each batch depends only on earlier ones (one value of a list; one row of
a plane), and its points' starts and then its attractors' descriptions run in parallel.  The
fresh starts depend on no batch: the next batch's are sent while this process groups and matches
the one before, so that the workers are not idle then.  Every
piece is a pure function of its inputs, so the result is the same for any executor, and a run
that resumes from its store gives what an uninterrupted run gives.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from oscillator.analysis.axes import Axis
from oscillator.analysis.execution import Executor
from oscillator.attractors.chain_attractors import ChainAttractors, land_chain
from oscillator.attractors.finding import Attractors, labelled
from oscillator.attractors.grouping import Attractor, group, unsettled
from oscillator.attractors.mapping import AttractorSettings, Landing, land
from oscillator.attractors.matching import Matcher, NearestSame, renumbered
from oscillator.attractors.seeding import Seeding
from oscillator.attractors.store import LandingStore
from oscillator.io.cases import Case, resolve_case
from oscillator.model.chains import FrictionChain
from oscillator.model.parameters import Parameters

__all__ = [
    "Continued",
    "Mapper",
    "Point",
    "Subject",
    "at_point",
    "continue_attractors",
    "land_at",
    "line_points",
    "path_points",
    "plane_points",
]

Describer = Callable[[Any, Attractor], Attractor]
#: What the loop runs: the article's case, or a declared system.
Subject = Case | FrictionChain


@dataclass(frozen=True)
class Point:
    """One parameter point: the values set there, the point its attractors are matched to
    (``parent``), the points whose attractors seed it (nearest first) and its batch."""

    values: tuple[tuple[str, float], ...]
    parent: int | None = None
    seeds_from: tuple[int, ...] = ()
    batch: int = 0


def line_points(param: str, values: Sequence[float] | np.ndarray) -> list[Point]:
    """The points of a list of values: each seeded by and matched to the one before, one batch each."""
    return [Point(((param, float(v)),), k - 1 if k else None, (k - 1,) if k else (), k) for k, v in enumerate(values)]


def path_points(path: Sequence[Mapping[str, float]]) -> list[Point]:
    """The points of a path through the parameters (each point a mapping ``name -> value``, e.g.
    a design's operating band, or a line across a plane): each seeded by and matched to the one
    before, one batch each.  Every name must be a parameter."""
    points = []
    for k, values in enumerate(path):
        named = tuple((Parameters.check_name(name, "path"), float(value)) for name, value in values.items())
        points.append(Point(named, k - 1 if k else None, (k - 1,) if k else (), k))
    return points


def plane_points(x: Axis, y: Axis) -> list[Point]:
    """The points of a plane, row after row (point ``row * x.count + column``): each seeded by
    the three nearest points of the row before (nearest first, then by column) and matched to
    the one below it (the first row: to the one on its left); one batch a row."""
    points = []
    for row, b in enumerate(y.values):
        for column, a in enumerate(x.values):
            near = sorted(
                (c for c in (column - 1, column, column + 1) if 0 <= c < x.count), key=lambda c: (abs(c - column), c)
            )
            seeds = tuple((row - 1) * x.count + c for c in near) if row else ()
            parent = (row - 1) * x.count + column if row else (column - 1 if column else None)
            points.append(Point(((x.name, float(a)), (y.name, float(b))), parent, seeds, row))
    return points


@dataclass(frozen=True)
class Mapper:
    """The starts of every point and how each is run: the ``fresh`` starts (the same at every
    point) with ``fresh_settings``, the seeds with ``seed_settings`` (by which the landings are
    also grouped)."""

    fresh: np.ndarray
    fresh_settings: AttractorSettings
    seed_settings: AttractorSettings

    def settings(self, index: int) -> AttractorSettings:
        return self.fresh_settings if index < len(self.fresh) else self.seed_settings


@dataclass(frozen=True)
class Continued:
    """The attractors at every point (:class:`~oscillator.attractors.finding.Attractors`, ids
    local to the point, the starts in order: fresh ones, then seeds) and each one's kept id
    (``ids[point][local id]``), numbered by :func:`~oscillator.attractors.matching.renumbered`."""

    points: tuple[Point, ...]
    found: tuple[Attractors, ...]
    ids: tuple[dict[int, int], ...]


def at_point(system: Subject, values: Mapping[str, float]) -> Subject:
    """The system at a parameter point: a case resolved with ``values``, or a chain with its
    numbers changed by name (each checked, the name refused with the closest one)."""
    if isinstance(system, FrictionChain):
        return system.with_values(values)
    return resolve_case(system, **values)


def land_at(system: Subject, settings: AttractorSettings, index: int, start: Sequence[float]) -> Landing:
    """One start's landing: :func:`~oscillator.attractors.mapping.land` for a case,
    :func:`~oscillator.attractors.chain_attractors.land_chain` for a chain."""
    if isinstance(system, FrictionChain):
        return land_chain(system, settings, index, start)
    return land(system, settings, index, tuple(start))


def _land(
    settings: AttractorSettings, system: Subject, point: int, index: int, start: tuple[float, ...]
) -> tuple[int, Landing]:
    return point, land_at(system, settings, index, start)


def _describe(describe: Describer, case: Subject, point: int, attractor: Attractor) -> tuple[int, Attractor]:
    return point, describe(case, attractor)


def _batch_name(points: Sequence[Point], batch: list[int]) -> str:
    return f"batch-{points[batch[0]].batch:05d}"


def _found_type(system: Subject) -> type[Any]:
    """What a point's attractors are held in: :class:`~oscillator.attractors.finding.Attractors`,
    or a chain's :class:`~oscillator.attractors.chain_attractors.ChainAttractors` (same fields)."""
    if isinstance(system, FrictionChain):
        return ChainAttractors
    return Attractors


class _Loop:
    """The state of one global continuation while it runs: the only stateful part."""

    def __init__(
        self,
        case: Subject,
        points: Sequence[Point],
        mapper: Mapper,
        describe: Describer,
        seeding: Seeding,
        matcher: Matcher,
    ) -> None:
        self.case, self.points, self.mapper = case, points, mapper
        self.describe, self.seeding, self.matcher = describe, seeding, matcher
        self.found: list[Attractors] = []
        self.ids: list[dict[int, int]] = []
        self.landed: list[dict[int, int]] = []
        self.next_id = 0
        #: The next batch, its systems and its fresh starts' landings, sent ahead.
        self.early: tuple[list[int], dict[int, Subject], Iterator[tuple[int, Landing]]] | None = None

    def systems(self, batch: list[int]) -> dict[int, Subject]:
        """The system at each point of ``batch`` (:func:`at_point`)."""
        return {k: at_point(self.case, dict(self.points[k].values)) for k in batch}

    def starts(self, k: int) -> tuple[np.ndarray, list[tuple[int, int]]]:
        """The starts of point ``k`` (fresh, then seeds) and each seed's origin."""
        sources = [(p, self.found[p].attractors) for p in self.points[k].seeds_from]
        seeds = self.seeding(sources)
        states = np.vstack([self.mapper.fresh, *[state[None, :] for state, _ in seeds]])
        return states, [origin for _, origin in seeds]

    def batch(self, batch: list[int], executor: Executor, store: LandingStore | None, following: list[int]) -> None:
        """Run one batch: its landings (read back from ``store`` when there), grouped, described
        and matched; the ``following`` batch's fresh starts are sent meanwhile (:meth:`ahead_of`)."""
        early = self.early if self.early is not None and self.early[0] == batch else None
        self.early = None
        cases = early[1] if early is not None else self.systems(batch)
        starts = {k: self.starts(k) for k in batch}
        name = _batch_name(self.points, batch)
        landings = store.read_batch(name, {k: s for k, (s, _) in starts.items()}) if store is not None else None
        if landings is None:
            landings = self.land(batch, cases, starts, executor, early[2] if early is not None else None)
            if store is not None:
                store.write_batch(landings, name)
        grouped = {k: group(landings[k], self.mapper.seed_settings) for k in batch}
        describing = executor.ahead(_describe, [(self.describe, cases[k], k, a) for k in batch for a in grouped[k][0]])
        if following:
            self.ahead_of(following, executor, store)
        described: dict[int, list[Attractor]] = {k: [] for k in batch}
        for k, attractor in describing:
            described[k].append(attractor)
        for k in batch:
            found, labels = grouped[k]
            attractors = tuple(sorted(described[k], key=lambda a: a.id))
            table = labelled(landings[k], labels, cases[k].system.state)
            here = _found_type(cases[k])(
                cases[k], self.mapper.seed_settings, attractors, table, tuple(unsettled(found))
            )
            self.match(k, here, starts[k][1], labels)

    def land(
        self,
        batch: list[int],
        cases: dict[int, Subject],
        starts: dict[int, tuple[np.ndarray, list[tuple[int, int]]]],
        executor: Executor,
        fresh: Iterator[tuple[int, Landing]] | None,
    ) -> dict[int, list[Landing]]:
        """The landings of a batch by point (fresh starts, then seeds): the seeds sent, then the
        fresh starts taken from ``fresh`` (sent ahead) or sent now."""
        count = len(self.mapper.fresh)
        tasks = [(cases[k], k, i, tuple(row)) for k in batch for i, row in enumerate(starts[k][0]) if i >= count]
        seeds = executor.map(_land, tasks, shared=(self.mapper.seed_settings,))
        landings: dict[int, list[Landing]] = {k: [] for k in batch}
        for k, landing in itertools.chain(fresh if fresh is not None else self.fresh(batch, cases, executor), seeds):
            landings[k].append(landing)
        return landings

    def fresh(self, batch: list[int], cases: dict[int, Subject], executor: Executor) -> Iterator[tuple[int, Landing]]:
        """The fresh starts' landings of a batch (they depend on no other batch), sent at once."""
        tasks = [(cases[k], k, i, tuple(row)) for k in batch for i, row in enumerate(self.mapper.fresh)]
        return executor.ahead(_land, tasks, shared=(self.mapper.fresh_settings,))

    def ahead_of(self, batch: list[int], executor: Executor, store: LandingStore | None) -> None:
        """Send the fresh starts of the next ``batch`` now, so that the workers run them while this
        process groups and matches the batch before (none where the store holds that batch)."""
        if store is None or not store.holds(_batch_name(self.points, batch)):
            cases = self.systems(batch)
            self.early = (batch, cases, self.fresh(batch, cases, executor))

    def match(self, k: int, here: Attractors, origins: list[tuple[int, int]], labels: dict[int, int]) -> None:
        """Number ``here``'s attractors by the ones they continue; ``labels``: each start's
        attractor (by the start's index; none for a failed start), as ``here.labels`` holds them."""
        fresh = len(self.mapper.fresh)
        landed: dict[int, int] = {}
        previous: list[tuple[Attractor, int]] = []
        for j, (point, local) in enumerate(origins):
            kept = self.ids[point][local]
            landed.setdefault(kept, labels.get(fresh + j, -1))
            previous.append((self.found[point].attractors[local], kept))
        parent = self.points[k].parent
        if parent is not None:
            seeded = {kept for _, kept in previous}
            previous += [
                (a, kept) for a in self.found[parent].attractors if (kept := self.ids[parent][a.id]) not in seeded
            ]
        ids, self.next_id = self.matcher(previous, here.attractors, landed, self.next_id)
        self.found.append(here)
        self.ids.append(ids)


def continue_attractors(
    case: Subject,
    points: Sequence[Point],
    mapper: Mapper,
    *,
    describe: Describer,
    seeding: Seeding,
    matcher: Matcher | None = None,
    executor: Executor | None = None,
    store: LandingStore | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> Continued:
    """The attractors at every point, batch after batch, matched from point to point.

    ``store``: each batch's landings kept as it finishes, and those already there read back (a
    run that resumes).  ``progress(done, total)`` in points, after every batch."""
    loop = _Loop(case, points, mapper, describe, seeding, matcher or NearestSame())
    executor = executor or Executor()
    batches = [list(members) for _, members in itertools.groupby(range(len(points)), key=lambda k: points[k].batch)]
    done = 0
    for n, batch in enumerate(batches):
        loop.batch(batch, executor, store, batches[n + 1] if n + 1 < len(batches) else [])
        done += len(batch)
        if progress is not None:
            progress(done, len(points))
    ids = renumbered([found.attractors for found in loop.found], loop.ids)
    return Continued(tuple(points), tuple(loop.found), tuple(ids))
