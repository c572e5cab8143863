"""The frequency response: every branch of periodic orbits over a parameter's span, with the
response measures at each point, and what slow sweeps up and down meet (issue 38).

:func:`frequency_response` works in four stages, each on the executor's workers
(:mod:`oscillator.attractors.responding` holds the tasks):

1. **branches**: the periodic attractors at ``seeds`` values of the parameter
   (:func:`~oscillator.attractors.finding.find_attractors` from the given starts), and, seed
   after seed, each orbit not on a branch already traced continued both ways to the span's ends
   through folds and unstable stretches (:func:`~oscillator.orbits.continuation.continue_orbit`;
   where the corrector fails or stalls inside the span, the orbits on both sides of that point
   continued both ways too);
2. **sweeps**: what an experiment turning the knob slowly sees: at each of ``sweep`` values, up
   the span and then down, the motion lands from where it was at the value before
   (:func:`~oscillator.attractors.mapping.land`; one that has not settled is told apart from an
   aperiodic one), and its attractor is measured; a ``jump`` marks a value where the attractor
   met is not the continuation of the one before;
3. **families the sweeps met**: each orbit of the sweeps on no branch yet continued both ways
   (nothing a sweep rides is missing from the branches), then the branches born at the period
   doublings;
4. **measures**: every point of every branch measured (:func:`~oscillator.orbits.response.branch_responses`:
   peaks, RMS values, rests, contacts, impact velocities, contact forces, energies, each orbit
   refined by Newton first).

With a :class:`~oscillator.attractors.frequency_parts.FrequencyStore`, each stage's parts are
kept as they finish, and a run into the same folder reads them back, each checked as its task's,
instead of computing them.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, overload

import numpy as np
import pandas as pd

from oscillator.analysis.execution import Executor, keyed
from oscillator.analysis.store import Expected
from oscillator.attractors.frequency_parts import (
    FrequencyStore,
    branch_part_columns,
    branches_from_disk,
    branches_on_disk,
    branches_problem,
    frequency_store,
    measures_part,
    no_points,
    sweep_part,
)
from oscillator.attractors.mapping import STATE, AttractorSettings, check_settings, check_states
from oscillator.attractors.responding import continued, distinct, doubled, measured, on_branch, seed_orbits, sweep
from oscillator.errors import InputError
from oscillator.io.cases import Case, resolve_case
from oscillator.model.chains import FrictionChain
from oscillator.orbits.branch import Bifurcation, Branch
from oscillator.orbits.settings import check_frequency
from oscillator.presenting import Presented, presenter
from oscillator.text import shown

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

    from oscillator.attractors.chain_frequency import ChainFrequencyResponse

__all__ = [
    "FrequencyResponse",
    "FrequencyStore",
    "check_frequency",
    "frequency_response",
    "frequency_store",
    "no_points",
]

#: The longest period of a branch born at a period doubling.
MAX_PERIOD = 16
#: The points of a branch measured in one task.
CHUNK = 16


@dataclass(frozen=True)
class FrequencyResponse(Presented):
    """What :func:`frequency_response` found: ``save(folder)`` writes it as ``oscillator frc``
    writes its folder, :func:`oscillator.read_run` reads either back, and it shows itself in
    Jupyter.

    Attributes
    ----------
    param : str
        The parameter swept (``"Omega"`` for a frequency response).
    branches : tuple of Branch
        Every branch continued, each from a seed (or a restart) to one end of the span, then the
        branches of period ``2n`` born at their period doublings.
    points : DataFrame
        One row per branch point: ``branch`` (its index in ``branches``), ``period`` (its
        orbits' forcing periods per return: 2n on a branch born at a period doubling), the branch's columns
        (the parameter, ``x1 v1 x2 v2`` at the section, the multipliers ``mu1..mu4``,
        ``stable``, ``signature``, ``piece``: :class:`~oscillator.orbits.branch.Branch`) and every
        response measure (:meth:`oscillator.Response.columns`).
    sweeps : DataFrame
        One row per sweep value: ``direction`` (``"up"``, ``"down"``), the parameter, ``period``
        (0: nothing settled, aperiodic or failed), ``signature``, ``x1 v1 x2 v2`` (the orbit met,
        at the section), ``jump`` (the orbit met is not the continuation of the one met before:
        :func:`~oscillator.attractors.responding.jumps`) and the response measures of the
        attractor met (NaN where it is not periodic).
    """

    param: str
    branches: tuple[Branch, ...]
    points: pd.DataFrame
    sweeps: pd.DataFrame
    case: Case = field(repr=False, compare=False)  #: the case, as given
    period: int = 1  #: forcing periods per return of the branches sought
    cutoff: float = 0.0  #: the cut-off (Hz) of the measures ``force_above`` and ``a_above``

    def nothing_found(self) -> str:
        """What was found where no branch was: the sentence the report and the command say."""
        met = int((self.sweeps["period"] > 0).sum()) if len(self.sweeps) else 0
        return (
            f"no periodic orbit of period {self.period} was found over {self.param}'s span: the seeds' attractors "
            f"hold none, and the sweeps met a periodic motion at {met} of their {len(self.sweeps)} values"
        )

    def plot(self, measure: str = "x_pp") -> Figure:
        """``measure`` against the parameter, in the engineers' style
        (:func:`oscillator.report.frequency.frequency_figure`): branches stable solid and unstable
        dashed, bifurcations marked, the sweeps with their jumps, sticking and contact shaded."""
        return presenter().plot_global(self, measure=measure)

    def noise(self, harmonics: int = 200, cutoff: float = 0.0) -> pd.DataFrame:
        """The noise measures at every branch point (docs/noise.md), one row per point as in
        :attr:`points`: ``branch``, the parameter, ``stable``, ``piece`` and every column of
        :meth:`oscillator.Noise.columns` (levels above ``cutoff`` Hz). Each point's return is
        integrated again (16 ms a point: benchmarks/noise.py, 2026-11-29)."""
        return self.noise_tables(harmonics, cutoff)[0]

    def noise_tables(
        self, harmonics: int = 200, cutoff: float = 0.0, progress: Callable[[int, int], None] | None = None
    ) -> tuple[pd.DataFrame, pd.DataFrame]:
        """:meth:`noise`'s table and every point's spectra (:meth:`oscillator.Noise.spectra`, each
        row with ``branch``, ``point``, its index in the branch, and the parameter first), from one
        pass over the points; ``progress(done, total)`` is told after each point."""
        from oscillator.orbits.noise import point_noise

        total, done = sum(len(branch.points) for branch in self.branches), 0
        rows, spectra = [], []
        for k, branch in enumerate(self.branches):
            for index, (row, found) in enumerate(point_noise(branch, harmonics)):
                rows.append({"branch": k} | row | found.columns(cutoff))
                where = {"branch": k, "point": index, self.param: row[self.param], "stable": row["stable"]}
                spectra.append(found.spectra().assign(**where))
                done += 1
                if progress is not None:
                    progress(done, total)
        table = pd.DataFrame(rows) if rows else pd.DataFrame({"branch": pd.Series(dtype=int)})
        if not spectra:
            return table, pd.DataFrame({"branch": pd.Series(dtype=int), "point": pd.Series(dtype=int)})
        joined = pd.concat(spectra, ignore_index=True)
        first = ["branch", "point", self.param, "stable"]
        return table, joined[[*first, *[c for c in joined.columns if c not in first]]]

    def plot_noise(self, table: pd.DataFrame, column: str = "impact_power_left") -> Figure:
        """The noise measure ``column`` of :meth:`noise`'s ``table`` against the parameter, each
        branch in its colour, stable solid and unstable dashed."""
        return presenter().plot_noise_response(self, table, column)

    @property
    def bifurcations(self) -> pd.DataFrame:
        """Every branch's bifurcations, with ``branch`` (its index in ``branches``) first."""
        frames = [
            branch.bifurcations.assign(branch=k) for k, branch in enumerate(self.branches) if len(branch.bifurcations)
        ]
        if not frames:  # none: the columns, each of its kind (an untyped empty column is refused on reading)
            kinds = {"branch": int, self.param: float, "kind": object, **dict.fromkeys(STATE, float), "jump": float}
            kinds |= {"before": object, "after": object}
            return pd.DataFrame({name: pd.Series(dtype=kind) for name, kind in kinds.items()})
        frame = pd.concat(frames)
        return frame[["branch", *[c for c in frame.columns if c != "branch"]]].reset_index(drop=True)

    @property
    def folds(self) -> pd.DataFrame:
        """The branches' folds: the parameter and the branch."""
        rows = self.bifurcations
        return rows.loc[rows["kind"] == Bifurcation.FOLD, ["branch", self.param]].reset_index(drop=True)

    def jumps(self, direction: str) -> list[float]:
        """The values at which the sweep ``direction`` (``"up"`` or ``"down"``) jumped."""
        rows = self.sweeps[(self.sweeps.direction == direction) & self.sweeps.jump]
        return [float(value) for value in rows[self.param]]


@overload
def frequency_response(
    case: FrictionChain,
    param: str = ...,
    span: tuple[float, float] = ...,
    *,
    period: int = ...,
    seeds: int = ...,
    states: Sequence[Sequence[float]] | np.ndarray | None = ...,
    sweep: int = ...,
    progress: Callable[[int, int], None] | None = ...,
) -> ChainFrequencyResponse: ...


@overload
def frequency_response(
    case: Case | str,
    param: str = ...,
    span: tuple[float, float] = ...,
    *,
    period: int = ...,
    seeds: int = ...,
    states: Sequence[Sequence[float]] | np.ndarray | None = ...,
    sweep: int = ...,
    settings: AttractorSettings | None = ...,
    max_points: int = ...,
    workers: int | None = ...,
    client: Any = ...,
    store: FrequencyStore | None = ...,
    progress: Callable[[int, int], None] | None = ...,
) -> FrequencyResponse: ...


def frequency_response(
    case: Case | FrictionChain | str,
    param: str = "Omega",
    span: tuple[float, float] = (1.3, 1.85),
    *,
    period: int = 1,
    seeds: int = 5,
    states: Sequence[Sequence[float]] | np.ndarray | None = None,
    sweep: int = 41,
    settings: AttractorSettings | None = None,
    max_points: int = 3000,
    workers: int | None = 1,
    client: Any = None,
    store: FrequencyStore | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> FrequencyResponse | ChainFrequencyResponse:
    """The branches of period-``period`` orbits over ``span`` of ``param`` with their response
    measures, and the sweeps up and down (module docstring).

    ``seeds`` values (2 to 1000, evenly over the span) look for attractors from ``states`` (the
    case's start by default); ``sweep`` values (2 to 100000) make each sweep; ``settings`` are the
    landings' (:class:`~oscillator.attractors.mapping.AttractorSettings`); ``max_points`` bounds
    each branch.  ``workers`` (None: every core) or a Dask ``client`` run the tasks; ``store``
    keeps them as they finish (:func:`frequency_store`); ``progress(done, total)`` is told after
    each task, in seeds, branch points and sweep values (the total grows as the branches are
    found).  A declared system's: :func:`~oscillator.attractors.chain_frequency.chain_frequency_response`
    (its period-1 branches; ``settings``, ``store``, ``client`` and ``max_points`` are the
    article's)."""
    if isinstance(case, FrictionChain):
        return _of_chain(case, param, span, period, seeds, states, sweep, progress, settings, store, client)
    base = resolve_case(case) if isinstance(case, str) else case
    if store is not None and not isinstance(store, FrequencyStore):
        raise InputError(
            f"store must be a FrequencyStore (frequency_store(folder, ...)), got {shown(store)}", field="store"
        )
    low, high = check_frequency(base, param, span, period=period, seeds=seeds, sweep=sweep, max_points=max_points)
    settings = check_settings(settings)
    starts = None if states is None else check_states(states)
    tally = _Tally(progress, seeds + 2 * sweep)
    tally.add()  # the total at once: seeds and sweep values (the branch points are added as found)
    with Executor(workers, client, progress) as executor:
        job = _Job(base, param, (low, high), period, settings, max_points, store, tally, executor)
        branches = job.branches(np.linspace(low, high, seeds), starts)
        sweeps = job.sweeps(sweep)
        branches = job.doublings(branches + job.from_sweeps(sweeps, branches))
        points = job.measures(branches)
    return FrequencyResponse(param, tuple(branches), points, sweeps, base, period, settings.cutoff)


def _of_chain(
    chain: FrictionChain,
    param: str,
    span: tuple[float, float],
    period: int,
    seeds: int,
    states: Any,
    sweep: int,
    progress: Callable[[int, int], None] | None,
    *articles: Any,
) -> ChainFrequencyResponse:
    """:func:`frequency_response` of a declared system; the article's options refused."""
    from oscillator.attractors.chain_frequency import chain_frequency_response

    if period != 1:
        raise InputError("period: a declared system's branches are of period-1 orbits", field="period")
    for name, value in zip(("settings", "store", "client"), articles, strict=True):
        if value is not None:
            raise InputError(f"{name} applies to the article's cases, not a declared system", field=name)
    return chain_frequency_response(chain, param, span, seeds=seeds, states=states, sweep=sweep, progress=progress)


class _Tally:
    """``progress(done, total)`` kept across the stages; the total grows by the branch points."""

    def __init__(self, progress: Callable[[int, int], None] | None, total: int) -> None:
        self.progress, self.done, self.total = progress, 0, total

    def add(self, done: int = 0, total: int = 0) -> None:
        self.done, self.total = self.done + done, self.total + total
        if self.progress is not None:
            self.progress(self.done, self.total)


@dataclass(frozen=True)
class _Job:
    """One frequency response as it is computed: the stages, each read back from the store where
    it holds them."""

    case: Case
    param: str
    span: tuple[float, float]
    period: int
    settings: AttractorSettings
    max_points: int
    store: FrequencyStore | None
    tally: _Tally
    executor: Executor

    def branches(self, values: np.ndarray, starts: np.ndarray | None) -> list[Branch]:
        """Seed after seed, the orbits at the seed not on a branch already traced, each continued
        both ways (the two directions of every new orbit of a seed in parallel)."""
        expected = {k: self._branches_part({"seed": k, "value": float(values[k])}) for k in range(len(values))}
        kept = {k: self._read(f"seed-{k:04d}", expected[k]) for k in range(len(values))}
        missing = [k for k, part in kept.items() if part is None]
        arguments = (self.case, self.param)
        tasks = [(k, seed_orbits, *arguments, float(values[k]), self.period, starts, self.settings) for k in missing]
        orbits = dict(self.executor.map(keyed, tasks))
        found: list[Branch] = []
        for k, value in enumerate(values):
            stored = kept[k]
            if stored is None:
                branches = self._continue(float(value), orbits[k], found)
                self._write(f"seed-{k:04d}", *branches_on_disk(self.param, branches), key=expected[k].key)
            else:
                branches = branches_from_disk(self.case, self.param, *stored)
            found += branches
            self.tally.add(1)
        return found

    def from_sweeps(self, sweeps: pd.DataFrame, found: list[Branch]) -> list[Branch]:
        """The orbits of period ``period`` the sweeps met that lie on no branch yet (a family no
        seed reached), each continued both ways (:meth:`_continue`), in the sweeps' order."""
        rows = sweeps[(sweeps["period"] == self.period) & sweeps[list(STATE)].notna().all(axis=1)]
        key = {"from": "sweeps", "values": [float(v) for v in rows[self.param]]}
        expected = self._branches_part(key)
        stored = self._read("from-sweeps", expected)
        if stored is not None:
            return branches_from_disk(self.case, self.param, *stored)
        new: list[Branch] = []
        for _, row in rows.iterrows():
            value, state = float(row[self.param]), row[list(STATE)].to_numpy(float)
            new += self._continue(value, [state], found + new)
        self._write("from-sweeps", *branches_on_disk(self.param, new), key=key)
        return new

    def doublings(self, found: list[Branch]) -> list[Branch]:
        """The period-``2n`` branches born at the branches' period doublings, level after level
        (period 2, then 4, ...; up to :data:`MAX_PERIOD`), each level's doublings in parallel."""
        level = list(range(len(found)))
        while level:
            kept: dict[str, list[Branch]] = {}
            keys: dict[str, Expected] = {}
            tasks = []
            for b in level:
                branch = found[b]
                rows = np.flatnonzero(branch.bifurcations["kind"] == Bifurcation.PERIOD_DOUBLING)
                for r in rows if 2 * branch.period <= MAX_PERIOD else []:
                    name = f"doubling-{b:04d}-{r:03d}"
                    at = float(branch.bifurcations[self.param].iloc[r])
                    keys[name] = self._branches_part({"branch": b, "doubling": int(r), "value": at})
                    stored = self._read(name, keys[name])
                    if stored is not None:
                        kept[name] = branches_from_disk(self.case, self.param, *stored)
                        continue
                    arguments = (self.case, self.param, self.span, branch, int(r), self.max_points, tuple(found))
                    tasks.append((name, doubled, *arguments))
            for name, branches in self.executor.map(keyed, tasks):
                kept[name] = [branch for branch in branches if len(branch.points) > 1]
                self._write(name, *branches_on_disk(self.param, kept[name]), key=keys[name].key)
            level = []
            for name in sorted(kept):
                level += range(len(found), len(found) + len(kept[name]))
                found += kept[name]
        return found

    def _continue(self, value: float, states: list[np.ndarray], found: list[Branch]) -> list[Branch]:
        low, high = self.span
        new = [state for state in states if not any(on_branch(self.case, b, value, state) for b in found)]
        arguments = (self.case, self.param, self.span)
        tasks = [
            (k, continued, *arguments, value, stop, self.period, state, self.max_points, tuple(found))
            for k, (state, stop) in enumerate((state, stop) for state in new for stop in (high, low) if stop != value)
        ]
        done = sorted(self.executor.map(keyed, tasks), key=lambda item: item[0])
        return distinct(self.case, [branch for _, branches in done for branch in branches], found)

    def measures(self, branches: list[Branch]) -> pd.DataFrame:
        """The response measures of every branch point, in chunks of :data:`CHUNK` points."""
        frames: dict[int, pd.DataFrame] = {}
        tasks = []
        expected = {b: measures_part(b, branch) for b, branch in enumerate(branches)}
        for b, branch in enumerate(branches):
            part = self._read(f"measures-{b:04d}", expected[b])
            if part is not None:
                frames[b] = part[0]
                continue
            count = len(branch.points)
            tasks += [
                (b, measured, branch, first, min(first + CHUNK, count), self.settings.cutoff)
                for first in range(0, count, CHUNK)
            ]
        self.tally.add(sum(len(frame) for frame in frames.values()), sum(len(branch.points) for branch in branches))
        chunks: dict[int, list[pd.DataFrame]] = {b: [] for b in range(len(branches)) if b not in frames}
        for b, chunk in self.executor.map(keyed, tasks):
            chunks[b].append(chunk)
            self.tally.add(len(chunk))
            if sum(len(c) for c in chunks[b]) == len(branches[b].points):
                frames[b] = pd.concat(chunks[b]).sort_index().reset_index(drop=True)
                self._write(f"measures-{b:04d}", frames[b], key=expected[b].key)
        parts = [_joined(b, branch, frames[b]) for b, branch in enumerate(branches) if len(frames[b])]
        return pd.concat(parts, ignore_index=True) if parts else no_points(self.param)

    def sweeps(self, count: int) -> pd.DataFrame:
        """The sweeps up and down, in parallel."""
        low, high = self.span
        up = np.linspace(low, high, count)
        found = {}
        tasks = []
        expected = {
            direction: sweep_part(self.param, direction, values)
            for direction, values in (("up", up), ("down", up[::-1]))
        }
        for direction, values in (("up", up), ("down", up[::-1])):
            part = self._read(f"sweep-{direction}", expected[direction])
            if part is None:
                tasks.append((direction, sweep, self.case, self.param, values, self.settings))
            else:
                found[direction] = part[0]
                self.tally.add(count)
        for direction, table in self.executor.map(keyed, tasks):
            found[direction] = table
            self._write(f"sweep-{direction}", table, key=expected[direction].key)
            self.tally.add(count)
        return pd.concat([found["up"], found["down"]], ignore_index=True)

    def _branches_part(self, key: dict[str, Any]) -> Expected:
        """What a part of branches (a seed's, a doubling's) must hold (:func:`_branches_problem`)."""
        check = functools.partial(branches_problem, self.param, self.span)
        return Expected(key, branch_part_columns(self.param), check=check)

    def _read(self, name: str, expected: Expected) -> tuple[pd.DataFrame, Any] | None:
        return None if self.store is None else self.store.read(name, expected)

    def _write(self, name: str, frame: pd.DataFrame, meta: Any = None, *, key: Any) -> None:
        if self.store is not None:
            self.store.write(name, frame, meta, key=key)


def _joined(index: int, branch: Branch, measures: pd.DataFrame) -> pd.DataFrame:
    """A branch's points (state, multipliers, signature) with their measures, ``branch`` first."""
    points = branch.points.reset_index(drop=True)
    extra = measures.drop(columns=[c for c in measures.columns if c in points.columns])
    joined = pd.concat([points, extra], axis=1).assign(branch=index, period=branch.period)
    return joined[["branch", "period", *points.columns, *extra.columns]]
