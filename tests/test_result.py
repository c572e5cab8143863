"""Result tables: columns, the trajectory on CVODE's steps or on a grid, and failures."""

import numpy as np
import pandas as pd
import pytest

from oscillator import OscillatorError, Reason, Status, simulate

REQUIRED_EVENT_COLUMNS = ["t", "mass", "kind", "boundary", "from_domain", "to_domain", "theorem", "equation",
                          "branch", "x1", "v1", "x2", "v2"]  # fmt: skip


def test_event_columns_and_kinds():
    events = simulate("instance-5").events
    assert list(events.columns[:13]) == REQUIRED_EVENT_COLUMNS
    assert {"G0_alpha", "G1_alpha", "G0_beta", "G1_beta", "G_alpha", "G_beta", "distance"} <= set(events.columns)
    assert events.G_alpha.tolist()[:2] == ["F1^(0>0_1)", "F2^(0>0_1)"]


def test_trajectory_on_a_grid_matches_the_step_trajectory():
    grid = np.linspace(1.5, 4.0, 26)
    on_grid = simulate("instance-3", t_eval=grid).trajectory
    assert np.array_equal(on_grid.t.to_numpy(), grid)
    steps = simulate("instance-3").trajectory.drop_duplicates("t", keep="last")
    # CVODE's interpolant on the grid agrees with a cubic fit through its own steps
    for column in ("x1", "x2"):
        assert np.interp(grid, steps.t, steps[column]) == pytest.approx(on_grid[column].to_numpy(), abs=2e-3)
    # domains on the grid follow the events: left contact between 3.0214 and 3.7780
    inside = on_grid[(on_grid.t > 3.03) & (on_grid.t < 3.77)]
    assert set(inside.system_state) <= {"III-a"} and len(inside) > 0


def test_event_rows_appear_twice_in_the_step_trajectory():
    result = simulate("instance-1")
    trajectory = result.trajectory
    for t in result.events.t[result.events.t > 1.0]:
        rows = trajectory[trajectory.t == t]
        assert len(rows) == 2 and rows.domain1.nunique() + rows.domain2.nunique() == 3


def test_trajectory_can_be_left_out():
    result = simulate("instance-3", record_trajectory=False)
    assert result.trajectory.empty and list(result.trajectory.columns)[:5] == ["t", "x1", "v1", "x2", "v2"]
    assert len(result.events) == 8


def test_solver_failure_names_time_domains_and_fix():
    # too few steps allowed between two outputs: CVODE gives up
    with pytest.raises(
        OscillatorError, match=r"CVODE failed after t = 1.5 s .* in domains m1: \d, m2: \d.*max_num_steps"
    ):
        simulate("instance-3", max_num_steps=1, t_eval=[1.5, 4.0])


def test_event_count_guard_names_the_last_event():
    with pytest.raises(OscillatorError, match=r"more than max_events = 3 .* mass \d") as info:
        simulate("instance-3", max_events=3)
    # the partial record travels with the error; the instant that tripped it is kept whole
    assert info.value.result.events.kind.tolist()[-2:] == ["left_contact_onset"] * 2
    assert len(info.value.result.events) == 5
    # the reason, for a program: on the error and on its partial result
    assert info.value.reason is Reason.MAX_EVENTS and info.value.reason.guard
    assert info.value.result.reason is Reason.MAX_EVENTS and info.value.result.status is Status.FAILED


def test_a_long_rest_under_forcing_is_not_a_stall(build):
    """A forced mass below its static threshold rests for 200 periods; its force extremum fires
    twice a period without a switch, which is no stall."""
    case = build(200 * 2 * np.pi, initial=(0.0, 0.0, 0.0, 0.0, 0.0), Q1=1.0, Q2=1.0)
    result = simulate(case, record_trajectory=False)
    assert result.events.empty
    assert result.stats.root_returns >= 399


def test_progress_is_reported_with_increasing_times():
    """After every return of the engine: at each root, and at most every STEPS_PER_RETURN steps."""
    from oscillator.hybrid.supervisor import STEPS_PER_RETURN

    seen = []
    result = simulate("instance-3", progress=seen.append)
    assert seen == sorted(seen) and seen[-1] == 4.0
    assert result.stats.root_returns <= len(seen) <= result.stats.root_returns + result.stats.returns // 2
    assert len(seen) >= result.stats.returns / STEPS_PER_RETURN


def test_events_can_be_kept_from_a_time_on():
    full = simulate("instance-3", record_trajectory=False)
    late = simulate("instance-3", record_trajectory=False, keep_events_from=3.0)
    assert late.stats.events == full.stats.events == 8
    pd.testing.assert_frame_equal(late.events.reset_index(drop=True),
                                  full.events[full.events.t >= 3.0].reset_index(drop=True))  # fmt: skip


def test_the_tables_read_any_number_of_times_and_from_copies():
    """A frozen Result is immutable in use: its tables read twice, and read from a copy made by
    ``dataclasses.replace`` before or after the original's, are the same tables (reading them
    consumed the records before: the second read raised AssertionError)."""
    import dataclasses

    result = simulate("instance-3")
    early_copy = dataclasses.replace(result, message="a copy made before any table was read")
    events, trajectory = result.events, result.trajectory
    pd.testing.assert_frame_equal(result.events, events)
    pd.testing.assert_frame_equal(result.trajectory, trajectory)
    late_copy = dataclasses.replace(result, message="a copy made after")
    for copy in (early_copy, late_copy):
        pd.testing.assert_frame_equal(copy.events, events)
        pd.testing.assert_frame_equal(copy.trajectory, trajectory)
    assert len(events) == 8 and len(trajectory) > 100


def test_run_json_is_written_and_checked_by_one_table(tmp_path):
    """What run_info writes passes every check of RUN_JSON; each field damaged in turn is named."""
    from oscillator.report.runs import RUN_JSON, _check_run_info, run_info

    info = run_info(simulate("instance-3", record_trajectory=False))
    assert set(RUN_JSON) - {"versions", "check", "figures"} <= set(info)
    assert _check_run_info(dict(info), tmp_path / "run.json") == info
    for key in RUN_JSON:
        with pytest.raises(OscillatorError, match=rf"run.json is damaged.*\b{key}\b") as caught:
            _check_run_info({**info, key: [[1]]}, tmp_path / "run.json")
        assert caught.value.field is not None
