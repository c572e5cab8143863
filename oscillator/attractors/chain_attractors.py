"""Attractors, basins and Lyapunov spectra of a friction chain (issue 52): the mapper of
:mod:`oscillator.attractors.mapping` and the describer of :mod:`oscillator.attractors.finding`
for a declared system, the grouper and the results shared.

Each start (a state of the chain's :attr:`~oscillator.model.chains.FrictionChain.system`, at its
``t0``: the forcing is T-periodic, so every run starts there) is run by
:func:`~oscillator.hybrid.chain_run.simulate_chain` until it has :func:`settled` (runs of
:data:`~oscillator.hybrid.batch.SETTLE_CHUNK` periods, then doubling, to ``transient`` at most),
then ``record`` periods more, the section points kept exactly (the solver stops at each
``t0 + kT``).  The landing (:class:`~oscillator.attractors.mapping.Landing`) reads the period of
its points (:func:`~oscillator.analysis.periods.detect_period`), each switching element's cycle
of events over the last return (:func:`chain_signature`), each mass's stick intervals per period
and share of the time stuck (a mass *rests* while it sticks to its floor or belt) and the stops'
and contacts' closings per period.  The landings are grouped as the article's are
(:func:`~oscillator.attractors.grouping.group`); a periodic attractor is refined by
:func:`~oscillator.orbits.chain_orbits.find_chain_orbit` from its cycle (exact multipliers through
every switch, its measures), an aperiodic one gets its largest Lyapunov exponent
(:func:`chain_lyapunov`: the QR average of the exact period maps' derivatives,
:func:`oscillator.orbits.chain_tangents.tangent_pass`).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from oscillator.analysis.axes import Axis, state_plane
from oscillator.analysis.execution import Executor, check_progress
from oscillator.analysis.periods import detect_period
from oscillator.attractors.basins import grid_landings
from oscillator.attractors.finding import attractor_numbered, described_landings, fractions_of, largest_exponent
from oscillator.attractors.grouping import Attractor
from oscillator.attractors.lyapunov import MAX_PERIODS, LyapunovSpectrum, qr_average
from oscillator.attractors.mapping import MAX_STARTS, AttractorSettings, Landing, settled
from oscillator.attractors.store import LandingStore
from oscillator.errors import InputError, OscillatorError, Reason, SimulationFailed
from oscillator.hybrid.batch import SETTLE_CHUNK
from oscillator.hybrid.chain_run import ChainResult, rows_at, simulate_chain, stuck_spans
from oscillator.model.chain_fields import state_of
from oscillator.model.chain_rules import ChainEventKind
from oscillator.model.chains import FrictionChain
from oscillator.model.parameters import SolverOptions, check_count
from oscillator.orbits.chain_orbits import find_chain_orbit
from oscillator.orbits.chain_response import orbit_measures
from oscillator.orbits.chain_tangents import tangent_pass
from oscillator.orbits.signature import own_cycle
from oscillator.presenting import Presented, presenter

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

    from oscillator.orbits.chain_noise import ChainNoise

__all__ = [
    "ChainAttractors",
    "ChainBasins",
    "ChainRefined",
    "chain_columns",
    "chain_grid",
    "chain_lyapunov",
    "chain_signature",
    "find_chain_attractors",
    "find_chain_basins",
    "land_chain",
]

#: CVODE's tolerances for the starts' runs (the article's landings' through ``simulate``).
LANDING_OPTIONS = SolverOptions()
#: The element types whose events make a chain's cycle of switches.
SWITCHING = ("friction", "stop", "contact", "jenkins")
_CLOSES = (ChainEventKind.STOP_CLOSES, ChainEventKind.CONTACT_CLOSES)


def _sections(chain: FrictionChain, state: np.ndarray, periods: int) -> tuple[np.ndarray, ChainResult]:
    """The run of ``periods`` forcing periods from ``state`` at the chain's ``t0``, and its
    section points (``periods + 1`` rows, the start first)."""
    marks = chain.t0 + chain.period * np.arange(periods + 1)
    run = simulate_chain(chain, float(marks[-1]), options=LANDING_OPTIONS, at=marks[1:-1], start_state=state)
    trajectory = run.trajectory.drop_duplicates("t", keep="last")
    times = trajectory.t.to_numpy(float)
    rows = rows_at(times, marks, chain.period)
    points = trajectory[list(chain.system.state)].to_numpy(float)[rows]
    points[-1] = run.y_end[: chain.system.size]
    return points, run


def _settle(chain: FrictionChain, start: np.ndarray, settings: AttractorSettings) -> tuple[np.ndarray, int]:
    """The state at the section once the motion has :func:`settled` (or after ``transient``
    periods), and the forcing periods it took."""
    state, ran, chunk = start, 0, SETTLE_CHUNK
    points = [start]
    while ran < settings.transient:
        n = min(chunk, settings.transient - ran)
        found, _ = _sections(chain, state, n)
        points += list(found[1:])
        state, ran = points[-1], ran + n
        chunk = chunk if ran < 2 * SETTLE_CHUNK else 2 * chunk
        if settings.settle and settled(np.array(points), settings.tolerance, settings.max_period):
            break
    return state, ran


def chain_signature(run: ChainResult, start: float, span: float) -> str:
    """Each switching element's cycle of events over the return ``[start, start + span]`` of
    ``run`` (:func:`~oscillator.orbits.signature.own_cycle`; a grazing is not a switch):
    ``"belt: sticks, slips; wall: stop_closes, stop_opens"``."""
    events = run.events[(run.events.t >= start - 1e-9 * span) & (run.events.kind != ChainEventKind.GRAZING.value)]
    parts = []
    for element in run.chain.elements:
        if element.type in SWITCHING:
            mine = events[events.element == element.name]
            cycle = own_cycle([(float(t), ChainEventKind(k)) for t, k in zip(mine.t, mine.kind, strict=True)], span)
            parts.append(f"{element.name}: {', '.join(cycle) if cycle else 'none'}")
    return "; ".join(parts)


def _rests(run: ChainResult, span: float) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Each mass's stick intervals per forcing period over the run (``span`` seconds from the
    chain's ``t0``), and its share of the time stuck to its floor or belt."""
    chain, events = run.chain, run.events
    period = chain.period
    rests, shares = [], []
    for mass in chain.masses:
        floors = [e.name for e in chain.elements if e.type == "friction" and e.on == mass.name]
        sticks = events[events.element.isin(floors) & (events.kind == ChainEventKind.STICKS.value)]
        stuck = sum(b - a for name in floors for a, b in stuck_spans(run, name, chain.t0, span))
        rests.append(len(sticks) * period / span)
        shares.append(min(1.0, stuck / span))
    return tuple(rests), tuple(shares)


def land_chain(chain: FrictionChain, settings: AttractorSettings, index: int, start: Sequence[float]) -> Landing:
    """Run one start of ``chain`` and read where it went (module docstring); a start the chain
    refuses or a failed run gives a landing with ``status = "failed"`` and the reason."""
    started = time.perf_counter()
    begin = tuple(float(v) for v in start)
    try:
        state, ran = _settle(chain, np.array(begin), settings)
        points, run = _sections(chain, state, settings.record)
    except OscillatorError as error:
        reason = error.reason if isinstance(error, SimulationFailed) else Reason.REFUSED
        return Landing(index, begin, "failed", reason, str(error), wall_time=time.perf_counter() - started)
    n = detect_period(points, settings.tolerance, settings.max_period)
    span = settings.record * chain.period
    rests, shares = _rests(run, span)
    closings = run.events.kind.isin([kind.value for kind in _CLOSES]).sum()
    last = chain.t0 + span - n * chain.period
    return Landing(
        index,
        begin,
        period=n,
        points=points,
        signature=chain_signature(run, last, n * chain.period) if n else "",
        rests=rests,
        contacts=float(closings * chain.period / span),
        wall_time=time.perf_counter() - started,
        rest_time=shares,
        transient=ran,
    )


@dataclass(frozen=True)
class ChainRefined:
    """The describer of a chain's attractors: a periodic one refined by
    :func:`~oscillator.orbits.chain_orbits.find_chain_orbit` from its cycle (its exact
    multipliers, its largest exponent from them, its measures:
    :func:`~oscillator.orbits.chain_response.orbit_measures`), an aperiodic one with the QR
    average of its largest exponent over ``lyapunov_periods`` (0: not computed); the chain's mass
    names on each."""

    lyapunov_periods: int = 300

    def __call__(self, chain: FrictionChain, attractor: Attractor) -> Attractor:
        period = chain.period
        named = dataclasses.replace(attractor, forcing_period=period, masses=tuple(m.name for m in chain.masses))
        if attractor.period:
            try:
                orbit = find_chain_orbit(chain, attractor.points[-1], period=attractor.period, transient=0)
            except OscillatorError as error:
                return dataclasses.replace(named, note=f"not refined: {error}")
            multipliers = orbit.multipliers
            largest = largest_exponent(multipliers, attractor.period * period) if len(multipliers) else 0.0
            note = "" if not orbit.neutral else orbit.verdict
            return dataclasses.replace(named, orbit=orbit, lyapunov=largest, note=note, measures=orbit_measures(orbit))
        if self.lyapunov_periods == 0:
            return named
        try:
            spectrum = chain_lyapunov(chain, guess=attractor.points[-1], transient=0, periods=self.lyapunov_periods)
        except OscillatorError as error:
            return dataclasses.replace(named, note=f"no Lyapunov exponent: {error}")
        return dataclasses.replace(named, lyapunov=spectrum.largest)


def chain_columns(attractor: Attractor) -> dict[str, float]:
    """A chain attractor's own columns in a table: each mass's ``rests:<mass>`` and
    ``rest_time:<mass>``, then its orbit's measures (``x_pp:<mass>``, ``stuck:<element>``, ...;
    none for an aperiodic set)."""
    columns = {f"rests:{m}": r for m, r in zip(attractor.masses, attractor.rests, strict=True)}
    columns |= {f"rest_time:{m}": r for m, r in zip(attractor.masses, attractor.rest_time, strict=True)}
    return columns | attractor.measures


def check_chain_states(chain: FrictionChain, states: object) -> np.ndarray:
    """The starts as an ``(N, n)`` array of the chain's state, checked (finite, the state's size,
    at most :data:`~oscillator.attractors.mapping.MAX_STARTS`)."""
    names = chain.system.state
    try:
        starts = np.array(states, dtype=float)
    except (TypeError, ValueError):
        starts = np.empty(0)
    starts = starts.reshape(1, -1) if starts.ndim == 1 else starts
    if starts.ndim != 2 or starts.shape[1] != len(names) or not len(starts) or not np.isfinite(starts).all():
        raise InputError(f"states must be rows of {len(names)} finite numbers ({', '.join(names)})", field="states")
    if len(starts) > MAX_STARTS:
        raise InputError(f"states: {len(starts):,} starts, more than {MAX_STARTS:,}", field="states")
    return starts


def find_chain_attractors(
    chain: FrictionChain,
    states: object = None,
    *,
    settings: AttractorSettings,
    executor: Executor,
    progress: Callable[[int, int], None] | None = None,
) -> ChainAttractors:
    """:func:`~oscillator.attractors.finding.find_attractors` for a friction chain: every
    attractor the starts (rows of its ``system.state``, its own start by default) reach, and
    which start reaches which (module docstring)."""
    chain = chain.checked()
    starts = check_chain_states(chain, state_of(chain) if states is None else states)
    with executor:
        landings = grid_landings(chain, settings, starts, None, executor, progress, land_chain)
        described, table, warnings = described_landings(
            chain, settings, landings, ChainRefined(settings.lyapunov_periods), executor
        )
    return ChainAttractors(chain, settings, described, table, warnings)


@dataclass(frozen=True)
class ChainAttractors:
    """What :func:`find_chain_attractors` found: the attractors and where each start went.

    Attributes
    ----------
    chain : FrictionChain
    settings : AttractorSettings
    attractors : tuple of Attractor
        Each with the chain's mass names (``masses``), its refined
        :class:`~oscillator.orbits.chain_orbits.ChainOrbit` (periodic ones) and its measures.
    labels : DataFrame
        One row per start: ``index``, the start (the chain's ``system.state`` columns),
        ``attractor`` (its id, -1 for a failed start), ``status``, ``reason``, ``message``,
        ``period``.
    warnings : tuple of str
        Where the grouping is not settled; empty when it is.
    """

    chain: FrictionChain
    settings: AttractorSettings
    attractors: tuple[Attractor, ...]
    labels: pd.DataFrame = field(repr=False)
    warnings: tuple[str, ...] = ()

    def fractions(self, confidence: float = 0.95) -> pd.DataFrame:
        """Each attractor's share of the starts, with Wilson's interval
        (:meth:`oscillator.attractors.finding.Attractors.fractions`)."""
        return fractions_of(self.attractors, self.labels, confidence)

    def noise(self, attractor: int, harmonics: int = 200) -> ChainNoise:
        """The spectra (docs/noise.md) of the attractor numbered ``attractor``: over one return of
        its refined orbit, with its noise measures (:meth:`ChainOrbit.noise`); else of the run of
        :meth:`~oscillator.attractors.grouping.Attractor.window` from the chain's ``t0`` (an
        aperiodic set: that window's spectra, the window taken as the period)."""
        from oscillator.orbits.chain_noise import chain_noise
        from oscillator.orbits.chain_orbits import ORBIT_OPTIONS, ChainOrbit

        found = attractor_numbered(self.attractors, attractor)
        if isinstance(found.orbit, ChainOrbit):
            return found.orbit.noise(harmonics)
        point, periods = found.window()
        end = self.chain.t0 + periods * self.chain.period
        return chain_noise(simulate_chain(self.chain, end, options=ORBIT_OPTIONS, start_state=point), harmonics)


@dataclass(frozen=True)
class ChainBasins(Presented):
    """The basins of a friction chain over a plane of two of its state coordinates: the
    attractors, and each cell's (the other coordinates at the chain's start).

    Attributes
    ----------
    found : ChainAttractors
        The attractors and the labels of every start (row ``j * x.count + i``).
    x, y : Axis
        The slice's axes (``x:<mass>``, ``v:<mass>``, ``z:<slider>``).
    """

    found: ChainAttractors
    x: Axis
    y: Axis

    @property
    def grid(self) -> np.ndarray:
        """The attractor of each cell, ``(y.count, x.count)``; -1 where the run failed."""
        labels: np.ndarray = self.found.labels.attractor.to_numpy()
        return labels.reshape(self.y.count, self.x.count)

    def plot(self) -> Figure:
        """The slice coloured by attractor, each attractor's section points on top."""
        return presenter().plot_chain_basins(self)


def find_chain_basins(
    chain: FrictionChain,
    x: Axis,
    y: Axis,
    store: LandingStore | None = None,
    *,
    settings: AttractorSettings | None = None,
    workers: int = 1,
    client: object = None,
    progress: Callable[[int, int], None] | None = None,
) -> ChainBasins:
    """The basins of ``chain`` over the plane of ``x`` and ``y`` (two of its ``system.state``;
    ``Axis("x:blade", -1, 1, 40)``), the other coordinates at its start: each cell's start run
    as :func:`find_chain_attractors` runs it, on ``workers`` processes or a Dask ``client``, the
    landings kept in ``store`` as they finish (``basin_store(folder, chain, x, y, settings)``:
    a run interrupted resumes) when one is given.  ``oscillator.find_basins(chain, x, y)`` calls
    it."""
    chain = chain.checked()
    settings = AttractorSettings() if settings is None else settings
    starts = chain_grid(chain, x, y)
    executor = Executor(workers, client, progress)
    if store is not None:
        store.open()
    with executor:
        landings = grid_landings(chain, settings, starts, store, executor, progress, land_chain)
        if store is not None:
            store.write_status("computed", starts=len(starts), failed=sum(not item.ok for item in landings))
        described, table, warnings = described_landings(
            chain, settings, landings, ChainRefined(settings.lyapunov_periods), executor
        )
    return ChainBasins(ChainAttractors(chain, settings, described, table, warnings), x, y)


def chain_grid(chain: FrictionChain, x: Axis, y: Axis) -> np.ndarray:
    """The slice's starts, ``(x.count * y.count, n)``, cell ``(i, j)`` at row ``j * x.count + i``;
    the other coordinates the chain's start.  The axes are checked to be two of its state's."""
    x, y = state_plane(x, y, chain.system.state)
    if x.count * y.count > MAX_STARTS:
        raise InputError(f"the slice has {x.count * y.count:,} starts, more than {MAX_STARTS:,}", field="axis")
    starts = np.tile(state_of(chain), (x.count * y.count, 1))
    xs, ys = np.meshgrid(x.values, y.values)
    starts[:, chain.system.state.index(x.name)] = xs.ravel()
    starts[:, chain.system.state.index(y.name)] = ys.ravel()
    return starts


def chain_lyapunov(
    chain: FrictionChain,
    *,
    periods: int = 500,
    transient: int = 100,
    guess: Sequence[float] | np.ndarray | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> LyapunovSpectrum:
    """The Lyapunov spectrum of the chain's motion from its start (or ``guess``, a state of its
    ``system.state`` at ``t0``) after ``transient`` forcing periods: the QR average
    (:func:`~oscillator.attractors.lyapunov.qr_average`) of the exact period maps' derivatives,
    tangent equations and saltation at every switch (:func:`~oscillator.orbits.chain_tangents.tangent_pass`).
    ``oscillator.lyapunov(chain)`` calls it."""
    chain = chain.checked()
    periods = check_count(periods, "periods", 1, MAX_PERIODS)
    transient = check_count(transient, "transient", 0, MAX_PERIODS)
    check_progress(progress)
    given = check_chain_states(chain, state_of(chain) if guess is None else guess)
    if len(given) != 1:
        raise InputError(f"guess must be one state of {chain.system.size} numbers, got {len(given)}", field="guess")
    y = given[0]
    if transient:
        y = _sections(chain, y, transient)[0][-1]

    def maps() -> Iterator[tuple[np.ndarray, np.ndarray]]:
        nonlocal y
        while True:
            run = simulate_chain(chain, chain.t0 + chain.period, options=LANDING_OPTIONS, start_state=y)
            y = np.asarray(run.y_end[: chain.system.size], dtype=float)
            yield tangent_pass(run).monodromy, y

    return qr_average(chain, maps(), chain.period, periods, progress)
