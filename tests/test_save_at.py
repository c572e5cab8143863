"""What a run keeps, said once (SaveAt): the segments, the derivative of the flow carried through
every switch, and the refusals (issue 26)."""

import itertools

import numpy as np
import pytest

from conftest import random_case
from oscillator import InputError, SaveAt, resolve_case, simulate
from oscillator.model.events import COLUMN
from oscillator.orbits.shooting import find_orbit


def test_the_segments_tile_the_run_and_hold_every_event():
    result = simulate("instance-4", save=SaveAt(steps=False, segments=True))
    segments = result.segments
    case = result.case
    assert segments[0].t0 == case.initial.t0 and segments[-1].t1 == result.final_state[0] == case.t_end
    for before, after in itertools.pairwise(segments):
        assert after.t0 == before.t1 and after.mode != before.mode
        assert np.max(np.abs(after.y0 - before.y1)) < 1e-9  # the switch projects the state, by rounding
    rows = np.concatenate([s.rows for s in segments])
    assert len(rows) == len(result.events) == result.stats.events
    assert np.array_equal(rows[:, COLUMN["t"]], result.events.t.to_numpy())
    # each segment's mode is the one the switch at its start (its last event row) enters
    for before, after in itertools.pairwise(segments):
        last = before.rows[-1]
        mass = int(last[COLUMN["mass"]])
        assert int(last[COLUMN["to_domain"]]) == after.mode.domain(mass)
    assert result.trajectory.empty and result.derivative is None


def test_the_derivative_through_every_switch_is_the_end_state_s_derivative():
    """``Result.derivative`` against central differences of the end state (each start moved
    along one axis), over two forcing periods of a random system with switches on the way."""
    case = resolve_case(random_case(145), rtol=1e-12, atol=1e-12)
    t_end = case.initial.t0 + 2 * case.parameters.period
    result = simulate(case, t_end=t_end, save=SaveAt(steps=False, segments=True, derivative=True))
    assert len(result.segments) > 3
    y0 = np.array(case.initial.y)
    h = 1e-6
    columns = []
    for k in range(4):
        ends = []
        for sign in (1, -1):
            moved = dict(zip(("x1", "v1", "x2", "v2"), y0 + sign * h * np.eye(4)[k], strict=True))
            ends.append(np.array(simulate(case, t_end=t_end, record_trajectory=False, **moved).final_state[1:]))
        columns.append((ends[0] - ends[1]) / (2 * h))
    differences = np.column_stack(columns)
    assert np.max(np.abs(result.derivative - differences)) < 1e-4 * max(1.0, np.max(np.abs(differences)))


def test_an_orbit_s_monodromy_is_one_run_s_derivative():
    orbit = find_orbit("instance-1")
    again = simulate(orbit.one_period(), save=SaveAt(steps=False, derivative=True))
    assert np.max(np.abs(again.derivative - orbit.monodromy)) < 1e-9
    assert np.max(np.abs(np.array(again.final_state[1:]) - orbit.state)) < 1e-8


@pytest.mark.parametrize(
    ("call", "field"),
    [
        (lambda: simulate("instance-3", save=SaveAt(), t_eval=[1.0, 2.0]), "save"),
        (lambda: simulate("instance-3", save=SaveAt(), record_trajectory=False), "save"),
        (lambda: simulate("instance-3", save="steps"), "save"),
        (lambda: simulate("instance-3", save=SaveAt(segments="yes")), "segments"),
        (lambda: simulate("instance-3", save=SaveAt(ts=np.array([3.0, 2.0]))), "t_eval"),
        (lambda: simulate("instance-3", save=SaveAt(events_from=float("nan"))), "events_from"),
        (lambda: simulate("instance-3", engine="scipy", save=SaveAt(derivative=True)), "engine"),
    ],
)
def test_what_to_keep_is_refused_before_anything_runs(call, field):
    with pytest.raises(InputError) as refused:
        call()
    assert refused.value.field == field
