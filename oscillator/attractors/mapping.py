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

import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from oscillator.analysis.axes import STATE
from oscillator.analysis.intervals import rest_intervals
from oscillator.analysis.periods import detect_period
from oscillator.errors import InputError, OscillatorError, Reason, SimulationFailed
from oscillator.hybrid.recording import SaveAt
from oscillator.hybrid.result import Result
from oscillator.hybrid.simulate import simulate
from oscillator.io.cases import Case, resolve_case, section_times
from oscillator.model.events import EventKind
from oscillator.model.parameters import check_count
from oscillator.orbits.signature import signature_of
from oscillator.text import shown

__all__ = ["MAX_STARTS", "STATE", "AttractorSettings", "Landing", "check_settings", "check_states", "land"]

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
    """

    transient: int = 200
    record: int = 32
    tolerance: float = 1e-6
    max_period: int = 16
    match: float = 1e-4
    lyapunov_periods: int = 300
    settle: bool = True

    def __post_init__(self) -> None:
        check_count(self.transient, "transient", 1, 1_000_000)
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
    start: tuple[float, float, float, float]
    status: Literal["ok", "failed"] = "ok"
    reason: Reason | None = None  #: why it failed, for a program

    message: str = ""  #: why it failed, in words
    period: int = 0  #: period-n of its section points, 0 if none up to ``max_period``
    points: np.ndarray = field(default_factory=lambda: np.empty((0, 4)), repr=False)  #: recorded section points
    signature: str = ""  #: each mass's cycle of switches over one period (periodic landings)
    rests: tuple[float, float] = (0.0, 0.0)  #: rest intervals per forcing period, of m1 and m2
    contacts: float = 0.0  #: contact onsets (either stop; a contact between the masses once) per forcing period
    wall_time: float = 0.0
    rest_time: tuple[float, float] = (0.0, 0.0)  #: the fraction of the time m1 and m2 rest (1: throughout)
    transient: int = 0  #: forcing periods run before the recorded window (fewer than asked where it settled)

    @property
    def ok(self) -> bool:
        """Whether the start ran and was read (else ``reason`` and ``message`` say why not)."""
        return self.status == "ok"


#: Forcing periods in the first two runs of a settling transient; the runs after double.
SETTLE_CHUNK = 8


def _run_from(
    case: Case, state: Sequence[float] | np.ndarray, first: int, last: int, *, events: bool
) -> tuple[Case, Result]:
    """``case`` from ``state`` at its ``t0`` (the section: the forcing is T-periodic), run to the
    ``last`` section, its section points ``first .. last`` kept (the events of that window, or
    none)."""
    point = resolve_case(case, **dict(zip(STATE, (float(v) for v in state), strict=True)))
    marks = section_times(point, first, last)
    keep = float(marks[0]) if events else float(marks[-1])
    return point, simulate(point, t_end=float(marks[-1]), save=SaveAt(ts=marks, steps=False, events_from=keep))


def settled(points: np.ndarray, tolerance: float, max_period: int) -> bool:
    """Whether section points have settled: for some ``n <= max_period`` the last ``n`` repeat
    the ``n`` before within ``d <= tolerance (1 + |P|)``, and, the repeats converging
    geometrically (``d`` over the ``d0`` of the ``n`` before that, ``rho = d / d0 < 1``), the
    distance still to go, ``d / (1 - rho)``, is within it too (a motion converging slowly is not
    settled while its steps are small)."""
    scale = tolerance * (1.0 + float(np.max(np.abs(points[-8:])))) if len(points) else tolerance
    for n in range(1, min(max_period, len(points) // 3) + 1):
        d = float(np.max(np.linalg.norm(points[-n:] - points[-2 * n : -n], axis=1)))
        d0 = float(np.max(np.linalg.norm(points[-2 * n : -n] - points[-3 * n : -2 * n], axis=1)))
        if d <= scale and (d == 0.0 or (d < d0 and d / (1.0 - d / d0) <= scale)):
            return True
    return False


def _settle(case: Case, start: Sequence[float], settings: AttractorSettings) -> tuple[np.ndarray, int]:
    """The state at the section once the motion has :func:`settled`, and the forcing periods it
    took: runs of :data:`SETTLE_CHUNK` periods, then doubling, to ``transient`` at most."""
    state, ran = np.array(start, dtype=float), 0
    points, chunk = [state], SETTLE_CHUNK
    while ran < settings.transient:
        n = min(chunk, settings.transient - ran)
        _, result = _run_from(case, state, 1, n, events=False)
        points += list(result.trajectory[list(STATE)].to_numpy())
        state, ran = points[-1], ran + n
        chunk = chunk if ran < 2 * SETTLE_CHUNK else 2 * chunk
        if settled(np.array(points), settings.tolerance, settings.max_period):
            break
    return state, ran


def land(case: Case, settings: AttractorSettings, index: int, start: Sequence[float]) -> Landing:
    """Run one start and read where it went (section points, period, switches per period).

    The transient ends where the motion has settled (``settings.settle``, :func:`settled`) or
    after ``settings.transient`` periods; then ``settings.record`` periods are recorded.  A start
    the model refuses or a failed run gives a landing with ``status = "failed"`` and the reason."""
    started = time.perf_counter()
    x1, v1, x2, v2 = (float(v) for v in start)
    begin = (x1, v1, x2, v2)
    try:
        if settings.settle:
            state, ran = _settle(case, begin, settings)
            point, result = _run_from(case, state, 0, settings.record, events=True)
        else:  # one run: the whole transient, then the recorded window
            ran = settings.transient
            point, result = _run_from(case, begin, ran, ran + settings.record, events=True)
    except OscillatorError as error:
        reason = error.reason if isinstance(error, SimulationFailed) else Reason.REFUSED
        return Landing(index, begin, "failed", reason, str(error), wall_time=time.perf_counter() - started)
    first_mark = 0 if settings.settle else ran  # the recorded window's first section, from the run's start
    marks = section_times(point, first_mark, first_mark + settings.record)
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
        transient=ran,
    )


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
