"""The installed command as a user runs it: a subprocess, exit codes, one-line errors."""

import subprocess
import sys
from pathlib import Path

import pytest


def run(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "oscillator", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd)  # fmt: skip


def test_named_case_runs_end_to_end(tmp_path):
    done = run("run", "instance-3", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "left_contact_onset" in done.stdout and "(5.50)" in done.stdout
    (folder,) = (tmp_path / "runs").iterdir()
    assert (folder / "report.html").exists() and (folder / "figures" / "fig-d-forces.svg").exists()


def test_unknown_case_is_one_line_and_exit_2():
    done = run("check", "instanse-3")
    assert done.returncode == 2
    assert done.stderr.count("\n") == 1 and "did you mean 'instance-3'" in done.stderr
    assert "Traceback" not in done.stderr


def test_check_exit_codes(tmp_path):
    assert run("check", "instance-4").returncode == 0
    # a start moved by 0.1 m shifts the switches beyond the article's tolerance
    moved = tmp_path / "moved.toml"
    moved.write_text(
        (Path(__file__).parents[1] / "cases" / "instance-3.toml").read_text().replace("x1 = 3.5", "x1 = 3.6")
    )
    assert run("check", moved).returncode == 1
    assert run("check", "instance-3", "--set", "x1=3.6").returncode == 2  # a changed case has no expectations


def test_version():
    done = run("--version")
    assert done.returncode == 0 and done.stdout.startswith("oscillator ")


def loaded(arguments: list[str], *modules: str) -> tuple[subprocess.CompletedProcess, list[str]]:
    """``oscillator ARGUMENTS`` in a fresh process: the process, then its exit code and, for each of
    ``modules``, whether it was loaded (``"True"`` or ``"False"``)."""
    script = (
        "import runpy, sys\n"
        f"sys.argv = ['oscillator', *{arguments!r}]\n"
        "try:\n    runpy.run_module('oscillator', run_name='__main__')\n"
        f"except SystemExit as done:\n    print(done.code, *(m in sys.modules for m in {modules!r}))\n"
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    return done, done.stdout.split()[-1 - len(modules) :]


def test_a_run_without_figures_never_loads_matplotlib(tmp_path):
    """``--no-plots`` spares the command matplotlib's import (a third of a second of its start)."""
    done, said = loaded(["run", "instance-3", "--no-plots", "--quiet", "--out", str(tmp_path / "out")], "matplotlib")
    assert said == ["0", "False"], (done.stdout, done.stderr)
    assert (tmp_path / "out" / "events.csv").is_file() and not (tmp_path / "out" / "figures").exists()


@pytest.mark.parametrize(
    "arguments",
    [
        ["orbit", "instance-1", "--period", "1000000"],
        ["continue", "instance-1", "--param", "mu_s", "--from", "0.2", "--to", "0.05"],
        ["continue", "instance-1", "--param", "Q2", "--from", "71.3", "--to", "71.0", "--max-points", "1"],
        ["frc", "instance-1", "--param", "Omega", "1.3", "1.3"],
        ["lyapunov", "instance-1", "--periods", "0"],
        ["explore", "instance-1", "--port", "-5"],
    ],
    ids=["orbit", "continue-range", "continue-points", "frc", "lyapunov", "explore"],
)
def test_a_refused_option_is_refused_before_the_numerical_libraries_load(arguments):
    """A command's options are checked before it loads numba and the solvers (a second and more
    of its start): a refusal is quick, and says what to fix."""
    done, said = loaded(arguments, "numba", "scipy.integrate")
    assert said == ["2", "False", "False"], (done.stdout, done.stderr)
    assert done.stderr.startswith("error: ") and done.stderr.count("\n") == 1, done.stderr
