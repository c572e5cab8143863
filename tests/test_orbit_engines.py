"""Periodic orbits on the compiled path held to CVODE, the reference (issue 53).

The period maps run on the compiled DOP853 engine by default: its derivative of the flow is carried
by the same stages as the state (the derivative of its own steps), through every switch by the
supervisor's saltation matrices, as CVODE's is.  The two engines must give the same monodromy
matrices, orbits and multipliers to 1e-9 and the same bifurcations to 1e-8; the corrector's column
in the parameter is exact (carried through every switch), where a difference quotient would
straddle a bifurcation as soon as the branch comes within its step of one.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from conftest import random_case
from oscillator import InputError, find_orbit, resolve_case
from oscillator.orbits.continuation import continue_orbit
from oscillator.orbits.sensitivity import map_gradient
from oscillator.orbits.shooting import orbit_case, period_map
from oscillator.orbits.stroboscopic import ORBIT_ENGINE

CASES = [("instance-1", {"Omega": 1.6}), ("instance-1", {"Omega": 1.3}), ("instance-2", {}), ("instance-5", {})]


def _relative(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.max(np.abs(a - b)) / max(1.0, float(np.max(np.abs(a)))))


def test_the_compiled_engine_is_the_orbits_default():
    assert ORBIT_ENGINE == "dop853"
    image = period_map(orbit_case("instance-2", {}), 0.0, np.array([1.0, 0.0, 2.0, 0.0]))
    assert image.result.stats.engine == "dop853"


@pytest.mark.parametrize(("name", "overrides"), CASES)
def test_both_engines_find_the_same_orbit_and_monodromy(name, overrides):
    by = {engine: find_orbit(name, engine=engine, **overrides) for engine in ("dop853", "cvode")}
    compiled, reference = by["dop853"], by["cvode"]
    assert _relative(compiled.state, reference.state) <= 1e-9
    assert _relative(compiled.monodromy, reference.monodromy) <= 1e-9
    assert np.max(np.abs(compiled.multipliers - reference.multipliers)) <= 1e-9
    assert compiled.signature == reference.signature
    # one map from the same start on each engine: the same end and the same derivative
    case = compiled.case
    ends = [period_map(case, compiled.section, compiled.state, engine=e) for e in ("dop853", "cvode")]
    assert _relative(ends[0].end, ends[1].end) <= 1e-9
    assert _relative(ends[0].monodromy, ends[1].monodromy) <= 1e-9


@pytest.mark.parametrize("seed", [3, 11])
def test_the_compiled_monodromy_is_the_derivative_of_the_compiled_map(seed):
    case = orbit_case(random_case(seed), {})
    y0 = np.array(case.initial.y[:4])
    image = period_map(case, case.initial.t0, y0)
    columns = []
    for j in range(4):
        h = 1e-6 * max(1.0, abs(y0[j]))
        step = np.zeros(4)
        step[j] = h
        plus = period_map(case, case.initial.t0, y0 + step, derivative=False).end
        minus = period_map(case, case.initial.t0, y0 - step, derivative=False).end
        columns.append((plus - minus) / (2 * h))
    assert image.monodromy is not None
    assert _relative(image.monodromy, np.column_stack(columns)) <= 1e-5


def test_both_engines_trace_the_same_branch_and_bifurcations():
    """The Omega branch of Instance 1 across sliding onset, a grazing and two sliding-vanish
    points 1e-5 apart: the same points and bifurcations on either engine."""
    branches = {
        engine: continue_orbit("instance-1", param="Omega", start=1.59, stop=1.62, engine=engine)
        for engine in ("dop853", "cvode")
    }
    compiled, reference = branches["dop853"], branches["cvode"]
    assert len(compiled.points) == len(reference.points)
    kinds = compiled.bifurcations["kind"].tolist()
    assert kinds == reference.bifurcations["kind"].tolist()
    assert kinds[:2] == ["sliding_onset", "grazing"] and kinds.count("sliding_vanish") >= 2
    located = compiled.bifurcations["Omega"].to_numpy() - reference.bifurcations["Omega"].to_numpy()
    assert np.max(np.abs(located)) <= 1e-8


def test_the_corrector_s_column_is_exact_where_a_difference_would_straddle_a_bifurcation():
    """1.6096889 lies 1e-6 below where a sticking phase of m2 vanishes (1.60969): a central
    difference of step 1e-6 reaches across it and is wrong by orders of magnitude; the column
    carried through the switches is the one-sided limit, as a small one-sided difference says."""
    omega = 1.6096889300646497
    case = orbit_case("instance-1", {"Omega": omega})
    orbit = find_orbit(case, guess=[3.6237, 3.9163, 4.7791, 2.1259], transient=0)
    image = period_map(case, orbit.section, orbit.state)
    p = case.parameters
    exact = map_gradient(image.segments, p, ("Omega",), image.t1, np.array([-p.period / p.Omega]))[:, 0]

    def end(value: float) -> np.ndarray:
        return period_map(resolve_case(case, Omega=value), orbit.section, orbit.state, derivative=False).end

    h = 1e-6 * omega
    straddling = (end(omega + h) - end(omega - h)) / (2 * h)
    assert np.max(np.abs(straddling - exact)) > 1.0
    small = 1e-9
    one_sided = (end(omega) - end(omega - small)) / small
    assert _relative(exact, one_sided) <= 1e-4


@pytest.mark.parametrize("params", [("Omega",), ("Q2", "mu_k", "d")])
def test_the_map_s_parameter_derivative_matches_richardson_differences(params):
    case = orbit_case("instance-1", {"Omega": 1.45})
    orbit = find_orbit(case)
    p = case.parameters
    image = period_map(case, orbit.section, orbit.state)
    dt_end = np.array([-p.period / p.Omega if name == "Omega" else 0.0 for name in params])
    exact = map_gradient(image.segments, p, params, image.t1, dt_end)
    for j, name in enumerate(params):
        value = getattr(p, name)

        def end(step: float, name: str = name, value: float = value) -> np.ndarray:
            moved = resolve_case(case, **{name: value + step})
            return period_map(moved, orbit.section, orbit.state, derivative=False).end

        h = 1e-4 * abs(value)
        coarse = (end(h) - end(-h)) / (2 * h)
        fine = (end(h / 2) - end(-h / 2)) / h
        richardson = (4 * fine - coarse) / 3
        assert _relative(exact[:, j], richardson) <= 1e-7


def test_an_engine_that_cannot_carry_the_derivative_is_refused_by_name():
    with pytest.raises(InputError, match="engine must be one of dop853, cvode") as refused:
        find_orbit("instance-1", engine="scipy")
    assert refused.value.field == "engine"
    with pytest.raises(InputError, match="engine"):
        continue_orbit("instance-1", param="Omega", start=1.6, stop=1.7, engine="sksundae")


def test_the_compiled_saltation_is_the_formula_at_every_switch_between_modes():
    """``carried_through`` (compiled, the supervisor's every switch) against ``R(after) S Phi`` from
    the Python saltation matrices, on every pair of modes a sequence of crossings joins."""
    import itertools

    from oscillator.model.phase_space import Mode
    from oscillator.model.saltation import carried_through, elementary_switches, rest_projection, saltation_matrix

    p = resolve_case("instance-1").parameters
    rng = np.random.default_rng(5)
    modes = set()
    for s1, s2, left, right in itertools.product((-1, 0, 1), (-1, 0, 1), (False, True), (False, True)):
        try:
            modes.add(Mode.from_signs(s1, s2, left=left, right=right))
        except ValueError:
            continue
    compared = 0
    for before, after in itertools.product(sorted(modes, key=str), repeat=2):
        try:
            elementary_switches(before, after)
        except ValueError:
            continue
        t, y, phi = rng.uniform(0, 10), 3 * rng.normal(size=4), rng.normal(size=(4, 4))
        expected = rest_projection(after) @ saltation_matrix(t, y, y, p, before, after) @ phi
        assert _relative(carried_through(phi, t, y, y, p, before, after), expected) <= 1e-14
        compared += 1
    assert compared > 1000


def _over(case, periods: int):
    """``case`` run over ``periods`` forcing periods from its start."""
    return dataclasses.replace(case, t_end=case.initial.t0 + periods * case.parameters.period)


def _maps() -> list:
    cases = [orbit_case(name, overrides) for name, overrides in CASES]
    return cases + [orbit_case(random_case(seed), {}) for seed in range(0, 12, 2)]


@pytest.mark.parametrize("derivative", [True, False])
def test_the_compiled_period_map_is_the_supervisor_s_run_to_the_bit(derivative):
    """A period map runs in one compiled call (``compiled_run``): its segments, event rows, end
    and derivative are those of ``simulate(..., engine="dop853")`` exactly, over one and three
    periods, on the instances and on random systems that pass stops, rests and releases."""
    from oscillator.hybrid.recording import SaveAt
    from oscillator.hybrid.simulate import simulate
    from oscillator.orbits.stroboscopic import compiled_run

    switches = 0
    for case in _maps():
        for periods in (1, 3):
            run = _over(case, periods)
            compiled = compiled_run(run, np.array(case.initial.y[:4]), derivative, periods)
            supervised = simulate(run, save=SaveAt(steps=False, segments=True, derivative=derivative), engine="dop853")
            assert compiled is not None
            assert compiled.final_state == supervised.final_state
            assert (compiled.derivative is None) == (not derivative)
            if derivative:
                assert np.array_equal(compiled.derivative, supervised.derivative)
            assert [(s.mode, s.t0, s.t1) for s in compiled.segments] == [
                (s.mode, s.t0, s.t1) for s in supervised.segments
            ]
            for ours, theirs in zip(compiled.segments, supervised.segments, strict=True):
                assert np.array_equal(ours.y0, theirs.y0) and np.array_equal(ours.y1, theirs.y1)
                assert np.array_equal(ours.rows, theirs.rows, equal_nan=True)
            assert compiled.events.equals(supervised.events)
            assert compiled.energy == supervised.energy
            switches += len(compiled.segments) - 1
    assert switches > 100


def test_a_map_the_compiled_run_cannot_finish_is_the_supervisor_s_failure_with_its_words():
    """A guard that stops the run (here at most 3 events) makes the compiled call give up; the map
    is then run by the supervisor, whose refusal names what happened."""
    from oscillator import SimulationFailed
    from oscillator.orbits.stroboscopic import compiled_run

    case = orbit_case("instance-1", {"Omega": 1.6, "max_events": 3})
    run = _over(case, 5)
    assert compiled_run(run, np.array(case.initial.y[:4]), True, 5) is None
    with pytest.raises(SimulationFailed, match="events") as failed:
        period_map(case, case.initial.t0, np.array(case.initial.y[:4]), 5)
    with pytest.raises(SimulationFailed) as reference:
        period_map(case, case.initial.t0, np.array(case.initial.y[:4]), 5, engine="cvode")
    assert failed.value.reason == reference.value.reason


@pytest.mark.parametrize("omega", [1.3, 1.6, 1.85])
def test_both_engines_give_an_orbit_the_same_response_measures(omega):
    """What the frequency response reads off each branch point (``measured`` on the map's run):
    every measure of the same orbit on either engine to 1e-9 (1e-11 measured)."""
    from oscillator.orbits.response import measured

    case = orbit_case("instance-1", {"Omega": omega})
    measures = {}
    for engine in ("dop853", "cvode"):
        orbit = find_orbit(case, engine=engine, tol=1e-11)
        measures[engine] = measured(period_map(case, orbit.section, orbit.state, engine=engine).result, 1).columns()
    assert measures["dop853"].keys() == measures["cvode"].keys()
    compared = 0
    for name, value in measures["cvode"].items():
        if np.isfinite(value):
            assert abs(measures["dop853"][name] - value) <= 1e-9 * max(1.0, abs(value)), name
            compared += 1
    assert compared >= 20
