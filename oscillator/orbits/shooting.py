"""Periodic orbits by shooting: the stroboscopic map, its derivative through every switch, Newton.

The stroboscopic map ``P: y(t0) -> y(t0 + N T)`` (``T = 2 pi / Omega``) is one run of
:func:`oscillator.simulate` that keeps its segments (:mod:`oscillator.orbits.stroboscopic`); its
derivative, the monodromy matrix, is carried by the same run: the engine integrates each mode's
variational equations with the state, and the supervisor applies the saltation matrix of each
switch it resolves (:func:`oscillator.model.saltation.carried_through`),

    M = Phi_n S_n ... Phi_1 S_1 Phi_0.

A period-``N`` orbit is a fixed point of ``P``, found by Newton's method ``y <- y - (M - I)^-1
(P(y) - y)`` (docs/orbits.md).
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, overload

import numpy as np
import pandas as pd

from oscillator.engines import check_engine
from oscillator.errors import InputError, Reason, SimulationFailed
from oscillator.hybrid.recording import SaveAt
from oscillator.hybrid.simulate import simulate
from oscillator.io.cases import Case, resolve_case
from oscillator.io.files import as_folder
from oscillator.model.chains import FrictionChain
from oscillator.model.events import EventKind
from oscillator.model.fields import kinetic_threshold, non_friction_force
from oscillator.model.parameters import InitialState, check_count, real_argument
from oscillator.model.system import ARTICLE
from oscillator.orbits.multipliers import multipliers_of, verdict_of
from oscillator.orbits.settings import MAX_TRANSIENT, check_guess, check_orbit_settings
from oscillator.orbits.signature import Signature, cyclic_signature, event_signature
from oscillator.orbits.stroboscopic import (
    ORBIT_ENGINE,
    ORBIT_ENGINES,
    PeriodMap,
    fixed_point_system,
    period_map,
    solve_step,
)
from oscillator.presenting import presenter

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

    from oscillator.orbits.chain_orbits import ChainOrbit
    from oscillator.orbits.noise import Noise
    from oscillator.orbits.response import Response
    from oscillator.orbits.sensitivity import Sensitivities

__all__ = [
    "Orbit",
    "PeriodMap",
    "find_orbit",
    "multipliers_of",
    "period_map",
]

#: Forcing periods simulated before Newton starts, when the case has no sweep settings.
TRANSIENT = 100
#: The tolerances of the period maps unless the caller sets them.
ORBIT_RTOL = 1e-12
#: The period map's own accuracy at :data:`ORBIT_RTOL`, relative to the state's scale: a residual
#: below it is the map's noise (measured: 5e-12 to 6e-11 from one Newton step to the next at an
#: orbit of Instance 1), which Newton asked for less cannot follow (:func:`newton`'s ``floor``).
FLOOR = 1e-10
#: The state's names (the article's system: :data:`oscillator.model.system.ARTICLE`).
STATE = ARTICLE.state


@dataclass(frozen=True)
class Orbit:
    """A periodic orbit of the stroboscopic map.

    Attributes
    ----------
    case : Case
        The case, with the overrides the orbit was found for.
    section : float
        The section's time: the orbit passes ``state`` at ``section + k N T``.
    state : ndarray
        ``(x1, v1, x2, v2)`` at ``section``.
    period : int
        ``N``: forcing periods per return.
    monodromy : ndarray
        ``dP/dy`` at the orbit (4 x 4).
    multipliers : ndarray
        Its eigenvalues (complex), largest modulus first.
    stable : bool
        No disturbance grows: every multiplier inside the unit circle, but for the exact
        multiplier 1 of each mass at rest all period (:attr:`resting`), which is neutral.
    residual : float
        ``|P(state) - state|`` (max norm).
    iterations : int
        Newton steps taken.
    events : DataFrame
        The event table over one period of the orbit (built from its rows, ``event_records``,
        when first asked for: most orbits an analysis finds are never shown event by event).
    history : tuple of float
        The residual before each Newton step and after the last.
    resting : tuple of int
        The masses at rest over the whole period.  Each rests where it stuck: a nearby
        displacement at rest is an orbit too (a continuum), so ``M`` has the multiplier 1 in
        ``x_i`` (and 0 in ``v_i``); Newton keeps ``x_i`` where it was.
    discontinuous : tuple of str
        The velocities at the section in which the map is discontinuous, e.g. ``("v2",)``: a
        mass resting there with its force between the kinetic and the static thresholds is held
        by static friction only, and any velocity disturbance sets it sliding (one against the
        force is reversed by it, and kinetic friction cannot stop it at zero velocity).  ``M``
        is then the derivative along the states where it rests (docs/orbits.md).
    note : str
        What Newton met on the way, when it matters: the guess's motion had another cycle of
        switches than the orbit found (another orbit may exist near the guess).
    """

    case: Case
    section: float
    state: np.ndarray
    period: int
    monodromy: np.ndarray
    multipliers: np.ndarray
    stable: bool
    residual: float
    iterations: int
    #: The event table, or its rows (:attr:`oscillator.Result.event_rows`) until :attr:`events` is asked for.
    event_records: pd.DataFrame | np.ndarray = field(repr=False, compare=False)
    history: tuple[float, ...] = ()
    resting: tuple[int, ...] = ()
    discontinuous: tuple[str, ...] = ()
    note: str = ""

    @functools.cached_property
    def events(self) -> pd.DataFrame:
        """The event table over one period of the orbit."""
        if isinstance(self.event_records, np.ndarray):
            from oscillator.io.tables import events_frame

            return events_frame(self.event_records)
        return self.event_records

    @property
    def signature(self) -> tuple[tuple[int, EventKind], ...]:
        """The switches over one period, in order, as ``(mass, kind)``
        (:func:`~oscillator.orbits.signature.event_signature`;
        :func:`~oscillator.orbits.signature.signature_text` for display)."""
        return event_signature(self.events)

    def one_period(self) -> Case:
        """The case of one return of the orbit: from ``state`` at ``section`` over ``period``
        forcing periods (``simulate(orbit.one_period())`` gives its trajectory)."""
        x1, v1, x2, v2 = (float(v) for v in self.state)
        initial = InitialState(t0=self.section, x1=x1, v1=v1, x2=x2, v2=v2)
        t_end = self.section + self.period * self.case.parameters.period
        return dataclasses.replace(self.case, initial=initial, t_end=t_end, expected=(), keep_events_from=None)

    def response(self, cutoff: float = 0.0) -> Response:
        """The orbit's response measures over one return (:func:`oscillator.orbits.response.response`:
        peaks, RMS values, rests, contacts, impact velocities, contact forces, energies; the forces'
        and accelerations' RMS above ``cutoff`` Hz)."""
        from oscillator.orbits.response import response

        return response(self.one_period(), self.period, cutoff)

    def noise(self, harmonics: int = 200) -> Noise:
        """The orbit's noise measures over one return (:func:`oscillator.orbits.noise.noise`: per
        contact the impact rate, impulse, energy lost per impact, impact power and the contact
        force's spectrum to ``harmonics`` harmonics of the return's frequency)."""
        from oscillator.orbits.noise import noise

        return noise(self.one_period(), self.period, harmonics)

    def sensitivities(self, params: str | Sequence[str]) -> Sensitivities:
        """The exact derivatives of the orbit in ``params`` through every switch: of its section
        point(s), switch times and response measures
        (:func:`oscillator.orbits.sensitivity.sensitivities`)."""
        from oscillator.orbits.sensitivity import sensitivities

        return sensitivities(self, params)

    def plot(self, panel: str = "c") -> Figure:
        """One panel of the article's figures over one return of the orbit (by default ``"c"``,
        the phase portraits: a closed curve); see :meth:`oscillator.Result.plot`."""
        return simulate(self.one_period()).plot(panel)

    def save(self, folder: str | Path) -> Path:
        """Write the orbit as a run folder of one return (tables, figures, report) whose
        ``run.json`` holds the orbit (``"kind": "orbit"``: state, multipliers, monodromy,
        verdict); :func:`oscillator.read_run` reads it back as an :class:`Orbit`."""
        return presenter().save_orbit(self, as_folder(folder))

    def _repr_html_(self) -> str:
        return presenter().orbit_html(self)

    @property
    def verdict(self) -> str:
        """The stability in words: ``"stable"``, ``"unstable"``, with what is neutral and where
        the map is discontinuous."""
        words = ["stable" if self.stable else "unstable"]
        for mass in self.resting:
            words.append(f"neutral in x{mass}: m{mass} rests all period where it stuck (multiplier 1)")
        for velocity in self.discontinuous:
            words.append(
                f"discontinuous in {velocity}: m{velocity[1]} rests between its kinetic and static "
                "thresholds, and any push sets it sliding"
            )
        return "; ".join(words)


def discontinuities(case: Case, image: PeriodMap) -> tuple[str, ...]:
    """The velocities ``"v1"``, ``"v2"`` in which the map is discontinuous at its start: those of
    the masses resting there with ``|A_i| > mu_k g + p_i``.  Static friction holds such a mass;
    pushed along its force it slides on, pushed against it it is stopped, reversed and slides
    on, since the kinetic field beyond zero velocity leaves the boundary too (Thm 5.1)."""
    t, y, mode = image.switches[0]
    p = case.parameters
    forces = non_friction_force(t, y, p, mode.left, mode.right)
    return tuple(
        f"v{mass}" for mass in (1, 2) if mode.sign(mass) == 0 and abs(forces[mass - 1]) > kinetic_threshold(p, mass)
    )


def _state_text(y: np.ndarray) -> str:
    return "(" + ", ".join(f"{name} = {value:.6g}" for name, value in zip(STATE, y, strict=True)) + ")"


def _scale(case: Case) -> float:
    """A length for the convergence test: the state's own size and the stops' distances."""
    p = case.parameters
    return max(1.0, abs(p.d), abs(p.d1))


def newton(
    case: Case,
    t0: float,
    y: np.ndarray,
    periods: int,
    *,
    tol: float,
    max_iterations: int,
    first_signature: list[Signature] | None = None,
    floor: bool = False,
    engine: str = ORBIT_ENGINE,
) -> tuple[np.ndarray, PeriodMap, list[float]]:
    """Newton's method on ``P(y) - y``; the fixed point, the map there and the residuals.

    It stops where the residual is within ``tol`` of the state's scale; with ``floor``, also where
    the residual, below the map's own accuracy (:data:`FLOOR`), no longer halves in a step: the
    best iterate is returned, its residual the last of the history (a ``tol`` below the map's
    accuracy is otherwise chased through its noise, and met by chance or not at all).

    ``first_signature``, when given, receives the :func:`cyclic_signature` of the map at the
    guess (to tell whether Newton went from one kind of motion to another).  The maps run on
    ``engine``.
    """
    history: list[float] = []
    y = np.array(y, dtype=float)
    best: tuple[np.ndarray, PeriodMap, int] | None = None
    for _ in range(max_iterations + 1):
        image = period_map(case, t0, y, periods, engine=engine)
        if first_signature is not None and not first_signature:
            first_signature.append(cyclic_signature(image))
        residual = image.end - y
        history.append(float(np.max(np.abs(residual))))
        if history[-1] <= tol * _scale(case):
            return y, image, history
        if best is None or history[-1] < history[best[2]]:
            best = (y, image, len(history) - 1)
        if floor and history[-1] <= FLOOR * _scale(case) and len(history) > 1 and history[-1] > history[-2] / 2:
            return best[0], best[1], history[: best[2] + 1]  # at the map's noise: its best iterate
        if len(history) > max_iterations:
            break
        matrix, residual = fixed_point_system(image)
        step = solve_step(matrix, -residual, f"Newton's method at {_state_text(y)}")
        y = y + step
        for mass in (1, 2):  # a mass at rest at t0 stays exactly at rest (v_i = 0 is its domain)
            if image.start[2 * mass - 1] == 0.0 and abs(y[2 * mass - 1]) <= 1e-9 * _scale(case):
                y[2 * mass - 1] = 0.0
    raise SimulationFailed(
        f"Newton's method did not converge in {max_iterations} steps (residuals "
        f"{', '.join(f'{r:.2e}' for r in history)}); give a better `guess`, a longer `transient` or a larger "
        "`max_iterations`",
        reason=Reason.NO_CONVERGENCE,
        field="guess",
    )


def orbit_case(case: Case | str, overrides: dict[str, float]) -> Case:
    """The case with the overrides, and CVODE's tolerances at most :data:`ORBIT_RTOL` unless the
    overrides set them (Newton needs the map accurate well below its own tolerance)."""
    return tightened(resolve_case(case, **overrides), overrides)


def tightened(case: Case, overrides: dict[str, Any]) -> Case:
    """``case`` with CVODE's tolerances at most :data:`ORBIT_RTOL`, but those ``overrides`` set."""
    tight = {name: min(getattr(case.options, name), ORBIT_RTOL) for name in ("rtol", "atol") if name not in overrides}
    return resolve_case(case, **tight) if tight else case


def settled(case: Case, state: np.ndarray | Sequence[float], periods: int, *, engine: str = ORBIT_ENGINE) -> np.ndarray:
    """The state ``(x1, v1, x2, v2)`` that ``periods`` forcing periods from ``state`` at the case's
    ``t0`` reach (the same section: the forcing has period ``T``); ``state`` itself for 0.  The
    run is on ``engine``."""
    y = np.array(state, dtype=float)
    if periods == 0:
        return y
    start = dataclasses.replace(case.initial, **dict(zip(case.system.state, (float(v) for v in y), strict=True)))
    end = case.initial.t0 + periods * case.parameters.period
    warm = simulate(
        dataclasses.replace(case, initial=start), t_end=end, save=SaveAt(steps=False, events_from=end), engine=engine
    )
    return np.asarray(warm.final_state[1:], dtype=float)


def start_of(
    case: Case, section: object, guess: object, transient: object, *, engine: str = ORBIT_ENGINE
) -> tuple[float, np.ndarray]:
    """The section's time and Newton's first state: ``guess``, or the state a transient reaches
    (on ``engine``).

    The section defaults to the case's start ``t0``; the transient runs a whole number of
    periods from it, which lands on the same section (the forcing has period ``T``).
    """
    if transient is None:
        transient = case.sweep.transient if case.sweep is not None else TRANSIENT
    transient = check_count(transient, "transient", 0, MAX_TRANSIENT)
    section = case.initial.t0 if section is None else real_argument(section, "section")
    if guess is not None:
        return section, check_guess(guess)
    if section != case.initial.t0:
        raise InputError(
            f"with a section (t = {section:g} s) other than the case's start t0 = {case.initial.t0:g} s, give a "
            "`guess` (x1, v1, x2, v2 there), or move the case's start with t0",
            field="guess",
        )
    return section, settled(case, case.initial.y, transient, engine=engine)


@overload
def find_orbit(
    case: FrictionChain,
    *,
    period: int = 1,
    section: float | None = None,
    guess: Sequence[float] | np.ndarray | None = None,
    transient: int | None = None,
    tol: float = 1e-9,
    max_iterations: int = 20,
    engine: str = ORBIT_ENGINE,
    **overrides: float,
) -> ChainOrbit: ...


@overload
def find_orbit(
    case: Case | str,
    *,
    period: int = 1,
    section: float | None = None,
    guess: Sequence[float] | np.ndarray | None = None,
    transient: int | None = None,
    tol: float = 1e-9,
    max_iterations: int = 20,
    engine: str = ORBIT_ENGINE,
    **overrides: float,
) -> Orbit: ...


def find_orbit(
    case: Case | FrictionChain | str,
    *,
    period: int = 1,
    section: float | None = None,
    guess: Sequence[float] | np.ndarray | None = None,
    transient: int | None = None,
    tol: float = 1e-9,
    max_iterations: int = 20,
    engine: str = ORBIT_ENGINE,
    **overrides: float,
) -> Orbit | ChainOrbit:
    """A period-``period`` orbit of the stroboscopic map ``y(section) -> y(section + period T)``.

    Parameters
    ----------
    case : Case, FrictionChain or str
        A case or a shipped case's name; a friction chain (its ``overrides`` by name, its orbit a
        :class:`~oscillator.orbits.chain_orbits.ChainOrbit`: :func:`~oscillator.orbits.chain_orbits.find_chain_orbit`).
    period : int
        Forcing periods per return, 1 to 1000 (1 for a period-1 orbit).
    section : float, optional
        The section's time (s); the case's start ``t0`` by default (the sweeps' Poincaré
        section).  Another section needs a ``guess``.
    guess : sequence of 4 floats, optional
        ``(x1, v1, x2, v2)`` at ``section`` to start Newton from; by default the state after
        ``transient`` forcing periods simulated from the case's start.
    transient : int, optional
        Forcing periods simulated to find the guess (the case's sweep transient, else 100).
    tol : float
        Converged when ``max |P(y) - y| <= tol`` (times the larger of 1 and the stops' distances).
    max_iterations : int
        Newton steps before giving up (1 to 200).
    engine : str
        The period maps' engine: ``"dop853"`` (compiled, the default) or ``"cvode"`` (the
        reference); both carry the monodromy through every switch and find the same orbit to
        1e-9.  A friction chain's maps run on its own CVODE engine.
    **overrides
        Any parameter, initial value (``t0`` moves the case's start, and so the default section)
        or solver option, as for :func:`oscillator.simulate`.  CVODE's ``rtol`` and ``atol``
        are at most 1e-12 unless given here.

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
    period, tol, max_iterations = check_orbit_settings(period, tol, max_iterations)
    engine = check_engine(engine, among=ORBIT_ENGINES)
    if isinstance(case, FrictionChain):
        from oscillator.orbits.chain_orbits import find_chain_orbit

        chain, given = (
            (case.with_values(overrides) if overrides else case),
            None if guess is None else np.asarray(guess),
        )
        transient = 100 if transient is None else transient
        return find_chain_orbit(chain, given, period=period, section=section, transient=transient, tol=tol)
    case = orbit_case(case, overrides)
    section, start = start_of(case, section, guess, transient, engine=engine)
    return _orbit(case, section, start, period, tol=tol, max_iterations=max_iterations, engine=engine)


def fixed_point(case: Case, guess: np.ndarray | Sequence[float], period: int, *, tol: float) -> np.ndarray:
    """The state at the case's start of the period-``period`` orbit that Newton reaches from
    ``guess``: :func:`find_orbit`'s Newton (the tolerances tightened likewise, 20 steps at most)
    without the :class:`Orbit` around it (no event table, no multipliers), for callers that want
    the state alone.

    Raises
    ------
    OscillatorError
        As :func:`find_orbit`: bad input, a failed simulation, or no convergence.
    """
    tight = orbit_case(case, {})
    return newton(tight, tight.initial.t0, check_guess(guess), period, tol=tol, max_iterations=20)[0]


def orbit_of(case: Case, section: float, state: np.ndarray, image: PeriodMap, history: list[float]) -> Orbit:
    """The :class:`Orbit` through ``state``, from the map ``image`` there and Newton's residuals."""
    assert image.monodromy is not None
    resting = image.resting
    return Orbit(
        case=case,
        section=section,
        state=state,
        period=round((image.t1 - image.t0) / case.parameters.period),
        monodromy=image.monodromy,
        multipliers=multipliers_of(image.monodromy),
        stable=verdict_of(image.monodromy, resting),
        residual=history[-1],
        iterations=len(history) - 1,
        event_records=image.events if image.result.event_rows is None else image.result.event_rows,
        history=tuple(history),
        resting=resting,
        discontinuous=discontinuities(case, image),
    )


def _orbit(
    case: Case, section: float, start: np.ndarray, period: int, *, tol: float, max_iterations: int, engine: str
) -> Orbit:
    first: list[Signature] = []
    state, image, history = newton(
        case, section, start, period, tol=tol, max_iterations=max_iterations, first_signature=first, engine=engine
    )
    orbit = orbit_of(case, section, state, image, history)
    found = cyclic_signature(image)
    if first and first[0] != found:
        note = (
            f"Newton started from a motion with another cycle of switches ({first[0]}) than the orbit it "
            f"found ({found}): another orbit may exist near the guess (an orbit ending nearby, or two "
            "coexisting); continue from a parameter value where it is clear, or give another guess"
        )
        orbit = dataclasses.replace(orbit, note=note)
    return orbit
