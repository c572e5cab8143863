"""Hostile input and faults met by a newcomer, through the installed command (issue 24): what
each now does, by the rule of ``test_hostile.py`` (exit 0 with a result, 2 with one line and
nothing created, 1 or 130 with what was computed kept)."""

from __future__ import annotations

import json
import re
import subprocess
import time

import pandas as pd
import pytest

from test_hostile import COMMAND, ENVIRONMENT, TIMEOUT, case_data, oscillator, refused, write_case

#: Every test runs the installed command in a subprocess: slow.
pytestmark = pytest.mark.slow


def test_a_window_between_two_samples_draws_the_interpolated_state(work):
    """--window inside one --sample step: the figures show the state interpolated at the window's
    ends (it was an internal AttributeError in run, a traceback in report)."""
    done = oscillator("run", "instance-1", "--t-end", "30", "--sample", "1", "--window", "10.2", "10.4",
                      "--out", "x", "-q", cwd=work)  # fmt: skip
    assert done.returncode == 0, done.stderr
    again = oscillator("report", "x", "--window", "10.25", "10.3", cwd=work)
    assert again.returncode == 0 and "Traceback" not in again.stderr, again.stderr
    info = json.loads((work / "x" / "run.json").read_text())
    assert info["figures"]["window"] == [10.25, 10.3] and info["pending"] == []


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (["--scheduler", "tcp://[::1"], "--scheduler 'tcp://[::1' is not the address of a Dask scheduler"),
        (["--from", "1e308", "--to", "-1e308"], "--to: the values from 1e+308 to -1e+308 leave floating point"),
        (["--param", "mu_s", "--from", "0.2", "--to", "0.05"], "--to = 0.05 is not a valid mu_s"),
        (["--from", "1e99", "--to", "2e99"], "its forcing period, 6.28e-99 s, is lost beside t0 = 1 s"),
    ],
)
def test_sweep_ranges_and_addresses_are_refused_before_anything_runs(work, args, fragment):
    refused(work, "sweep", "bifurcation-omega", "--steps", "3", "--transient", "1", "--record", "1", *args,
            "--out", "s", fragments=(fragment,))  # fmt: skip


def test_a_sweep_whose_every_point_failed_exits_1_with_the_reason(work):
    done = oscillator("sweep", "bifurcation-omega", "--steps", "2", "--transient", "1", "--record", "1",
                      "--set", "max_num_steps=5", "--workers", "1", "--no-plots", "--out", "s", cwd=work)  # fmt: skip
    assert done.returncode == 1, done.stderr
    assert done.stderr.startswith("error: every point of the sweep failed; the first: CVODE failed")
    assert "never slides" not in done.stdout
    assert (pd.read_parquet(work / "s" / "summary.parquet").status == "failed").all()


def test_an_expected_time_outside_the_run_is_refused(tmp_path, work):
    data = case_data()
    data["expected"][0]["t"] = data["run"]["t_end"] + 1.0
    path = write_case(tmp_path, data)
    for command in ("run", "check", "show"):
        refused(work, command, path, fragments=("lies outside the run", "could never be checked"))


def test_a_byte_order_mark_is_read_as_utf8(tmp_path, work):
    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf" + write_case(tmp_path, case_data()).read_bytes())
    done = oscillator("check", path, cwd=work)
    assert done.returncode == 0, done.stderr


@pytest.mark.parametrize("encoding", ["ascii", "latin-1"])
def test_a_terminal_without_unicode_gets_escapes_not_a_crash(work, encoding):
    env = {**ENVIRONMENT, "PYTHONIOENCODING": encoding}
    shown = subprocess.run([COMMAND, "show", "instance-2"], cwd=work, env=env, capture_output=True)
    assert shown.returncode == 0 and b"\\u2202\\u03a912(2)" in shown.stdout, shown.stderr  # ∂Ω12(2)
    ran = subprocess.run([COMMAND, "run", "instance-3", "--no-plots", "--out", "x"], cwd=work, env=env,
                         capture_output=True, timeout=TIMEOUT)  # fmt: skip
    assert ran.returncode == 0 and b"Traceback" not in ran.stderr, ran.stderr
    assert b"written to x" in ran.stdout


def test_scipy_tolerances_it_cannot_meet_are_named(work):
    refused(work, "run", "instance-1", "--engine", "scipy", "--set", "rtol=1e-15", "--out", "x",
            fragments=("rtol = 1e-15 is below what SciPy's solve_ivp accepts",))  # fmt: skip
    refused(work, "run", "instance-1", "--engine", "scipy", "--set", "atol=1e-300", "--out", "x",
            fragments=("atol = 1e-300 is too small for SciPy's error norm",))  # fmt: skip


@pytest.mark.parametrize(
    ("name", "prefix"), [("x" * 240, "x" * 100), ("a\tb", "a_b"), (".hidden", "_hidden"), ("a\\b", "a_b")]
)
def test_a_default_folder_is_made_from_any_case_name(tmp_path, work, name, prefix):
    """The case's name comes from its file's name: the default folder is made safe from it (at
    most 100 bytes of it, no control character, separator or leading dot), instead of refusing
    an --out the user never gave."""
    path = write_case(tmp_path, case_data(), name=f"{name}.toml")
    done = oscillator("run", path, "--no-plots", "--no-report", "-q", cwd=work)
    assert done.returncode == 0, done.stderr
    (folder,) = (work / "runs").iterdir()
    assert re.fullmatch(re.escape(prefix) + r"-\d{8}-\d{6}", folder.name), folder.name


def test_a_long_run_keeps_its_late_events_and_its_report_summarises(tmp_path, work):
    """--keep-events-from (and [run] keep_events_from in a case file) keep the late events only;
    a log of more than 200 events lists the first and last 100 and counts the rest."""
    done = oscillator("run", "instance-1", "--t-end", "400", "--sample", "0.5", "--keep-events-from", "300",
                      "--no-plots", "--out", "kept", "-q", cwd=work)  # fmt: skip
    assert done.returncode == 0, done.stderr
    events = pd.read_parquet(work / "kept" / "events.parquet")
    info = json.loads((work / "kept" / "run.json").read_text())
    assert events.t.min() >= 300 and info["counts"]["events"] > 3 * len(events)
    assert "keep_events_from = 300.0" in (work / "kept" / "case.toml").read_text()
    data = case_data("instance-1")
    data["run"].update(t_end=400.0, keep_events_from=300.0)
    data.pop("expected", None)
    again = oscillator("run", write_case(tmp_path, data), "--sample", "0.5", "--no-plots", "--out", "file", "-q",
                       cwd=work)  # fmt: skip
    assert again.returncode == 0, again.stderr
    pd.testing.assert_frame_equal(events, pd.read_parquet(work / "file" / "events.parquet"))

    whole = oscillator("run", "instance-1", "--t-end", "400", "--no-plots", "--out", "whole", "-q", cwd=work)
    assert whole.returncode == 0, whole.stderr
    count = len(pd.read_parquet(work / "whole" / "events.parquet"))
    report = (work / "whole" / "report.md").read_text(encoding="utf-8")
    log = report.split("## Transition log")[1].split("## Time in each domain")[0]
    assert count > 400 and log.count("\n- ") == 201
    assert f"{count - 200:,} events from t = " in log and "are not listed here" in log


def test_a_killed_sweep_leaves_no_warning_on_the_terminal(work):
    """SIGKILL to a sweep's parent: its pool's semaphores are removed without the resource
    tracker's "leaked semaphore objects" warning."""
    process = subprocess.Popen([COMMAND, "sweep", "bifurcation-omega", "--steps", "40", "--transient", "100",
                                "--record", "10", "--workers", "2", "--no-plots", "-q", "--out", "s"], cwd=work,
                               stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)  # fmt: skip
    deadline = time.monotonic() + TIMEOUT
    while time.monotonic() < deadline and not list((work / "s").glob("parts/*.summary.parquet")):
        time.sleep(0.1)
    assert list((work / "s").glob("parts/*.summary.parquet")), "no point finished"
    process.kill()
    _, stderr = process.communicate(timeout=TIMEOUT)  # until every writer, the tracker among them, is gone
    assert "leaked" not in stderr and "Traceback" not in stderr, stderr
