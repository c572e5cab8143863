"""Every attractor a case reaches from many starting states, and which start reaches which.

The starts are run by the mapper (:func:`~oscillator.attractors.mapping.land`) and grouped by
the grouper (:func:`~oscillator.attractors.grouping.group`); then each periodic attractor is
refined by :func:`~oscillator.orbits.shooting.find_orbit` from its cycle (its Floquet
multipliers, its stability), and each aperiodic one gets its largest Lyapunov exponent
(:func:`~oscillator.attractors.lyapunov.lyapunov`), which tells a chaotic set (positive) from a
quasi-periodic one (zero): :class:`Refined`, the describer of :func:`find_attractors`, of the
basins and of the attractors over a parameter.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, TypeVar, overload

import numpy as np
import pandas as pd

from oscillator.analysis.execution import Executor
from oscillator.attractors.grouping import Attractor, group, unsettled
from oscillator.attractors.lyapunov import lyapunov
from oscillator.attractors.mapping import STATE, AttractorSettings, Landing, check_settings, check_states, land
from oscillator.errors import InputError, OscillatorError
from oscillator.io.cases import Case, resolve_case
from oscillator.model.chains import FrictionChain
from oscillator.orbits.shooting import Orbit, find_orbit
from oscillator.text import shown

if TYPE_CHECKING:  # pragma: no cover
    from oscillator.attractors.chain_attractors import ChainAttractors
    from oscillator.orbits.noise import Noise

__all__ = [
    "Attractors",
    "Refined",
    "assemble",
    "attractor_numbered",
    "described_landings",
    "find_attractors",
    "fractions_of",
    "labelled",
    "share_interval",
    "share_text",
]

#: A system a describer takes: a case, or a friction chain.
S = TypeVar("S", Case, FrictionChain)


def largest_exponent(multipliers: np.ndarray, span: float) -> float:
    """The largest Lyapunov exponent of a periodic orbit: ``log |mu_1| / span`` from its Floquet
    multipliers over one return of ``span`` seconds (``-inf`` where every multiplier is 0)."""
    with np.errstate(divide="ignore"):  # a multiplier 0: the flow collapses every direction
        return float(np.log(np.max(np.abs(multipliers)))) / span


def _responses(orbit: Orbit, cutoff: float) -> dict[str, float]:
    """The orbit's response measures by column, ``force_above`` and ``a_above`` above ``cutoff``
    Hz (none where its return cannot be run again)."""
    try:
        return orbit.response(cutoff).columns()
    except OscillatorError:
        return {}


@dataclass(frozen=True)
class Refined:
    """The describer of :func:`find_attractors`: a periodic attractor with its orbit refined by
    Newton from its cycle (multipliers, stability), its largest exponent from them and its
    response measures (:meth:`~oscillator.orbits.shooting.Orbit.response`, in ``measures``); an
    aperiodic one with the QR average of its largest exponent over ``lyapunov_periods`` (0: not
    computed).  What the refinement met is in the attractor's ``note``; ``cutoff`` (Hz) that of
    the measures ``force_above`` and ``a_above``."""

    lyapunov_periods: int = 300
    cutoff: float = 0.0

    def __call__(self, case: Case, attractor: Attractor) -> Attractor:
        period = case.parameters.period
        if attractor.period:
            try:
                orbit = find_orbit(case, period=attractor.period, guess=attractor.points[-1], transient=0)
            except OscillatorError as error:
                return dataclasses.replace(attractor, forcing_period=period, note=f"not refined: {error}")
            largest = largest_exponent(orbit.multipliers, attractor.period * period)
            measures = _responses(orbit, self.cutoff)
            return dataclasses.replace(
                attractor, orbit=orbit, lyapunov=largest, forcing_period=period, note=orbit.note, measures=measures
            )
        if self.lyapunov_periods == 0:
            return dataclasses.replace(attractor, forcing_period=period)
        try:
            spectrum = lyapunov(case, guess=attractor.points[-1], transient=0, periods=self.lyapunov_periods)
        except OscillatorError as error:
            return dataclasses.replace(attractor, forcing_period=period, note=f"no Lyapunov exponent: {error}")
        return dataclasses.replace(attractor, lyapunov=spectrum.largest, forcing_period=period)


@dataclass(frozen=True)
class Attractors:
    """What :func:`find_attractors` found: the attractors and where each start went.

    Attributes
    ----------
    case : Case
        The case, with the overrides.
    settings : AttractorSettings
    attractors : tuple of Attractor
    labels : DataFrame
        One row per start: ``index``, ``x1 v1 x2 v2`` (the start), ``attractor`` (its id, -1 for
        a failed start), ``status``, ``reason``, ``message``, ``period``.
    warnings : tuple of str
        Where the grouping is not settled (:func:`unsettled`); empty when it is.
    """

    case: Case
    settings: AttractorSettings
    attractors: tuple[Attractor, ...]
    labels: pd.DataFrame = field(repr=False)
    warnings: tuple[str, ...] = ()

    def fractions(self, confidence: float = 0.95) -> pd.DataFrame:
        """Each attractor's share of the starts (failed ones counted, as ``-1``), with its
        :func:`share_interval`: ``attractor, name, starts, fraction, low, high``."""
        return fractions_of(self.attractors, self.labels, confidence)

    def noise(self, attractor: int, harmonics: int = 200) -> Noise:
        """The noise measures and spectra (docs/noise.md) of the attractor numbered ``attractor``:
        over one return of its refined orbit (:meth:`Orbit.noise`), or of the run from its last
        section point where Newton did not refine it; of an aperiodic set over the run of
        :meth:`~oscillator.attractors.grouping.Attractor.window` (from its first section point,
        as many forcing periods as it has recorded points, at most 100), that window's spectra:
        harmonic ``k`` at ``k / (n T)`` Hz, the window taken as the period."""
        from oscillator.orbits.noise import noise

        found = attractor_numbered(self.attractors, attractor)
        if isinstance(found.orbit, Orbit):
            return found.orbit.noise(harmonics)
        point, periods = found.window()
        begin = dict(zip(self.case.system.state, (float(v) for v in point), strict=True))
        return noise(resolve_case(self.case, **begin), periods, harmonics)


def attractor_numbered(attractors: Sequence[Attractor], number: object) -> Attractor:
    """The attractor whose :attr:`~oscillator.attractors.grouping.Attractor.id` is ``number``."""
    found = next((a for a in attractors if not isinstance(number, bool) and a.id == number), None)
    if found is None:
        known = ", ".join(str(a.id) for a in attractors) or "none were found"
        raise InputError(f"attractor must be the number of one found ({known}), got {shown(number)}", field="attractor")
    return found


def fractions_of(attractors: Sequence[Attractor], labels: pd.DataFrame, confidence: float = 0.95) -> pd.DataFrame:
    """:meth:`Attractors.fractions` of the ``attractors`` and the starts' ``labels``."""
    total = len(labels)
    rows = []
    names = {a.id: a.name for a in attractors}
    counts = labels.attractor.value_counts()
    for ident in [a.id for a in attractors] + ([-1] if (labels.attractor == -1).any() else []):
        k = int(counts.get(ident, 0))
        rows.append((ident, names.get(ident, "failed"), k, k / total, *share_interval(k, total, confidence)))
    return pd.DataFrame(rows, columns=["attractor", "name", "starts", "fraction", "low", "high"])


def share_interval(k: int, total: int, confidence: float = 0.95) -> tuple[float, float]:
    """Wilson's interval for the share of the sampled starting states that reach an attractor,
    estimated from ``k`` of ``total`` starts (the share of a slice's area, for a grid of it);
    NaN for fewer than two starts, where it says nothing."""
    if total < 2:
        return math.nan, math.nan
    from scipy.stats import binomtest

    interval = binomtest(k, total).proportion_ci(confidence_level=confidence, method="wilson")
    return float(interval.low), float(interval.high)


def share_text(fraction: float, low: float, high: float) -> str:
    """A share for people: ``"61.7 % [58.4 %, 64.8 %]"``, or ``"100.0 %"`` without an interval."""
    if math.isnan(low):
        return f"{fraction:.1%}"
    return f"{fraction:.1%} [{low:.1%}, {high:.1%}]"


@overload
def find_attractors(case: FrictionChain, **options: Any) -> ChainAttractors: ...


@overload
def find_attractors(case: Case | str, **options: Any) -> Attractors: ...


def find_attractors(
    case: Case | FrictionChain | str,
    *,
    states: Sequence[Sequence[float]] | np.ndarray | None = None,
    transient: int | None = None,
    record: int | None = None,
    settings: AttractorSettings | None = None,
    workers: int = 1,
    client: Any = None,
    progress: Callable[[int, int], None] | None = None,
    **overrides: float,
) -> Attractors | ChainAttractors:
    """Every attractor the starts reach, and which start reaches which.

    Parameters
    ----------
    case : Case, FrictionChain or str
        A case or a shipped case's name; or a declared system
        (:func:`oscillator.attractors.chain_attractors.find_chain_attractors`).
    states : array of shape (N, 4), optional
        The starts ``(x1, v1, x2, v2)`` at the case's ``t0`` (a chain's ``system.state``); the
        case's own start by default.
    transient, record : int, optional
        Forcing periods run before recording, and recorded (``settings``' by default).
    settings : AttractorSettings, optional
        Transient, recorded periods, tolerances (the defaults of :class:`AttractorSettings`).
    workers : int or None
        Local processes (1: this process; None: one per core; at most 4 per core).  Each imports
        the calling script again as it starts (multiprocessing's ``forkserver``, or ``spawn``
        without it): in a script, call with ``workers > 1`` under ``if __name__ == "__main__":``
        (without it the call raises :class:`~oscillator.errors.InputError` saying so).
    client : dask.distributed.Client, optional
        Run the starts on this Dask cluster instead.
    progress : callable, optional
        ``progress(done, total)`` after every start.
    **overrides
        Any parameter or solver option, as for :func:`oscillator.simulate`; a chain's numbers by
        their names (``Omega=1.2``, ``**{"platform.F": 0.5}``).

    Examples
    --------
    >>> from oscillator.attractors.finding import find_attractors
    >>> found = find_attractors("instance-1", Omega=1.85)
    >>> [(a.period, a.stable) for a in found.attractors]
    [(1, True)]
    """
    settings = check_settings(settings)
    executor = Executor(workers, client, progress)
    chosen: dict[str, Any] = {
        name: value for name, value in (("transient", transient), ("record", record)) if value is not None
    }
    settings = dataclasses.replace(settings, **chosen) if chosen else settings
    if isinstance(case, FrictionChain):
        from oscillator.attractors.chain_attractors import find_chain_attractors

        chain = case.with_values(overrides) if overrides else case
        return find_chain_attractors(chain, states, settings=settings, executor=executor, progress=progress)
    case = resolve_case(case, **overrides)
    starts = check_states(case.initial.y if states is None else states)
    landings = []
    tasks = [(index, tuple(row)) for index, row in enumerate(starts)]
    with executor:
        for landing in executor.map(land, tasks, shared=(case, settings)):
            landings.append(landing)
            if progress is not None:
                progress(len(landings), len(tasks))
        return assemble(case, settings, landings, executor=executor)


def assemble(
    case: Case,
    settings: AttractorSettings,
    landings: list[Landing],
    *,
    describe: Callable[[Case, Attractor], Attractor] | None = None,
    executor: Executor | None = None,
) -> Attractors:
    """The :class:`Attractors` of finished landings: grouped, described (by ``describe``, the
    :class:`Refined` of ``settings`` by default; on ``executor``, in this process by default),
    each start labelled."""
    described, table, warnings = described_landings(
        case, settings, landings, describe or Refined(settings.lyapunov_periods, settings.cutoff), executor
    )
    return Attractors(case, settings, described, table, warnings)


def described_landings(
    system: S,
    settings: AttractorSettings,
    landings: list[Landing],
    describe: Callable[[S, Attractor], Attractor],
    executor: Executor | None = None,
) -> tuple[tuple[Attractor, ...], pd.DataFrame, tuple[str, ...]]:
    """The landings grouped (:func:`~oscillator.attractors.grouping.group`), each attractor
    described by ``describe(system, attractor)`` (on ``executor``, in this process by default),
    each start labelled (:func:`labelled`, the system's state as its columns), and the warnings
    where the grouping is not settled."""
    found, labels = group(landings, settings)
    run = executor.map if executor is not None else Executor().map
    described = sorted(run(describe, [(system, attractor) for attractor in found]), key=lambda a: a.id)
    table = labelled(landings, labels, system.system.state)
    return tuple(described), table, tuple(unsettled(found))


def labelled(landings: Sequence[Landing], labels: dict[int, int], state: Sequence[str] = STATE) -> pd.DataFrame:
    """One row per start (in the starts' order): ``index``, the start (its ``state`` columns),
    its ``attractor`` (-1 for a failed start), ``status``, ``reason``, ``message``, ``period``."""
    rows = [
        (item.index, *item.start, labels.get(item.index, -1), item.status, item.reason or "", item.message, item.period)
        for item in sorted(landings, key=lambda item: item.index)
    ]
    return pd.DataFrame(rows, columns=["index", *state, "attractor", "status", "reason", "message", "period"])
