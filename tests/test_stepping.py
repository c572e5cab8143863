"""The trajectory at every step, taken in compiled code (engines/stepping.py): the same run, to
the bit, as CVODE returning to Python after each step (issue 27)."""

import numpy as np
import pandas as pd
import pytest

import oscillator.hybrid.supervisor as supervisor
from conftest import random_case
from oscillator import OscillatorError, Reason, simulate


@pytest.fixture
def per_step(monkeypatch):
    """simulate() with the stepping loop switched off: one return to Python per CVODE step."""
    original = supervisor.Supervisor.__init__

    def without_loop(self, *args, **options):
        original(self, *args, **options)
        self._stepper = self._grid = None

    def run(*args, **options):
        with monkeypatch.context() as patch:
            patch.setattr(supervisor.Supervisor, "__init__", without_loop)
            return simulate(*args, **options)

    return run


@pytest.mark.parametrize("case", ["instance-1", "instance-3", "instance-5", 7, 145, 200])
def test_the_loop_gives_the_same_run_as_a_return_per_step(case, per_step):
    case = random_case(case) if isinstance(case, int) else case
    looped, stepped = simulate(case, t_end=None), per_step(case)
    pd.testing.assert_frame_equal(looped.events, stepped.events, check_exact=True)
    pd.testing.assert_frame_equal(looped.trajectory, stepped.trajectory, check_exact=True)
    assert looped.final_state == stepped.final_state and looped.stats.returns == stepped.stats.returns
    assert looped.energy == stepped.energy


@pytest.mark.parametrize("case", ["instance-1", "instance-4", 7, 145])
def test_the_grid_loop_gives_the_same_run_as_a_return_per_grid_time(case, per_step):
    case = random_case(case) if isinstance(case, int) else case
    t0 = simulate(case, record_trajectory=False).case.initial.t0
    t_end = t0 + 40.0
    grid = np.append(np.linspace(t0, t_end - 1.0, 997), t_end)  # the end time on the grid, once
    looped, stepped = simulate(case, t_end=t_end, t_eval=grid), per_step(case, t_end=t_end, t_eval=grid)
    pd.testing.assert_frame_equal(looped.events, stepped.events, check_exact=True)
    pd.testing.assert_frame_equal(looped.trajectory, stepped.trajectory, check_exact=True)
    assert len(looped.trajectory) == len(grid)
    assert looped.final_state == stepped.final_state and looped.stats.returns == stepped.stats.returns


def test_a_failure_inside_the_loop_is_told_after_the_last_step_it_took(per_step):
    """CVODE fails within a batch: the steps before it are kept, and the failure names the last
    point reached, as when each step came back to Python."""
    errors = []
    for run in (simulate, per_step):
        with pytest.raises(OscillatorError) as caught:
            run("instance-3", max_num_steps=60)
        errors.append(caught.value)
    looped, stepped = errors
    assert str(looped) == str(stepped) and looped.reason is stepped.reason is Reason.STEP_LIMIT
    pd.testing.assert_frame_equal(looped.result.trajectory, stepped.result.trajectory, check_exact=True)


def test_max_trajectory_rows_trips_at_the_same_row(per_step):
    messages = []
    for run in (simulate, per_step):
        with pytest.raises(OscillatorError) as caught:
            run("instance-1", t_end=60.0, max_trajectory_rows=1000)
        messages.append(str(caught.value))
        assert len(caught.value.result.trajectory) == 1000
    assert messages[0] == messages[1]


def test_an_engine_of_the_user_s_without_size_or_loops_runs_a_return_at_a_time():
    """The Engine protocol of before (no ``size``, no compiled loops) still runs, the same run."""
    from oscillator.engines.sksundae import SksundaeEngine

    class Wrapped:
        name = "wrapped"

        def __init__(self, params, options):
            self._engine = SksundaeEngine(params, options)

        def reset(self, mode, t, y):
            self._engine.reset(mode, t, y)

        def advance(self, target, *, t_stop, one_step):
            return self._engine.advance(target, t_stop=t_stop, one_step=one_step)

        def close(self):
            self._engine.close()

        rhs_evaluations = property(lambda self: self._engine.rhs_evaluations)
        restarts = property(lambda self: self._engine.restarts)

    wrapped, direct = simulate("instance-3", engine=Wrapped), simulate("instance-3", engine="sksundae")
    pd.testing.assert_frame_equal(wrapped.events, direct.events, check_exact=True)
    pd.testing.assert_frame_equal(wrapped.trajectory, direct.trajectory, check_exact=True)
