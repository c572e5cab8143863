"""Exact derivatives of friction chains' orbits through every switch (issue 52:
oscillator/orbits/chain_tangents.py, chain_sensitivity.py): the monodromy against central
differences of the period map on orbits that stick and slip on a belt, pass their floor's speed,
close and open a stop and a contact, and hold and slip a Jenkins slider; the sensitivities in
element fields against Richardson differences (1e-7 relative, as for the article's system); a
linear chain's against its closed form; the refusals."""

from __future__ import annotations

import functools
import math
from pathlib import Path

import numpy as np
import pytest

from oscillator.errors import InputError
from oscillator.io.chains import load_system
from oscillator.model.chains import FrictionChain
from oscillator.orbits.chain_orbits import chain_period_map, find_chain_orbit
from oscillator.orbits.chain_response import orbit_measures
from oscillator.orbits.chain_sensitivity import chain_sensitivities
from oscillator.orbits.chain_tangents import tangent_pass
from test_chain_orbits import OMEGA, linear_chain
from test_sensitivities import richardson

SYSTEMS = Path(__file__).resolve().parents[1] / "docs" / "systems"


def belt_chain() -> FrictionChain:
    """A forced mass on a belt: it sticks to the belt and slips off it once a period."""
    return (
        FrictionChain(Omega=0.6)
        .mass("m", 1.0)
        .spring("m", k=1.0)
        .damper("m", c=0.05)
        .friction("m", name="belt", mu_s=0.4, mu_k=0.25, N=1.0, w=0.3)
        .force("m", Q=0.4)
    )


def impact_chain() -> FrictionChain:
    """Two masses, a cubic spring between them, one on a floor with friction: its stop closes and
    opens, the contact between them closes and opens, its speed passes the floor's."""
    return (
        FrictionChain(Omega=0.7)
        .mass("a", 1.0)
        .mass("b", 0.6)
        .spring("a", k=1.0)
        .spring("b", "a", k=0.8, k3=0.2)
        .damper("a", c=0.04)
        .damper("b", c=0.03)
        .friction("a", name="floor", mu_s=0.12, mu_k=0.08, N=1.0)
        .stop("a", name="wall", side="right", at=0.45, K=40.0, C=0.2)
        .contact("b", "a", name="gap", side="right", gap=0.3, K=30.0, C=0.1)
        .force("a", Q=0.5)
    )


def blade_chain() -> FrictionChain:
    """docs/systems/blade-damper.toml: a blade, a Jenkins damper that holds and slips."""
    return load_system(SYSTEMS / "blade-damper.toml")


CASES = {
    "belt": (belt_chain, {"slips", "sticks"}, ["belt.w", "belt.mu_s", "belt.mu_k", "m.m", "Omega"]),
    "impacts": (
        impact_chain,
        {"passable", "stop_closes", "stop_opens", "contact_closes", "contact_opens"},
        ["wall.at", "gap.K", "spring-2.k3", "floor.mu_k", "Omega"],
    ),
    "blade": (blade_chain, {"slider_slips", "slider_sticks"}, ["platform.F", "platform.kt", "spring-1.k", "Omega"]),
}


@pytest.fixture(scope="module", params=sorted(CASES))
def case(request):
    make, kinds, params = CASES[request.param]
    orbit = find_chain_orbit(make(), transient=150)
    return orbit, kinds, params


def map_differences(orbit, free: list[int]) -> np.ndarray:
    """The period map's derivative over the state's indices ``free`` by central differences (a
    step of 1e-6 of each coordinate's scale): what the chain orbits took before the tangent pass
    (benchmarks/systems.py times the two)."""
    size, columns = orbit.chain.system.size, []
    for k in free:
        h = 1e-6 * max(1.0, abs(orbit.state[k]))
        ends = []
        for sign in (1.0, -1.0):
            start = orbit.state.copy()
            start[k] += sign * h
            ends.append(chain_period_map(orbit.chain, orbit.section, start).y_end[:size])
        columns.append((ends[0] - ends[1])[free] / (2 * h))
    return np.array(columns).T


def test_the_exact_monodromy_equals_the_period_maps_differences(case):
    """``M`` through the saltation of every switch the orbit makes equals central differences of
    the period map (step 1e-6 at CVODE's 1e-12, the differences good to about 1e-7: agreement to 1e-6
    of M's scale; a missed saltation term is of order one)."""
    orbit, kinds, _ = case
    assert kinds <= set(orbit.events.kind), set(orbit.events.kind)
    names = list(orbit.chain.system.state)
    differences = map_differences(orbit, [names.index(name) for name in orbit.free])
    scale = np.abs(differences).max()
    assert np.abs(orbit.monodromy - differences).max() <= 1e-6 * scale
    assert orbit.stable and np.abs(orbit.multipliers).max() < 1.0


def test_the_tangents_at_many_times_are_those_at_each_time(case):
    """The tangents at an array of times (the sensitivities' Gauss nodes, one call a piece) are
    the blocks at each time alone, across pieces and at their switches, with numbers and without
    (a chain affine in its state: the exponential of each mode's Jacobian); a time outside the run
    is refused."""
    orbit, _, params = case
    run = chain_period_map(orbit.chain, orbit.section, orbit.state)
    t = run.times
    times = np.concatenate([t, (t[:-1] + t[1:]) / 2])
    for along in (tangent_pass(run, params), tangent_pass(run)):
        assert np.array_equal(along.at(times), np.stack([along.at(float(s)) for s in times]))
        with pytest.raises(ValueError, match="outside the run"):
            along.at(np.array([t[0], t[-1] + 1.0]))


def test_sensitivities_in_element_fields_equal_richardson_differences(case):
    """``dy*/dc`` and every measure's derivative in element fields, masses and ``Omega`` equal
    Richardson-extrapolated central differences of the orbits found at ``c +- h`` (h 1e-4
    relative): 1e-7 of each column's scale."""
    orbit, _, params = case
    found = orbit.sensitivities(params)
    measures = orbit_measures(orbit)
    kinds = ("x_max", "x_min", "x_pp", "stuck", "closed", "closings", "impact_velocity", "a_max", "force_max", "slip")
    kinds += ("impact_rate", "impact_energy", "impact_power", "impulse", "impulse_rate", "slip_steps", "slip_step_max")
    sliders = {f"dissipated:{e.name}" for e in orbit.chain.elements if e.type == "jenkins"}  # F times the slip
    closing = {f"{kind}:{e.name}" for e in orbit.chain.elements if e.type in ("stop", "contact")
               for kind in ("work", "dissipated")}  # fmt: skip
    derived = [name for name in measures if name.split(":")[0] in kinds or name in sliders | closing]
    assert list(found.measures.index) == derived
    np.testing.assert_allclose(found.measures.value, [measures[name] for name in derived], rtol=0, atol=0)

    def seen(name: str, value: float) -> np.ndarray:
        moved = find_chain_orbit(orbit.chain.with_values({name: value}), orbit.state, transient=0, tol=1e-13)
        measures = orbit_measures(moved)
        return np.concatenate([moved.state, [measures[k] for k in found.measures.index]])

    for name in params:
        value = orbit.chain.value(name)
        h = 1e-4 * max(1.0, abs(value))
        wide = (seen(name, value + h) - seen(name, value - h)) / (2 * h)
        narrow = (seen(name, value + h / 2) - seen(name, value - h / 2)) / h
        richardson = (4 * narrow - wide) / 3
        exact = np.concatenate([found.state[f"d/d{name}"], found.measures[f"d/d{name}"]])
        assert np.abs(richardson - exact).max() <= 1e-7 * np.abs(exact).max(), name


def test_switch_times_move_as_the_orbit_found_at_a_nearby_value_says():
    """``dt/dc`` of each switch equals the difference of the switch times of the orbits at
    ``c +- h`` (the same switches, in the same order)."""
    orbit = find_chain_orbit(belt_chain(), transient=150)
    found = orbit.sensitivities("belt.mu_s")
    h = 1e-5
    times = [
        find_chain_orbit(belt_chain().with_values({"belt.mu_s": 0.4 + s}), orbit.state, transient=0).events.t.to_numpy()
        for s in (h, -h)
    ]
    assert list(found.switches.kind) == ["slips", "sticks"]
    np.testing.assert_allclose(found.switches["dt/dbelt.mu_s"], (times[0] - times[1]) / (2 * h), rtol=1e-6)


def test_a_linear_chains_sensitivities_are_its_closed_forms():
    """``x* = Im(X e^{i phi})`` with ``A X = F``, ``A = K - Omega^2 M + i Omega C``: ``dX/dQ =
    X / Q``, ``dX/dk = -A^-1 (dA/dk) X`` (1e-9)."""
    orbit = find_chain_orbit(linear_chain(), transient=5)
    found = orbit.sensitivities(["force-5.Q", "spring-2.k", "damper-3.c"])
    mass, damping = np.diag([1.0, 0.5]), np.diag([0.1, 0.05])
    stiffness = np.array([[3.0, -1.0], [-1.0, 1.0]])
    matrix = stiffness - OMEGA**2 * mass + 1j * OMEGA * damping
    amplitude = np.linalg.solve(matrix, [1.0, 0.0])

    def state(moved: np.ndarray) -> np.ndarray:
        moved = moved * np.exp(0.3j)
        return np.ravel(np.column_stack([moved.imag, (1j * OMEGA * moved).imag]))

    coupling = np.array([[1.0, -1.0], [-1.0, 1.0]])
    expected = {
        "force-5.Q": state(amplitude),
        "spring-2.k": state(-np.linalg.solve(matrix, coupling @ amplitude)),
        "damper-3.c": state(-np.linalg.solve(matrix, 1j * OMEGA * np.diag([1.0, 0.0]) @ amplitude)),
    }
    for name, value in expected.items():
        np.testing.assert_allclose(found.state[f"d/d{name}"], value, rtol=0, atol=1e-9, err_msg=name)
    assert math.isclose(found.of("x_pp:a")["d/dforce-5.Q"], found.measures.value["x_pp:a"], rel_tol=1e-9)


def test_unknown_names_and_other_values_are_refused():
    orbit = find_chain_orbit(belt_chain(), transient=150)
    with pytest.raises(InputError, match=r"belt\.mu_s") as caught:
        orbit.sensitivities("belt.mu_z")
    assert caught.value.field == "belt.mu_z"
    with pytest.raises(InputError, match=r"x_max:m"):
        orbit.sensitivities("belt.w").of("x_max:blade")
    with pytest.raises(InputError, match="ChainOrbit"):
        chain_sensitivities("orbit", "belt.w")  # type: ignore[arg-type]


def test_each_elements_energy_over_an_orbit_balances_and_the_slips_agree_with_it(case):
    """Over one return the works of all elements sum to zero (the state returns), the springs'
    each to zero, the forcing's to what the others dissipate; a slider dissipates ``F`` times its
    slip (its ``z``'s moves, from the events) and a friction element ``(mu_k N + P)`` times its
    slip measured as ``|v - w|`` integrated along the run (the trapezoid over the solver's steps);
    a stop's or contact's fastest closing speed is the gap's rate at its fastest closing."""
    orbit, _, _ = case
    measures, chain = orbit_measures(orbit), orbit.chain
    works = {e.name: measures[f"work:{e.name}"] for e in chain.elements}
    scale = max(abs(w) for w in works.values())
    assert abs(sum(works.values())) <= 1e-8 * scale
    trajectory = orbit.run.trajectory
    t = trajectory.t.to_numpy()
    for element in chain.elements:
        name = element.name
        if element.type == "spring":
            assert abs(works[name]) <= 1e-9 * scale
        elif element.type == "jenkins":
            assert math.isclose(
                element.values["F"] * measures[f"slip:{name}"], measures[f"dissipated:{name}"], rel_tol=1e-8
            )
        elif element.type == "friction":
            v = trajectory[chain.system.velocity(element.on)].to_numpy()
            integrated = np.trapezoid(np.abs(v - element.values["w"]), t)
            assert math.isclose(measures[f"slip:{name}"], integrated, rel_tol=1e-4), (name, integrated)
        elif element.type in ("stop", "contact"):
            closings = orbit.events[(orbit.events.element == name) & orbit.events.kind.str.endswith("closes")]
            assert measures[f"closings:{name}"] == len(closings)
            rows = trajectory[np.isin(t, closings.t)]
            rate = rows[chain.system.velocity(element.on)].to_numpy()
            if element.with_:
                rate = rate - rows[chain.system.velocity(element.with_)].to_numpy()
            assert math.isclose(measures[f"impact_velocity:{name}"], np.abs(rate).max(), rel_tol=1e-12)


def test_a_stops_noise_measures_have_exact_derivatives_and_the_others_say_they_have_none():
    """A stop's and a contact's noise measures (docs/noise.md) are what they dissipate and push per
    closing and per second; their derivatives (the force's integral and the work moved along the
    tangents, each closed span's ends riding their switches) equal Richardson differences of the
    orbits found nearby, each measure to 1e-7 of its own scale over the numbers; a measure with no
    derivative yet (a damper's energy) is refused saying so."""
    orbit = find_chain_orbit(impact_chain(), transient=150)
    measures, span = orbit_measures(orbit), orbit.period * orbit.chain.period
    for name in ("wall", "gap"):
        closings, lost = measures[f"closings:{name}"], measures[f"dissipated:{name}"]
        assert closings > 0 and lost > 0
        assert measures[f"impact_rate:{name}"] == closings / span
        assert measures[f"impact_energy:{name}"] * closings == pytest.approx(lost, rel=1e-15)
        assert measures[f"impact_power:{name}"] * span == pytest.approx(lost, rel=1e-15)
    params = ["wall.C", "gap.K", "floor.mu_k", "Omega"]
    found = orbit.sensitivities(params)
    kinds = ("work", "dissipated", "impact_energy", "impact_power", "impulse", "impulse_rate")
    rows = [f"{kind}:{name}" for name in ("wall", "gap") for kind in kinds]
    assert found.of("impact_rate:wall")["d/dwall.C"] == 0.0

    def seen(name: str, value: float) -> np.ndarray:
        moved = find_chain_orbit(orbit.chain.with_values({name: value}), orbit.state, transient=0, tol=1e-13)
        return np.array([orbit_measures(moved)[row] for row in rows])

    differences = []
    for name in params:
        value = orbit.chain.value(name)
        differences.append(richardson(functools.partial(seen, name), value, 1e-4 * max(1.0, abs(value))))
    exact = found.measures.loc[rows, [f"d/d{name}" for name in params]].to_numpy()
    error = np.abs(np.array(differences).T - exact).max(axis=1)
    assert (error <= 1e-7 * np.abs(exact).max(axis=1)).all(), dict(zip(rows, error, strict=True))
    assert np.abs(exact).min(axis=1).max() > 0  # every measure moves
    with pytest.raises(InputError, match="dissipated:damper-3 has no exact derivative yet"):
        found.of("dissipated:damper-3")


def test_the_largest_stick_slip_step_moves_as_its_closed_form_and_richardson_say():
    """``slip_step_max``'s derivative: slipping off the belt the step is ``(mu_s - mu_k) N / m``,
    so its derivative in ``mu_s`` is ``N / m`` (1e-9); where sticking steps more (the
    acceleration relative to the belt as the mass joins it), its derivatives in the belt's
    ``mu_s`` and speed and in ``Omega`` equal Richardson differences (1e-7), the switch's state
    and time moving."""
    from oscillator.orbits.chain_peaks import slip_steps

    slipping = find_chain_orbit(belt_chain(), transient=150)
    assert slipping.sensitivities(["belt.mu_s"]).of("slip_step_max:belt")["d/dbelt.mu_s"] == pytest.approx(
        1.0, rel=1e-9
    )
    chain = belt_chain()
    chain = chain.with_values({"belt.mu_s": 0.26})  # a small gap: the sticking step is the larger
    orbit = find_chain_orbit(chain, transient=150)
    steps = slip_steps(orbit.run)["belt"]
    assert max(steps) > 10 * min(steps)
    params = ["belt.mu_s", "belt.w", "Omega"]
    found = orbit.sensitivities(params).of("slip_step_max:belt").to_numpy(float)

    def seen(name: str, value: float) -> float:
        moved = find_chain_orbit(orbit.chain.with_values({name: value}), orbit.state, transient=0, tol=1e-13)
        return orbit_measures(moved)["slip_step_max:belt"]

    differences = [
        richardson(functools.partial(seen, n), chain.value(n), 1e-4 * max(1.0, abs(chain.value(n)))) for n in params
    ]
    assert np.abs(np.array(differences) - found).max() <= 1e-7 * np.abs(found).max()
    assert np.abs(found).min() > 0.1
