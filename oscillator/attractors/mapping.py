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

    @property
    def ok(self) -> bool:
        """Whether the start ran and was read (else ``reason`` and ``message`` say why not)."""
        return self.status == "ok"


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
        result = simulate(point, t_end=float(marks[-1]), save=SaveAt(ts=marks, events_from=float(marks[0])))
    except OscillatorError as error:
        reason = error.reason if isinstance(error, SimulationFailed) else Reason.REFUSED
        return Landing(index, begin, "failed", reason, str(error), wall_time=time.perf_counter() - started)
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
