"""Every command shown in README.md, docs/*.md and the ``--help`` examples runs as shown.

The commands of each source run in the order shown, in one scratch folder per source, as a user
following that page would run them (``oscillator report runs/omega-1.7`` after the run that made
it). The files a page names without shipping them are made first: ``my-case.toml`` is the
example of docs/cases.md, ``broken.toml`` and ``chatter.toml`` are as docs/cli.md describes them.

Where a console block shows what a command prints (``error: ...``), the command must print that
(``...`` stands for anything) and fail with exit code 2 or 1; every other command must succeed.
Long commands run with small settings, the same for every page (:func:`shrunk`): a sweep on 3
values with 5 + 2 periods in one process, a run of at most 200 s, and locate's look at both ends
of its bracket (which must differ) without the bisection.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest
from typer.testing import CliRunner

from conftest import chatter_case
from oscillator.cli.app import app
from oscillator.io.cases import case_to_toml

#: Each page's commands run through the installed command, end to end: slow (``pytest -m slow``).
pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]
COMMAND = str(Path(sys.executable).with_name("oscillator"))
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
COMMANDS = (
    "list", "show", "run", "check", "report", "sweep", "locate", "orbit", "continue",
    "basins", "attractors", "lyapunov", "frc", "atlas", "curve", "design", "calibrate", "explore",
)  # fmt: skip


@dataclass
class Shown:
    """A command as a page shows it, and the output the page shows under it."""

    source: str
    line: str
    output: list[str]


def _console_blocks(text: str):
    for match in re.finditer(r"```(sh|console|bash)\n(.*?)```", text, re.S):
        yield match.group(1), match.group(2).splitlines()


def shown_in_page(path: Path) -> list[Shown]:
    found: list[Shown] = []
    for language, lines in _console_blocks(path.read_text(encoding="utf-8")):
        for line in lines:
            command = line[2:] if language == "console" and line.startswith("$ ") else line
            if language == "console" and not line.startswith("$ "):
                if found and found[-1].source.startswith(path.name):
                    found[-1].output.append(line)
                continue
            if command.startswith("oscillator "):
                found.append(Shown(f"{path.name}: {command}", command, []))
    return found


def shown_in_help(names: tuple[str, ...] = COMMANDS) -> list[Shown]:
    found = []
    for name in names:
        done = subprocess.run([COMMAND, name, "--help"], capture_output=True, text=True, env={**os.environ,
                              "COLUMNS": "200"}, check=True)  # fmt: skip
        joined = re.sub(r" \\\n\s*", " ", done.stdout)  # an example continued on the next line
        for line in joined.splitlines():
            if line.strip().startswith("oscillator "):
                found.append(Shown(f"{name} --help: {line.strip()}", line.strip(), []))
    return found


def _set(arguments: list[str], option: str, value: str) -> list[str]:
    if option in arguments:
        arguments = list(arguments)
        arguments[arguments.index(option) + 1] = value
        return arguments
    return [*arguments, option, value]


def shrunk(arguments: list[str]) -> list[str]:
    """The command with small settings: the same command, quicker."""
    command = arguments[0]
    if command == "sweep":
        for option, value in (("--steps", "3"), ("--transient", "5"), ("--record", "2"), ("--workers", "1")):
            arguments = _set(arguments, option, value)
    elif command == "continue":  # a coarse branch: the same command, fewer points
        arguments = _set(arguments, "--step", "0.5")
    elif command in ("basins", "attractors"):  # a 3 x 3 slice, short runs, a coarse bisection
        for option in ("--x", "--y"):
            if option in arguments:
                arguments = list(arguments)
                arguments[arguments.index(option) + 4] = "3"
        for option, value in (("--transient", "20"), ("--record", "4"), ("--workers", "1")):
            arguments = _set(arguments, option, value)
        if command == "attractors":
            arguments = _set(_set(arguments, "--steps", "3"), "--tol", "1e-3")
    elif command == "atlas":  # a 3 x 2 plane, short runs, no figures, in this process
        for option, count in (("--x", "3"), ("--y", "2")):
            arguments = list(arguments)
            arguments[arguments.index(option) + 4] = count
        for option, value in (("--workers", "1"), ("--transient", "30"), ("--record", "8")):
            arguments = _set(arguments, option, value)
        if "--no-plots" not in arguments:  # tests/test_attractors.py draws them; `report` on its folder too
            arguments = [*arguments, "--no-plots"]
    elif command == "frc" and arguments[1].startswith("docs/systems/"):  # a system file's sweeps: three values
        arguments = _set(_set(arguments, "--sweep", "3"), "--transient", "40")
    elif command == "frc":  # two seeds, short branches, the sweeps' two ends, in this process
        for option, value in (("--seeds", "2"), ("--sweep", "2"), ("--max-points", "12"), ("--workers", "1")):
            arguments = _set(arguments, option, value)
    elif command == "design" and arguments[1].startswith("docs/systems/"):  # a system's design: 5 sweep values
        arguments = _set(arguments, "--band", "5")
    elif command == "design":  # two band values, one start, three candidates, short runs, in this process
        for option, value in (("--band", "2"), ("--starts", "1"), ("--candidates", "3"), ("--transient", "30"),
                              ("--record", "4"), ("--workers", "1"), ("--front", "2")):  # fmt: skip
            arguments = _set(arguments, option, value)
        arguments = (
            [*arguments, "--no-plots"] if "--no-plots" not in arguments else arguments
        )  # tests/test_design.py draws
    elif command == "explore":  # served on a free port (tests run side by side)
        arguments = _set(arguments, "--port", "0")
    elif command == "curve":  # a coarse curve: the same command, fewer points
        arguments = _set(arguments, "--step", "0.5")
    elif command == "lyapunov":
        arguments = _set(_set(arguments, "--periods", "20"), "--transient", "10")
    elif command == "locate":  # both ends are simulated, and must differ; no bisection
        a, b = (float(v) for v in arguments[arguments.index("--between") + 1 :][:2])
        arguments = _set(arguments, "--tolerance", f"{abs(b - a):.17g}")
    elif command == "run" and "--t-end" in arguments:
        t_end = float(arguments[arguments.index("--t-end") + 1])
        arguments = _set(arguments, "--t-end", f"{min(t_end, 200.0):g}")
        if "--window" in arguments:
            index = arguments.index("--window")
            arguments[index + 1 : index + 3] = ["190", "200"]
    elif command == "report" and "--window" in arguments:
        index = arguments.index("--window")
        arguments[index + 1 : index + 3] = ["180", "190"]
    return arguments


def _fixtures(folder: Path) -> None:
    """The files the pages name: their example case, a malformed file, a chattering case, the
    system files of docs/systems/."""
    cases = (ROOT / "docs" / "cases.md").read_text(encoding="utf-8")
    (folder / "my-case.toml").write_text(cases.split("```toml\n", 1)[1].split("```", 1)[0], encoding="utf-8")
    (folder / "broken.toml").write_text("[parameters]\nm1 = 1.0\nm2 = = 2\n", encoding="utf-8")
    (folder / "chatter.toml").write_text(case_to_toml(chatter_case()), encoding="utf-8")
    shutil.copytree(ROOT / "docs" / "systems", folder / "docs" / "systems")  # the system files docs/systems.md shows
    shutil.copytree(ROOT / "docs" / "measured", folder / "docs" / "measured")  # docs/calibration.md's measurements


def _serve_once(shown: Shown, arguments: list[str], folder: Path) -> None:
    """``oscillator explore``, which serves until Ctrl-C, started as a user starts it (on a free
    port): it prints its address, the page is there, and Ctrl-C stops it with exit code 0."""
    from urllib.request import urlopen

    from oscillator.exploring.driving import Served

    served = Served(*arguments[1:], cwd=folder)
    try:
        with urlopen(served.url, timeout=60) as page:
            assert page.status == 200 and b"bokeh" in page.read().lower(), shown.source
    finally:
        code, out, err = served.stop()
    assert code == 0 and out.strip() == "stopped" and "Traceback" not in err, (shown.source, code, out, err)


def _matches(expected: str, printed: str) -> bool:
    pattern = ".*".join(re.escape(part) for part in expected.split("..."))
    return re.fullmatch(pattern, printed, re.S) is not None


def _run_in_order(commands: list[Shown], folder: Path, monkeypatch) -> None:
    """Run the commands in ``folder``, in this process (the command's own code, without the cost
    of starting Python for each; tests/test_main.py and test_hostile.py start it as a user does)."""
    _fixtures(folder)
    monkeypatch.chdir(folder)
    runner = CliRunner()
    for shown in commands:
        arguments = shrunk(shlex.split(shown.line, comments=True)[1:])
        if arguments[0] == "explore":
            _serve_once(shown, arguments, folder)
            continue
        done = runner.invoke(app, arguments)
        assert done.exception is None or isinstance(done.exception, SystemExit), (shown.source, done.exception)
        if shown.output:
            assert done.exit_code in (1, 2), (shown.source, done.exit_code, done.stdout)
            printed = [line for line in done.stderr.splitlines() if line]
            assert len(printed) == len(shown.output), (shown.source, printed, shown.output)
            for expected, line in zip(shown.output, printed, strict=True):
                assert _matches(expected, line), (shown.source, expected, line)
        else:
            assert done.exit_code == 0, (shown.source, arguments, done.stderr[-2000:])


@pytest.mark.parametrize("page", PAGES, ids=[p.name for p in PAGES])
def test_every_command_of_a_page_runs_as_shown(tmp_path, monkeypatch, page):
    commands = shown_in_page(page)
    if not commands:
        pytest.skip(f"{page.name} shows no command")
    _run_in_order(commands, tmp_path, monkeypatch)


#: The commands whose --help examples run together, in this order (``report``'s example reads a
#: folder that ``run``'s example writes); the groups run side by side.
HELP_GROUPS = {"runs": ("list", "show", "check", "run", "report"), "sweeps": ("sweep", "locate"),
               "orbits": ("orbit", "continue"), "attractors": ("basins", "attractors", "lyapunov"),
               "atlas": ("atlas", "curve", "explore"), "frc": ("frc",), "design": ("design", "calibrate")}  # fmt: skip


def test_every_command_has_a_help_example_in_a_group():
    assert sorted(name for group in HELP_GROUPS.values() for name in group) == sorted(COMMANDS)


@pytest.mark.parametrize("group", sorted(HELP_GROUPS))
def test_every_help_example_runs_as_shown(tmp_path, monkeypatch, group):
    commands = shown_in_help(HELP_GROUPS[group])
    assert {shown.line.split()[1] for shown in commands} == set(HELP_GROUPS[group])  # every command has one
    _run_in_order(commands, tmp_path, monkeypatch)


def test_the_pages_show_the_commands_they_are_tested_with():
    """The extraction itself: the README shows its tour, docs/cli.md its errors with their output."""
    readme = [shown.line for shown in shown_in_page(ROOT / "README.md")]
    assert "oscillator report runs/omega-1.7                  # rebuild a run's report" in readme
    errors = [shown for shown in shown_in_page(ROOT / "docs" / "cli.md") if shown.output]
    assert len(errors) >= 6 and all(line.startswith(("error: ", "the partial")) for e in errors for line in e.output)
    assert shrunk(["sweep", "bifurcation-q2", "--steps", "36"]) == [
        "sweep", "bifurcation-q2", "--steps", "3", "--transient", "5", "--record", "2", "--workers", "1"
    ]  # fmt: skip
