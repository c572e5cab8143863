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
import math
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from oscillator.analysis.execution import run_tasks
from oscillator.analysis.sweeps import detect_period
from oscillator.attractors.lyapunov import lyapunov
from oscillator.errors import InputError, OscillatorError, Reason, SimulationFailed
from oscillator.hybrid.simulate import simulate
from oscillator.io.cases import Case, resolve_case
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
    contacts: float = 0.0  #: contact onsets (either stop) per forcing period
    wall_time: float = 0.0


def _section_case(case: Case, start: Sequence[float], settings: AttractorSettings) -> tuple[Case, np.ndarray]:
    begin = dict(zip(STATE, (float(v) for v in start), strict=True))
    point = resolve_case(case, **begin)
    t0, period = point.initial.t0, point.parameters.period
    marks = t0 + period * np.arange(settings.transient, settings.transient + settings.record + 1)
    return point, marks


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
    contacts = sum(kind.contact_starts for _, _, kind in mine) / window
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
        The largest Lyapunov exponent (1/s) of an aperiodic set (NaN when not computed).
    note : str
        What the refinement met.
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
        parts = [f"m{mass} rests {rate:g}/period" for mass, rate in zip((1, 2), self.rests, strict=True) if rate]
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


def _set_distance(a: np.ndarray, b: np.ndarray) -> float:
    """The median distance from a point of ``a`` to the set ``b``."""
    gaps = np.linalg.norm(a[:, None, :] - b[None, :, :], axis=2)
    return float(np.median(np.min(gaps, axis=1)))


def _same(landing: Landing, points: np.ndarray, period: int, signature: str, settings: AttractorSettings) -> bool:
    if landing.period != period or landing.signature != signature:
        return False
    mine = landing.points[-period:] if period else landing.points
    scale = 1.0 + max(float(np.max(np.abs(mine))), float(np.max(np.abs(points))))
    if period:
        return _cycle_distance(mine, points) <= settings.match * scale
    size = max(float(np.ptp(mine, axis=0).max()), float(np.ptp(points, axis=0).max()))
    near = 0.1 * size + settings.match * scale
    return _set_distance(mine, points) <= near and _set_distance(points, mine) <= near


def group(landings: Iterable[Landing], settings: AttractorSettings) -> tuple[list[Attractor], dict[int, int]]:
    """The attractors of the landings, and each landing's attractor (``index -> id``, failed ones
    absent), numbered in the starts' order."""
    found: list[Attractor] = []
    labels: dict[int, int] = {}
    for landing in sorted(landings, key=lambda item: item.index):
        if landing.status != "ok":
            continue
        for k, attractor in enumerate(found):
            if _same(landing, attractor.points, attractor.period, attractor.signature, settings):
                labels[landing.index] = attractor.id
                found[k] = dataclasses.replace(attractor, starts=attractor.starts + 1)
                break
        else:
            points = landing.points[-landing.period :] if landing.period else landing.points
            attractor = Attractor(
                len(found), landing.period, points, landing.signature, landing.rests, landing.contacts, 1
            )
            found.append(attractor)
            labels[landing.index] = attractor.id
    return found, labels


def _refined(case: Case, attractor: Attractor, settings: AttractorSettings) -> Attractor:
    """The attractor with its orbit (periodic) or its largest Lyapunov exponent (aperiodic)."""
    period = case.parameters.period
    if attractor.period:
        try:
            orbit = find_orbit(case, period=attractor.period, guess=attractor.points[-1], transient=0)
        except OscillatorError as error:
            return dataclasses.replace(attractor, forcing_period=period, note=f"not refined: {error}")
        return dataclasses.replace(attractor, orbit=orbit, forcing_period=period, note=orbit.note)
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
    """

    case: Case
    settings: AttractorSettings
    attractors: tuple[Attractor, ...]
    labels: pd.DataFrame = field(repr=False)

    def fractions(self, confidence: float = 0.95) -> pd.DataFrame:
        """Each attractor's share of the starts (failed ones counted, as ``-1``), with Wilson's
        confidence interval: ``attractor, name, starts, fraction, low, high``."""
        from scipy.stats import binomtest

        total = len(self.labels)
        rows = []
        names = {a.id: a.name for a in self.attractors}
        counts = self.labels.attractor.value_counts()
        for ident in [a.id for a in self.attractors] + ([-1] if (self.labels.attractor == -1).any() else []):
            k = int(counts.get(ident, 0))
            interval = binomtest(k, total).proportion_ci(confidence_level=confidence, method="wilson")
            rows.append((ident, names.get(ident, "failed"), k, k / total, interval.low, interval.high))
        return pd.DataFrame(rows, columns=["attractor", "name", "starts", "fraction", "low", "high"])


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
    workers : int
        Local processes (1: this process).
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
    settings = settings or AttractorSettings()
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
    return Attractors(case, settings, refined, pd.DataFrame(rows, columns=columns))
