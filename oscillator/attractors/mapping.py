"""The mapper: where one start goes.

Each start ``(x1, v1, x2, v2)`` at the case's ``t0`` (the stroboscopic section) is simulated
for ``transient`` forcing periods and then ``record`` more, keeping the section points ``P_k =
y(t0 + k T)`` of the recorded window (:func:`land`: a pure function, so the same landings come
out in this process, on a process pool or on a Dask cluster).  A start whose points repeat
with period ``n <= max_period`` has reached a period-``n`` orbit: its cycle is the last ``n``
points, with each mass's cycle of switches (:class:`~oscillator.orbits.signature.Signature`),
its rests and contacts per period; one whose points do not repeat has reached an aperiodic set
(or not yet settled).  Attractors.jl calls this piece the mapper (``AttractorsViaRecurrences``
and ``AttractorsViaFeaturizing`` are its others).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from oscillator.analysis.axes import STATE
from oscillator.analysis.execution import before_workers
from oscillator.analysis.intervals import rest_intervals
from oscillator.analysis.periods import detect_period
from oscillator.engines import check_engine
from oscillator.engines.dop853 import new_work
from oscillator.errors import InputError, OscillatorError, Reason, SimulationFailed
from oscillator.hybrid.batch import OK, SETTLE_CHUNK, SHORTER_CYCLE, land_compiled, options_vector, recorded
from oscillator.hybrid.counting import counted
from oscillator.hybrid.guards import ARITHMETIC_ERRORS
from oscillator.hybrid.recording import SaveAt
from oscillator.hybrid.result import Result
from oscillator.hybrid.simulate import simulate
from oscillator.io.cases import Case, resolve_case, section_times
from oscillator.model.events import COLUMN, KINDS, WIDTH, EventKind
from oscillator.model.fields import coefficients
from oscillator.model.parameters import check_count
from oscillator.orbits.signature import signature_of
from oscillator.orbits.spectra import check_cutoff
from oscillator.orbits.stroboscopic import compile_period_map
from oscillator.text import shown

__all__ = [
    "MAX_STARTS",
    "STATE",
    "AttractorSettings",
    "Landing",
    "check_settings",
    "check_states",
    "land",
]

#: The most starts one search takes (a 1000 x 1000 grid).
MAX_STARTS = 1_000_000


@dataclass(frozen=True)
class AttractorSettings:
    """How starts are run and landings told apart.

    Attributes
    ----------
    transient : int
        Forcing periods run before the section points are recorded (1 to 10^6): at most, with
        ``settle``.
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
    settle : bool
        End the transient once the motion has settled (:func:`settled`): its section points
        repeat with a period up to ``max_period`` and the estimated distance to where they
        converge is within ``tolerance``; the whole ``transient`` without (and for a motion that
        does not settle: an aperiodic one, or one converging too slowly).
    engine : str
        The integrator of the runs: ``"dop853"`` (the default) runs each start whole in compiled
        code (:mod:`oscillator.hybrid.batch`); another engine's name
        (:data:`oscillator.engines.ENGINES`: ``"cvode"``, the reference) runs it through
        :func:`~oscillator.hybrid.simulate.simulate`.
    cutoff : float
        The cut-off in Hz of the response measures ``force_above`` and ``a_above`` of each periodic
        attractor (the RMS of the harmonics above it; 0: every harmonic but the mean, docs/noise.md).
    """

    transient: int = 200
    record: int = 32
    tolerance: float = 1e-6
    max_period: int = 16
    match: float = 1e-4
    lyapunov_periods: int = 300
    settle: bool = True
    engine: str = "dop853"
    cutoff: float = 0.0

    def __post_init__(self) -> None:
        check_count(self.transient, "transient", 1, 1_000_000)
        check_cutoff(self.cutoff)
        check_engine(self.engine)
        check_count(self.record, "record", 2, 100_000)
        check_count(self.max_period, "max_period", 1, 1000)
        check_count(self.lyapunov_periods, "lyapunov_periods", 0, 10_000_000)
        if not isinstance(self.settle, bool):
            raise InputError(f"settle must be True or False, got {shown(self.settle)}", field="settle")
        for name in ("tolerance", "match"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and not isinstance(value, bool) and 0 < value < 1):
                raise InputError(f"{name} must be a number between 0 and 1, got {shown(value)}", field=name)


@dataclass(frozen=True)
class Landing:
    """Where one start went: what :func:`land` returns for it."""

    index: int
    start: tuple[float, ...]  #: the state it started from (the system's ``state`` order)
    status: Literal["ok", "failed"] = "ok"
    reason: Reason | None = None  #: why it failed, for a program

    message: str = ""  #: why it failed, in words
    period: int = 0  #: period-n of its section points, 0 if none up to ``max_period``
    points: np.ndarray = field(default_factory=lambda: np.empty((0, 4)), repr=False)  #: recorded section points
    signature: str = ""  #: each mass's cycle of switches over one period (periodic landings)
    rests: tuple[float, ...] = (0.0, 0.0)  #: rest intervals per forcing period, of each mass (m1 and m2)
    contacts: float = 0.0  #: contact onsets (either stop; a contact between the masses once) per forcing period
    wall_time: float = 0.0
    rest_time: tuple[float, ...] = (0.0, 0.0)  #: the fraction of the time each mass rests (1: throughout)
    transient: int = 0  #: forcing periods run before the recorded window (fewer than asked where it settled)

    @property
    def ok(self) -> bool:
        """Whether the start ran and was read (else ``reason`` and ``message`` say why not)."""
        return self.status == "ok"


#: Event rows the compiled run keeps room for per recorded forcing period (a start with more runs
#: through ``simulate``).
WINDOW_ROWS = 64


def _run_from(
    case: Case, state: Sequence[float] | np.ndarray, first: int, last: int, *, events: bool, engine: str
) -> tuple[Case, Result]:
    """``case`` from ``state`` at its ``t0`` (the section: the forcing is T-periodic), run to the
    ``last`` section, its section points ``first .. last`` kept (the events of that window, or
    none)."""
    point = resolve_case(case, **dict(zip(STATE, (float(v) for v in state), strict=True)))
    marks = section_times(point, first, last)
    keep = float(marks[0]) if events else float(marks[-1])
    save = SaveAt(ts=marks, steps=False, events_from=keep)
    return point, simulate(point, t_end=float(marks[-1]), save=save, engine=engine)


def settled(points: np.ndarray, tolerance: float, max_period: int) -> int:
    """The period section points have settled with, 0 if they have not: the least
    ``n <= max_period`` whose last ``n`` points repeat the ``n`` before within
    ``d <= tolerance (1 + |P|)`` while, the repeats converging geometrically (``d`` over the
    ``d0`` of the ``n`` before that, ``rho = d / d0 < 1``), the distance still to go,
    ``d / (1 - rho)``, is within it too (a motion converging slowly is not settled while its
    steps are small).  Not settled either while the repeats of a divisor of ``n`` are within
    :data:`~oscillator.hybrid.batch.SHORTER_CYCLE` times that: the motion is still converging to
    the shorter cycle (beside a period doubling).  (:func:`oscillator.hybrid.batch.settled_compiled`
    is the same test, compiled.)"""
    scale = tolerance * (1.0 + float(np.max(np.abs(points[-8:])))) if len(points) else tolerance

    def repeat(end: int, n: int) -> float:
        stop = end if end < len(points) else None
        return float(np.max(np.linalg.norm(points[end - n : stop] - points[end - 2 * n : end - n], axis=1)))

    count = len(points)
    for n in range(1, min(max_period, count // 3) + 1):
        d, d0 = repeat(count, n), repeat(count - n, n)
        if d <= scale and (d == 0.0 or (d < d0 and d / (1.0 - d / d0) <= scale)):
            shorter = any(n % m == 0 and repeat(count, m) <= SHORTER_CYCLE * scale for m in range(1, n))
            return 0 if shorter else n
    return 0


def _settle(case: Case, start: Sequence[float], settings: AttractorSettings) -> tuple[np.ndarray, int, int]:
    """The state at the section once the motion has :func:`settled` (or after ``transient``
    periods), the forcing periods it took and the period it settled with (0: it did not): runs
    of :data:`SETTLE_CHUNK` periods, then doubling, checked at their ends."""
    state, ran = np.array(start, dtype=float), 0
    points, chunk = [state], SETTLE_CHUNK
    while ran < settings.transient:
        n = min(chunk, settings.transient - ran)
        _, result = _run_from(case, state, 1, n, events=False, engine=settings.engine)
        points += list(result.trajectory[list(STATE)].to_numpy())
        state, ran = points[-1], ran + n
        chunk = chunk if ran < 2 * SETTLE_CHUNK else 2 * chunk
        if period := settled(np.array(points), settings.tolerance, settings.max_period):
            return state, ran, period
    return state, ran, 0


@dataclass(frozen=True)
class _Window:
    """The recorded window of one start: its section points, which masses rest at each, and its
    events (arrays by column: ``t, mass, from_domain, to_domain``, and the kinds)."""

    points: np.ndarray
    resting: np.ndarray
    events: dict[str, np.ndarray]
    kinds: list[EventKind]
    ran: int  #: forcing periods run before the window
    first: int  #: the window's first section, counted from the run's start
    record: int  #: forcing periods recorded (:func:`~oscillator.hybrid.batch.recorded`)


def land(case: Case, settings: AttractorSettings, index: int, start: Sequence[float]) -> Landing:
    """Run one start and read where it went (section points, period, switches per period).

    The transient ends where the motion has settled (``settings.settle``, :func:`settled`) or
    after ``settings.transient`` periods; then ``settings.record`` periods are recorded, or two
    cycles of the period it settled with if fewer (:func:`~oscillator.hybrid.batch.recorded`:
    the rest would repeat them).  With ``settings.engine = "dop853"`` (the default) the whole
    run is compiled (:func:`oscillator.hybrid.batch.land_compiled`); a start that fails there, or
    any start with another engine, runs through :func:`~oscillator.hybrid.simulate.simulate`.  A
    start the model refuses or a failed run gives a landing with ``status = "failed"`` and the
    reason."""
    started = time.perf_counter()
    begin = (float(start[0]), float(start[1]), float(start[2]), float(start[3]))
    try:
        window = _compiled_window(case, settings, begin) if settings.engine == "dop853" else None
        if window is not None:
            counted()
        else:
            window = _simulated_window(case, settings, begin)
    except OscillatorError as error:
        reason = error.reason if isinstance(error, SimulationFailed) else Reason.REFUSED
        return Landing(index, begin, "failed", reason, str(error), wall_time=time.perf_counter() - started)
    return _read(window, case, settings, index, begin, started)


def _simulated_window(case: Case, settings: AttractorSettings, begin: tuple[float, ...]) -> _Window:
    """The window through :func:`~oscillator.hybrid.simulate.simulate` (the settings' engine;
    CVODE where the compiled run failed)."""
    engine = "cvode" if settings.engine == "dop853" else settings.engine
    if settings.settle:
        state, ran, n = _settle(case, begin, dataclasses.replace(settings, engine=engine))
        record = recorded(settings.record, n, ran)
        _, result = _run_from(case, state, 0, record, events=True, engine=engine)
    else:  # one run: the whole transient, then the recorded window
        ran, record = settings.transient, settings.record
        _, result = _run_from(case, begin, ran, ran + record, events=True, engine=engine)
    rows = result.trajectory
    events = result.events
    return _Window(
        rows[list(STATE)].to_numpy(),
        rows[["domain1", "domain2"]].to_numpy() == 0,
        {name: events[name].to_numpy() for name in ("t", "mass", "from_domain", "to_domain")},
        [EventKind(kind) for kind in events.kind],
        ran,
        0 if settings.settle else ran,  # a settled start's window is a run of its own
        record,
    )


def _compiled_window(case: Case, settings: AttractorSettings, begin: tuple[float, ...]) -> _Window | None:
    """The window of :func:`oscillator.hybrid.batch.land_compiled`, or None where it failed."""
    p, o = case.parameters, case.options
    section_times(case, 0, 1)  # refuses an Omega whose period is lost beside t0
    points = np.empty((settings.record + 1, 6))
    rows = np.empty((WINDOW_ROWS * (settings.record + 1), WIDTH))
    try:
        status, ran, record, kept = land_compiled(
            coefficients(p),
            case.initial.t0,
            p.period,
            np.array(begin),
            new_work(p, o),
            options_vector(o),
            (settings.settle, settings.transient, settings.record, settings.tolerance, settings.max_period),
            points,
            rows,
        )
    except ARITHMETIC_ERRORS:  # the switching rules' arithmetic left floating point
        return None
    if status != OK:
        return None
    rows, points = rows[:kept], points[: record + 1]
    events = {name: rows[:, COLUMN[name]] for name in ("t", "mass", "from_domain", "to_domain")}
    kinds = [KINDS[int(k)] for k in rows[:, COLUMN["kind"]]]
    return _Window(points[:, :4], points[:, 4:] == 0, events, kinds, ran, ran, record)


def _read(
    window: _Window, case: Case, settings: AttractorSettings, index: int, begin: tuple[float, ...], started: float
) -> Landing:
    """The landing of a recorded window: period, cycle of switches, rests and contacts per period."""
    points, events, period = window.points, window.events, case.parameters.period
    n = detect_period(points, settings.tolerance, settings.max_period)
    span = n if n else window.record
    end = case.initial.t0 + period * (window.first + window.record)
    last = end - span * period
    masses = events["mass"].astype(int).tolist()
    mine = [
        (t, m, kind)
        for t, m, kind in zip(events["t"].tolist(), masses, window.kinds, strict=True)
        if t >= last - 1e-9 * period
    ]
    rests = [sum(kind.starts_rest for _, m, kind in mine if m == mass) / span for mass in (1, 2)]
    resting = window.resting[len(points) - 1 - span]  # where the last ``span`` periods begin
    rest_time = [
        sum(b - a for a, b in rest_intervals(events, mass, bool(resting[mass - 1]), last, end)) / (span * period)
        for mass in (1, 2)
    ]
    contacts = sum(kind.contact_starts and kind.stands_for_event(m) for _, m, kind in mine) / span
    return Landing(
        index,
        (begin[0], begin[1], begin[2], begin[3]),
        period=n,
        points=points,
        signature=str(signature_of(mine, n * period)) if n else "",
        rests=(float(rests[0]), float(rests[1])),
        contacts=float(contacts),
        wall_time=time.perf_counter() - started,
        rest_time=(float(rest_time[0]), float(rest_time[1])),
        transient=window.ran,
    )


@before_workers
def _compile_landing() -> None:
    """The compiled landing's kernels (:mod:`oscillator.hybrid.batch`, the DOP853 engine) compiled
    into numba's cache in this process, or loaded from it: one start of Instance 1 landed over a
    few periods.  Where there is no cache, each worker compiles them anyway: nothing to do."""
    from oscillator.compiled import CACHE

    if CACHE:
        case = resolve_case("instance-1")
        land(case, AttractorSettings(transient=1, record=2, settle=False), 0, tuple(case.initial.y))


#: The period maps' kernels too: the analyses' workers refine orbits and continue branches.
before_workers(compile_period_map)


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
