"""The attractors over a parameter: found at each value, matched from value to value, their basin
fractions, and the parameter values where each one appears or ends, located by bisection.

The global continuation of :mod:`~oscillator.attractors.continuing` over a list of values: at
each value the starts are the fresh ones (the same at every value: a slice of the state space,
or the case's start) and one *seed* per attractor of the value before, its last section point
(:class:`~oscillator.attractors.seeding.LastPoints`); the attractors are grouped and refined as
:func:`~oscillator.attractors.finding.find_attractors` does; an attractor continues one of the
value before when that one's seed lands on it and it has the same period and cycle of switches,
and keeps its number (``id``); any other is new (:class:`~oscillator.attractors.matching.NearestSame`).
Basin fractions count the fresh starts only.

Where an attractor is present at one value and absent at the next, the parameter is bisected
between them: at the midpoint a run from the attractor's last point (a ``transient``, then the
recorded periods) tells whether it still lands on an attractor with the same cycle of switches
and period; the interval is halved until it is shorter than ``tol``.  So a window where two
attractors coexist (hysteresis) is bounded at both ends to ``tol``.
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from oscillator.analysis.axes import Axis
from oscillator.analysis.execution import Executor
from oscillator.analysis.store import identity
from oscillator.attractors.chain_attractors import ChainRefined, chain_columns, check_chain_states
from oscillator.attractors.continuing import Mapper, Subject, at_point, continue_attractors, land_at, line_points
from oscillator.attractors.finding import Refined, share_interval
from oscillator.attractors.grouping import Attractor
from oscillator.attractors.mapping import AttractorSettings, Landing, check_settings, check_states
from oscillator.attractors.seeding import LastPoints
from oscillator.attractors.store import LandingStore
from oscillator.errors import InputError, OscillatorError
from oscillator.io.cases import Case, resolve_case
from oscillator.model.chain_fields import state_of
from oscillator.model.chains import FrictionChain
from oscillator.model.parameters import Parameters
from oscillator.presenting import Presented, presenter
from oscillator.text import shown

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

    from oscillator.orbits.branch import Branch
    from oscillator.orbits.chain_branch import ChainBranch

__all__ = ["AttractorsOver", "End", "check_values", "follow_attractors", "following_store", "local_branches"]

#: The most parameter values, and the smallest bisection tolerance.
MAX_VALUES = 10_000
MIN_TOL = 1e-12


@dataclass(frozen=True)
class End:
    """Where an attractor appears or ends between two parameter values.

    ``inside`` is the last value found with it and ``outside`` the first without it (``|inside -
    outside| <= tol``); ``becomes`` is the attractor its seed reached at ``outside`` (its name),
    or ``""`` if the run failed."""

    id: int
    name: str
    inside: float
    outside: float
    becomes: str

    @property
    def at(self) -> float:
        return 0.5 * (self.inside + self.outside)

    def change(self, start: float, stop: float) -> str:
        """``"ends"`` if the attractor is lost going from ``start`` to ``stop``, else ``"appears"``."""
        return "ends" if (self.outside - self.inside) * (stop - start) > 0 else "appears"


@dataclass(frozen=True)
class AttractorsOver(Presented):
    """The attractors over a parameter (:func:`follow_attractors`).

    Attributes
    ----------
    case : Case or FrictionChain
        The article's case, or a declared system.
    param : str
        A parameter's name (a chain's number by its name: ``platform.F``, ``Omega``).
    values : ndarray
    found : tuple of Attractors or ChainAttractors
        At each value, the attractors (with ids local to that value) and the starts' labels.
    ids : tuple of dict
        At each value, local id -> the id kept over the parameter.
    ends : tuple of End
        The located appearances and ends.
    """

    case: Subject
    param: str
    values: np.ndarray
    found: tuple[Any, ...] = field(repr=False)
    ids: tuple[dict[int, int], ...] = field(repr=False)
    fresh: int = 1
    ends: tuple[End, ...] = ()

    def table(self) -> pd.DataFrame:
        """One row per value and attractor: the value, ``id``, name, period, cycle of switches,
        share of the fresh starts with its confidence interval, stability, largest multiplier,
        largest Lyapunov exponent, the response measures of its orbit (a chain's: each mass's
        ``rests:<mass>``, ``rest_time:<mass>`` and the measures of
        :func:`~oscillator.orbits.chain_response.orbit_measures`), section points (JSON)."""
        chain = isinstance(self.case, FrictionChain)
        rows = []
        for value, found, ids in zip(self.values, self.found, self.ids, strict=True):
            fresh = found.labels[found.labels["index"] < self.fresh]
            for attractor in found.attractors:
                k = int((fresh.attractor == attractor.id).sum())
                interval = share_interval(k, len(fresh))
                measured = chain_columns(attractor) if chain else attractor.response_columns()
                row = _row(self.param, float(value), ids[attractor.id], attractor, k, len(fresh), interval)
                rows.append(row | measured | {"points": json.dumps(attractor.points.tolist())})
        return pd.DataFrame(rows)

    def plot(self, coordinate: str | None = None, *, branches: bool = True) -> Figure:
        """Each attractor's section points (``coordinate``: ``x2`` by default, a chain's first
        mass's ``x:<mass>``) and share against the parameter, where each appears or ends, and
        with ``branches`` the periodic orbits' branches (continued here: :func:`local_branches`),
        as ``oscillator attractors`` draws it."""
        chosen = default_coordinate(self.case) if coordinate is None else coordinate
        return presenter().plot_global(self, coordinate=chosen, branches=local_branches(self) if branches else [])

    def ends_table(self) -> pd.DataFrame:
        """One row per end: ``id, name, change`` (``appears`` or ``ends`` along the values, from the
        first to the last), ``inside, outside, at, becomes``."""
        start, stop = float(self.values[0]), float(self.values[-1])
        columns = ["id", "name", "change", "inside", "outside", "at", "becomes"]
        rows = [(e.id, e.name, e.change(start, stop), e.inside, e.outside, e.at, e.becomes) for e in self.ends]
        return pd.DataFrame(rows, columns=columns)


def _row(
    param: str, value: float, ident: int, attractor: Attractor, k: int, total: int, interval: tuple[float, float]
) -> dict[str, Any]:
    orbit = attractor.orbit
    return {
        param: value,
        "id": ident,
        "name": attractor.name.split(": ", 1)[-1],
        "kind": attractor.kind,
        "period": attractor.period,
        "signature": attractor.signature,
        "starts": k,
        "fraction": k / total if total else math.nan,
        "low": interval[0],
        "high": interval[1],
        "stable": None if orbit is None else bool(orbit.stable),
        "largest_multiplier": math.nan if orbit is None else float(np.max(np.abs(orbit.multipliers))),
        "lyapunov": attractor.lyapunov,
    }


def default_coordinate(system: Subject) -> str:
    """The section coordinate drawn by default: the article's ``x2``, a chain's first mass's
    displacement."""
    return system.system.state[0] if isinstance(system, FrictionChain) else "x2"


def check_values(case: Subject, param: str, values: Sequence[float] | np.ndarray, tol: float) -> np.ndarray:
    """The values of ``param`` to follow the attractors over, checked: a parameter (a chain's
    number by its name), 2 to :data:`MAX_VALUES` finite numbers increasing or decreasing, both
    ends admitted by the model, ``tol`` at least :data:`MIN_TOL`."""
    if not isinstance(case, FrictionChain):
        Parameters.check_name(param)
    try:
        array: np.ndarray = np.asarray(values, dtype=float)
    except (TypeError, ValueError):  # text, a generator, a ragged list
        array = np.empty((0, 0))
    if array.ndim != 1 or not 2 <= len(array) <= MAX_VALUES or not np.isfinite(array).all():
        raise InputError(f"values must be 2 to {MAX_VALUES} finite numbers, got {shown(values)}", field="values")
    if not (np.all(np.diff(array) > 0) or np.all(np.diff(array) < 0)):
        raise InputError("values must increase or decrease throughout", field="values")
    if not (isinstance(tol, (int, float)) and MIN_TOL <= tol):
        raise InputError(f"tol must be a number >= {MIN_TOL:g}, got {shown(tol)}", field="tol")
    for end in (array[0], array[-1]):
        at_point(case, {param: float(end)})  # both ends valid: the constraints are intervals
    return array


def following_store(
    folder: Path,
    case: Subject,
    param: str,
    values: np.ndarray,
    slice_: tuple[Axis, Axis] | None,
    settings: AttractorSettings,
) -> LandingStore:
    """The resumable folder of the attractors over ``values`` of ``param``, from the case's start
    or a slice's starts (its axes, not its starts, in the identity)."""
    states = None if slice_ is None else list(slice_)
    known = identity(case, param=param, values=values, states=states, settings=settings)
    return LandingStore.of(folder, "attractors.json", known, case)


def follow_attractors(
    case: Case | FrictionChain | str,
    param: str,
    values: Sequence[float] | np.ndarray,
    *,
    states: Sequence[Sequence[float]] | np.ndarray | None = None,
    settings: AttractorSettings | None = None,
    tol: float = 1e-5,
    workers: int = 1,
    client: Any = None,
    store: LandingStore | None = None,
    progress: Callable[[int, int], None] | None = None,
    **overrides: float,
) -> AttractorsOver:
    """The attractors at each of ``values`` of ``param``, matched from value to value, and where
    each one appears or ends, to ``tol``.

    Parameters
    ----------
    case : Case, FrictionChain or str
        A case or a shipped case's name, or a declared system (its starts run by
        :func:`~oscillator.attractors.chain_attractors.land_chain`, its periodic attractors
        refined by :class:`~oscillator.attractors.chain_attractors.ChainRefined`).
    param : str
        The parameter varied (a chain's number by its name: ``"platform.F"``, ``"Omega"``).
    values : sequence of float
        Its values, increasing or decreasing (2 to 10,000).
    states : array of shape (N, 4), optional
        The fresh starts at every value (the case's start by default; rows of a chain's
        ``system.state``).
    settings : AttractorSettings, optional
    tol : float
        The width to which each appearance and end is bisected.
    workers, client
        Local processes (as for :func:`~oscillator.attractors.finding.find_attractors`: under a
        ``__main__`` guard in a script), or a Dask client.
    store : LandingStore, optional
        Keep each value's landings in this folder as it finishes, and read those of values
        already there (a run that resumes).
    progress : callable, optional
        ``progress(done, total)`` after every value.
    **overrides
        Parameters and solver options, as for :func:`oscillator.simulate` (a chain's numbers by
        their names).
    """
    settings = check_settings(settings)
    executor = Executor(workers, client, progress)
    if store is not None and not isinstance(store, LandingStore):
        raise InputError(f"store must be a LandingStore or None, got {shown(store)}", field="store")
    describe: Callable[[Any, Attractor], Attractor]
    if isinstance(case, FrictionChain):
        case = (case.with_values(overrides) if overrides else case).checked()
        array = check_values(case, param, values, tol)
        fresh = check_chain_states(case, state_of(case) if states is None else states)
        describe = ChainRefined(settings.lyapunov_periods)
    else:
        case = resolve_case(case, **overrides)
        array = check_values(case, param, values, tol)
        fresh = check_states(case.initial.y if states is None else states)
        describe = Refined(settings.lyapunov_periods, settings.cutoff)
    mapper = Mapper(fresh, settings, settings)
    with executor:
        continued = continue_attractors(
            case,
            line_points(param, array),
            mapper,
            describe=describe,
            seeding=LastPoints(),
            executor=executor,
            store=store,
            progress=progress,
        )
    over = AttractorsOver(case, param, array, continued.found, continued.ids, len(fresh))
    return dataclasses.replace(over, ends=tuple(_ends(over, settings, tol)))


def _ends(over: AttractorsOver, settings: AttractorSettings, tol: float) -> list[End]:
    """Each attractor's appearance or end between two values where it is present at one only
    (none where its seed still reaches it at the other: the fresh starts there missed it)."""
    ends = []
    for k in range(len(over.values) - 1):
        here = {over.ids[k][a.id]: a for a in over.found[k].attractors}
        there = {over.ids[k + 1][a.id]: a for a in over.found[k + 1].attractors}
        for ident in sorted(set(here) - set(there)):
            ends.append(_bisect(over, settings, ident, here[ident], over.values[k], over.values[k + 1], tol))
        for ident in sorted(set(there) - set(here)):
            ends.append(_bisect(over, settings, ident, there[ident], over.values[k + 1], over.values[k], tol))
    return [end for end in ends if end is not None]


def _bisect(
    over: AttractorsOver,
    settings: AttractorSettings,
    ident: int,
    attractor: Attractor,
    inside: float,
    outside: float,
    tol: float,
) -> End | None:
    """Halve ``[inside, outside]`` until shorter than ``tol``: at the midpoint, does a run from
    the attractor's last point land on one with its period and cycle of switches?  None where
    the run reaches it at ``outside`` too: it is there, the fresh starts missed it."""
    seed = attractor.points[-1]
    landing = land_at(at_point(over.case, {over.param: float(outside)}), settings, 0, tuple(seed))
    if landing.ok and landing.period == attractor.period and landing.signature == attractor.signature:
        return None  # there too: the fresh starts there missed it
    becomes = _described(landing, attractor.masses)
    while abs(outside - inside) > tol:
        middle = 0.5 * (inside + outside)
        landing = land_at(at_point(over.case, {over.param: float(middle)}), settings, 0, tuple(seed))
        if landing.ok and landing.period == attractor.period and landing.signature == attractor.signature:
            inside, seed = middle, landing.points[-1]
        else:
            outside, becomes = middle, _described(landing, attractor.masses)
    return End(ident, attractor.name.split(": ", 1)[-1], float(inside), float(outside), becomes)


def _described(landing: Landing, masses: tuple[str, ...]) -> str:
    if not landing.ok:
        return f"failed: {landing.message}"
    return dataclasses.replace(Attractor.of_landing(0, landing), masses=masses).name.split(": ", 1)[-1]


def local_branches(over: AttractorsOver) -> list[tuple[int, Branch | ChainBranch]]:
    """The branch of periodic orbits through each periodic attractor (:func:`~oscillator.continue_orbit`
    from the first value where it was found, to either end of the values): it shows where the
    orbit goes on beyond the attractor's end (an unstable part, a fold, another cycle of
    switches).  A continuation that fails is left out; a chain's period-1 orbits only
    (:func:`~oscillator.orbits.chain_branch.continue_chain_orbit`)."""
    from oscillator.orbits.chain_branch import continue_chain_orbit
    from oscillator.orbits.continuation import continue_orbit

    chain = isinstance(over.case, FrictionChain)
    branches = []
    seen: set[int] = set()
    for value, found, ids in zip(over.values, over.found, over.ids, strict=True):
        for attractor in found.attractors:
            ident = ids[attractor.id]
            if ident in seen or attractor.orbit is None or (chain and attractor.period != 1):
                continue
            seen.add(ident)
            for stop in (over.values[0], over.values[-1]):
                if stop == value:
                    continue
                value_, stop_, guess = float(value), float(stop), attractor.orbit.state
                try:
                    if isinstance(over.case, FrictionChain):
                        branch: Branch | ChainBranch = continue_chain_orbit(
                            over.case, param=over.param, start=value_, stop=stop_, guess=guess, transient=0
                        )
                    else:
                        branch = continue_orbit(
                            over.case,
                            param=over.param,
                            start=value_,
                            stop=stop_,
                            period=attractor.period,
                            guess=guess,
                            transient=0,
                        )
                except OscillatorError:
                    continue
                branches.append((ident, branch))
    return branches
