"""Hostile input and faults, through the installed command as a user (or an attacker) drives it.

Each call runs ``python -m oscillator`` in a subprocess with a timeout (no call may hang) and must
end in one of three ways:

* exit 0 with its result;
* exit 2: one line on stderr, ``error: ...`` naming the field, no traceback, and nothing created;
* exit 1 or 130: a clear message, and what was computed kept in a folder marked incomplete.

The classes: case files (encoding, size, nesting, non-regular files, control characters, length,
types), ``--set`` values, markup in text, output folders, concurrent runs, a full disk, signals,
damaged run and sweep folders, and the sweep's and locate's settings.  The report's escaping of
hostile text is tested on the rendered HTML and Markdown in ``test_report_escaping.py``.
"""

from __future__ import annotations

import json
import os
import resource
import signal
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import pandas as pd
import pytest
import tomli_w

from oscillator import load_case
from oscillator.io.cases import case_to_toml

#: Every test runs the installed command in a subprocess, most of them several times: slow.
pytestmark = pytest.mark.slow

#: Only against a hang: a loaded machine may take many times the usual seconds.
TIMEOUT = 300
CASE = "instance-3"


#: The installed command, as a user runs it.
COMMAND = str(Path(sys.executable).with_name("oscillator"))
#: Wide enough that no table wraps a text the tests look for.
ENVIRONMENT = {**os.environ, "COLUMNS": "250"}


def oscillator(*args, cwd: Path, timeout: float = TIMEOUT, **options) -> subprocess.CompletedProcess:
    command = [COMMAND, *(os.fsdecode(a) if isinstance(a, bytes) else str(a) for a in args)]
    return subprocess.run(command, cwd=cwd, capture_output=True, text=True, timeout=timeout, errors="replace",
                          env=ENVIRONMENT, **options)  # fmt: skip


def snapshot(folder: Path) -> set[str]:
    return {str(p.relative_to(folder)) for p in folder.rglob("*")}


def assert_refused(done: subprocess.CompletedProcess, *fragments: str, cwd: Path, before: set[str]) -> None:
    """Exit 2, one line naming the field, no traceback, and nothing created in ``cwd``."""
    message = done.stderr.strip()
    assert done.returncode == 2, (done.returncode, done.stdout[-500:], done.stderr[-2000:])
    assert message.startswith("error: ") and "\n" not in message, message
    assert "Traceback" not in done.stdout + done.stderr
    assert len(message) < 600, message  # a hostile value is quoted in part, never whole
    for fragment in fragments:
        assert fragment in message, message
    assert snapshot(cwd) == before, snapshot(cwd) - before


def refused(tmp_path: Path, *args, fragments=(), **options) -> None:
    before = snapshot(tmp_path)
    assert_refused(oscillator(*args, cwd=tmp_path, **options), *fragments, cwd=tmp_path, before=before)


def case_data(name: str = CASE) -> dict:
    return tomllib.loads(case_to_toml(load_case(name)))


def write_case(folder: Path, data: dict, name: str = "hostile.toml") -> Path:
    path = folder / name
    path.write_text(tomli_w.dumps(data), encoding="utf-8")
    return path


# ----------------------------------------------------------------------------- case files


def _raw_cases() -> dict:
    """Case files as bytes, each with the fragments its refusal must name."""
    text = case_to_toml(load_case(CASE))
    first, rest = text.split("\n", 1)
    sweep = '\n[sweep]\nparam = "Omega"\nfrom = 1.5\nto = 1.7\n'
    cases = {
        "non-UTF-8 byte in the title": (text.replace("Instance 3", "Instance \udcff3"), ["not UTF-8", "0xff"]),
        "integer of 5,000 digits": (text.replace("m1 = 2.0", "m1 = " + "9" * 5000), ["more than 4300 digits"]),
        "expression of 100,000 characters": (
            text.replace("m1 = 2.0", f'm1 = "{"(" * 50_000}1{")" * 50_000}"'),
            ["parameters.m1", "at most 200"],
        ),
        "arrays nested 50,000 deep": (text + "\nx = " + "[" * 50_000 + "]" * 50_000, ["nested too deeply"]),
        "a file of 2 MB": (text + "\n#" + "x" * 2_000_000 + "\n", ["larger than 1,048,576 bytes"]),
        "an unknown key of 900 kB": (
            text.replace("[run]", "[run]\n" + "k" * 900_000 + " = 1"),
            ["unknown run setting 'kkkk"],
        ),
        "an escape sequence in the title": (
            text.replace('title = "', 'title = "\\u001b[2J', 1),
            ["title", "control character \\x1b"],
        ),
        "a bidi override in a label": (
            text.replace('label = "', 'label = "\\u202e', 1),
            ["label", "control character \\u202e"],
        ),
        "a title of 400 characters": (text.replace('title = "', 'title = "' + "t" * 400, 1), ["title", "at most 300"]),
        "a title that is a number": ("title = 5\n" + rest, ["title must be text"]),
        "a table for a parameter": (text.replace("m1 = 2.0", "m1 = {a = 1}"), ["m1 must be a number"]),
        "[sweep] mass = true": (text + sweep + "mass = true\n", ["mass must be 1 or 2"]),
        "[sweep] steps = 1e12": (text + sweep + "steps = 1e12\n", ["steps must be a whole number from 1 to 100,000"]),
        "[sweep] record = 1e12": (text + sweep + "record = 1e12\n", ["record must be a whole number from 1 to"]),
    }
    assert first.startswith("title = ")
    return {name: (case.encode("utf-8", "surrogateescape"), fragments) for name, (case, fragments) in cases.items()}


RAW = _raw_cases()


@pytest.mark.parametrize("name", sorted(RAW))
@pytest.mark.parametrize("command", ["run", "show"])
def test_a_hostile_case_file_is_refused_in_one_line(tmp_path, work, name, command):
    content, fragments = RAW[name]
    path = tmp_path / "hostile.toml"
    path.write_bytes(content)
    refused(work, command, path, fragments=fragments)


@pytest.mark.parametrize("kind", ["fifo", "device", "folder"])
@pytest.mark.parametrize("command", ["run", "show", "check"])
def test_a_case_path_that_is_no_regular_file_is_refused_without_reading_it(tmp_path, work, kind, command):
    if kind == "fifo":
        path = tmp_path / "case.toml"
        os.mkfifo(path)
    elif kind == "device":
        path = Path("/dev/zero")
    else:
        path = tmp_path / "folder.toml"
        path.mkdir()
    expected = "is a folder" if kind == "folder" else "is not a regular file"
    refused(work, command, path, fragments=[expected])


def test_an_expected_event_without_a_time_checks_that_it_happens(tmp_path, work):
    data = case_data()
    data["expected"] = [{"mass": 1, "kind": "left_contact_onset", "label": "m1 reaches m2's stop"}]
    done = oscillator("check", write_case(tmp_path, data), cwd=work)
    assert done.returncode == 0, done.stderr
    assert "all 1 expected times within tolerance" in done.stdout
    data["expected"] = [{"mass": 1, "kind": "right_contact_onset", "label": "never happens"}]
    done = oscillator("check", write_case(tmp_path, data), cwd=work)
    assert done.returncode == 1 and "1 expected time(s) out of tolerance" in done.stderr
    done = oscillator("run", write_case(tmp_path, data), "--no-plots", "--out", "x", cwd=work)
    assert done.returncode == 0 and "expected events within tolerance: 0/1" in done.stdout


# ----------------------------------------------------------------------------- --set


@pytest.mark.parametrize(
    ("assignment", "fragments"),
    [
        ("m1=" + "(" * 50_000 + "1" + ")" * 50_000, ["--set m1", "at most 200"]),
        ("m1=" + "9" * 5000, ["--set m1", "at most 200"]),
        ("x1=1e100", ["at the start", "x1 = 1e+100", "overflows"]),
        ("v1=1e90", ["at the start", "v1 = 1e+90", "overflow"]),
        ("Omega=5e-324", ["Omega", "below any physical scale"]),
        ("max_num_steps=1e30", ["max_num_steps", "whole number from 1 to 10^12"]),
        ("title=x", ["unknown setting 'title'"]),
    ],
    ids=["long-expression", "5000-digits", "x1-1e100", "v1-1e90", "omega-denormal", "steps-1e30", "not-a-setting"],
)
def test_a_refused_set_value_creates_nothing_even_a_deep_out(work, assignment, fragments):
    refused(work, "run", CASE, "--set", assignment, "--out", "new/deep/x", fragments=fragments)
    refused(work, "run", CASE, "--set", assignment, fragments=fragments)  # and no runs/ either


def test_a_run_that_fails_after_it_started_exits_1_with_a_marked_partial_folder(work):
    done = oscillator("run", CASE, "--set", "max_num_steps=1", "--out", "x", cwd=work)
    assert done.returncode == 1, done.stderr
    assert done.stderr.startswith("error: CVODE took more than max_num_steps = 1 steps")
    info = json.loads((work / "x" / "run.json").read_text())
    assert info["complete"] is False and info["status"] == "failed" and info["pending"] == ["figures", "report"]


# ----------------------------------------------------------------------------- markup in text


def test_markup_in_titles_labels_and_folder_names_is_printed_as_written(tmp_path, work):
    data = case_data()
    data["title"] = "closing [/nope] tag [bold]x[/bold] :thumbs_up:"
    data["expected"][0]["label"] = "[/x] bad [red]label"
    path = write_case(tmp_path, data)
    done = oscillator("run", path, "--no-plots", "--no-report", "--out", "a[/b]", cwd=work)
    assert done.returncode == 0, done.stderr
    assert "closing [/nope] tag [bold]x[/bold] :thumbs_up:" in done.stdout and "a[/b]" in done.stdout
    assert (work / "a[/b]" / "run.json").is_file()
    shown = oscillator("show", path, cwd=work)
    assert shown.returncode == 0 and "closing [/nope] tag" in shown.stdout and "[/x] bad [red]label" in shown.stdout
    checked = oscillator("check", path, cwd=work)
    assert checked.returncode == 0 and "[/x] bad [red]label" in checked.stdout
    quiet = oscillator("run", CASE, "--no-plots", "--no-report", "-q", "--out", "x[red]y", cwd=work)
    assert quiet.returncode == 0 and quiet.stdout == "x[red]y\n"  # a script reads the path as written


# ----------------------------------------------------------------------------- output folders


@pytest.mark.parametrize(
    ("out", "fragments"),
    [
        ("n" * 300, ["folder name is 300 bytes long"]),
        ("n" * 240, ["folder name is 240 bytes long", "at most 237"]),
        (b"bad\xffname", ["not UTF-8 text"]),
        ("tab\tname", ["control characters"]),
        ("a-file/x", ["cannot write in"]),
        ("dangling", ["is a link", "folder of its own"]),
        ("existing", ["exists already"]),
    ],
    ids=["300-bytes", "240-bytes", "non-utf8", "control", "under-a-file", "dangling-link", "existing"],
)
@pytest.mark.parametrize("command", ["run", "sweep"])
def test_a_bad_output_folder_is_refused_before_anything_runs(work, out, fragments, command):
    (work / "a-file").write_text("")
    (work / "dangling").symlink_to(work / "nowhere")
    (work / "existing").mkdir()
    (work / "existing" / "keep.txt").write_text("precious")
    if command == "sweep":
        args = ["sweep", "bifurcation-omega", "--steps", "2", "--transient", "1", "--record", "1", "--workers", "1"]
        fragments = [f.replace("exists already", "exists") for f in fragments]
    else:
        args = ["run", CASE]
    refused(work, *args, "--out", out, fragments=fragments)
    assert (work / "existing" / "keep.txt").read_text() == "precious"


def test_runs_started_together_never_lose_a_result(work):
    command = [COMMAND, "run", CASE, "--no-plots", "--no-report", "-q"]
    started = [subprocess.Popen(command, cwd=work, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
               for _ in range(3)]  # fmt: skip
    outputs = [p.communicate(timeout=TIMEOUT) for p in started]
    assert [p.returncode for p in started] == [0, 0, 0], outputs
    folders = {out.strip() for out, _ in outputs}
    assert len(folders) == 3 and all((work / f / "events.parquet").is_file() for f in folders)
    same = [*command, "--out", "same"]
    racing = [subprocess.Popen(same, cwd=work, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
              for _ in range(2)]  # fmt: skip
    results = [(p.communicate(timeout=TIMEOUT)[1], p.returncode) for p in racing]
    assert sorted(code for _, code in results) == [0, 2], results
    message = next(text for text, code in results if code == 2).strip()
    assert message.startswith("error: --out same ") and ("being written by another run" in message
                                                        or "exists already" in message)  # fmt: skip
    assert "Traceback" not in "".join(text for text, _ in results)
    assert [p.name for p in work.iterdir() if p.name.startswith(".")] == []


def _limit_file_size(size: int):
    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (size, size))

    return limit


@pytest.mark.parametrize("command", ["run", "sweep"])
def test_a_full_disk_is_one_clear_message_and_exit_1(work, command):
    """Writes fail past a size (RLIMIT_FSIZE), as on a full disk: an OSError from write."""
    if command == "run":
        args, limit = ["run", "instance-1", "--t-end", "60", "--no-plots", "--out", "x"], 100_000
    else:  # a summary part takes 8 kB
        args = ["sweep", "bifurcation-omega", "--steps", "3", "--transient", "1", "--record", "1", "--workers", "1",
                "--no-plots", "--out", "x"]  # fmt: skip
        limit = 7_000
    done = oscillator(*args, cwd=work, preexec_fn=_limit_file_size(limit))
    assert done.returncode == 1, (done.stdout, done.stderr)
    message = done.stderr.strip()
    assert message.startswith("error: cannot write ") and "\n" not in message and "File too large" in message
    if command == "run":
        assert "nothing was written" in message and not (work / "x").exists()
        assert [p.name for p in work.iterdir()] == []
    else:
        assert "the points finished so far are kept" in message


# ----------------------------------------------------------------------------- signals

SLOW_FIGURES = """
import sys, time
import oscillator.report.figures as plotting
draw = plotting.write_figures
def slow(*args, **kwargs):
    print("drawing", file=sys.stderr, flush=True)
    time.sleep(60)
    return draw(*args, **kwargs)
plotting.write_figures = slow
from oscillator.cli.app import main
main(sys.argv[1:])
"""


def test_ctrl_c_while_the_figures_are_drawn_keeps_the_run_and_report_finishes_it(work):
    process = subprocess.Popen([sys.executable, "-c", SLOW_FIGURES, "run", CASE, "--out", "x"], cwd=work,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)  # fmt: skip
    assert process.stderr.readline().strip() == "drawing"
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=TIMEOUT)
    assert process.returncode == 130 and "Traceback" not in stderr, stderr
    assert stderr.startswith("error: interrupted; the run's tables are in x; `oscillator report x` makes")
    info = json.loads((work / "x" / "run.json").read_text())
    assert info["complete"] is True and info["pending"] == ["figures", "report"]
    assert pd.read_parquet(work / "x" / "events.parquet").shape[0] == 8
    finished = oscillator("report", "x", cwd=work)
    assert finished.returncode == 0, finished.stderr
    info = json.loads((work / "x" / "run.json").read_text())
    assert info["pending"] == [] and (work / "x" / "figures" / "fig-d-forces.svg").is_file()
    assert (work / "x" / "report.html").read_text().count("data:image/png;base64,") == 4


@pytest.mark.parametrize("delay", [0.15, 0.4, 1.0])
def test_ctrl_c_at_any_moment_of_the_start_is_one_line(work, delay):
    # a run of seconds even on a fast machine: the interrupt always comes before its end
    process = subprocess.Popen([COMMAND, "run", "instance-1", "--t-end", "20000", "-q",
                                "--no-plots", "--out", "x"], cwd=work, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)  # fmt: skip
    time.sleep(delay)
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=TIMEOUT)
    assert process.returncode == 130, stderr
    assert stderr.startswith("error: interrupted") and "Traceback" not in stderr, stderr
    if (work / "x").exists():  # interrupted while running, or after its tables were written
        info = json.loads((work / "x" / "run.json").read_text())
        assert info["status"] == "interrupted" or (info["status"] == "complete" and info["pending"] == ["report"])


SWEEP = ["sweep", "bifurcation-omega", "--steps", "8", "--transient", "10", "--record", "2", "--workers", "2",
         "--no-plots", "-q"]  # fmt: skip


@pytest.mark.parametrize("delay", [0.5, 2.0, 4.0])
def test_ctrl_c_to_a_whole_sweep_is_one_line_without_worker_tracebacks(work, delay):
    process = subprocess.Popen([COMMAND, *SWEEP, "--out", "s"], cwd=work,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               start_new_session=True)  # fmt: skip
    time.sleep(delay)
    os.killpg(process.pid, signal.SIGINT)  # as Ctrl-C in a terminal: the parent and its workers
    _, stderr = process.communicate(timeout=TIMEOUT)
    assert process.returncode in (0, 130), stderr
    if process.returncode == 130:
        assert stderr.count("\n") == 1 and stderr.startswith("error: interrupted"), stderr


def _descendants(pid: int) -> list[int]:
    """Every process below ``pid``: its children (the resource tracker, the fork server) and
    theirs (the workers, forked by the fork server)."""
    parents = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            parents[int(entry.name)] = int(fields[1])
    found, below = [], [pid]
    while below:
        parent = below.pop()
        children = [child for child, of in parents.items() if of == parent]
        found += children
        below += children
    return found


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads /proc")
def test_a_killed_sweep_leaves_no_worker_behind(work):
    process = subprocess.Popen([COMMAND, *SWEEP, "--steps", "40", "--out", "s"], cwd=work,
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)  # fmt: skip
    deadline = time.monotonic() + TIMEOUT
    while time.monotonic() < deadline and not list((work / "s").glob("parts/*.summary.parquet")):
        time.sleep(0.1)
    children = _descendants(process.pid)
    assert len(children) >= 3, children  # the two workers and the resource tracker (and a fork server)
    process.kill()
    process.wait()
    deadline = time.monotonic() + TIMEOUT
    while time.monotonic() < deadline and any(_alive(pid) for pid in children):
        time.sleep(0.2)
    assert not [pid for pid in children if _alive(pid)]


# ----------------------------------------------------------------------------- damaged folders


def _python_edit(path: Path, edit) -> None:
    frame = pd.read_parquet(path)
    edit(frame)
    frame.to_parquet(path)


def _json_edit(path: Path, edit) -> None:
    data = json.loads(path.read_text())
    edit(data)
    path.write_text(json.dumps(data))


DAMAGE = {
    "run.json not JSON": (lambda d: (d / "run.json").write_text("{not json"), ["run.json is damaged", "not JSON"]),
    "run.json a list": (lambda d: (d / "run.json").write_text("[1, 2]"), ["run.json is damaged", "JSON object"]),
    "run.json not UTF-8": (lambda d: (d / "run.json").write_bytes(b"\xff\xfe{}"), ["run.json is not UTF-8"]),
    "run.json of 2 MB": (lambda d: (d / "run.json").write_text(" " * 2_000_000 + "{}"), ["larger than"]),
    "run.json a FIFO": (lambda d: ((d / "run.json").unlink(), os.mkfifo(d / "run.json")), ["not a regular file"]),
    "energy not a number": (
        lambda d: _json_edit(d / "run.json", lambda j: j["energy"].update(E0="x")),
        ["energy.E0 is not a number"],
    ),
    "status unknown": (lambda d: _json_edit(d / "run.json", lambda j: j.update(status="<b>")), ["status must be"]),
    "t_final a text": (lambda d: _json_edit(d / "run.json", lambda j: j.update(t_final="x")), ["t_final"]),
    "events garbage": (lambda d: (d / "events.parquet").write_text("garbage"), ["events.parquet is damaged"]),
    "events without t": (
        lambda d: _python_edit(d / "events.parquet", lambda f: f.pop("t")),
        ["events.parquet is damaged", "column 't'"],
    ),
    "events kind unknown": (
        lambda d: _python_edit(d / "events.parquet", lambda f: f.__setitem__("kind", "<i>")),
        ["unknown event kind"],
    ),
    "events time a text": (
        lambda d: _python_edit(d / "events.parquet", lambda f: f.__setitem__("t", "x")),
        ["column 't' must hold numbers"],
    ),
    "events times NaN": (
        lambda d: _python_edit(d / "events.parquet", lambda f: f.__setitem__("t", float("nan"))),
        ["column 't' must hold finite times"],
    ),
    "trajectory missing": (lambda d: (d / "trajectory.parquet").unlink(), ["trajectory.parquet is missing"]),
    "trajectory garbage": (
        lambda d: (d / "trajectory.parquet").write_text("garbage"),
        ["trajectory.parquet is damaged"],
    ),
    "trajectory state unknown": (
        lambda d: _python_edit(d / "trajectory.parquet", lambda f: f.__setitem__("system_state", "X-z")),
        ["system state"],
    ),
    "trajectory domain unknown": (
        lambda d: _python_edit(d / "trajectory.parquet", lambda f: f.__setitem__("domain2", 3)),
        ["domain"],
    ),
    "case.toml missing": (lambda d: (d / "case.toml").unlink(), ["case.toml is missing"]),
    "case.toml garbage": (lambda d: (d / "case.toml").write_text("= ="), ["malformed TOML"]),
    "events.csv only, wrong": (
        lambda d: ((d / "events.parquet").unlink(), (d / "events.csv").write_text("a,b\n")),
        ["events.csv is damaged"],
    ),
}


@pytest.fixture(scope="module")
def finished_run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("finished") / "run"
    done = oscillator("run", CASE, "--out", folder, "-q", cwd=folder.parent)
    assert done.returncode == 0, done.stderr
    return folder


@pytest.mark.parametrize("damage", sorted(DAMAGE))
def test_report_of_a_damaged_folder_names_the_file(tmp_path, finished_run, damage):
    import shutil

    folder = tmp_path / "run"
    shutil.copytree(finished_run, folder)
    spoil, fragments = DAMAGE[damage]
    spoil(folder)
    before = snapshot(tmp_path)
    done = oscillator("report", folder, cwd=tmp_path)
    assert_refused(done, *fragments, cwd=tmp_path, before=before)


def test_report_redraws_missing_figures_and_shows_only_those_present(tmp_path, finished_run):
    import shutil

    folder = tmp_path / "run"
    shutil.copytree(finished_run, folder)
    (folder / "figures" / "fig-b-velocity.png").unlink()
    (folder / "figures" / "fig-c-phase.svg").write_bytes(b"")  # as a full disk leaves one
    done = oscillator("report", folder, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert (folder / "figures" / "fig-b-velocity.png").read_bytes()[:4] == b"\x89PNG"
    assert (folder / "figures" / "fig-c-phase.svg").stat().st_size > 0
    assert (folder / "report.md").read_text().count("](figures/fig-") == 4


@pytest.fixture(scope="module")
def finished_sweep(tmp_path_factory):
    folder = tmp_path_factory.mktemp("sweep") / "s"
    args = ["sweep", "bifurcation-omega", "--steps", "3", "--transient", "1", "--record", "1", "--workers", "1",
            "--no-plots", "-q", "--out", folder]  # fmt: skip
    done = oscillator(*args, cwd=folder.parent)
    assert done.returncode == 0, done.stderr
    return args, folder


SWEEP_DAMAGE = {
    "sweep.json not JSON": (lambda d: (d / "sweep.json").write_text("{"), ["sweep.json is damaged", "not JSON"]),
    "sweep.json a list": (lambda d: (d / "sweep.json").write_text("[]"), ["sweep.json is damaged"]),
    "parts missing": (lambda d: __import__("shutil").rmtree(d / "parts"), ["parts/ is missing"]),
    "a garbage part": (
        lambda d: (d / "parts" / "000001.switches.parquet").write_text("x"),
        ["000001.switches.parquet is damaged", "delete it"],
    ),
    "a stray file in parts": (lambda d: (d / "parts" / "notes.parquet").write_text("x"), ["notes.parquet"]),
}


@pytest.mark.parametrize("damage", sorted(SWEEP_DAMAGE))
def test_resuming_a_damaged_sweep_names_the_file(tmp_path, finished_sweep, damage):
    import shutil

    args, original = finished_sweep
    folder = tmp_path / "s"
    shutil.copytree(original, folder)
    spoil, fragments = SWEEP_DAMAGE[damage]
    spoil(folder)
    before = snapshot(tmp_path)
    done = oscillator(*args[:-1], folder, cwd=tmp_path)
    assert_refused(done, *fragments, cwd=tmp_path, before=before)


# ----------------------------------------------------------------------------- sweep and locate settings


@pytest.mark.parametrize(
    ("options", "fragments"),
    [
        (["--scheduler", "garbage"], ["--scheduler 'garbage' is not the address"]),
        (["--scheduler", "tcp://127.0.0.1:1"], ["cannot reach the Dask scheduler"]),
        (["--workers", "100000"], ["--workers must be a whole number"]),
        (["--workers", "0"], ["--workers must be a whole number"]),
        (["--steps", "1000000000000"], ["steps must be a whole number from 1 to 100,000"]),
        (["--record", "1000000000000"], ["record must be a whole number"]),
        (["--transient", "-1"], ["transient must be a whole number"]),
        (["--param", "Omgea"], ["did you mean 'Omega'"]),
        (["--from", "nan"], ["start must be finite"]),
    ],
)
def test_sweep_settings_are_refused_before_a_folder_exists(work, options, fragments):
    refused(work, "sweep", "bifurcation-omega", *options, "--out", "s", fragments=fragments)


@pytest.mark.parametrize(
    ("options", "fragments"),
    [
        (["--tolerance", "0"], ["--tolerance must be a width of at least"]),
        (["--tolerance", "-1"], ["--tolerance"]),
        (["--tolerance", "1e-30"], ["4 ulp"]),
        (["--tolerance", "nan"], ["--tolerance"]),
        (["--between", "1.6", "1.6"], ["two different values"]),
        (["--between", "1.6", "inf"], ["finite"]),
        (["--what", "chaos"], ["--what must be one of"]),
    ],
)
def test_locate_refuses_settings_it_could_never_finish_with(work, options, fragments):
    between = [] if "--between" in options else ["--between", "1.59", "1.61"]
    refused(work, "locate", "bifurcation-omega", *between, *options, fragments=fragments)
