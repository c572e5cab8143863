"""A friction chain's response: the measures of a periodic orbit, and a frequency sweep of orbits
(issue 52, its first steps).

:func:`orbit_measures` reads a :class:`~oscillator.orbits.chain_orbits.ChainOrbit`'s return: each
mass's largest and smallest displacement and its peak-to-peak ``x_pp`` (the extremes exact to the
solver's tolerance: between two steps where the velocity changes sign, the quintic through both
ends' positions, velocities and accelerations has its turn); each friction element's and Jenkins slider's
share of the period stuck and its slip distance; each stop's and contact's share closed, its
closings and its fastest closing speed; each element's work and the energy it dissipates over
the return (the energy audit's: :attr:`~oscillator.hybrid.chain_run.ChainResult.energy`).
:func:`frequency_sweep` follows the orbit over values of a parameter (``Omega`` by default),
each found by Newton from the one before, as a sweep up or down a test rig's band does: where
the orbit it follows ends (a fold, a grazing), the next value starts again from a transient, and
the row says so.  The continuation of every branch
through its folds, as the article's system has, comes next (issue 52).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np
import pandas as pd

from oscillator.errors import InputError, OscillatorError
from oscillator.hybrid.chain_run import ChainResult, closed_spans, mode_spans, stuck_spans
from oscillator.model.chains import FrictionChain
from oscillator.orbits.chain_orbits import ChainOrbit, find_chain_orbit
from oscillator.orbits.chain_peaks import impulses, peaks, rates_at, sides, slip_steps

__all__ = [
    "MEASURE_UNITS",
    "frequency_sweep",
    "measure_names",
    "measure_unit",
    "orbit_measures",
    "turning_points",
    "turns",
]

#: Each measure's unit by its kind (the part of its name before ``:``); ``""``: a share or a count.
MEASURE_UNITS = {
    "x_max": "m",
    "x_min": "m",
    "x_pp": "m",
    "stuck": "",
    "closed": "",
    "closings": "",
    "impact_velocity": "m/s",
    "a_max": "m/s^2",
    "force_max": "N",
    "work": "J",
    "dissipated": "J",
    "slip": "m",
    "impact_rate": "1/s",
    "impact_energy": "J",
    "impact_power": "W",
    "impulse": "N s",
    "impulse_rate": "N",
    "slip_steps": "",
    "slip_step_max": "m/s^2",
}
_SLIDING = ("friction", "jenkins")
#: The noise measures of each stop and contact (:func:`orbit_measures`).
_NOISE = ("impact_rate", "impact_energy", "impact_power", "impulse", "impulse_rate")
_CLOSING = ("stop", "contact")
#: The stick-slip measures of each friction element (:func:`~oscillator.orbits.chain_peaks.slip_steps`).
_STEPS = ("slip_steps", "slip_step_max")


def turning_points(t: np.ndarray, x: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
    """The positions where the velocity changes sign between two rows (or is zero at one): on the
    quintic through both rows' position, velocity and acceleration (Hermite: exact to the step's
    sixth power), at its turn inside the step.  ``a`` holds the accelerations of the rows before
    and after each sign change (any value elsewhere)."""
    return turns(t, x, v, a)[1]


def turns(t: np.ndarray, x: np.ndarray, v: np.ndarray, a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`turning_points` with their times: ``(times, positions)``."""
    still = np.flatnonzero(v == 0.0)
    times, found = list(t[still]), list(x[still])
    for k in np.flatnonzero(v[:-1] * v[1:] < 0.0).tolist():
        h = t[k + 1] - t[k]
        x0, v0, a0, v1, a1 = x[k], v[k] * h, a[k] * h * h, v[k + 1] * h, a[k + 1] * h * h
        d, e, f = x[k + 1] - x0 - v0 - a0 / 2, v1 - v0 - a0, a1 - a0
        c3, c4, c5 = 10 * d - 4 * e + f / 2, -15 * d + 7 * e - f, 6 * d - 3 * e + f / 2
        roots = np.roots([5 * c5, 4 * c4, 3 * c3, a0, v0])
        inside = [r.real for r in roots if abs(r.imag) < 1e-9 and -1e-9 <= r.real <= 1 + 1e-9]
        if inside:
            s = min(inside, key=lambda r: abs(r - 0.5))
            times.append(t[k] + s * h)
            found.append(x0 + v0 * s + a0 / 2 * s**2 + c3 * s**3 + c4 * s**4 + c5 * s**5)
    return np.array(times, dtype=float), np.array(found, dtype=float)


def _accelerations(run: ChainResult, rows: np.ndarray) -> np.ndarray:
    """Each mass's acceleration at the trajectory's ``rows`` (one row of masses each; nan
    elsewhere), from the chain's field in the row's mode."""
    found = np.full((len(run.times), len(run.chain.system.masses)), math.nan)
    found[rows] = rates_at(run, rows)[:, 1 : 2 * len(run.chain.system.masses) : 2]
    return found


def orbit_measures(orbit: ChainOrbit) -> dict[str, float]:
    """The measures of one return of ``orbit``: ``x_max:<mass>``, ``x_min:<mass>``,
    ``x_pp:<mass>`` (m) for each mass; ``stuck:<element>`` (the share of the return it holds, 0 to
    1) and ``slip:<element>`` (m) for each friction element and Jenkins slider;
    ``closed:<element>`` (share), ``closings:<element>``, ``impact_velocity:<element>`` (m/s)
    and ``force_max:<element>`` (N, the largest force while closed) for each stop and contact;
    ``a_max:<mass>`` (m/s^2, the largest acceleration) for each mass
    (:func:`~oscillator.orbits.chain_peaks.peaks`); ``work:<element>`` and
    ``dissipated:<element>`` (J) for every element; and the noise measures of each stop and
    contact (docs/noise.md): ``impact_rate:<element>`` (closings per second),
    ``impact_energy:<element>`` (J: what it dissipates per closing), ``impact_power:<element>``
    (W: what it dissipates per second), ``impulse:<element>`` (N s: its force's integral while
    closed per closing, :func:`~oscillator.orbits.chain_peaks.impulses`, its size) and
    ``impulse_rate:<element>`` (N: that integral per second, the mean force); and each friction
    element's stick-slip measures: ``slip_steps:<element>`` (its mass's sticks and slips in the
    return) and ``slip_step_max:<element>`` (m/s^2: the largest step of its acceleration there,
    :func:`~oscillator.orbits.chain_peaks.slip_steps`)."""
    return _measures(orbit.run, orbit.section, orbit.period * orbit.chain.period)


def measure_names(chain: FrictionChain) -> tuple[str, ...]:
    """The names :func:`orbit_measures` gives the orbits of ``chain``, in its order: known before
    any orbit is found, to check a measure asked for."""
    names = [f"{kind}:{m.name}" for m in chain.masses for kind in ("x_max", "x_min", "x_pp")]
    for element in chain.elements:
        if element.type in _SLIDING:
            names.append(f"stuck:{element.name}")
        elif element.type in _CLOSING:
            names += [f"{kind}:{element.name}" for kind in ("closed", "closings", "impact_velocity")]
    names += [f"a_max:{m.name}" for m in chain.masses]
    names += [f"force_max:{e.name}" for e in chain.elements if e.type in _CLOSING]
    for element in chain.elements:
        names += [f"work:{element.name}", f"dissipated:{element.name}"]
        names += [f"slip:{element.name}"] if element.type in _SLIDING else []
    for element in chain.elements:
        names += [f"{kind}:{element.name}" for kind in _NOISE] if element.type in _CLOSING else []
    names += [f"{kind}:{e.name}" for e in chain.elements if e.type == "friction" for kind in _STEPS]
    return tuple(names)


def measure_unit(name: str) -> str:
    """The unit of a measure of :func:`orbit_measures` (``force_max:wall``: ``N``; ``""`` for a
    share or a count)."""
    return MEASURE_UNITS[name.partition(":")[0]]


def extremes(run: ChainResult) -> dict[str, tuple[float, float, float, float]]:
    """Each mass's ``(t_max, x_max, t_min, x_min)`` over ``run``: its largest and smallest
    displacement and when (the run's ends, and every turn: :func:`turns`)."""
    system, t, states = run.chain.system, run.times, run.states
    velocities = states[:, [system.state.index(system.velocity(m)) for m in system.masses]]
    turning = np.flatnonzero((velocities[:-1] * velocities[1:] < 0.0).any(axis=1))
    accelerations = _accelerations(run, np.union1d(turning, turning + 1))
    found: dict[str, tuple[float, float, float, float]] = {}
    for i, mass in enumerate(system.masses):
        x = states[:, system.state.index(system.position(mass))]
        times, places = turns(t, x, velocities[:, i], accelerations[:, i])
        times, places = np.concatenate([t[[0, -1]], times]), np.concatenate([x[[0, -1]], places])
        high, low = int(np.argmax(places)), int(np.argmin(places))
        found[str(mass)] = (float(times[high]), float(places[high]), float(times[low]), float(places[low]))
    return found


def _measures(run: ChainResult, start: float, span: float) -> dict[str, float]:
    found: dict[str, float] = {}
    for mass, (_, high, _, low) in extremes(run).items():
        found[f"x_max:{mass}"], found[f"x_min:{mass}"], found[f"x_pp:{mass}"] = high, low, high - low
    for element in run.chain.elements:
        if element.type in _SLIDING:
            spans = stuck_spans(run, element.name, start, span)
            found[f"stuck:{element.name}"] = float(sum(b - a for a, b in spans) / span)
        elif element.type in _CLOSING:
            found |= _contact_measures(run, element.name, start, span)
    at = sides(run)  # the field at every step's ends, once for the peaks, impulses and stick-slip steps
    found |= peaks(run, at) | _energy_measures(run, start, span)
    pushed = impulses(run, at)
    for element in run.chain.elements:  # what each closing loses and gives, per closing and per second
        if element.type in _CLOSING:
            name = element.name
            closings, lost, given = found[f"closings:{name}"], found[f"dissipated:{name}"], abs(pushed[name])
            found[f"impact_rate:{name}"] = closings / span
            found[f"impact_energy:{name}"] = lost / closings if closings else 0.0
            found[f"impact_power:{name}"] = lost / span
            found[f"impulse:{name}"] = given / closings if closings else 0.0
            found[f"impulse_rate:{name}"] = given / span
    for name, steps in slip_steps(run, at).items():
        found[f"slip_steps:{name}"], found[f"slip_step_max:{name}"] = float(len(steps)), max(steps, default=0.0)
    return found


def _contact_measures(run: ChainResult, name: str, start: float, span: float) -> dict[str, float]:
    """A stop's or contact's share of the return closed, its closings, and the fastest closing's
    speed (m/s: the gap's rate as it closes, from the event)."""
    events = run.events
    closings = events[(events.element == name) & events.kind.isin(["stop_closes", "contact_closes"])]
    spans = closed_spans(run, name, start, span)
    return {
        f"closed:{name}": float(sum(b - a for a, b in spans) / span),
        f"closings:{name}": float(len(closings)),
        f"impact_velocity:{name}": float(closings.G0.abs().max()) if len(closings) else 0.0,
    }


def _energy_measures(run: ChainResult, start: float, span: float) -> dict[str, float]:
    """Each element's work on the masses over the return and the energy it dissipates (J, the
    run's energy audit); each friction element's and slider's slip distance (m): the sum over its
    slips (each of one sign) of how far its mass moved against the belt (``x - w t``), or its
    ``z`` moved, from the states at the slip's ends."""
    chain, t, states = run.chain, run.times, run.states
    table = run.energy.table.set_index("element")
    found: dict[str, float] = {}
    for element in chain.elements:
        name = element.name
        found[f"work:{name}"] = float(table.work[name])
        found[f"dissipated:{name}"] = float(table.dissipated[name])
        if element.type in _SLIDING:
            spans, state = mode_spans(run, name, start, span), chain.system.state
            if element.type == "friction":  # the place against the belt's: x - w t
                place = states[:, state.index(chain.system.position(element.on))] - element.values["w"] * t
            else:
                place = states[:, state.index(f"z:{name}")]
            moves = [abs(np.interp(b, t, place) - np.interp(a, t, place)) for a, b, m in spans if m]
            found[f"slip:{name}"] = float(sum(moves))
    return found


def frequency_sweep(
    chain: FrictionChain,
    values: Sequence[float] | np.ndarray,
    *,
    param: str = "Omega",
    transient: int = 100,
    max_iterations: int = 25,
    progress: Callable[[int, int], None] | None = None,
) -> pd.DataFrame:
    """The period-1 orbit of ``chain`` at each of ``values`` of ``param`` (a name of
    :meth:`~oscillator.model.chains.FrictionChain.parameter_names`), in the order given (a sweep
    up, or down), each from the orbit before it; one row per value: the value, ``status``
    (``"followed"``, ``"restarted"`` after a transient where the orbit followed was lost, or
    ``"failed"`` with ``message``), ``stable`` and ``largest`` (the largest multiplier's modulus),
    the measures (:func:`orbit_measures`) and the orbit's state at the section.  ``progress(done,
    total)`` is told after each value.  A name the chain has not, or a value it refuses, is refused
    before any orbit is sought (the field named)."""
    values = np.asarray(values, dtype=float).ravel()
    if not len(values) or not np.isfinite(values).all():
        raise InputError("values must be finite numbers, at least one", field="values")
    points = [chain.with_values({param: value}) for value in values.tolist()]  # each checked, the field named
    names = chain.system.state
    rows: list[dict[str, object]] = []
    guess: np.ndarray | None = None
    for k, (value, point) in enumerate(zip(values.tolist(), points, strict=True)):
        row: dict[str, object] = {param: value}
        try:
            orbit, row["status"] = _followed(point, guess, transient, max_iterations)
        except OscillatorError as error:
            rows.append(row | {"status": "failed", "message": str(error), "stable": False, "largest": math.nan})
            guess = None
        else:
            largest = float(np.max(np.abs(orbit.multipliers), initial=0.0))
            rows.append(row | {"message": "", "stable": orbit.stable, "largest": largest} | orbit_measures(orbit))
            rows[-1] |= dict(zip(names, orbit.state.tolist(), strict=True))
            guess = orbit.state
        if progress is not None:
            progress(k + 1, len(values))
    return pd.DataFrame(rows)


def _followed(
    point: FrictionChain, guess: np.ndarray | None, transient: int, max_iterations: int
) -> tuple[ChainOrbit, str]:
    """The orbit from ``guess`` (the one before), or after a transient where there is none or it
    is lost; and which."""
    if guess is not None:
        try:
            return find_chain_orbit(point, guess, transient=0, max_iterations=max_iterations), "followed"
        except OscillatorError:
            pass
    found = find_chain_orbit(point, transient=transient, max_iterations=max_iterations)
    return found, "restarted" if guess is not None else "followed"
