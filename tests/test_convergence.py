"""Event times converge as tolerances tighten; the energy audit closes."""

import numpy as np
import pytest

from oscillator import simulate

INSTANCES = [f"instance-{i}" for i in range(1, 6)]


@pytest.mark.parametrize("name", INSTANCES)
def test_default_tolerances_are_within_1e_8_s_of_a_1e_13_run(name):
    default = simulate(name, record_trajectory=False)
    tight = simulate(name, rtol=1e-13, atol=1e-13, record_trajectory=False)
    assert list(default.events.kind) == list(tight.events.kind)
    assert np.max(np.abs(default.events.t.to_numpy() - tight.events.t.to_numpy())) < 1e-8


def test_event_time_error_shrinks_with_the_tolerance():
    reference = simulate("instance-3", rtol=1e-13, atol=1e-13, record_trajectory=False).events.t.to_numpy()
    errors = []
    for tol in (1e-5, 1e-7, 1e-9):
        times = simulate("instance-3", rtol=tol, atol=tol, record_trajectory=False).events.t.to_numpy()
        errors.append(np.max(np.abs(times - reference)))
    assert errors[0] > errors[1] > errors[2]
    assert errors[2] < 1e-6


@pytest.mark.parametrize("name", INSTANCES)
def test_work_energy_audit_closes(name):
    """E(t1) - E(t0) = forcing + feedback work - damper and friction losses."""
    energy = simulate(name, record_trajectory=False).energy
    scale = abs(energy.forcing) + abs(energy.damping) + abs(energy.friction) + energy.E0
    assert abs(energy.residual) < 1e-8 * scale
    assert energy.damping >= 0 and energy.friction >= 0


def test_energy_audit_detects_a_wrong_friction_law():
    """The audit can fail: bookkeeping friction with the wrong coefficient leaves a residual."""
    result = simulate("instance-3", record_trajectory=False)
    e = result.energy
    wrong = e.E1 - e.E0 - (e.forcing + e.feedback - e.damping - 1.05 * e.friction)
    assert abs(wrong) > 1e3 * abs(e.residual)
