"""Hardening: solver failures, the event-storm guard, kills at any moment, and fuzzed input.

Every failure must be one clear message (the library's own error type), keep the partial result
marked incomplete, and never leave a half-written file.
"""

import json
import math
import os
import re
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from typer.testing import CliRunner

from conftest import CHATTER, assert_same_tables, chatter_case, start_reaching, start_running
from oscillator import OscillatorError, Parameters, Reason, SolverOptions, Status, load_case, simulate
from oscillator.analysis.sweeps import read_sweep
from oscillator.cli.app import app
from oscillator.io.cases import case_to_toml
from oscillator.io.signals import interrupts_heard
from oscillator.process import in_fragile_code
from oscillator.report.runs import read_events_csv, read_run_folder

runner = CliRunner()
#: Only against a hang: a loaded machine may take many times the usual seconds.
TIMEOUT = 300


def invoke(*args):
    return runner.invoke(app, [str(a) for a in args])


# ----------------------------------------------------------------------------- solver failures


def test_too_many_steps_stops_with_time_domains_state_and_keeps_the_partial_result():
    full = simulate("instance-3", record_trajectory=False)
    with pytest.raises(OscillatorError) as caught:
        simulate("instance-3", record_trajectory=False, max_num_steps=60)
    error = caught.value
    message = str(error)
    first = full.events.iloc[0]  # m1 crosses its velocity boundary at 1.5621 s, into domain 2
    assert f"CVODE failed after t = {first.t:.10g} s with flag -1" in message
    assert "max_num_steps" in message and "m1: 2, m2: 1" in message and "x1=" in message
    assert error.reason is Reason.SOLVER_FAILURE and not error.reason.guard
    partial = error.result
    assert partial.status is Status.FAILED and not partial.success and partial.message == message
    assert partial.final_state[0] == first.t
    # the partial result is the full run's beginning, to the last digit
    assert len(partial.events) == partial.stats.events == 1
    np.testing.assert_array_equal(partial.events.t, full.events.t.iloc[:1])
    np.testing.assert_array_equal(partial.final_state[1:], first[["x1", "v1", "x2", "v2"]].to_numpy(float))


def test_absurd_tolerances_collapse_the_step_and_say_so():
    case = load_case("instance-3")
    with pytest.raises(OscillatorError) as caught:
        simulate(case, rtol=1e-15, atol=1e-300)
    message = str(caught.value)
    assert "flag -4" in message and "min step size" in message and "loosen rtol/atol" in message
    assert f"after t = {case.initial.t0:g} s" in message
    partial = caught.value.result
    assert partial.status is Status.FAILED and partial.final_state == (case.initial.t0, *case.initial.y)
    assert partial.events.empty


def test_a_refused_input_carries_no_partial_result():
    with pytest.raises(OscillatorError) as caught:
        simulate("instance-3", Omega=-1.0)
    assert caught.value.field == "Omega" and not hasattr(caught.value, "result")


# ----------------------------------------------------------------------------- event storms


def test_a_chattering_case_stops_with_the_boundary_and_the_time():
    started = time.perf_counter()
    with pytest.raises(OscillatorError) as caught:
        simulate(chatter_case(), record_trajectory=False)
    assert time.perf_counter() - started < 60  # it would otherwise run for 3.2e7 events
    error = caught.value
    assert error.field == "storm_events" and error.reason is Reason.STORM
    message = str(error)
    assert message.startswith("event storm: 1001 events within")
    assert "1000 of them mass 2 passable on ∂Ω12(2)" in message and "raise storm_events" in message
    events = error.result.events
    assert len(events) == 1001 and events.kind.iloc[0] == "sliding_vanish"
    assert f"t = {events.t.iloc[-1]:.10g} s" in message
    # two sign changes of v2 per forcing period: the 1000 crossings span 500 periods
    period = 2 * math.pi / CHATTER["Omega"]
    span = events.t.iloc[-1] - events.t.iloc[1]
    assert span == pytest.approx(499.5 * period, rel=2e-3)
    assert span < SolverOptions().storm_window


def test_the_storm_guard_is_configurable():
    period = 2 * math.pi / CHATTER["Omega"]
    tolerated = simulate(chatter_case(t_end=300 * period, storm_events=10**6), record_trajectory=False)
    assert tolerated.success and tolerated.stats.events == pytest.approx(601, abs=2)
    with pytest.raises(OscillatorError, match="event storm: 51 events") as caught:
        simulate(chatter_case(storm_events=50), record_trajectory=False)
    assert len(caught.value.result.events) == 51
    # a window shorter than the time between two crossings never holds 51 of them
    quiet = simulate(chatter_case(t_end=300 * period, storm_events=50, storm_window=0.1 * period))
    assert quiet.success


@pytest.mark.parametrize(
    ("name", "value", "fragment"),
    [
        ("storm_events", 0, "whole number from 1 to 10^12"),
        ("storm_events", 2**63, "whole number from 1 to 10^12"),
        ("storm_window", -1.0, "must be > 0"),
        ("storm_window", math.inf, "finite"),
    ],
)
def test_storm_settings_are_checked(name, value, fragment):
    with pytest.raises(OscillatorError, match=re.escape(fragment)) as caught:
        SolverOptions(**{name: value})
    assert caught.value.field == name


def test_a_run_of_absurd_length_is_refused_before_it_starts():
    with pytest.raises(OscillatorError, match=r"is 1.43e\+49 forcing periods, more than max_periods") as caught:
        simulate("instance-1", Omega=1e50)
    assert caught.value.field == "max_periods" and not hasattr(caught.value, "result")
    assert simulate("instance-1", t_end=1.0 + 5 * 2 * math.pi / 1.6, max_periods=5, record_trajectory=False).success


def test_a_trajectory_too_long_to_hold_stops_with_the_rows_so_far():
    full = simulate("instance-3")
    with pytest.raises(OscillatorError, match="passed max_trajectory_rows = 100 rows") as caught:
        simulate("instance-3", max_trajectory_rows=100)
    partial = caught.value.result
    assert caught.value.field == "max_trajectory_rows" and len(partial.trajectory) == 100
    np.testing.assert_array_equal(partial.trajectory.t, full.trajectory.t.iloc[:100])


# ----------------------------------------------------------------------------- the command line


def test_a_failed_run_writes_its_partial_result_marked_failed(tmp_path):
    case_file = tmp_path / "chatter.toml"
    case_file.write_text(case_to_toml(chatter_case()), encoding="utf-8")
    folder = tmp_path / "run"
    result = invoke("run", case_file, "--no-plots", "--out", folder)
    assert result.exit_code == 1, result.stderr
    assert result.stderr.strip().startswith("error: event storm") and "Traceback" not in result.stderr
    assert f"is in {folder}" in result.stderr and '"status": "failed"' in result.stderr
    info = json.loads((folder / "run.json").read_text(encoding="utf-8"))
    assert info["complete"] is False and info["status"] == "failed"
    assert info["failure"].startswith("event storm: 1001 events")
    events = read_events_csv(folder / "events.csv")
    assert len(events) == 1001 and info["t_final"] == events.t.iloc[-1]
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]
    rebuilt = invoke("report", folder)
    assert rebuilt.exit_code == 0, rebuilt.stderr
    assert "**Incomplete run (failed)" in (folder / "report.md").read_text(encoding="utf-8")
    assert read_run_folder(folder).run["status"] == "failed"


def test_a_complete_run_says_so(tmp_path):
    folder = tmp_path / "run"
    assert invoke("run", "instance-1", "--no-plots", "--no-report", "--quiet", "--out", folder).exit_code == 0
    info = json.loads((folder / "run.json").read_text(encoding="utf-8"))
    assert info["complete"] is True and info["status"] == "complete" and info["failure"] is None


def _start(command: list[str]) -> subprocess.Popen:
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    return subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)


LONG_RUN = ["run", "instance-1", "--t-end", "40000", "--no-plots", "--quiet"]


#: A Ctrl-C that lands in a finalizer (numba frees its LLVM objects at any time): Python would print
#: it as an ignored exception with a traceback and go on; the command's handler sends it again
#: until it lands in the command's own code.
FINALIZER = """
import os, signal, time
from oscillator.process import interrupts_where_safe
interrupts_where_safe()
class Freed:
    def __del__(self):
        signal.raise_signal(signal.SIGINT)
        print("freed")
try:
    Freed()
    time.sleep(60)  # ended by the interrupt at once; 60 s only if it never comes
    print("not interrupted")
except KeyboardInterrupt:
    print("interrupted")
"""


def test_a_ctrl_c_in_a_finalizer_reaches_the_command_without_a_traceback():
    done = subprocess.run([sys.executable, "-c", FINALIZER], capture_output=True, text=True, timeout=TIMEOUT)
    assert done.stdout.split() == ["freed", "interrupted"] and done.stderr == "", (done.stdout, done.stderr)


def _frame_of(module: str, function: str = "here"):
    """A frame of a function ``function`` defined in a module named ``module``."""
    namespace = {"__name__": module, "sys": sys}
    exec(f"def {function}():\n    return sys._getframe()", namespace)
    return namespace[function]()


def test_fragile_code_is_numbas_llvmlites_and_finalizers():
    assert in_fragile_code(_frame_of("llvmlite.binding.ffi")) and in_fragile_code(_frame_of("numba.core.caching"))
    assert in_fragile_code(_frame_of("oscillator.anything", "__del__"))
    assert not in_fragile_code(_frame_of("oscillator.hybrid.supervisor")) and not in_fragile_code(_frame_of("numbers"))
    assert not in_fragile_code(sys._getframe()) and not in_fragile_code(None)


def test_an_interrupt_heard_in_a_finalizer_is_remembered_not_raised_there():
    raised_in_finalizer = []

    class Freed:
        def __del__(self):
            try:
                signal.raise_signal(signal.SIGINT)
                sum(range(10))  # the handler runs here, inside the finalizer
            except KeyboardInterrupt:
                raised_in_finalizer.append(True)

    with interrupts_heard() as heard:
        Freed()
        assert heard() and not raised_in_finalizer
    with pytest.raises(KeyboardInterrupt), interrupts_heard() as heard:
        signal.raise_signal(signal.SIGINT)  # in this test's own code: raised at once
    assert heard()


@pytest.mark.slow
def test_sigint_keeps_the_run_so_far_marked_interrupted(tmp_path):
    folder = tmp_path / "interrupted"
    process = start_running([*LONG_RUN, "--out", folder])
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=TIMEOUT)
    assert process.returncode == 130, stderr
    assert stderr.startswith("error: interrupted; the partial result up to t = ") and "Traceback" not in stderr
    run = read_run_folder(folder)
    assert run.run["status"] == "interrupted" and run.run["failure"] == "interrupted by the user"
    t_final = run.run["t_final"]
    assert 1.0 < t_final < 40000 and run.trajectory.t.iloc[-1] == t_final
    # what was kept is the true beginning of the run (an event at t_final itself is past the rerun's end)
    # (to the event-time accuracy: another end time gives CVODE other steps)
    again = simulate("instance-1", t_end=t_final, record_trajectory=False).events.t
    kept = run.events.t[run.events.t < t_final - 1e-9]
    np.testing.assert_allclose(kept, again[again < t_final - 1e-9], rtol=0, atol=1e-8)


@pytest.mark.slow
def test_sigkill_leaves_no_folder_and_nothing_that_looks_complete(tmp_path):
    folder = tmp_path / "killed"
    process = start_running([*LONG_RUN, "--out", folder])
    process.kill()
    process.communicate(timeout=TIMEOUT)
    assert not folder.exists()
    assert not [p for p in tmp_path.iterdir() if not p.name.startswith(".")]


KILLED_WHILE_WRITING = textwrap.dedent(
    """
    import sys, time
    from pathlib import Path
    from oscillator import simulate
    from oscillator.report import runs as output
    from oscillator.io import cases

    result = simulate("instance-3")
    claim = output.claim_output(Path(sys.argv[1]), "instance-3")
    to_toml = cases.case_to_toml

    def slow(case):  # the tables are written by now, case.toml and run.json not yet
        print("writing", flush=True)
        time.sleep(60)
        return to_toml(case)

    output.case_to_toml = slow
    output.write_run(result, claim)
    """
)

REPLACED_WHILE_WRITING = textwrap.dedent(
    """
    import sys, time
    from pathlib import Path
    from oscillator.io.files import atomic_path

    with atomic_path(Path(sys.argv[1]) / "table.txt") as tmp:
        tmp.write_text("new, half")
        print("writing", flush=True)
        time.sleep(60)
    """
)


@pytest.mark.parametrize("script", [KILLED_WHILE_WRITING, REPLACED_WHILE_WRITING], ids=["new", "replace"])
def test_sigkill_while_writing_leaves_the_previous_state(tmp_path, script):
    target = tmp_path / "out"
    if script is REPLACED_WHILE_WRITING:  # a table, sweep.json or figure being rewritten
        target.mkdir()
        (target / "table.txt").write_text("old")
    process = _start([sys.executable, "-c", script, str(target)])
    assert process.stdout.readline().strip() == "writing", process.stderr.read()
    process.kill()
    process.communicate(timeout=TIMEOUT)
    if script is REPLACED_WHILE_WRITING:
        assert (target / "table.txt").read_text() == "old"
        assert [p.name for p in target.iterdir() if not p.name.startswith(".")] == ["table.txt"]
    else:
        assert not target.exists()


def test_a_sweep_interrupted_with_sigint_resumes_to_the_same_tables(tmp_path):
    arguments = ["--param", "Omega", "--from", "1.5", "--to", "1.7", "--steps", "8", "--transient", "6",
                 "--record", "3", "--workers", "1", "--no-plots", "--quiet"]  # fmt: skip
    reference = invoke("sweep", "bifurcation-omega", *arguments, "--out", tmp_path / "reference")
    assert reference.exit_code == 0, reference.stderr
    folder = tmp_path / "interrupted"
    # interrupted in its third point (in this process: --workers 1), two points finished
    process = start_reaching("oscillator.analysis.sweep_points.run_point", ["sweep", "bifurcation-omega", *arguments,
                             "--out", folder], call=3)  # fmt: skip
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=TIMEOUT)
    assert process.returncode == 130, stderr
    assert "run the same command to resume" in stderr and "Traceback" not in stderr
    assert json.loads((folder / "sweep.json").read_text(encoding="utf-8"))["status"] != "complete"
    assert len(list(folder.glob("parts/*.summary.parquet"))) == 2
    resumed = invoke("sweep", "bifurcation-omega", *arguments, "--out", folder)
    assert resumed.exit_code == 0, resumed.stderr
    assert_same_tables(read_sweep(tmp_path / "reference"), read_sweep(folder))


# ----------------------------------------------------------------------------- fuzzing

NAMES = (*Parameters.names(), "t0", "x1", "v1", "x2", "v2", *SolverOptions.names())

ODD_NUMBERS = (0.0, -0.0, -1.0, 1e-300, 5e-324, 1e300, 1.7976931348623157e308, 2.0**53 + 1)
ODD_TEXT = ("pi/8", "2*pi", "pi**400", "1/0", "(", "1e999", "nan", "inf", "٣", "__import__('os')", "", " ", "1_0")

values = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(min_value=-100, max_value=100),
    st.sampled_from(ODD_NUMBERS),
    st.integers(min_value=-(10**30), max_value=10**30),
    st.booleans(),
    st.text(max_size=12),
    st.sampled_from(ODD_TEXT),
    st.lists(st.integers(), max_size=3),
    st.dictionaries(st.text(max_size=4), st.integers(), max_size=2),
)


def _short(case):
    """Two forcing periods at most, and never more than half a second: every example is quick."""
    return min(case.t_end, case.initial.t0 + min(0.5, 2 * case.parameters.period))


def _runs_or_refuses(case) -> None:
    steps = min(case.options.max_num_steps, 20_000)  # a stiff example fails in 0.2 s, not 2 s
    try:
        result = simulate(case, t_end=_short(case), record_trajectory=False, max_num_steps=steps)
    except OscillatorError as error:
        assert str(error) and error.field is not None
    else:
        assert result.success and all(math.isfinite(v) for v in result.final_state)


#: The places of a case file: mostly the real ones, sometimes made-up sections and keys.
PLACES = st.one_of(
    st.sampled_from(
        [("parameters", n) for n in Parameters.names()]
        + [("initial", n) for n in ("t0", "x1", "v1", "x2", "v2")]
        + [("run", n) for n in ("t_end", *SolverOptions.names())]
        + [("sweep", n) for n in ("param", "from", "to", "steps", "transient", "record", "mass")]
    ),
    st.tuples(st.sampled_from(("parameters", "initial", "run", "expected", "sweep", "other")), st.text(max_size=8)),
)
#: Values that pass the type checks more often than not, to reach the simulator.
PLAUSIBLE = st.one_of(st.floats(min_value=-10, max_value=10), st.floats(min_value=0, max_value=1e3), values)


@given(
    changes=st.lists(st.tuples(PLACES, PLAUSIBLE), min_size=1, max_size=4),
    dropped=st.lists(st.sampled_from(Parameters.names()), max_size=2),
)
def test_fuzzed_case_files_run_or_are_refused(tmp_path_factory, changes, dropped):
    import tomllib

    import tomli_w

    data = tomllib.loads(case_to_toml(load_case("instance-1")))
    for (section, key), value in changes:
        table = data.setdefault(section, {})
        if isinstance(table, dict):
            table[key] = value
        else:
            data[section] = value
    for name in dropped:
        data["parameters"].pop(name, None)
    path = tmp_path_factory.mktemp("fuzz") / "case.toml"
    path.write_text(tomli_w.dumps(data), encoding="utf-8")
    try:
        case = load_case(path)
    except OscillatorError as error:
        assert str(error) and error.field is not None
        return
    _runs_or_refuses(case)


@given(text=st.text(max_size=200))
def test_fuzzed_case_text_is_refused_with_its_reason(tmp_path_factory, text):
    path = tmp_path_factory.mktemp("fuzz") / "case.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(OscillatorError):  # no text this short is a whole case
        load_case(path)


@given(name=st.one_of(st.sampled_from(NAMES), st.text(max_size=8)), value=PLAUSIBLE)
def test_fuzzed_overrides_of_the_api_run_or_are_refused(name, value):
    try:
        case = load_case("instance-1")
        from oscillator.hybrid.simulate import resolve_case

        case = resolve_case(case, **{name: value})
    except OscillatorError as error:
        assert str(error) and error.field is not None
        return
    _runs_or_refuses(case)


@given(
    name=st.one_of(st.sampled_from(NAMES), st.text(max_size=8)),
    text=st.one_of(st.text(max_size=12), st.sampled_from(ODD_TEXT), values.map(str)),
)
def test_fuzzed_set_values_on_the_command_line_run_or_are_refused(tmp_path_factory, name, text):
    folder = tmp_path_factory.mktemp("fuzz") / "run"
    result = runner.invoke(
        app,
        ["run", "instance-1", "--t-end", "1.5", "--set", "max_trajectory_rows=200000", "--set", f"{name}={text}",
         "--no-plots", "--no-report", "--quiet", "--out", str(folder)],
    )  # fmt: skip
    assert result.exception is None or isinstance(result.exception, SystemExit), repr(result.exception)
    if result.exit_code == 0:
        assert read_run_folder(folder).run["status"] == "complete"
    else:
        assert result.exit_code in (1, 2) and result.stderr.startswith("error: "), result.stderr
        assert "Traceback" not in result.stderr
        if result.exit_code == 2:
            assert not Path(folder).exists()


#: End times that are refused, or short enough to run (a valid huge one would just run long).
END_TIMES = st.one_of(
    st.floats(min_value=1.0, max_value=1.5),
    st.sampled_from((math.nan, math.inf, -math.inf, 0.0, -5.0, 1.0)),
    st.text(max_size=5),
    st.booleans(),
    st.lists(st.floats(), max_size=2),
)


@given(
    t_end=END_TIMES,
    t_eval=st.one_of(st.none(), st.lists(st.floats(allow_nan=True, allow_infinity=True), max_size=5), values),
    keep=st.one_of(st.none(), values),
)
def test_fuzzed_keywords_of_simulate_run_or_are_refused(t_end, t_eval, keep):
    try:
        result = simulate("instance-1", t_end=t_end, t_eval=t_eval, keep_events_from=keep, record_trajectory=True)
    except OscillatorError as error:
        assert str(error) and error.field is not None
        return
    assert result.success


# ----------------------------------------------------------------------------- the library's own input


def test_a_progress_that_is_not_a_function_is_refused():
    with pytest.raises(OscillatorError, match="progress must be a function") as caught:
        simulate("instance-1", progress="x")
    assert caught.value.field == "progress"


def test_an_exception_of_the_progress_callback_reaches_the_caller_unchanged():
    def progress(t):
        raise ZeroDivisionError("the caller's own bug")

    with pytest.raises(ZeroDivisionError, match="the caller's own bug"):
        simulate("instance-1", progress=progress)


def test_a_ctrl_c_in_the_progress_callback_leaves_the_trajectory_ending_at_the_last_point():
    """The progress callback runs after the supervisor notes a point and before its row is
    kept; a Ctrl-C there must still give a partial result whose trajectory ends at t_final."""
    from oscillator.errors import Interrupted

    calls = []

    def progress(t):
        calls.append(t)
        if len(calls) == 50:
            raise KeyboardInterrupt

    with pytest.raises(Interrupted) as caught:
        simulate("instance-1", t_end=40.0, progress=progress)
    partial = caught.value.result
    assert partial.status is Status.INTERRUPTED
    t_final = partial.final_state[0]
    assert t_final == calls[-1] and partial.trajectory.t.iloc[-1] == t_final
    assert np.all(np.diff(partial.trajectory.t.to_numpy()) >= 0)


def test_numpy_numbers_are_numbers():
    plain = simulate("instance-1", Omega=1.5, max_events=10**6, record_trajectory=False)
    numpy = simulate("instance-1", Omega=np.float32(1.5), max_events=np.int64(10**6), record_trajectory=False)
    np.testing.assert_array_equal(plain.events.t, numpy.events.t)
    with pytest.raises(OscillatorError, match="must be a number"):
        simulate("instance-1", Omega=np.bool_(True))


def test_grid_times_outside_the_run_are_refused_not_dropped():
    with pytest.raises(OscillatorError, match=r"t_eval holds t = 0.5 s, outside the run \[t0, t_end\] = \[1.0, 1.9\]"):
        simulate("instance-1", t_eval=[0.5, 1.2])
    with pytest.raises(OscillatorError, match=r"t = 2\.0 s, outside"):
        simulate("instance-1", t_eval=[1.2, 2.0])


def test_the_step_limit_holds_when_every_step_is_recorded():
    with pytest.raises(OscillatorError, match="more than max_num_steps = 5 steps without a switch") as caught:
        simulate("instance-1", max_num_steps=5)
    partial = caught.value.result
    assert caught.value.field == "max_num_steps" and partial.status is Status.FAILED
    after_last_switch = partial.trajectory.t > partial.events.t.iloc[-1]
    assert after_last_switch.sum() == 6  # five steps allowed, the sixth stops the run


@pytest.mark.parametrize(("name", "value"), [("Omega", 5e-324), ("m1", 1e-200), ("g", 1e-101)])
def test_positive_parameters_below_any_physical_scale_are_refused(name, value):
    with pytest.raises(OscillatorError, match="below any physical scale") as caught:
        simulate("instance-1", **{name: value})
    assert caught.value.field == name


def test_run_json_is_strict_json_even_with_infinite_values():
    import json

    from oscillator.report.runs import json_text

    text = json_text({"energy": {"E0": math.inf, "residual": math.nan, "E1": np.float64(2.5)}, "n": np.int64(3)})
    assert json.loads(text) == {"energy": {"E0": None, "residual": None, "E1": 2.5}, "n": 3}
    assert "Infinity" not in text and "NaN" not in text


@pytest.mark.parametrize(
    ("changes", "fragment"),
    [
        ({"mass": True}, "mass must be 1 or 2"),
        ({"steps": 10**12}, "steps must be a whole number from 1 to 100,000"),
        ({"record": 10**12}, "record must be a whole number from 1 to 100,000"),
        ({"transient": 2.5}, "transient must be a whole number"),
    ],
)
def test_sweep_settings_that_could_not_finish_are_refused(changes, fragment):
    from oscillator import SweepSettings

    with pytest.raises(OscillatorError, match=re.escape(fragment)):
        SweepSettings(**{"param": "Omega", "start": 1.5, "stop": 1.7, **changes})


@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")  # the drop this test makes
def test_a_ctrl_c_that_python_drops_in_a_del_still_stops_the_run():
    """SIGINT's ``KeyboardInterrupt`` raised inside an object's ``__del__`` is dropped by Python
    ("Exception ignored in ..."): a garbage collection runs one anywhere (llvmlite's, while numba
    loads its kernels, lost a Ctrl-C once). The run still stops at the engine's next return, with
    the run so far."""
    import os

    from oscillator.errors import Interrupted

    class Dropping:
        def __del__(self):
            os.kill(os.getpid(), signal.SIGINT)
            for _ in range(1000):  # the handler runs here, between bytecodes: its exception is dropped
                pass

    told = []

    def progress(t):
        if not told:
            told.append(t)
            Dropping()

    with pytest.raises(Interrupted) as stopped:
        simulate("instance-1", t_end=2000.0, progress=progress)
    partial = stopped.value.result
    assert partial.status.value == "interrupted" and told[0] <= partial.final_state[0] < 2000.0
