"""The engine layer: both integrators behind one interface give the same switching sequence."""

import numpy as np
import pytest

from conftest import random_case
from oscillator import InputError, Status, simulate
from oscillator.engines import ENGINES, EngineFailure, Step, StepKind, build_engine
from oscillator.engines.scipy import ScipyEngine
from oscillator.model.phase_space import Mode


def switching(result):
    events = result.events[result.events.kind != "grazing"]
    return list(zip(events.mass, events.kind, events.to_domain, strict=True)), events.t.to_numpy()


@pytest.mark.parametrize("case", ["instance-1", "instance-3", "instance-4", 145, 200])
def test_cvode_and_scipy_give_the_same_switches(case):
    case = random_case(case) if isinstance(case, int) else case
    ours = simulate(case, rtol=1e-12, atol=1e-12, record_trajectory=False)
    theirs = simulate(case, rtol=1e-12, atol=1e-12, record_trajectory=False, engine="scipy")
    (seq_a, t_a), (seq_b, t_b) = switching(ours), switching(theirs)
    assert seq_a == seq_b and len(seq_a) > 0
    assert np.max(np.abs(t_a - t_b)) < 1e-7
    assert ours.stats.engine == "cvode" and theirs.stats.engine == "scipy"
    python = simulate(case, rtol=1e-12, atol=1e-12, record_trajectory=False, engine="sksundae")
    assert switching(python)[0] == seq_a and np.array_equal(switching(python)[1], t_a)
    # the audit closes on both: the quadratures are integrated by either engine
    assert abs(theirs.energy.residual) < 1e-6 * (abs(theirs.energy.forcing) + theirs.energy.E0 + 1)


def test_the_engines_record_the_same_grid():
    grid = np.linspace(3.0, 10.0, 29)
    a = simulate("instance-2", t_end=10.0, t_eval=grid)
    b = simulate("instance-2", t_end=10.0, t_eval=grid, engine="scipy", rtol=1e-12, atol=1e-12)
    assert a.trajectory.t.tolist() == b.trajectory.t.tolist() == grid.tolist()
    assert np.allclose(a.trajectory[["x1", "x2"]], b.trajectory[["x1", "x2"]], atol=1e-6)


def test_an_engine_can_be_given_as_a_factory():
    built = []

    def factory(params, options):
        built.append(params.Omega)
        return ScipyEngine(params, options, method="RK45")

    result = simulate("instance-1", t_end=5.0, engine=factory, record_trajectory=False)
    assert built == [1.6] and result.success and result.status is Status.COMPLETE


def test_an_unknown_engine_is_refused_by_name():
    with pytest.raises(InputError, match="engine must be one of cvode, sksundae, dop853, scipy") as caught:
        simulate("instance-1", engine="rk4")
    assert caught.value.field == "engine"
    assert set(ENGINES) == {"cvode", "sksundae", "dop853", "scipy"}


@pytest.mark.parametrize("name", sorted(ENGINES))
def test_an_engine_steps_returns_roots_and_reaches_targets(name):
    from oscillator import load_case

    case = load_case("instance-1")
    engine = build_engine(name, case.parameters, case.options)
    mode = Mode(domain1=0, domain2=0, left=False, right=False)
    y = np.zeros(8)
    y[:4] = case.initial.y
    engine.reset(mode, case.initial.t0, y)
    step = engine.advance(1.05, t_stop=2.0, one_step=False)
    assert isinstance(step, Step) and step.kind is StepKind.TARGET and step.t == 1.05
    step = engine.advance(2.0, t_stop=2.0, one_step=False)
    # both masses rest at the start: the first root is m2's flow barrier (Thm 5.4), at 1.1746 s
    assert step.kind is StepKind.ROOT and step.t == pytest.approx(1.1745832575, abs=1e-8) and step.roots
    # CVODE was initialised once; solve_ivp is called once per stretch (to 1.05 s, then on)
    assert engine.restarts == (2 if name == "scipy" else 1) and engine.rhs_evaluations > 0
    engine.close()


def test_a_solver_failure_is_told_with_the_engine_flag():
    error = EngineFailure("too much work", -1)
    assert error.flag == -1 and str(error) == "too much work"
