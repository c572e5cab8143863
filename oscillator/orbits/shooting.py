"""Periodic orbits by shooting: the stroboscopic map, its derivative through every switch, Newton.

The stroboscopic map ``P: y(t0) -> y(t0 + N T)`` (``T = 2 pi / Omega``) is computed by the same
supervisor and engine as :func:`oscillator.simulate`; its derivative, the monodromy matrix, is the
product of each mode's flow derivative (:class:`~oscillator.orbits.variational.ModeFlow`) and of
the saltation matrix of each switch (:func:`~oscillator.orbits.saltation.saltation_matrix`),

    M = Phi_n S_n ... Phi_1 S_1 Phi_0.

A period-``N`` orbit is a fixed point of ``P``, found by Newton's method ``y <- y - (M - I)^-1
(P(y) - y)`` (docs/orbits.md).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

from oscillator.engines import build_engine
from oscillator.errors import InputError, SimulationFailed
from oscillator.hybrid.record import RunRecord
from oscillator.hybrid.recording import NoTrajectory
from oscillator.hybrid.result import Result
from oscillator.hybrid.simulate import admit, simulate
from oscillator.hybrid.supervisor import Supervisor
from oscillator.io.cases import Case, resolve_case
from oscillator.model.events import EventKind
from oscillator.model.phase_space import Mode
from oscillator.orbits.saltation import saltation_matrix
from oscillator.orbits.variational import ModeFlow

__all__ = ["Orbit", "PeriodMap", "cyclic_signature", "event_signature", "find_orbit", "multipliers_of", "period_map"]

#: Forcing periods simulated before Newton starts, when the case has no sweep settings.
TRANSIENT = 100
#: CVODE's tolerances for orbits unless the caller sets them.
ORBIT_RTOL = 1e-12
STATE = ("x1", "v1", "x2", "v2")


class _Switches(NoTrajectory):
    """A recording that keeps the start and the state and mode after every switch, nothing else."""

    def start(self, record: RunRecord, t0: float, y: np.ndarray, mode: Mode, t_end: float) -> None:
        self.row(record, t0, y, mode)

    def switched(self, record: RunRecord, t: float, y: np.ndarray, mode: Mode) -> None:
        self.row(record, t, y, mode)


@dataclass(frozen=True)
class PeriodMap:
    """``P(y)`` and what it passed: one evaluation of the stroboscopic map.

    Attributes
    ----------
    t0, t1 : float
        Start and end of the map (``t1 = t0 + N T``).
    start, end : ndarray
        ``y(t0)`` and ``y(t1)`` = ``P(y(t0))``.
    switches : list of (t, y, Mode)
        The start and every switch: the time, the state after it, the mode after it.
    events : DataFrame
        The event table over ``[t0, t1]`` (as ``Result.events``).
    monodromy : ndarray or None
        ``dP/dy`` (4 x 4), when asked for.
    """

    t0: float
    t1: float
    start: np.ndarray
    end: np.ndarray
    switches: list[tuple[float, np.ndarray, Mode]]
    events: pd.DataFrame
    monodromy: np.ndarray | None = None


def period_map(case: Case, t0: float, y: np.ndarray, periods: int = 1, *, derivative: bool = True) -> PeriodMap:
    """``P(y)`` over ``periods`` forcing periods from ``t0``, and its derivative if asked.

    Raises
    ------
    SimulationFailed
        The simulation failed, or the orbit grazes a boundary (the map has no derivative there).
    """
    p, options = case.parameters, case.options
    t1 = t0 + periods * p.period
    start = np.array(y[:4], dtype=float)
    initial = dataclasses.replace(case.initial, t0=t0, **dict(zip(STATE, start, strict=True)))
    run_case = dataclasses.replace(case, initial=initial, t_end=t1, expected=())
    admit(run_case)
    engine = build_engine(None, p, options)
    policy = _Switches(options.max_trajectory_rows, 4 * p.period)
    record = RunRecord()
    try:
        Supervisor(p, options, engine, policy).run(t0, tuple(start), t1, record)
    finally:
        engine.close()
    result = Result.from_record(run_case, record, engine=engine.name)
    end = np.asarray(result.final_state[1:], dtype=float)
    switches = list(record.rows)
    monodromy = _monodromy(case, switches, t1, options.rtol) if derivative else None
    return PeriodMap(t0, t1, start, end, switches, result.events, monodromy)


def _monodromy(case: Case, switches: list[tuple[float, np.ndarray, Mode]], t1: float, rtol: float) -> np.ndarray:
    """``M = Phi_n S_n ... S_1 Phi_0`` along the recorded switches (the module's docstring)."""
    p = case.parameters
    flow = ModeFlow(p, rtol=min(rtol, 1e-11), atol=min(rtol, 1e-11))
    try:
        matrix = np.eye(4)
        for k, (t_a, y_a, mode) in enumerate(switches):
            t_b = switches[k + 1][0] if k + 1 < len(switches) else t1
            y_b, phi = flow(mode, t_a, y_a, t_b)
            matrix = phi @ matrix
            if k + 1 < len(switches):
                _, y_next, mode_next = switches[k + 1]
                try:
                    salt = saltation_matrix(t_b, y_b, y_next, p, mode, mode_next)
                except ZeroDivisionError as exc:
                    raise SimulationFailed(f"no monodromy matrix: {exc} (a grazing orbit)", field="orbit") from exc
                matrix = salt @ matrix
        return matrix
    finally:
        flow.close()


def event_signature(events: pd.DataFrame) -> str:
    """The orbit's events over one period as text: ``"m2 sliding_onset, m2 sliding_vanish, ..."``
    (grazing contacts are not switches and are left out)."""
    kinds = events[events.kind != EventKind.GRAZING.value]
    return ", ".join(f"m{mass} {kind}" for mass, kind in zip(kinds["mass"], kinds["kind"], strict=True))


def cyclic_signature(image: PeriodMap) -> str:
    """The signature of an orbit through ``image``, whatever the section and however the two
    masses' events interleave: ``"m1: passable, passable; m2: passable, sliding_onset, ..."``.

    Each mass's events over one period are read as a cycle (a switch at both ends of
    ``[t0, t1]``, there because the orbit is on a boundary at the section, counted once) and
    written from the rotation whose text sorts first.  Along a branch an event passing through
    the section, or one mass's event passing another's, then does not change the signature;
    only a change of a mass's own cycle of switches does (a rest interval or a pair of
    switches appearing or vanishing).
    """
    events = image.events[image.events.kind != EventKind.GRAZING.value]
    span = image.t1 - image.t0
    parts = []
    for mass in (1, 2):
        own = events[events["mass"] == mass]
        kinds, times = list(own["kind"]), own["t"].to_numpy(float)
        if len(kinds) > 1 and kinds[0] == kinds[-1] and abs((times[-1] - times[0]) - span) <= 1e-6 * span:
            kinds.pop()
        cycle = min((kinds[k:] + kinds[:k] for k in range(len(kinds))), default=[])
        parts.append(f"m{mass}: {', '.join(cycle)}" if cycle else f"m{mass}: none")
    return "; ".join(parts)


@dataclass(frozen=True)
class Orbit:
    """A periodic orbit of the stroboscopic map.

    Attributes
    ----------
    case : Case
        The case, with the overrides the orbit was found for.
    t0 : float
        The section's time: the orbit passes ``state`` at ``t0 + k N T``.
    state : ndarray
        ``(x1, v1, x2, v2)`` at ``t0``.
    period : int
        ``N``: forcing periods per return.
    monodromy : ndarray
        ``dP/dy`` at the orbit (4 x 4).
    multipliers : ndarray
        Its eigenvalues (complex), largest modulus first.
    stable : bool
        Every multiplier inside the unit circle.
    residual : float
        ``|P(state) - state|`` (max norm).
    iterations : int
        Newton steps taken.
    events : DataFrame
        The event table over one period of the orbit.
    history : tuple of float
        The residual before each Newton step and after the last.
    """

    case: Case
    t0: float
    state: np.ndarray
    period: int
    monodromy: np.ndarray
    multipliers: np.ndarray
    stable: bool
    residual: float
    iterations: int
    events: pd.DataFrame
    history: tuple[float, ...] = ()

    @property
    def signature(self) -> str:
        """The kinds of the events over one period, in order (:func:`event_signature`)."""
        return event_signature(self.events)


def multipliers_of(monodromy: np.ndarray) -> np.ndarray:
    """The eigenvalues of the monodromy matrix, largest modulus first."""
    values = np.linalg.eigvals(monodromy)
    return values[np.argsort(-np.abs(values), kind="stable")]


def _scale(case: Case) -> float:
    """A length for the convergence test: the state's own size and the stops' distances."""
    p = case.parameters
    return max(1.0, abs(p.d), abs(p.d1))


def newton(
    case: Case, t0: float, y: np.ndarray, periods: int, *, tol: float, max_iterations: int
) -> tuple[np.ndarray, PeriodMap, list[float]]:
    """Newton's method on ``P(y) - y``; the fixed point, the map there and the residuals."""
    history: list[float] = []
    y = np.array(y, dtype=float)
    for _ in range(max_iterations + 1):
        image = period_map(case, t0, y, periods)
        residual = image.end - y
        history.append(float(np.max(np.abs(residual))))
        if history[-1] <= tol * _scale(case):
            return y, image, history
        if len(history) > max_iterations:
            break
        assert image.monodromy is not None
        step = np.linalg.solve(image.monodromy - np.eye(4), -residual)
        y = y + step
        for mass in (1, 2):  # a mass at rest at t0 stays exactly at rest (v_i = 0 is its domain)
            if image.start[2 * mass - 1] == 0.0 and abs(y[2 * mass - 1]) <= 1e-9 * _scale(case):
                y[2 * mass - 1] = 0.0
    raise SimulationFailed(
        f"Newton's method did not converge in {max_iterations} steps (residuals "
        f"{', '.join(f'{r:.2e}' for r in history)}); give a better guess, a longer transient or more iterations",
        field="guess",
    )


def orbit_case(case: Case | str, overrides: dict[str, float]) -> Case:
    """The case with the overrides, and CVODE's tolerances at most :data:`ORBIT_RTOL` unless the
    overrides set them (Newton needs the map accurate well below its own tolerance)."""
    resolved = resolve_case(case, **overrides)
    tight = {
        name: min(getattr(resolved.options, name), ORBIT_RTOL) for name in ("rtol", "atol") if name not in overrides
    }
    return resolve_case(resolved, **tight) if tight else resolved


def check_count(value: object, name: str, least: int) -> int:
    """A whole number ``>= least`` (a bool is not one)."""
    if not isinstance(value, (int, np.integer)) or isinstance(value, bool) or value < least:
        raise InputError(f"{name} must be a whole number >= {least}, got {value!r}", field=name)
    return int(value)


def start_of(case: Case, t0: float | None, guess: object, transient: int | None) -> tuple[float, np.ndarray]:
    """The section's time and Newton's first state: ``guess``, or the state a transient reaches.

    The section defaults to the case's start ``t0``; the transient runs a whole number of
    periods from it, which lands on the same section (the forcing has period ``T``).
    """
    if transient is None:
        transient = case.sweep.transient if case.sweep is not None else TRANSIENT
    transient = check_count(transient, "transient", 0)
    if t0 is None:
        t0 = case.initial.t0
    t0 = float(t0)
    if not math.isfinite(t0):
        raise InputError(f"t0 must be a finite time in s, got {t0!r}", field="t0")
    if guess is not None:
        start = np.asarray(guess, dtype=float)
        if start.shape != (4,) or not np.isfinite(start).all():
            raise InputError("guess must be four finite numbers (x1, v1, x2, v2)", field="guess")
        return t0, start
    if t0 != case.initial.t0:
        raise InputError("with t0 other than the case's start, give a guess (x1, v1, x2, v2 at t0)", field="guess")
    if transient == 0:
        return t0, np.array(case.initial.y, dtype=float)
    end = t0 + transient * case.parameters.period
    warm = simulate(case, t_end=end, record_trajectory=False, keep_events_from=end)
    return t0, np.asarray(warm.final_state[1:], dtype=float)


def find_orbit(
    case: Case | str,
    *,
    period: int = 1,
    t0: float | None = None,
    guess: tuple[float, float, float, float] | np.ndarray | None = None,
    transient: int | None = None,
    tol: float = 1e-9,
    max_iterations: int = 20,
    **overrides: float,
) -> Orbit:
    """A period-``period`` orbit of the stroboscopic map ``y(t0) -> y(t0 + period T)``.

    Parameters
    ----------
    case : Case or str
        A case or a shipped case's name.
    period : int
        Forcing periods per return (1 for a period-1 orbit).
    t0 : float, optional
        The section's time; the case's start by default (the sweeps' Poincaré section).
    guess : sequence of 4 floats, optional
        ``(x1, v1, x2, v2)`` at ``t0`` to start Newton from; by default the state after
        ``transient`` forcing periods simulated from the case's start.
    transient : int, optional
        Forcing periods simulated to find the guess (the case's sweep transient, else 100).
    tol : float
        Converged when ``max |P(y) - y| <= tol`` (times the larger of 1 and the stops' distances).
    max_iterations : int
        Newton steps before giving up.
    **overrides
        Any parameter, initial value or solver option, as for :func:`oscillator.simulate`.
        CVODE's ``rtol`` and ``atol`` are at most 1e-12 unless given here.

    Raises
    ------
    InputError
        Bad input.
    SimulationFailed
        The simulation failed, the orbit grazes a boundary, or Newton did not converge.

    Examples
    --------
    >>> from oscillator import find_orbit
    >>> orbit = find_orbit("instance-1", Omega=1.85)
    >>> orbit.stable, orbit.residual < 1e-9
    (True, True)
    """
    case = orbit_case(case, overrides)
    period = check_count(period, "period", 1)
    max_iterations = check_count(max_iterations, "max_iterations", 1)
    t0, start = start_of(case, t0, guess, transient)
    return _orbit(case, t0, start, period, tol=tol, max_iterations=max_iterations)


def _orbit(case: Case, t0: float, start: np.ndarray, period: int, *, tol: float, max_iterations: int) -> Orbit:
    state, image, history = newton(case, t0, start, period, tol=tol, max_iterations=max_iterations)
    assert image.monodromy is not None
    values = multipliers_of(image.monodromy)
    return Orbit(
        case=case,
        t0=t0,
        state=state,
        period=period,
        monodromy=image.monodromy,
        multipliers=values,
        stable=bool(np.all(np.abs(values) < 1.0)),
        residual=history[-1],
        iterations=len(history) - 1,
        events=image.events,
        history=tuple(history),
    )
