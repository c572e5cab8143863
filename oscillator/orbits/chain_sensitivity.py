"""Exact sensitivities of a friction chain's periodic orbit in any of its numbers, by element and
field (issue 52): ``orbit.sensitivities(["platform.F", "blade.k", "Omega"])``.

The numbers are named as ``--set`` names them (:meth:`~oscillator.model.chains.FrictionChain.
parameter_names`): ``<element>.<field>`` (``platform.F``, ``support.k``, ``belt.w``),
``<mass>.m``, ``Omega`` and ``g``.  The tangent pass (:mod:`oscillator.orbits.chain_tangents`)
gives the period map's derivatives ``M = dP/dy`` and ``dP/dc`` through every switch; the orbit
``y* = P(y*, c)`` moves by

    (I - M) dy*/dc = dP/dc

over the coordinates that move at the section (:attr:`ChainOrbit.free`), with the velocity of a
mass stuck there moving with its belt's speed and a neutral coordinate held (a mass stuck, or a
slider holding, the whole period: its place is any nearby one).  Along the orbit a point moves by
``delta(t) = Phi(t) dy*/dc + Psi(t)``; a switch time by ``-(grad g . delta + dg/dc) / (grad g . f-
+ dg/dt)``.  The measures follow: a mass's largest (smallest) displacement moves as its
position at the turn (the velocity is zero there, so the turn's own shift does not count), a
stuck or closed share as the times that bound its spans, over the return's span
``N 2 pi / Omega``; a count of closings not at all.  A slip distance (each slip's ``|place(b) -
place(a)|``, the place ``x - w t`` of a mass on its belt or a slider's ``z``) moves by the sign of
each slip times the moves of the places at its ends, each end riding its switch (or the section,
whose end moves with ``Omega``); a Jenkins slider's dissipated energy, ``F`` times its slip,
with it.  A stop's or contact's force integral ``I`` and work ``W`` (its power ``F (v_on -
v_with)`` integrated) over its closed spans move by each span's ends riding their switches
(``F`` or the power there, on the closed side, times the end's time's move) and inside by
``integral (grad f . delta(t) + df/dc) dt``, Gauss-Legendre on each solver step (:data:`GAUSS`
nodes; the state there the quintic through the step's ends): ``dissipated = -W`` (nothing is
stored over a return), the impact energy and power ``-W`` per closing and per second, the impulse
and impulse rate ``|I|`` per closing and per second.  A friction element's largest stick-slip
step ``|a+ - a-|`` moves as both sides' field at the switch's state (the mode after, the mode
before), each riding the switch: ``grad a . dy_s + a_t dt_s + da/dc``.  The works and energies of
the other elements of :func:`~oscillator.orbits.chain_response.orbit_measures` have no derivative
here yet: their rows are left out (a count of stick-slip steps has zero).  A fastest closing speed
moves as the gap's rate at that closing, at the closing's moving time.  A peak (``a_max``,
``force_max``: :func:`~oscillator.orbits.chain_peaks.peak_places`) moves as the quantity at its
time: inside a piece its rate is zero there, so ``grad f . delta(t*) + df/dc``; on a switch it
rides the switch, ``grad f . dy_s + f_t dt_s + df/dc``.

Where a switch of the orbit is a grazing (the flow's speed across the boundary near zero against
its terms, :data:`MARGIN`), the map has no derivative there: refused, naming the switch.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from oscillator.errors import InputError, Reason, SimulationFailed
from oscillator.hybrid.chain_run import closed_spans, mode_spans, stuck_spans
from oscillator.model.chain_fields import chain_derivative, chain_jacobian, element_force, element_gradient
from oscillator.model.chains import Element, FrictionChain
from oscillator.orbits.chain_orbits import ChainOrbit
from oscillator.orbits.chain_peaks import Peak, impulses, nodes_of, peak_places, sides, slip_steps
from oscillator.orbits.chain_response import extremes, measure_names, orbit_measures
from oscillator.orbits.chain_tangents import ChainPass, NumberData, check_names, tangent_pass
from oscillator.text import printable

__all__ = ["GAUSS", "MARGIN", "ChainSensitivities", "chain_sensitivities", "moving_point"]

#: The smallest crossing speed, relative to its terms, at which a switch counts as transversal.
MARGIN = 1e-6
#: Gauss-Legendre nodes per solver step in the derivatives of the stops' and contacts' integrals.
GAUSS = 6


@dataclass(frozen=True)
class ChainSensitivities:
    """The derivatives of a chain's orbit in ``params``; each table has a ``d/d<param>`` column
    per number.

    Attributes
    ----------
    orbit : ChainOrbit
    params : tuple of str
    map : DataFrame
        ``dP/dc`` at the orbit's state (index: the state's names).
    state : DataFrame
        ``value`` and ``dy*/dc``: how the orbit's state at the section moves.
    switches : DataFrame
        Every switch over one return: ``t``, ``element``, ``kind``, ``margin`` (the crossing's
        speed relative to its terms), ``dt/d<param>``.
    measures : DataFrame
        Every measure of :func:`~oscillator.orbits.chain_response.orbit_measures`: ``value`` and
        its derivatives.
    """

    orbit: ChainOrbit
    params: tuple[str, ...]
    map: pd.DataFrame
    state: pd.DataFrame
    switches: pd.DataFrame
    measures: pd.DataFrame
    #: What :meth:`levels` needs: the tangent pass and ``dy*/dc``.
    _motion: tuple[ChainPass, np.ndarray] = field(repr=False, compare=False)

    def levels(self, cutoff: float = 0.0) -> pd.DataFrame:
        """Each stop's and contact's force's and each mass's acceleration's level above ``cutoff``
        Hz (dB, every harmonic) and its exact derivatives
        (:func:`oscillator.orbits.chain_levels.chain_level_derivatives`, docs/noise.md)."""
        from oscillator.orbits.chain_levels import chain_level_derivatives

        return chain_level_derivatives(self, cutoff)

    def of(self, measure: str) -> pd.Series:
        """One measure's derivatives (``x_max:blade``, ``stuck:platform``)."""
        if measure not in self.measures.index:
            known = ", ".join(self.measures.index)
            if measure in measure_names(self.orbit.chain):  # a measure, but one without a derivative yet
                raise InputError(
                    f"{printable(measure)} has no exact derivative yet (the works and energies of the springs, "
                    f"dampers, friction and forces have none); choose one of {known}",
                    field="measure",
                )
            raise InputError(f"no measure named {printable(measure)}; choose one of {known}", field="measure")
        return self.measures.loc[measure, [f"d/d{name}" for name in self.params]]


def _moved_start(orbit: ChainOrbit, along: ChainPass) -> np.ndarray:
    """``dy*/dc``: Newton's linear system over the free coordinates; a held velocity moves with
    its belt's speed, a neutral coordinate not at all."""
    chain, names = orbit.chain, list(orbit.chain.system.state)
    n, params = len(names), along.params
    moved = np.zeros((n, len(params)))
    for element in chain.elements:
        velocity = chain.system.velocity(element.on)
        if element.type == "friction" and velocity not in orbit.free:
            moved[names.index(velocity)] = [1.0 if name == f"{element.name}.w" else 0.0 for name in params]
    free = [names.index(name) for name in orbit.free]
    held = [k for k in range(n) if k not in free]
    monodromy = along.monodromy
    right = along.derivatives[free] + monodromy[np.ix_(free, held)] @ moved[held]
    moved[free] = np.linalg.solve(np.eye(len(free)) - monodromy[np.ix_(free, free)], right)
    return moved


def chain_sensitivities(orbit: ChainOrbit, params: str | Sequence[str]) -> ChainSensitivities:
    """The exact derivatives of ``orbit`` (:func:`~oscillator.orbits.chain_orbits.
    find_chain_orbit`'s) in the chain's numbers ``params`` (module docstring).

    Raises
    ------
    InputError
        A name the chain has not (the closest named).
    SimulationFailed
        (``reason = "not_differentiable"``) a switch of the orbit is a grazing.
    """
    if not isinstance(orbit, ChainOrbit):
        raise InputError("orbit must be a ChainOrbit (find_orbit's for a system)", field="orbit")
    names = check_names(orbit.chain, params)
    if not names:
        raise InputError("params must name one or more numbers of the system", field="params")
    for element in orbit.chain.elements:
        if element.type == "jenkins" and element.values["F"] == 0 and f"{element.name}.F" in names:
            raise SimulationFailed(
                f"no derivative in {element.name}.F at F = 0: the slider's slip turns with the motion there, "
                "without an event (the amplitude has a corner); take F > 0",
                reason=Reason.NOT_DIFFERENTIABLE,
            )
    along = tangent_pass(orbit.run, names)
    nearest = min(along.crossings, key=lambda c: c.margin, default=None)
    if nearest is not None and nearest.margin < MARGIN:
        raise SimulationFailed(
            f"the orbit grazes at t = {nearest.t!r} s ({nearest.element}, {nearest.kind}: the flow crosses at "
            f"{nearest.margin:.1e} of its terms): its measures have no derivative there",
            reason=Reason.NOT_DIFFERENTIABLE,
        )
    moved = _moved_start(orbit, along)
    columns = [f"d/d{name}" for name in names]
    state_names = list(orbit.chain.system.state)
    table = pd.DataFrame(moved, index=state_names, columns=columns)
    table.insert(0, "value", orbit.state)
    switches = pd.DataFrame(
        [[c.t, c.element, c.kind, c.margin, *c.time_derivative(moved).tolist()] for c in along.crossings],
        columns=["t", "element", "kind", "margin", *(f"dt/d{name}" for name in names)],
    )
    return ChainSensitivities(
        orbit,
        names,
        pd.DataFrame(along.derivatives, index=state_names, columns=columns),
        table,
        switches,
        _measures(orbit, along, moved),
        (along, moved),
    )


def _slip_derivative(
    orbit: ChainOrbit, name: str, along: ChainPass, moved: np.ndarray, stretch: np.ndarray
) -> np.ndarray:
    """The derivative of the friction element's or slider's slip distance (module docstring);
    ``stretch`` the return's end's derivative in each number."""
    chain, params = orbit.chain, along.params
    element = next(e for e in chain.elements if e.name == name)
    names, t = list(chain.system.state), orbit.run.trajectory.t.to_numpy(float)
    span = orbit.period * chain.period
    start, end = orbit.section, orbit.section + span
    belt = element.type == "friction"
    k = names.index(chain.system.position(element.on) if belt else f"z:{name}")
    w = element.values["w"] if belt else 0.0
    by_w = np.array([1.0 if belt and p == f"{name}.w" else 0.0 for p in params])
    place = orbit.run.trajectory[names[k]].to_numpy(float) - w * t
    riding = {c.t: c for c in along.crossings}

    def moves(at: float) -> np.ndarray:  # d place(at)/dc, the end riding its switch
        if at in (start, end):  # the section: the orbit's own start (its end moves with Omega)
            found: np.ndarray = moved[k] - w * (stretch if at == end else 0.0) - by_w * at
            return found
        crossing = riding[at]
        riding_end: np.ndarray = crossing.state_derivative(moved)[k] - w * crossing.time_derivative(moved) - by_w * at
        return riding_end

    total = np.zeros(len(params))
    for a, b, mode in mode_spans(orbit.run, name, start, span):
        if mode:
            total += np.sign(np.interp(b, t, place) - np.interp(a, t, place)) * (moves(b) - moves(a))
    return total


def _slip_step_derivative(orbit: ChainOrbit, along: ChainPass, moved: np.ndarray, element: Element) -> np.ndarray:
    """The derivative of a friction element's largest stick-slip step ``|a+ - a-|`` (module
    docstring): both sides' field at the switch's state, in the mode after and the mode before,
    each moving with the switch (``grad a . dy_s + a_t dt_s + da/dc``)."""
    run, chain, params = orbit.run, orbit.chain, along.params
    steps = slip_steps(run)[element.name]
    if not steps:
        return np.zeros(len(params))
    modes, t, states = run.modes(), run.times, run.states
    row = next(k for k, e in enumerate(chain.elements) if e.name == element.name)
    turned = np.flatnonzero((modes[:-1, row] == 0.0) != (modes[1:, row] == 0.0))
    k = int(turned[int(np.argmax(steps))])
    switch_time, state = float(t[k + 1]), states[k + 1]
    crossing = min(along.crossings, key=lambda c: abs(c.t - switch_time))
    n = chain.system.size
    dy, dt = crossing.state_derivative(moved)[:n], crossing.time_derivative(moved)
    i = 2 * [m.name for m in chain.masses].index(element.on) + 1  # the mass's velocity row
    numbers = NumberData(chain, params)

    def side(mode: np.ndarray) -> tuple[float, np.ndarray]:
        d, ahead, behind = numbers.of(mode)
        jacobian, partial = np.empty((n, n)), np.empty(n)
        chain_jacobian(switch_time, state, d, jacobian, partial)

        def value(data: np.ndarray) -> float:
            out = np.empty(numbers.arrays.size)
            chain_derivative(switch_time, state, out, data)
            return float(out[i])

        by_number = np.array([(value(ahead[p]) - value(behind[p])) / (2 * h) for p, h in enumerate(numbers.steps)])
        return value(d), jacobian[i] @ dy + partial[i] * dt + by_number

    after, before = side(modes[k + 1]), side(modes[k])
    found: np.ndarray = np.sign(after[0] - before[0]) * (after[1] - before[1])
    return found


def _closing_weights(chain: FrictionChain, element: Element) -> np.ndarray:
    """The weights over the state of a stop's or contact's closing speed: ``v_on - v_with``."""
    names = list(chain.system.state)
    weights = np.zeros(len(names))
    weights[names.index(chain.system.velocity(element.on))] = 1.0
    if element.with_ is not None:
        weights[names.index(chain.system.velocity(element.with_))] = -1.0
    return weights


def _impact_derivative(orbit: ChainOrbit, name: str, along: ChainPass, moved: np.ndarray) -> np.ndarray:
    """The derivative of a stop's or contact's fastest closing speed: the gap's rate at that
    closing, at its moving time (``delta- + f- dt_s``, the rate's row), signed as the speed."""
    chain, events = orbit.chain, orbit.events
    closings = events[(events.element == name) & events.kind.isin(["stop_closes", "contact_closes"])]
    if closings.empty:
        return np.zeros(len(along.params))
    fastest = closings.loc[closings.G0.abs().idxmax()]
    crossing = next(c for c in along.crossings if c.t == fastest.t)
    rate = _closing_weights(chain, next(e for e in chain.elements if e.name == name))
    found: np.ndarray = np.sign(fastest.G0) * (rate @ crossing.state_derivative(moved))
    return found


def _peak_derivative(
    orbit: ChainOrbit, along: ChainPass, peak: Peak, name: str, point: Callable[[float], np.ndarray]
) -> np.ndarray:
    """The derivative of a peak (:func:`~oscillator.orbits.chain_peaks.peak_places`) in the
    numbers: ``grad f . dy + df/dt dt + df/dc`` at the peak, its sign the peak's.  At a turn inside
    a piece ``f' = 0`` and the state moves as ``point`` says; at a switch the peak rides the
    switch, whose state moves as :meth:`Crossing.state_derivative` and its time as
    :meth:`Crossing.time_derivative`; ``df/dc`` by the central difference of
    :class:`~oscillator.orbits.chain_tangents.NumberData` in the peak's mode."""
    chain, n = orbit.chain, orbit.chain.system.size
    data = NumberData(chain, along.params)
    d, ahead, behind = data.of(peak.mode)
    kind, _, owner = name.partition(":")
    grad = np.zeros(n)
    if kind == "a_max":
        i = chain.system.masses.index(owner)
        jacobian, partial = np.empty((n, n)), np.empty(n)
        chain_jacobian(peak.t, peak.y, d, jacobian, partial)
        grad, rate = jacobian[2 * i + 1], partial[2 * i + 1]

        def value(data_: np.ndarray) -> float:
            out = np.empty(data.arrays.size)
            chain_derivative(peak.t, peak.y, out, data_)
            return float(out[2 * i + 1])
    else:
        row = next(k for k, e in enumerate(chain.elements) if e.name == owner)
        rate = element_gradient(peak.t, peak.y, d, row, grad)

        def value(data_: np.ndarray) -> float:
            return float(element_force(peak.t, peak.y, data_, row))

    by_number = np.array([(value(ahead[k]) - value(behind[k])) / (2 * step) for k, step in enumerate(data.steps)])
    crossing = next((c for c in along.crossings if c.t == peak.t), None)
    if crossing is None:
        total = grad @ point(peak.t)[:n] + by_number
    else:
        start = point(orbit.section)
        total = grad @ crossing.state_derivative(start)[:n] + rate * crossing.time_derivative(start) + by_number
    found: np.ndarray = np.sign(peak.value) * total
    return found


def _contact_integrals(
    orbit: ChainOrbit,
    along: ChainPass,
    motion: tuple[np.ndarray, Callable[[float | np.ndarray], np.ndarray], np.ndarray],
) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Each stop's and contact's derivatives of its force's integral over the return and of its
    work, the integral of its power ``F (v_on - v_with)`` (module docstring); ``motion``:
    ``dy*/dc``, the point's move at a time and the return's end's.  Each closed span's ends ride
    their switches (the return's end moves with ``Omega``, its start not at all); inside, the
    integrand moves by its gradient in the state times ``delta(t)`` plus its central difference in
    each number (exact: the force is affine in both), by :data:`GAUSS` Gauss-Legendre nodes on each
    solver step, the state there the quintic through the step's ends."""
    moved, point, stretch = motion
    run, chain = orbit.run, orbit.chain
    t, states, modes = run.times, run.states, run.modes()
    at, numbers = sides(run), NumberData(chain, along.params)
    start, span = orbit.section, orbit.period * chain.period
    when = {c.t: c.time_derivative(moved) for c in along.crossings}
    nodes, weights = np.polynomial.legendre.leggauss(GAUSS)
    where = (nodes + 1.0) / 2.0
    found, packed = {}, {}
    for row in at.contacts:
        element = chain.elements[row]
        rel = _closing_weights(chain, element)
        closed = np.flatnonzero((modes[:-1, row] != 0.0) & (np.diff(t) > 0.0))
        total = np.zeros((2, len(along.params)))
        times, states_at = nodes_of(run, at, closed, where)  # every closed step's nodes at once
        deltas = point(times.ravel()).reshape(*times.shape, *moved.shape)
        scales = 0.5 * (t[closed + 1] - t[closed])[:, None] * weights[None, :]
        for k, step in enumerate(closed.tolist()):
            key = modes[step].tobytes()
            if key not in packed:
                packed[key] = numbers.of(modes[step])
            for time, y, delta, scale in zip(times[k].tolist(), states_at[k], deltas[k], scales[k], strict=True):
                total += scale * _integrands_moved(time, y, delta, packed[key], (row, rel), numbers)
        for a, b in closed_spans(run, element.name, start, span):  # the ends, each on its closed side
            for time, side in ((a, -1.0), (b, 1.0)):
                moves = (
                    stretch if time == start + span else np.zeros(len(along.params)) if time == start else when[time]
                )
                k = int(closed[np.argmin(np.abs(t[closed + (side > 0)] - time))])
                y, d = states[k + (side > 0)], at.data[k]
                force = element_force(time, y, d, row)
                total += side * np.outer([force, force * (rel @ y)], moves)
        found[element.name] = (total[0], total[1])
    return found


def _integrands_moved(
    t: float,
    y: np.ndarray,
    moved: np.ndarray,
    data: tuple[np.ndarray, np.ndarray, np.ndarray],
    element: tuple[int, np.ndarray],
    numbers: NumberData,
) -> np.ndarray:
    """How a closed element's force and power at ``(t, y)`` move in each number (two rows): the
    state moving by ``moved`` (``delta(t)``), the data ``(d, ahead, behind)`` by each number's step;
    ``element``: its row and its relative velocity's weights ``rel`` (``v_on - v_with = rel . y``)."""
    row, rel = element
    d, ahead, behind = data
    n = len(rel)
    grad = np.empty(n)
    element_gradient(t, y, d, row, grad)
    delta = moved[:n]
    force = element_force(t, y, d, row)
    by_number = np.array(
        [
            (element_force(t, y, ahead[p], row) - element_force(t, y, behind[p], row)) / (2 * step)
            for p, step in enumerate(numbers.steps)
        ]
    )
    by_force = grad @ delta + by_number
    return np.stack([by_force, (rel @ y) * by_force + force * (rel @ delta)])


def _closing_measures(
    orbit: ChainOrbit,
    along: ChainPass,
    motion: tuple[np.ndarray, Callable[[float | np.ndarray], np.ndarray], np.ndarray],
    values: dict[str, float],
) -> dict[str, np.ndarray]:
    """Each stop's and contact's work, dissipated energy, impact rate, energy and power, impulse
    and impulse rate moved (module docstring); ``values`` the orbit's measures."""
    chain, stretch = orbit.chain, motion[2]
    span, zero = orbit.period * chain.period, np.zeros(len(along.params))
    integrals = _contact_integrals(orbit, along, motion)
    pushed = impulses(orbit.run)
    found = {}
    for element in (e for e in chain.elements if e.type in ("stop", "contact")):  # per closing and per second
        name, closings = element.name, values[f"closings:{element.name}"]
        by_force, by_work = integrals[name]
        found[f"work:{name}"], found[f"dissipated:{name}"] = by_work, -by_work  # nothing stored over a return
        found[f"impact_rate:{name}"] = -values[f"impact_rate:{name}"] * stretch / span  # a count over the span
        found[f"impact_energy:{name}"] = -by_work / closings if closings else zero
        found[f"impact_power:{name}"] = -by_work / span - values[f"impact_power:{name}"] * stretch / span
        by_size = np.sign(pushed[name]) * by_force  # the impulse is the integral's size
        found[f"impulse:{name}"] = by_size / closings if closings else zero
        found[f"impulse_rate:{name}"] = by_size / span - values[f"impulse_rate:{name}"] * stretch / span
    return found


def moving_point(orbit: ChainOrbit, along: ChainPass, moved: np.ndarray) -> Callable[[float | np.ndarray], np.ndarray]:
    """``delta(t)``: how the orbit's state at the time ``t`` moves in each number (``Phi(t)
    dy*/dc + Psi(t)``; at the section, ``dy*/dc``); at an array of times, one ``delta`` a time
    (the first axis)."""
    n, span = orbit.chain.system.size, orbit.period * orbit.chain.period

    def point(t: float | np.ndarray) -> np.ndarray:
        if np.ndim(t) == 0 and t in (orbit.section, orbit.section + span):  # the section: the orbit's own start
            return moved
        block = along.at(t)
        found: np.ndarray = block[..., :n] @ moved + block[..., n:]
        return found

    return point


def _measures(orbit: ChainOrbit, along: ChainPass, moved: np.ndarray) -> pd.DataFrame:
    chain, names = orbit.chain, list(orbit.chain.system.state)
    params = along.params
    span = orbit.period * chain.period
    stretch = np.array([-span / chain.Omega if name == "Omega" else 0.0 for name in params])
    point = moving_point(orbit, along, moved)

    found: dict[str, np.ndarray] = {}
    for mass, (t_high, _, t_low, _) in extremes(orbit.run).items():
        x = names.index(chain.system.position(mass))
        high, low = point(t_high)[x], point(t_low)[x]
        found[f"x_max:{mass}"], found[f"x_min:{mass}"], found[f"x_pp:{mass}"] = high, low, high - low
    when = {c.t: c.time_derivative(moved) for c in along.crossings}
    start, end = orbit.section, orbit.section + span
    for element in chain.elements:
        if element.type not in ("friction", "jenkins", "stop", "contact"):
            continue
        held = element.type in ("friction", "jenkins")
        spans = (stuck_spans if held else closed_spans)(orbit.run, element.name, start, span)
        share = sum(b - a for a, b in spans) / span

        def moves(t: float) -> np.ndarray:
            return stretch if t == end else np.zeros(len(params)) if t == start else when[t]

        total = sum((moves(b) - moves(a) for a, b in spans), np.zeros(len(params)))
        found[f"{'stuck' if held else 'closed'}:{element.name}"] = total / span - share * stretch / span
        if not held:  # a count: it moves only where the orbit changes (not differentiable there)
            found[f"closings:{element.name}"] = np.zeros(len(params))
            found[f"impact_velocity:{element.name}"] = _impact_derivative(orbit, element.name, along, moved)
    places = peak_places(orbit.run)
    for name, peak in places.items():
        found[name] = _peak_derivative(orbit, along, peak, name, point)
    values = orbit_measures(orbit)
    for element in (e for e in chain.elements if e.type in ("friction", "jenkins")):  # in orbit_measures' order
        rate = _slip_derivative(orbit, element.name, along, moved, stretch)
        if element.type == "jenkins":  # it dissipates F times its slip
            by_f = np.array([1.0 if p == f"{element.name}.F" else 0.0 for p in params])
            found[f"dissipated:{element.name}"] = by_f * values[f"slip:{element.name}"] + element.values["F"] * rate
        found[f"slip:{element.name}"] = rate
    found |= _closing_measures(orbit, along, (moved, point, stretch), values)
    for element in (e for e in chain.elements if e.type == "friction"):  # a count: it moves where the orbit changes
        found[f"slip_steps:{element.name}"] = np.zeros(len(params))
        found[f"slip_step_max:{element.name}"] = _slip_step_derivative(orbit, along, moved, element)
    ordered = {name: found[name] for name in values if name in found}  # in orbit_measures' order
    table = pd.DataFrame.from_dict(ordered, orient="index", columns=[f"d/d{name}" for name in params])
    table.insert(0, "value", [values[name] for name in table.index])
    return table
