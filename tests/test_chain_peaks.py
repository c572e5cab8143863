"""The peaks of a chain's orbit (issue 52's measures ``a_max:<mass>`` and ``force_max:<element>``):
against closed forms of linear chains (1e-9), against the stop's largest penetration where it has
no damping, and against an independent implementation's field sampled densely along its own
solution (tests/chain_independent.py) on an orbit with a stop, a contact, a floor and a passing."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from oscillator import FrictionChain
from oscillator.orbits.chain_orbits import find_chain_orbit
from oscillator.orbits.chain_peaks import peak_places, peaks, quintic, rates_at
from oscillator.orbits.chain_response import orbit_measures
from test_chain_sensitivities import impact_chain


def test_a_linear_oscillators_largest_acceleration_is_omega_squared_times_its_amplitude():
    m, k, c, q, omega = 2.0, 3.0, 0.2, 0.5, 1.3
    chain = FrictionChain(Omega=omega).mass("m", m).spring("m", k=k).damper("m", c=c).force("m", Q=q)
    amplitude = q / math.hypot(k - m * omega**2, c * omega)
    measured = orbit_measures(find_chain_orbit(chain, transient=50))
    assert measured["a_max:m"] == pytest.approx(omega**2 * amplitude, rel=1e-9)


def test_a_stop_that_stays_closed_pushes_with_its_static_and_its_dynamic_force():
    """A left stop at 1 m holding a spring's mass at K/(k + K): the motion is linear with stiffness
    k + K and damping c + C, and the stop's force ``K (at - x) - C v`` peaks at
    ``K (at - x0) + X sqrt(K^2 + C^2 Omega^2)``."""
    k, big_k, big_c, c, q, omega = 1.0, 4.0, 0.2, 0.1, 0.3, 1.0
    x0 = big_k / (k + big_k)
    chain = FrictionChain(Omega=omega).mass("m", 1.0, x=x0).spring("m", k=k).damper("m", c=c).force("m", Q=q)
    chain = chain.stop("m", name="stop", side="left", at=1.0, K=big_k, C=big_c)
    orbit = find_chain_orbit(chain, transient=50)
    assert orbit.events.empty  # closed throughout
    amplitude = q / math.hypot(k + big_k - omega**2, (c + big_c) * omega)
    measured = orbit_measures(orbit)
    assert measured["force_max:stop"] == pytest.approx(
        big_k * (1.0 - x0) + amplitude * math.hypot(big_k, big_c * omega), rel=1e-9
    )
    assert measured["a_max:m"] == pytest.approx(omega**2 * amplitude, rel=1e-9)


def test_an_undamped_stops_largest_force_is_its_stiffness_times_the_largest_penetration():
    chain = FrictionChain(Omega=0.8).mass("m", 1.0).spring("m", k=1.0).damper("m", c=0.05).force("m", Q=0.4)
    chain = chain.stop("m", name="wall", side="right", at=0.5, K=50.0)
    orbit = find_chain_orbit(chain, transient=100)
    assert set(orbit.events.kind) == {"stop_closes", "stop_opens"}
    measured = orbit_measures(orbit)
    assert measured["force_max:wall"] == pytest.approx(50.0 * (measured["x_max:m"] - 0.5), rel=1e-9)
    # momentum over a period: the stop's impulse (pushing back, a negative force) is what the spring
    # takes, k times the integral of x (the damper's and the force's integrals vanish; x's is
    # negative, the stop holding the mass back); that integral by Simpson's rule on the
    # states the solver stops at, a grid of 4000 steps
    from oscillator.hybrid.chain_run import simulate_chain

    span = 2 * math.pi / 0.8
    grid = orbit.section + np.linspace(0.0, span, 4001)
    run = simulate_chain(chain, orbit.section + span, start_state=orbit.state, at=grid[1:-1])
    run_t, x = run.times, run.states[:, 0]
    x_at = np.array([x[np.flatnonzero(run_t == t)[-1]] if t in run_t else np.interp(t, run_t, x) for t in grid])
    h = span / 4000
    integral = h / 3 * (x_at[0] + x_at[-1] + 4 * x_at[1:-1:2].sum() + 2 * x_at[2:-1:2].sum())
    assert integral < 0 and measured["impulse_rate:wall"] == pytest.approx(-1.0 * integral / span, rel=1e-6)
    assert measured["impulse:wall"] == pytest.approx(-integral / measured["closings:wall"], rel=1e-6)


def test_the_peaks_are_an_independent_implementations_sampled_densely():
    import chain_independent
    from test_chain_runs import _as_dicts

    chain = impact_chain()
    orbit = find_chain_orbit(chain, transient=100)
    masses, elements = _as_dicts(chain)
    for mass, (x, v) in zip(masses, orbit.state.reshape(-1, 2), strict=True):
        mass["x"], mass["v"] = float(x), float(v)
    pieces: list = []
    chain_independent.run(
        masses, elements, chain.Omega, chain.g, orbit.section, orbit.section + chain.period, pieces=pieces
    )
    machine, quantities = pieces[0], {}
    for i, mass in enumerate(machine.names):
        quantities[f"a_max:{mass}"] = lambda t, y, mode, i=i: abs(machine.rhs(t, y, mode)[2 * i + 1])
    for e in machine.elements:
        if e["type"] in ("stop", "contact"):
            quantities[f"force_max:{e['name']}"] = lambda t, y, mode, e=e: abs(machine.force(e, t, y, mode))
    found = {name: max(_piece_peak(piece, of) for piece in pieces[1:]) for name, of in quantities.items()}
    measured = peaks(orbit.run)
    assert set(measured) == set(found) == {"a_max:a", "a_max:b", "force_max:wall", "force_max:gap"}
    for name, value in found.items():
        assert measured[name] == pytest.approx(value, rel=1e-8), (name, measured[name] / value - 1)


def _piece_peak(piece, of) -> float:
    """The largest ``of(t, y, mode)`` over one smooth piece of the independent run: sampled, then
    refined about the largest sample on the piece's dense solution (or an end of the piece)."""
    from scipy.optimize import minimize_scalar

    start, end, solution, mode = piece
    times = np.linspace(start, end, 400)
    values = [of(t, solution(t), mode) for t in times]
    k = int(np.argmax(values))
    if k in (0, len(times) - 1):
        return float(values[k])
    best = minimize_scalar(
        lambda t: -of(t, solution(t), mode),
        bounds=(times[k - 1], times[k + 1]),
        method="bounded",
        options={"xatol": 1e-13},
    )
    return max(float(values[k]), -float(best.fun))


def test_a_peak_on_a_switch_moves_with_the_switch():
    """A soft, strongly damped stop pushes hardest as it closes: both peaks sit on the closing
    (the acceleration's and the force's jump there), and their derivatives, which ride the
    switch (its moving time and state), equal Richardson differences of the orbits at c +- h
    (h 1e-4 relative) to 1e-7; so do the peaks inside a piece, in tests/test_chain_sensitivities.py."""
    chain = FrictionChain(Omega=0.8).mass("m", 1.0).spring("m", k=1.0).damper("m", c=0.05).force("m", Q=0.5)
    chain = chain.stop("m", name="wall", side="right", at=0.5, K=1.0, C=2.0)
    orbit = find_chain_orbit(chain, transient=100, tol=1e-13)
    closing = float(orbit.events.t[orbit.events.kind == "stop_closes"].iloc[0])
    assert {peak.t for peak in peak_places(orbit.run).values()} == {closing}
    names, rows = ["wall.C", "wall.at", "Omega", "spring-1.k"], ["force_max:wall", "a_max:m"]
    found = orbit.sensitivities(names).measures.loc[rows]

    def seen(name: str, value: float) -> np.ndarray:
        moved = find_chain_orbit(chain.with_values({name: value}), orbit.state, transient=0, tol=1e-13)
        return np.array([orbit_measures(moved)[row] for row in rows])

    for name, value in zip(names, (2.0, 0.5, 0.8, 1.0), strict=True):
        h = 1e-4 * max(1.0, value)
        wide = (seen(name, value + h) - seen(name, value - h)) / (2 * h)
        narrow = (seen(name, value + h / 2) - seen(name, value - h / 2)) / h
        exact = found[f"d/d{name}"].to_numpy()
        assert np.abs((4 * narrow - wide) / 3 - exact).max() <= 1e-7 * np.abs(exact).max(), name


def test_a_long_runs_peaks_are_its_rows_largest_or_a_turn_between_them():
    """Over a run of many steps, stick-slip and impacts (the impact chain, 30 periods from rest):
    the field at every row as :func:`rates_at` evaluates it at once is the field each row's mode
    gives one call at a time; each peak is at least every row's value, and either is one (a row
    or a switch's other side, in the step's mode) or lies between two rows where the quantity's
    rate vanishes."""
    from oscillator.hybrid.chain_run import simulate_chain
    from oscillator.model.chain_fields import arrays_of, chain_derivative, element_force, pack

    chain = impact_chain()
    run = simulate_chain(chain, chain.t0 + 30 * chain.period)
    t, states, modes, arrays = run.times, run.states, run.modes(), arrays_of(chain)
    assert len(t) > 1000 and len(run.switches()[0]) > 20
    rows = np.arange(0, len(t), 7)
    one_by_one = np.empty((len(rows), chain.system.size))
    for j, k in enumerate(rows.tolist()):
        chain_derivative(t[k], states[k], one_by_one[j], pack(arrays, modes[k]))
    assert np.array_equal(rates_at(run, rows), one_by_one)
    accelerations = rates_at(run, np.arange(len(t)))[:, 1 : 2 * len(chain.masses) : 2]
    places = peak_places(run)
    for i, mass in enumerate(chain.masses):
        peak = places[f"a_max:{mass.name}"]
        assert abs(peak.value) >= np.abs(accelerations[:, i]).max()
        if peak.t not in set(t.tolist()):
            k = int(np.searchsorted(t, peak.t))
            assert t[k - 1] < peak.t < t[k] and np.array_equal(peak.mode, modes[k - 1])
            rate = np.empty(chain.system.size)
            chain_derivative(peak.t, peak.y, rate, pack(arrays, peak.mode))
            assert rate[2 * i + 1] == pytest.approx(peak.value, rel=1e-12)
    for k, element in enumerate(chain.elements):
        if element.type in ("stop", "contact"):
            peak, closed = places[f"force_max:{element.name}"], np.flatnonzero(modes[:, k] != 0.0)
            forces = [element_force(t[j], states[j], pack(arrays, modes[j]), k) for j in closed.tolist()]
            assert abs(peak.value) >= max(np.abs(forces)) > 0.0


def test_a_packed_mode_is_a_copy_of_the_chains_vector():
    """pack() gives a vector of its own each call (the compiled calls write their scratch in
    it), from the chain's vector that no call can change."""
    from oscillator.model.chain_fields import arrays_of, pack

    arrays = arrays_of(impact_chain())
    first, second = pack(arrays, [1] * len(arrays.kind)), pack(arrays, [0] * len(arrays.kind))
    first[-1] = 123.0
    assert second[-1] == 0.0 and arrays.packed[-1] == 0.0 and not arrays.packed.flags.writeable
    assert np.array_equal(first[:-1][5 : 5 + len(arrays.kind)], np.ones(len(arrays.kind)))
    assert np.array_equal(
        np.delete(first, np.s_[5 : 5 + len(arrays.kind)])[:-1], np.delete(second, np.s_[5 : 5 + len(arrays.kind)])[:-1]
    )


def test_the_quintic_is_exact_on_polynomials_of_its_degree():
    s, h = 0.3, 0.7
    p = np.polynomial.Polynomial([0.5, -1.0, 2.0, 0.3, -0.7, 0.2])  # in t over a step of length h
    d1, d2 = p.deriv(), p.deriv(2)
    ends = tuple(np.array([f(t)]) for t in (0.0, h) for f in (p, d1, d2))
    assert quintic(s, h, ends)[0] == pytest.approx(p(s * h), abs=1e-14)


@pytest.mark.slow
def test_a_sweeps_points_are_where_the_independent_implementation_settles():
    """At two points of a frequency sweep (stop, contact, floor), the independent implementation
    (tests/chain_independent.py), started 1e-4 away from the sweep's orbit and run 40 periods,
    settles on it (1e-7), with the same largest displacements, shares of the period stuck and
    closed, and fastest closing speeds (1e-7), these read from its own events and dense solution."""
    import chain_independent
    from oscillator.orbits.chain_response import frequency_sweep
    from test_chain_runs import _as_dicts

    table = frequency_sweep(impact_chain(), [0.6, 0.7], transient=100)
    assert list(table.status) == ["followed", "followed"] and table.stable.all()
    for row in table.to_dict("records"):
        chain = impact_chain().with_values({"Omega": row["Omega"]})
        state = np.array([row[name] for name in chain.system.state])
        masses, elements = _as_dicts(chain)
        for mass, (x, v) in zip(masses, (state + 1e-4).reshape(-1, 2), strict=True):
            mass["x"], mass["v"] = float(x), float(v)
        pieces: list = []
        periods, period = 40, chain.period
        chain_independent.run(masses, elements, chain.Omega, chain.g, 0.0, periods * period, pieces=pieces)
        machine, start = pieces[0], (periods - 1) * period
        assert np.max(np.abs(pieces[-1][2](periods * period) - state)) < 1e-7
        last = [(max(a, start), b, sol, mode) for a, b, sol, mode in pieces[1:] if b > start]
        for i, mass in enumerate(machine.names):
            found = max(_piece_peak(piece, lambda t, y, mode, i=i: y[2 * i]) for piece in last)
            assert found == pytest.approx(row[f"x_max:{mass}"], abs=1e-7)
        for name, wanted in (("floor", 0), ("wall", 1), ("gap", 1)):
            share = sum(b - a for a, b, _, mode in last if mode[name] == wanted) / period
            assert share == pytest.approx(row[f"{'stuck' if name == 'floor' else 'closed'}:{name}"], abs=1e-7)
        for name in ("wall", "gap"):
            e = next(e for e in machine.elements if e["name"] == name)
            closings = [
                abs(machine.u(e, before[2](before[1]))[1])
                for before, after in itertools.pairwise(last)
                if before[3][name] == 0 and after[3][name] == 1
            ]
            assert max(closings) == pytest.approx(row[f"impact_velocity:{name}"], abs=1e-7)
            assert len(closings) == row[f"closings:{name}"]


def _independent_measures(chain: FrictionChain, state: np.ndarray, periods: int = 4) -> tuple[float, float]:
    """The independent implementation run ``periods`` periods from ``state``: it must stay on that
    orbit (1e-8), and its own ``x_max`` of the first mass and share of the period the wall is
    closed, over the last period, from its dense solution and its modes."""
    import chain_independent
    from test_chain_runs import _as_dicts

    masses, elements = _as_dicts(chain)
    for mass, (x, v) in zip(masses, state.reshape(-1, 2), strict=True):
        mass["x"], mass["v"] = float(x), float(v)
    pieces: list = []
    period = chain.period
    chain_independent.run(masses, elements, chain.Omega, chain.g, 0.0, periods * period, pieces=pieces)
    assert np.max(np.abs(pieces[-1][2](periods * period) - state)) < 1e-8
    start = (periods - 1) * period
    last = [(max(a, start), b, sol, mode) for a, b, sol, mode in pieces[1:] if b > start]
    highest = max(_piece_peak(piece, lambda t, y, mode: y[0]) for piece in last)
    return highest, sum(b - a for a, b, _, mode in last if mode["wall"] == 1) / period


@pytest.mark.slow
def test_the_exact_derivatives_are_the_independent_implementations_differences():
    """``d x_max:a / d wall.at`` and ``d closed:wall / d wall.at`` of the orbit with a stop, a
    contact and a floor equal Richardson-extrapolated central differences of the measures the
    independent implementation (tests/chain_independent.py) reads from its own solution on the
    orbits at ``wall.at +- h, +- 2h`` (each checked periodic there by that implementation) to 1e-6
    relative."""
    chain = impact_chain()
    orbit = find_chain_orbit(chain, transient=150)
    found = orbit.sensitivities(["wall.at"])
    exact = [found.of(name)["d/dwall.at"] for name in ("x_max:a", "closed:wall")]
    at, h = 0.45, 1e-3
    measured = {}
    for step in (-2 * h, -h, h, 2 * h):
        moved = chain.with_values({"wall.at": at + step})
        measured[step] = np.array(_independent_measures(moved, find_chain_orbit(moved, orbit.state, transient=0).state))
    central = {k: (measured[k * h] - measured[-k * h]) / (2 * k * h) for k in (1, 2)}
    richardson = (4 * central[1] - central[2]) / 3
    assert richardson == pytest.approx(exact, rel=1e-6)


@pytest.mark.parametrize("damper", [0.0, 0.5])
def test_a_stops_impulse_is_the_momentum_it_turns_round(damper):
    """A free mass (no spring, friction or force) meets a stop at speed 1: while closed the stop's
    force is the only one, so its integral is ``m (v_out - v_in)`` (2 m with no damper), to the
    solver's tolerance; the orbit measures give it per closing and per second."""
    from oscillator import SolverOptions
    from oscillator.errors import InputError
    from oscillator.hybrid.chain_run import simulate_chain
    from oscillator.orbits.chain_peaks import impulses

    chain = FrictionChain(Omega=1.0).mass("m", m=2.0, x=0.0, v=1.0).stop("m", name="wall", side="right", at=0.5,
                                                                          K=50.0, C=damper)  # fmt: skip
    with pytest.raises(InputError, match="options must be a SolverOptions"):
        simulate_chain(chain, 3.0, options={"rtol": 1e-12})
    run = simulate_chain(chain, 3.0, options=SolverOptions(rtol=1e-12, atol=1e-12))
    events = run.events
    assert list(events.kind[events.element == "wall"]) == ["stop_closes", "stop_opens"]
    out = float(run.states[-1, 1])  # free flight after the stop: the speed it left with
    assert out < 0 and (out == pytest.approx(-1.0, rel=1e-9) if damper == 0 else out > -0.99)
    assert impulses(run)["wall"] == pytest.approx(2.0 * (out - 1.0), rel=1e-9)


def test_a_mass_slipping_off_its_belt_steps_its_acceleration_by_the_friction_gap():
    """On the belt chain's orbit the mass sticks to its belt and slips off it once a period: slipping
    off, the force that held it falls from the static threshold to the kinetic one, a step of
    ``(mu_s - mu_k) N / m`` (1e-9); sticking, the step is the acceleration it had relative to the
    belt; the orbit measures count both and keep the larger."""
    from oscillator.orbits.chain_peaks import slip_steps
    from test_chain_sensitivities import belt_chain

    orbit = find_chain_orbit(belt_chain(), transient=100)
    kinds = list(orbit.events.kind[orbit.events.element == "belt"])
    steps = slip_steps(orbit.run)["belt"]
    assert sorted(kinds) == ["slips", "sticks"] and len(steps) == 2
    slipped = steps[kinds.index("slips")]
    assert slipped == pytest.approx((0.4 - 0.25) * 1.0 / 1.0, rel=1e-9)
    stuck = steps[kinds.index("sticks")]
    measured = orbit_measures(orbit)
    assert measured["slip_steps:belt"] == 2 and measured["slip_step_max:belt"] == max(slipped, stuck) > 0
