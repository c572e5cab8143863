"""``python -m oscillator``: runs a case end to end, exit codes, one-line errors."""

import subprocess
import sys


def run(*args):
    return subprocess.run([sys.executable, "-m", "oscillator", *args], capture_output=True, text=True)


def test_named_case_runs_end_to_end():
    done = run("instance-3")
    assert done.returncode == 0, done.stderr
    assert "left_contact_onset" in done.stdout and "(5.50)" in done.stdout
    assert "all expected times within tolerance" in done.stdout


def test_unknown_case_is_one_line_and_exit_2():
    done = run("instanse-3")
    assert done.returncode == 2
    assert done.stderr.count("\n") == 1 and "did you mean 'instance-3'" in done.stderr
    assert "Traceback" not in done.stderr


def test_expected_time_out_of_tolerance_exits_1():
    # ending before m1 leaves rest leaves an expected event unmatched: the check must say so
    done = run("instance-1", "--t-end", "1.25")
    assert done.returncode == 1
    assert "OUT OF TOLERANCE" in done.stdout
