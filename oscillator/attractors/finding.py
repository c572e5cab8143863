"""Every attractor a case reaches from many starting states, and which start reaches which.

Each start ``(x1, v1, x2, v2)`` at the case's ``t0`` (the stroboscopic section) is simulated
for ``transient`` forcing periods and then ``record`` more, keeping the section points ``P_k =
y(t0 + k T)`` of the recorded window (:func:`land`: a pure function, so the same landings come
out in this process, on a process pool or on a Dask cluster).  A start whose points repeat
with period ``n <= max_period`` has reached a period-``n`` orbit: its cycle is the last ``n``
points; one whose points do not repeat has reached an aperiodic set (or not yet settled).

Landings are grouped into attractors in the starts' order (so the same starts give the same
attractors, numbered the same, for any number of workers): two periodic landings are one
attractor when their cycles of switches are the same (:class:`~oscillator.orbits.shooting.Signature`)
and their cycles of section points agree, in some rotation, within ``match`` (relative to the
state's size); two aperiodic ones when each one's points lie near the other's set.  Then each
periodic attractor is refined by :func:`~oscillator.orbits.shooting.find_orbit` from its cycle
(its Floquet multipliers, its stability), and each aperiodic one gets its largest Lyapunov
exponent (:func:`~oscillator.attractors.lyapunov.lyapunov`), which tells a chaotic set (positive)
from a quasi-periodic one (zero).
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from oscillator.analysis.execution import check_runner, run_tasks
from oscillator.analysis.intervals import rest_intervals
from oscillator.analysis.sweeps import detect_period
from oscillator.attractors.lyapunov import lyapunov
from oscillator.errors import InputError, OscillatorError, Reason, SimulationFailed
from oscillator.hybrid.simulate import simulate
from oscillator.io.cases import Case, resolve_case, section_times
from oscillator.model.events import EventKind
from oscillator.orbits.shooting import Orbit, check_count, find_orbit, signature_of
from oscillator.text import shown

__all__ = ["Attractor", "AttractorSettings", "Attractors", "Landing", "find_attractors", "group", "land"]

STATE = ("x1", "v1", "x2", "v2")
#: The most starts one search takes (a 1000 x 1000 grid).
MAX_STARTS = 1_000_000
#: ``lambda_1 T`` above which an aperiodic attractor is called chaotic, and below whose size it is
#: called quasi-periodic (the exponent is zero within what the averaging resolves).
CHAOTIC = 0.01
#: Two aperiodic landings are one attractor when their points :func:`interleaving` at least this
#: much (1: as two samples of one set; 0: sets apart) ...
INTERLEAVED = 0.5
#: ... and the grouping is said not to be settled where two sets kept apart interleave more than this.
UNSETTLED = 0.1
#: The most section points an aperiodic attractor pools from its landings, to tell later ones by.
SET_POINTS = 4096


@dataclass(frozen=True)
class AttractorSettings:
    """How starts are run and landings told apart.

    Attributes
    ----------
    transient : int
        Forcing periods run before the section points are recorded (1 to 10^6).
    record : int
        Forcing periods recorded after it (2 to 10^5): the longest period found is
        ``min(max_period, record - 1)``, and an aperiodic set is sampled by ``record + 1`` points.
    tolerance : float
        Two section points of one landing are equal within ``tolerance (1 + |P|)`` (its period).
    max_period : int
        The longest period looked for.
    match : float
        Two landings' cycles are the same attractor within ``match (1 + |P|)``.
    lyapunov_periods : int
        Forcing periods over which an aperiodic attractor's largest exponent is averaged (0: not
        computed).
    """

    transient: int = 200
    record: int = 32
    tolerance: float = 1e-6
    max_period: int = 16
    match: float = 1e-4
    lyapunov_periods: int = 300

    def __post_init__(self) -> None:
        check_count(self.transient, "transient", 1, 1_000_000)
        check_count(self.record, "record", 2, 100_000)
        check_count(self.max_period, "max_period", 1, 1000)
        check_count(self.lyapunov_periods, "lyapunov_periods", 0, 10_000_000)
        for name in ("tolerance", "match"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and not isinstance(value, bool) and 0 < value < 1):
                raise InputError(f"{name} must be a number between 0 and 1, got {shown(value)}", field=name)


@dataclass(frozen=True)
class Landing:
    """Where one start went: what :func:`land` returns for it."""

    index: int
    start: tuple[float, float, float, float]
    status: str = "ok"  #: ``ok`` or ``failed``
    reason: str = ""  #: why it failed, for a program (:class:`~oscillator.errors.Reason`)
    message: str = ""  #: why it failed, in words
    period: int = 0  #: period-n of its section points, 0 if none up to ``max_period``
    points: np.ndarray = field(default_factory=lambda: np.empty((0, 4)), repr=False)  #: recorded section points
    signature: str = ""  #: each mass's cycle of switches over one period (periodic landings)
    rests: tuple[float, float] = (0.0, 0.0)  #: rest intervals per forcing period, of m1 and m2
    contacts: float = 0.0  #: contact onsets (either stop; a contact between the masses once) per forcing period
    wall_time: float = 0.0
    rest_time: tuple[float, float] = (0.0, 0.0)  #: the fraction of the time m1 and m2 rest (1: throughout)


def _section_case(case: Case, start: Sequence[float], settings: AttractorSettings) -> tuple[Case, np.ndarray]:
    begin = dict(zip(STATE, (float(v) for v in start), strict=True))
    point = resolve_case(case, **begin)
    return point, section_times(point, settings.transient, settings.transient + settings.record)


def land(case: Case, settings: AttractorSettings, index: int, start: Sequence[float]) -> Landing:
    """Run one start and read where it went (section points, period, switches per period).

    A start the model refuses or a failed run gives a landing with ``status = "failed"`` and the
    reason."""
    started = time.perf_counter()
    x1, v1, x2, v2 = (float(v) for v in start)
    begin = (x1, v1, x2, v2)
    try:
        point, marks = _section_case(case, begin, settings)
        result = simulate(point, t_end=float(marks[-1]), t_eval=marks, keep_events_from=float(marks[0]))
    except OscillatorError as error:
        reason = error.reason if isinstance(error, SimulationFailed) else Reason.REFUSED
        return Landing(index, begin, "failed", reason.value, str(error), wall_time=time.perf_counter() - started)
    points = result.trajectory[list(STATE)].to_numpy()
    n = detect_period(points, settings.tolerance, settings.max_period)
    period = point.parameters.period
    window = n if n else settings.record
    last = float(marks[-1]) - window * period
    events = result.events
    kinds = [(float(t), int(m), EventKind(k)) for t, m, k in zip(events.t, events["mass"], events.kind, strict=True)]
    mine = [(t, m, kind) for t, m, kind in kinds if t >= last - 1e-9 * period]
    rests = tuple(sum(kind.starts_rest for _, m, kind in mine if m == mass) / window for mass in (1, 2))
    first = result.trajectory.iloc[len(marks) - 1 - window]  # the state where the window starts
    rest_time = tuple(
        sum(b - a for a, b in rest_intervals(events, mass, int(first[f"domain{mass}"]) == 0, last, float(marks[-1])))
        / (window * period)
        for mass in (1, 2)
    )
    contacts = sum(kind.contact_starts and kind.stands_for_event(m) for _, m, kind in mine) / window
    signature = str(signature_of(mine, n * period)) if n else ""
    return Landing(
        index,
        begin,
        period=n,
        points=points,
        signature=signature,
        rests=(float(rests[0]), float(rests[1])),
        contacts=float(contacts),
        wall_time=time.perf_counter() - started,
        rest_time=(float(rest_time[0]), float(rest_time[1])),
    )


@dataclass(frozen=True)
class Attractor:
    """One attractor: a period-n orbit of the stroboscopic map, or an aperiodic set.

    Attributes
    ----------
    id : int
        Its number, from 0, in the order the starts first reached it.
    period : int
        Forcing periods per return; 0 for an aperiodic set.
    points : ndarray
        Its section points ``(x1, v1, x2, v2)``: the ``period`` points of the cycle, or the
        recorded points of the set.
    signature : str
        Each mass's cycle of switches over one return (periodic attractors).
    rests : tuple of float
        Rest intervals per forcing period of m1 and of m2.
    contacts : float
        Contact onsets (either stop) per forcing period.
    starts : int
        How many starts reached it.
    orbit : Orbit or None
        The periodic orbit refined by Newton from its cycle (multipliers, stability); None for an
        aperiodic set or when Newton failed (``note`` says why).
    lyapunov : float
        The largest Lyapunov exponent (1/s): ``log |mu_1| / (n T)`` of a refined periodic orbit
        (its largest Floquet multiplier; 0 where a mass rests all period, ``-inf`` where the
        flow collapses every direction), the QR average of an aperiodic set; NaN when not
        computed.
    note : str
        What the refinement met.
    forcing_period : float
        ``T`` of the case it was found in.
    rest_time : tuple of float
        The fraction of the time m1 and m2 rest (1: a mass that rests throughout, with no rest
        interval beginning).
    """

    id: int
    period: int
    points: np.ndarray = field(repr=False)
    signature: str
    rests: tuple[float, float]
    contacts: float
    starts: int
    orbit: Orbit | None = field(default=None, repr=False)
    lyapunov: float = math.nan
    note: str = ""
    forcing_period: float = math.nan
    rest_time: tuple[float, float] = (0.0, 0.0)

    @classmethod
    def of_landing(cls, ident: int, landing: Landing) -> Attractor:
        """The attractor a landing has reached, as far as the landing tells (one start, its cycle
        or its recorded set; not refined)."""
        points = landing.points[-landing.period :] if landing.period else landing.points
        return cls(
            ident,
            landing.period,
            points,
            landing.signature,
            landing.rests,
            landing.contacts,
            1,
            rest_time=landing.rest_time,
        )

    @property
    def kind(self) -> str:
        """``periodic``, ``chaotic`` (largest exponent positive), ``quasi-periodic`` (zero) or
        ``aperiodic`` (no period found and no exponent to tell)."""
        if self.period:
            return "periodic"
        if math.isnan(self.lyapunov) or math.isnan(self.forcing_period):
            return "aperiodic"
        scaled = self.lyapunov * self.forcing_period
        if scaled > CHAOTIC:
            return "chaotic"
        return "quasi-periodic" if scaled > -CHAOTIC else "aperiodic"

    @property
    def name(self) -> str:
        """A label for legends and tables: ``"A0: period-1, m2 rests 2/period"``."""
        what = f"period-{self.period}" if self.period else self.kind
        parts = [
            f"m{mass} rests {rate:g}/period" if rate else f"m{mass} rests throughout"
            for mass, rate, share in zip((1, 2), self.rests, self.rest_time, strict=True)
            if rate or share > 0
        ]
        if self.contacts:
            parts.append(f"{self.contacts:g} contacts/period")
        return f"A{self.id}: {what}" + (", " + ", ".join(parts) if parts else ", no rest")

    @property
    def stable(self) -> bool | None:
        """The refined orbit's stability (None when there is no refined orbit)."""
        return None if self.orbit is None else self.orbit.stable


def _cycle_distance(a: np.ndarray, b: np.ndarray) -> float:
    """The smallest, over rotations of ``b``, largest distance between the two cycles' points."""
    return min(float(np.max(np.linalg.norm(a - np.roll(b, r, axis=0), axis=1))) for r in range(len(b)))


def interleaving(a: np.ndarray, b: np.ndarray) -> float:
    """How much two point sets interleave: the share of all their points whose nearest other
    point belongs to the other set, over the share expected were both samples of one set
    (``2 |a| |b| / (n (n - 1))``).  About 1 for two samples of one attractor, however sparse;
    near 0 for two sets apart.  Distances are taken in units of the union's extent in each
    component, so that displacements and velocities weigh alike."""
    from scipy.spatial import cKDTree

    both = np.vstack([a, b])
    n = len(both)
    if len(a) == 0 or len(b) == 0 or n < 3:
        return 0.0
    extent = np.ptp(both, axis=0)
    scaled = both / np.where(extent > 0, extent, 1.0)
    _, nearest = cKDTree(scaled).query(scaled, k=2)
    owner = np.arange(n) >= len(a)
    crossing = float(np.mean(owner[nearest[:, 1]] != owner))
    return crossing / (2.0 * len(a) * len(b) / (n * (n - 1)))


def _same_cycle(landing: Landing, attractor: Attractor, settings: AttractorSettings) -> bool:
    if landing.period != attractor.period or landing.signature != attractor.signature:
        return False
    mine = landing.points[-attractor.period :]
    scale = 1.0 + max(float(np.max(np.abs(mine))), float(np.max(np.abs(attractor.points))))
    return _cycle_distance(mine, attractor.points) <= settings.match * scale


def _pooled(keep: Attractor, points: np.ndarray, starts: int) -> Attractor:
    """An aperiodic attractor with more starts and their points pooled into its own (at most
    :data:`SET_POINTS`, the earlier ones kept)."""
    pool = np.vstack([keep.points, points])[:SET_POINTS]
    return dataclasses.replace(keep, points=pool, starts=keep.starts + starts)


def group(landings: Iterable[Landing], settings: AttractorSettings) -> tuple[list[Attractor], dict[int, int]]:
    """The attractors of the landings, and each landing's attractor (``index -> id``, failed ones
    absent), in :func:`ordered` order: the same starts give the same attractors, numbered the
    same, for any number of workers and in any command.

    A periodic landing joins the attractor with its period, its cycle of switches and its cycle of
    section points (within ``match``); an aperiodic one joins the aperiodic attractor whose
    points it :func:`interleaving` most, if at least :data:`INTERLEAVED`, and adds its points to
    it.  Then aperiodic attractors whose pooled points interleave are merged (two samples of one
    set that met no common landing on the way)."""
    found: list[Attractor] = []
    members: list[list[int]] = []
    for landing in sorted(landings, key=lambda item: item.index):
        if landing.status != "ok":
            continue
        k = _joined(landing, found, settings)
        if k is None:
            found.append(Attractor.of_landing(len(found), landing))
            members.append([landing.index])
            continue
        if landing.period:
            found[k] = dataclasses.replace(found[k], starts=found[k].starts + 1)
        else:
            found[k] = _pooled(found[k], landing.points, 1)
        members[k].append(landing.index)
    found, members = _merge_interleaved(found, members)
    return ordered(found, members)


def _joined(landing: Landing, found: list[Attractor], settings: AttractorSettings) -> int | None:
    """The attractor of ``found`` the landing belongs to, or None."""
    if landing.period:
        return next((k for k, a in enumerate(found) if _same_cycle(landing, a, settings)), None)
    scores = [(interleaving(landing.points, a.points), k) for k, a in enumerate(found) if not a.period]
    best = max(scores, default=(0.0, -1))
    return best[1] if best[0] >= INTERLEAVED else None


def _merge_interleaved(found: list[Attractor], members: list[list[int]]) -> tuple[list[Attractor], list[list[int]]]:
    """The aperiodic attractors whose points interleave, merged (the first one keeps the rest)."""
    merged = True
    while merged:
        merged = False
        aperiodic = [k for k, a in enumerate(found) if not a.period]
        for i, j in itertools.combinations(aperiodic, 2):
            if interleaving(found[i].points, found[j].points) >= INTERLEAVED:
                found[i] = _pooled(found[i], found[j].points, found[j].starts)
                members[i] += members[j]
                del found[j], members[j]
                merged = True
                break
    return found, members


def order_key(attractor: Attractor) -> tuple[Any, ...]:
    """What orders attractors, whatever the order the starts met them: periodic ones first by
    period, rests, contacts and cycle of switches, then by their section points; aperiodic ones
    last, by the centre of their points."""
    if attractor.period:
        first = min(tuple(np.round(point, 6)) for point in attractor.points)
        return (0, attractor.period, attractor.rests, attractor.contacts, attractor.signature, first)
    return (
        1,
        0,
        attractor.rests,
        attractor.contacts,
        "",
        tuple(np.round(np.asarray(attractor.points).mean(axis=0), 3)),
    )


def ordered(found: list[Attractor], members: list[list[int]]) -> tuple[list[Attractor], dict[int, int]]:
    """The attractors sorted by :func:`order_key` and numbered from 0, and each member's number."""
    order = sorted(range(len(found)), key=lambda k: order_key(found[k]))
    attractors = [dataclasses.replace(found[k], id=new) for new, k in enumerate(order)]
    labels = {index: new for new, k in enumerate(order) for index in members[k]}
    return attractors, labels


def unsettled(attractors: Sequence[Attractor]) -> list[str]:
    """Warnings where the grouping of aperiodic sets is not settled: two sets kept apart whose
    points interleave more than :data:`UNSETTLED` (they may be one attractor, sampled too thinly)."""
    aperiodic = [a for a in attractors if not a.period]
    said = []
    for a, b in itertools.combinations(aperiodic, 2):
        score = interleaving(a.points, b.points)
        if score >= UNSETTLED:
            said.append(
                f"A{a.id} and A{b.id} may be one aperiodic attractor: their section points interleave "
                f"({score:.2f}; 1 for two samples of one set, 0 for sets apart); record more periods (--record) to "
                "tell"
            )
    return said


def largest_exponent(multipliers: np.ndarray, span: float) -> float:
    """The largest Lyapunov exponent of a periodic orbit: ``log |mu_1| / span`` from its Floquet
    multipliers over one return of ``span`` seconds (``-inf`` where every multiplier is 0)."""
    with np.errstate(divide="ignore"):  # a multiplier 0: the flow collapses every direction
        return float(np.log(np.max(np.abs(multipliers)))) / span


def _refined(case: Case, attractor: Attractor, settings: AttractorSettings) -> Attractor:
    """The attractor with its orbit (periodic) or its largest Lyapunov exponent (aperiodic)."""
    period = case.parameters.period
    if attractor.period:
        try:
            orbit = find_orbit(case, period=attractor.period, guess=attractor.points[-1], transient=0)
        except OscillatorError as error:
            return dataclasses.replace(attractor, forcing_period=period, note=f"not refined: {error}")
        largest = largest_exponent(orbit.multipliers, attractor.period * period)
        return dataclasses.replace(attractor, orbit=orbit, lyapunov=largest, forcing_period=period, note=orbit.note)
    if settings.lyapunov_periods == 0:
        return dataclasses.replace(attractor, forcing_period=period)
    try:
        spectrum = lyapunov(case, guess=attractor.points[-1], transient=0, periods=settings.lyapunov_periods)
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
        total = len(self.labels)
        rows = []
        names = {a.id: a.name for a in self.attractors}
        counts = self.labels.attractor.value_counts()
        for ident in [a.id for a in self.attractors] + ([-1] if (self.labels.attractor == -1).any() else []):
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


def check_settings(settings: object) -> AttractorSettings:
    """``settings`` if it is an :class:`AttractorSettings`, the defaults for None, else refused."""
    if settings is None:
        return AttractorSettings()
    if not isinstance(settings, AttractorSettings):
        raise InputError(
            f"settings must be an AttractorSettings (or None for the defaults), got {shown(settings)}; give "
            "AttractorSettings(transient=..., record=...)",
            field="settings",
        )
    return settings


def check_states(states: object) -> np.ndarray:
    """Starts as an ``(N, 4)`` array of finite numbers, ``1 <= N <= MAX_STARTS``."""
    try:
        array = np.asarray(states, dtype=float)
    except (TypeError, ValueError):
        array = np.empty((0, 0))
    if array.ndim == 1 and array.size == 4:
        array = array[None, :]
    if array.ndim != 2 or array.shape[1] != 4 or not 1 <= len(array) <= MAX_STARTS or not np.isfinite(array).all():
        raise InputError(
            f"states must be rows of four finite numbers (x1, v1, x2, v2), 1 to {MAX_STARTS} of them; got "
            f"{shown(states)}",
            field="states",
        )
    return array


def find_attractors(
    case: Case | str,
    *,
    states: Sequence[Sequence[float]] | np.ndarray | None = None,
    transient: int | None = None,
    record: int | None = None,
    settings: AttractorSettings | None = None,
    workers: int = 1,
    client: Any = None,
    progress: Callable[[int, int], None] | None = None,
    **overrides: float,
) -> Attractors:
    """Every attractor the starts reach, and which start reaches which.

    Parameters
    ----------
    case : Case or str
        A case or a shipped case's name.
    states : array of shape (N, 4), optional
        The starts ``(x1, v1, x2, v2)`` at the case's ``t0``; the case's own start by default.
    transient, record : int, optional
        Forcing periods run before recording, and recorded (``settings``' by default).
    settings : AttractorSettings, optional
        Transient, recorded periods, tolerances (the defaults of :class:`AttractorSettings`).
    workers : int or None
        Local processes (1: this process; None: one per core; at most 4 per core).  They are
        started with ``spawn``, which imports the calling script again in each: in a script, call
        with ``workers > 1`` under ``if __name__ == "__main__":`` (without it the call raises
        :class:`~oscillator.errors.InputError` saying so).
    client : dask.distributed.Client, optional
        Run the starts on this Dask cluster instead.
    progress : callable, optional
        ``progress(done, total)`` after every start.
    **overrides
        Any parameter or solver option, as for :func:`oscillator.simulate`.

    Examples
    --------
    >>> from oscillator.attractors.finding import find_attractors
    >>> found = find_attractors("instance-1", Omega=1.85)
    >>> [(a.period, a.stable) for a in found.attractors]
    [(1, True)]
    """
    settings = check_settings(settings)
    workers = check_runner(workers, client, progress)
    chosen = {name: value for name, value in (("transient", transient), ("record", record)) if value is not None}
    settings = dataclasses.replace(settings, **chosen) if chosen else settings
    case = resolve_case(case, **overrides)
    starts = check_states(case.initial.y if states is None else states)
    landings = []
    tasks = [(index, tuple(row)) for index, row in enumerate(starts)]
    for landing in run_tasks(land, tasks, shared=(case, settings), workers=workers, client=client):
        landings.append(landing)
        if progress is not None:
            progress(len(landings), len(tasks))
    return assemble(case, settings, landings)


def assemble(case: Case, settings: AttractorSettings, landings: list[Landing]) -> Attractors:
    """The :class:`Attractors` of finished landings: grouped, refined, each start labelled."""
    found, labels = group(landings, settings)
    refined = tuple(_refined(case, attractor, settings) for attractor in found)
    rows = [
        (item.index, *item.start, labels.get(item.index, -1), item.status, item.reason, item.message, item.period)
        for item in sorted(landings, key=lambda item: item.index)
    ]
    columns = ["index", *STATE, "attractor", "status", "reason", "message", "period"]
    return Attractors(case, settings, refined, pd.DataFrame(rows, columns=columns), tuple(unsettled(found)))
