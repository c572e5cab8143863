"""The explorer of a friction chain (issue 51: "the explorer's scene works for any system"): what it
shows is what ``simulate_chain`` gives; a control for every number of the chain by its name; a
change on the page is the chain ``with_values`` gives; refusals name the field; the case file it
offers reads back; ``oscillator explore FILE`` serves it.  The browser's view: test_explore_browser.py."""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

from oscillator.exploring import explore
from oscillator.exploring.app import css_class
from oscillator.exploring.controls import chain_controls
from oscillator.exploring.scene import chain_scene_of
from oscillator.exploring.subjects import ChainSubject, subject_of
from oscillator.hybrid.chain_run import simulate_chain
from oscillator.io.chains import chain_from_dict, load_system
from oscillator.model.chains import FrictionChain

ROOT = Path(__file__).resolve().parents[1]
SYSTEMS = ROOT / "docs" / "systems"


def conveyor() -> FrictionChain:
    """A trough on a spring between two walls, a part on it by friction: stops on both sides,
    contacts closing and opening, the part sticking and slipping (docs/systems/conveyor.toml)."""
    return load_system(SYSTEMS / "conveyor.toml")


def test_a_chain_scene_is_the_motion_simulate_chain_gives_with_its_strobe_points_and_intervals():
    chain = conveyor()
    scene = chain_scene_of(chain, 8)
    marks = chain.t0 + chain.period * np.arange(9)
    direct = simulate_chain(chain, float(marks[-1]), at=marks)
    assert len(scene.events) == len(direct.events) > 20 and scene.events.equals(direct.events)
    # the strobe points are the state at t0 + kT exactly: the trajectory holds those times
    assert scene.strobe.t.tolist() == marks.tolist() and scene.strobe.k.tolist() == list(range(9))
    for _, row in scene.strobe.iterrows():
        at = scene.trajectory[scene.trajectory.t == row.t]
        assert len(at) >= 1 and np.allclose(at.iloc[0, 1:], row.iloc[2:], rtol=0, atol=0)
    # each contact interval opens at a stop's closing event and ends at its opening (or the end)
    for name, intervals in scene.contacts.items():
        mine = direct.events[direct.events.element == name]
        closes = mine[mine.kind.str.endswith("_closes")].t.to_numpy()
        opens = mine[mine.kind.str.endswith("_opens")].t.to_numpy()
        assert len(intervals) == len(closes) > 0, name
        assert np.allclose([a for a, _ in intervals], closes, atol=1e-7)
        assert np.allclose([b for _, b in intervals if b < scene.t_end], opens, atol=1e-7)
    # the part's rests: it sticks where the events say, and leaves where they say
    part = direct.events[direct.events.element == "part on the floor"]
    sticks, slips = part[part.mode_after == 0].t.tolist(), part[part.mode_before == 0].t.tolist()
    assert slips[0] < sticks[0]  # at rest from the start
    assert scene.rests["part"] == [pytest.approx(pair) for pair in zip([0.0, *sticks], slips, strict=False)]
    assert scene.rests["trough"] == []  # no friction element: it never rests
    assert scene.status == "complete" and scene.engine == "cvode" and not scene.bounded


def test_the_section_times_change_no_event_beyond_the_solver_tolerance():
    """CVODE stopping at each t0 + kT (for the strobe points) changes its steps, not the motion: the
    friction damper's events with and without the stops agree to 1e-7 s (the rattling conveyor's
    part drifts apart in time, as a chaotic motion does: its scene is compared with the same run)."""
    chain = load_system(SYSTEMS / "blade-damper.toml")
    scene, direct = chain_scene_of(chain, 20), simulate_chain(chain, chain.t0 + 20 * chain.period)
    assert len(scene.events) == len(direct.events) > 50
    assert np.allclose(scene.events.t, direct.events.t, rtol=0, atol=1e-7)
    assert scene.events[["element", "kind", "mode_after"]].equals(direct.events[["element", "kind", "mode_after"]])


def test_every_number_of_a_chain_has_a_control_named_as_set_names_it():
    chain = load_system(SYSTEMS / "blade-damper.toml")
    controls = chain_controls(chain)
    names = [c.name for c in controls]
    assert names == [n for n in chain.parameter_names() if n != "t0"]
    units = {c.name: c.unit for c in controls}
    assert (units["Omega"], units["blade.m"], units["platform.F"], units["platform.kt"]) == ("rad/s", "kg", "N", "N/m")
    for control in controls:
        assert control.start <= control.value <= control.end and control.step > 0, control
        if control.name.endswith((".m", ".kt")) or control.name in ("Omega", "g"):
            assert control.start > 0, control
        for end in (control.start, control.end):  # the arrow keys come back to the file's value
            steps = (control.value - end) / control.step
            assert abs(steps - round(steps)) < 1e-6, (control, steps)
    assert css_class("blade damping.c") == "control-blade-damping-c" and css_class("K3") == "control-K3"


def test_a_change_on_the_page_is_the_chain_with_values_gives_and_a_refusal_names_the_field(tmp_path):
    explorer = explore(str(SYSTEMS / "blade-damper.toml"), periods=10)
    assert isinstance(explorer.subject, ChainSubject) and explorer.engine == "cvode"
    assert explorer.scene is not None and "10 periods" in explorer.status.object
    explorer.set_box.value = "platform.F=0.45"
    chain = load_system(SYSTEMS / "blade-damper.toml").with_values({"platform.F": 0.45})
    expected = chain_scene_of(chain, 10)
    assert explorer.values()["platform.F"] == 0.45 and explorer.scene.case == chain
    assert explorer.scene.events.t.tolist() == expected.events.t.tolist()
    assert "platform.F 0.3 → 0.45" in explorer.heading.object
    explorer.set_box.value = "platform.F=-1"
    assert "oscillator-error" in explorer.status.object and "F must not be negative" in explorer.status.object
    assert explorer.values()["platform.F"] == 0.45  # not put on the slider; the last motion stays
    explorer.set_box.value = "platfrom.F=1"
    assert "platform.F" in explorer.status.object  # the closest name said
    # the case file offered reads back as the chain on screen
    data = tomllib.loads(explorer._case_file().getvalue())
    assert chain_from_dict(data) == chain
    # the downloads: the events and the trajectory by the chain's names
    assert explorer._events_file().getvalue().startswith("t,element,type,mass,with")
    assert explorer._trajectory_file().getvalue().startswith("t,x:blade,v:blade,x:damper,v:damper,z:platform")


def test_a_system_file_with_overrides_and_a_chain_value_are_explored_alike():
    chain = load_system(SYSTEMS / "belt-chain.toml")
    by_path = subject_of(str(SYSTEMS / "belt-chain.toml"), **{"m2.m": 1.5})
    by_value = subject_of(chain.with_values({"m2.m": 1.5}))
    assert by_path.system == by_value.system and by_path.name == "belt-chain"
    scene = by_path.scene(by_path.system, 5, engine="dop853")
    assert scene.engine == "cvode" and [m[1] for m in scene.outline.masses] == ["m1", "m2", "m3"]
    assert set(scene.rests) == {"m1", "m2", "m3"}


def test_a_chain_run_the_explorer_bounds_is_drawn_up_to_there_and_said(monkeypatch):
    """A run that passes the explorer's event bound (lowered here to 40: the conveyor makes about 190
    events in 8 periods) is shown up to there, with the bound said."""
    from oscillator.exploring import scene as scenes

    monkeypatch.setattr(scenes, "MAX_EVENTS", 40)
    bounded = chain_scene_of(conveyor(), 8)
    assert bounded.bounded and bounded.status.startswith("stopped after 40 events")
    assert 40 <= len(bounded.events) <= 42 and bounded.trajectory.t.iloc[-1] < bounded.t_end


@pytest.mark.parametrize("periods", [0, 10_001, 2.5])
def test_periods_out_of_range_are_refused(periods):
    from oscillator.errors import InputError

    with pytest.raises(InputError, match="periods"):
        chain_scene_of(conveyor(), periods)


def test_a_stopping_server_ends_every_pages_job_before_the_interpreter_does():
    """``close_all`` (called as the server stops): a job running in a page's thread is told to stop
    and its thread has ended when it returns, so that no job is left in compiled code while the
    interpreter shuts down (a Ctrl-C during a page's check once ended the explorer with SIGSEGV)."""
    import threading
    import time

    from oscillator.exploring.runner import Job, Runner, close_all

    started = threading.Event()

    def work(stopped):
        started.set()
        while not stopped():
            time.sleep(0.01)
        return "stopped"

    delivered = []
    runner = Runner(lambda job, result, error: delivered.append(result), on_loop=lambda call: call(), quiet=0.0)
    runner.ask(Job(work, 1), change=False)
    assert started.wait(10)
    thread = runner._thread
    assert thread is not None and thread.is_alive()
    close_all(timeout=10)
    assert not thread.is_alive() and runner.latest == 0
