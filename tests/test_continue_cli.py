"""``oscillator orbit`` and ``oscillator continue`` under hostile input and faults.

Each command runs in a subprocess and must end in one of three ways (as in test_hostile.py):
exit 0 with its result; exit 2 with one line naming the field and nothing created; exit 1 or 130
with what was computed kept in a folder that says it is incomplete or interrupted.  Signals are
sent once the process has printed that it reached the moment under test, never after a sleep.
"""

from __future__ import annotations

import json
import os
import signal

import numpy as np
import pandas as pd
import pytest

from conftest import start_reaching
from oscillator import Reason, read_run
from test_hostile import TIMEOUT, _limit_file_size, oscillator, refused, snapshot

#: Every test runs the installed command in a subprocess: slow.
pytestmark = pytest.mark.slow

#: A short continuation: Instance 1's system down in Q2 across its sliding bifurcation.
CONTINUE = ["continue", "instance-1", "--param", "Q2", "--from", "71.3", "--to", "71.0", "--step", "0.5"]


def run_json(folder):
    return json.loads((folder / "run.json").read_text(encoding="utf-8"))


def test_a_branch_that_ends_early_exits_1_and_keeps_what_it_traced(work):
    done = oscillator(*CONTINUE, "--max-points", "3", "--out", "x", cwd=work)
    assert done.returncode == 1, done.stderr
    assert done.stderr.startswith("error: the branch ended early: max_points = 3 reached at Q2 = ")
    assert "the branch so far is in x" in done.stderr and "Traceback" not in done.stderr
    info = run_json(work / "x")
    assert info["status"] == "incomplete" and info["complete"] is False and info["pending"] == []
    assert info["reason"] == "max_points" and read_run(work / "x").reason is Reason.MAX_POINTS
    assert len(pd.read_parquet(work / "x" / "branch.parquet")) == 3
    assert "Ended early: max\\_points = 3 reached" in (work / "x" / "report.md").read_text(encoding="utf-8")


def test_quiet_prints_the_folder_and_report_redraws_an_empty_figure(work):
    done = oscillator(*CONTINUE, "--out", "x", "-q", cwd=work)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "x" and done.stderr == ""
    assert run_json(work / "x")["status"] == "complete"
    (work / "x" / "figures" / "branch.png").write_bytes(b"")  # as a full disk leaves one
    assert oscillator("report", "x", cwd=work).returncode == 0
    assert (work / "x" / "figures" / "branch.png").read_bytes()[:4] == b"\x89PNG"


def interrupted_at(function: str, args: list[str], cwd) -> tuple[int, str]:
    """Run ``oscillator ARGS`` with ``function`` wrapped; Ctrl-C once it is reached."""
    process = start_reaching(function, args, cwd=cwd)
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=TIMEOUT)
    return process.returncode, stderr


def test_ctrl_c_during_the_continuation_keeps_the_branch_so_far(work):
    """Interrupted while it steps along the branch: the points traced so far are written,
    marked interrupted (the Python API raises Interrupted carrying the partial Branch)."""
    code, stderr = interrupted_at("oscillator.orbits.locating.between", [*CONTINUE, "--out", "x"], work)
    assert code == 130 and "Traceback" not in stderr, stderr
    assert stderr.strip().startswith("error: interrupted at Q2 = 71.3; the branch so far is in x"), stderr
    info = run_json(work / "x")
    assert info["status"] == "interrupted" and info["complete"] is False
    assert pd.read_parquet(work / "x" / "branch.parquet").Q2.tolist() == [71.3]


def test_ctrl_c_while_the_figures_are_drawn_keeps_the_branch_and_report_finishes_it(work):
    code, stderr = interrupted_at("oscillator.report.orbits.draw_branch", [*CONTINUE, "--out", "x"], work)
    assert code == 130 and "Traceback" not in stderr, stderr
    assert "error: interrupted; the branch's tables are in x; `oscillator report x` makes" in stderr
    info = run_json(work / "x")
    assert info["status"] == "complete" and info["pending"] == ["figures", "report"]
    assert not (work / "x" / "figures" / "branch.png").exists()  # never a half-written figure
    finished = oscillator("report", "x", cwd=work)
    assert finished.returncode == 0, finished.stderr
    assert run_json(work / "x")["pending"] == []
    html = (work / "x" / "report.html").read_text(encoding="utf-8")
    assert html.count("data:image/png;base64,") == 2


def test_a_full_disk_is_one_message_and_leaves_nothing(work):
    done = oscillator(*CONTINUE, "--out", "x", cwd=work, preexec_fn=_limit_file_size(3000))
    assert done.returncode == 1, (done.stdout, done.stderr)
    message = done.stderr.strip()
    assert message.startswith("error: cannot write the branch to x: ") and "File too large" in message
    assert "nothing was written" in message
    assert "\n" not in message and "Traceback" not in message
    assert "Q2 = 71.15774" in done.stdout  # what was computed was shown before the write failed
    assert list(work.iterdir()) == []  # no folder, no lock, no temporary


def _sweep_folder(root, *, frame=None, raw=None, link=None):
    folder = root / "sweep"
    folder.mkdir()
    path = folder / "poincare.parquet"
    if frame is not None:
        frame.to_parquet(path)
    elif raw is not None:
        path.write_bytes(raw)
    else:
        (root / "elsewhere").write_bytes(b"PAR1 not really")
        path.symlink_to(root / "elsewhere")
    return folder


GOOD = pd.DataFrame({"Q2": [71.0, 71.1], "x2": [4.7, 4.8]})


@pytest.mark.parametrize(
    ("damage", "fragment"),
    [
        ({"raw": b"garbage"}, "poincare.parquet is damaged: it cannot be read as a table"),
        ({"raw": GOOD.to_parquet()[:40]}, "poincare.parquet is damaged: it cannot be read as a table"),
        ({"link": True}, "poincare.parquet is damaged: it cannot be read as a table"),
        ({"frame": GOOD.drop(columns="x2")}, "poincare.parquet is damaged: it has no column 'x2'"),
        ({"frame": GOOD.assign(Q2=["a", "b"])}, "poincare.parquet is damaged: its column 'Q2' is not numbers"),
        ({"frame": GOOD.rename(columns={"Q2": "Omega"})}, "is not a sweep of 'Q2'"),
    ],
)
def test_a_damaged_sweep_to_draw_over_is_refused_before_anything_runs(tmp_path, work, damage, fragment):
    over = _sweep_folder(tmp_path, **damage)
    refused(work, *CONTINUE, "--over", over, "--out", "x", fragments=(fragment,))


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (["--to", "1e308"], "--to = 1e+308 is not a valid Q2"),
        (["--param", "mu_s", "--from", "0.2", "--to", "0.05"], "--to = 0.05 is not a valid mu_s"),
        (["--param", "Omega", "--from", "1.6", "--to", "0"], "--to = 0.0 is not a valid Omega"),
        (["--param", "m1", "--from", "1", "--to", "-1"], "--to = -1.0 is not a valid m1"),
        (["--to", repr(float(np.nextafter(71.3, 72)))], "--to must be at least 1e-08 away from --from"),
        (["--step", "1e-300"], "--step must be from 1e-06 to 1"),
        (["--set", "Q2=3"], "Q2 is given by --param (the continued parameter)"),
        (["--max-points", "1"], "--max-points must be a whole number from 2 to 100000"),
        (["--period", "1000000"], "--period must be a whole number from 1 to 1000"),
        (["--guess", "1,2,3"], "--guess must be four numbers"),
        (["--transient", "-1"], "--transient must be a whole number"),
    ],
)
def test_continue_settings_are_refused_before_anything_runs(work, args, fragment):
    base = CONTINUE.copy()
    for flag, value in zip(args[::2], args[1::2], strict=True):
        if flag in base:
            base[base.index(flag) + 1] = value
        else:
            base += [flag, value]
    refused(work, *base, "--out", "x", fragments=(fragment,))


def test_orbit_refuses_an_absurd_period_at_once(work):
    refused(work, "orbit", "instance-1", "--period", "1000000", fragments=("--period",))


def test_orbit_advice_names_options_the_command_has(work):
    """Newton out of steps: the advice names --guess, --transient and --max-iterations, and
    each of them works."""
    done = oscillator("orbit", "instance-1", "--transient", "0", "--max-iterations", "1", cwd=work)
    assert done.returncode == 1, done.stderr
    message = done.stderr.strip()
    assert "did not converge" in message and "--guess" in message and "--transient" in message
    assert "--max-iterations" in message and "`" not in message
    found = oscillator("orbit", "instance-1", "--set", "Omega=1.85", "--transient", "50", cwd=work)
    assert found.returncode == 0, found.stderr
    state = next(line for line in found.stdout.splitlines() if "x1 = " in line)
    guess = ",".join(part.split("=")[1].strip() for part in state.split(","))
    again = oscillator("orbit", "instance-1", "--set", "Omega=1.85", "--guess", guess, "--transient", "0", cwd=work)
    assert again.returncode == 0 and "after 0 Newton step(s); stable" in again.stdout, again.stdout


def test_orbit_of_a_parked_mass_reads_neutral_not_unstable(work):
    done = oscillator("orbit", "instance-1", "--set", "Q2=0", "--set", "x2=0.5", "--set", "d=1000", cwd=work)
    assert done.returncode == 0, done.stderr
    assert "stable; neutral in x2: m2 rests all period where it stuck" in done.stdout
    assert "unstable" not in done.stdout


def test_snapshot_is_unchanged_by_a_refused_over(tmp_path, work):
    """A sweep folder that does not exist is refused with the flag named."""
    before = snapshot(work)
    done = oscillator(*CONTINUE, "--over", tmp_path / "missing", cwd=work)
    assert done.returncode == 2 and done.stderr.startswith("error: ") and "is not a folder" in done.stderr
    assert snapshot(work) == before and os.listdir(work) == []
