"""Bad input to the global analyses' Python API: one InputError naming the field, before any work
(issue 35, hostile input IV, item 9), and a script without a ``__main__`` guard (item 3)."""

from __future__ import annotations

import contextlib
import re
import subprocess
import sys
import textwrap

import pytest

import oscillator
from oscillator import find_attractors, lyapunov
from oscillator.attractors.following import follow_attractors
from oscillator.errors import InputError

MISUSES = [
    # (call, the field the message names)
    (lambda: find_attractors("instance-1", settings="fast"), "settings"),
    (lambda: find_attractors("instance-1", workers="2"), "workers"),
    (lambda: find_attractors("instance-1", workers=0), "workers"),
    (lambda: find_attractors("instance-1", workers=-1), "workers"),
    (lambda: find_attractors("instance-1", workers=2.5), "workers"),
    (lambda: find_attractors("instance-1", workers=True), "workers"),
    (lambda: find_attractors("instance-1", workers=10**6), "workers"),  # at most 4 per core
    (lambda: find_attractors("instance-1", client="tcp://127.0.0.1:8786"), "client"),
    (lambda: find_attractors("instance-1", progress="x"), "progress"),
    (lambda: lyapunov("instance-1", progress="x"), "progress"),
    (lambda: follow_attractors("instance-1", "Q2", "abc"), "values"),
    (lambda: follow_attractors("instance-1", "Q2", (v for v in (70.0, 71.0))), "values"),
    (lambda: follow_attractors("instance-1", "Q2", [70.0, 71.0], settings="x"), "settings"),
    (lambda: follow_attractors("instance-1", "Q2", [70.0, 71.0], store="x"), "store"),
    (lambda: follow_attractors("instance-1", "Q2", [70.0, 71.0], workers=None, progress=1), "progress"),
    (lambda: oscillator.read_run(None), "folder"),
    (lambda: oscillator.read_run(123), "folder"),
    (lambda: oscillator.read_run(b"runs/x"), "folder"),
    # wrong exception types once (TypeError, AttributeError)
    (lambda: oscillator.design("instance-1", {"d1": (3, 4)}, {"Omega": (1.4, 1.6)}, None), "objective"),
    (lambda: oscillator.design("instance-1", {"d1": (3, 4)}, {"Omega": (1.4, 1.6)}, "x_max_m1", store="x"), "store"),
    (lambda: oscillator.sensitivities(None, ["d1"]), "orbit"),
    (lambda: oscillator.frequency_response("instance-1", store="/tmp/x"), "store"),
    (lambda: find_attractors("instance-1", settings=oscillator.AttractorSettings(engine="cvodes")), "engine"),
]


@pytest.mark.parametrize(("call", "field"), MISUSES)
def test_misuse_of_the_global_api_is_one_input_error_naming_the_field(call, field):
    with pytest.raises(InputError) as raised:
        call()
    assert raised.value.field == field
    assert field in str(raised.value)


def test_saving_to_something_that_is_not_a_folder_name_is_refused():
    result = oscillator.simulate("instance-1", t_end=1.5)
    for bad in (None, 5, b"x"):
        with pytest.raises(InputError, match="folder must be a folder's name"):
            result.save(bad)


def test_a_script_without_a_main_guard_gets_one_error_naming_the_guard(tmp_path):
    script = tmp_path / "plain.py"
    script.write_text(
        textwrap.dedent(
            """
            from oscillator import find_attractors
            from oscillator.errors import InputError
            try:
                find_attractors("instance-1", states=[[0, 0, 3, 0], [0, 0, 6, 0]], transient=2, record=2, workers=2)
            except InputError as error:
                print("REFUSED", error.field, error)
            """
        ),
        encoding="utf-8",
    )
    done = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr
    assert "REFUSED workers" in done.stdout
    assert 'if __name__ == "__main__":' in done.stdout
    assert "Traceback" not in done.stderr  # the workers end quietly: the parent alone explains


def test_the_same_script_with_the_guard_runs_on_two_workers(tmp_path):
    script = tmp_path / "guarded.py"
    script.write_text(
        textwrap.dedent(
            """
            from oscillator import find_attractors
            if __name__ == "__main__":
                found = find_attractors("instance-1", states=[[0, 0, 3, 0], [0, 0, 6, 0]], transient=2, record=2,
                                        workers=2)
                print("STARTS", len(found.labels))
            """
        ),
        encoding="utf-8",
    )
    done = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr
    assert "STARTS 2" in done.stdout


def test_a_scheduler_address_where_no_dask_scheduler_listens_is_refused_without_hanging(monkeypatch):
    """A web server (says nothing first), an SSH server (a banner Dask would read as a frame size of
    exabytes), a server that sends a size and then nothing (Dask waited forever) and one whose
    message is shorter than Dask's framing (a ``struct.error``): each refused in one line, within
    the greeting's time (10 s; 5 s here, the four tried at once)."""
    import concurrent.futures
    import http.server
    import socket
    import struct
    import threading

    import oscillator.analysis.execution as execution
    from oscillator.analysis.execution import connect

    monkeypatch.setattr(
        execution, "_GREETING_TIMEOUT", 5.0
    )  # the greeting threads send at once; 5 s even on a busy machine

    web = http.server.HTTPServer(("127.0.0.1", 0), http.server.SimpleHTTPRequestHandler)  # says nothing first
    threading.Thread(target=web.serve_forever, daemon=True).start()
    greetings = {
        "ssh": b"SSH-2.0-OpenSSH_9.2\r\n",
        "silent after its size": struct.pack("<Q", 100),
        "short": struct.pack("<Q", 4) + b"abcd",
    }
    servers = {name: socket.create_server(("127.0.0.1", 0)) for name in greetings}

    def greet(name: str) -> None:
        peer, _ = servers[name].accept()
        with peer, contextlib.suppress(OSError):  # the probe hangs up after the greeting
            peer.sendall(greetings[name])
            peer.recv(1)

    for name in greetings:
        threading.Thread(target=greet, args=(name,), daemon=True).start()
    addresses = {name: f"tcp://127.0.0.1:{server.getsockname()[1]}" for name, server in servers.items()}
    addresses["web"] = f"tcp://127.0.0.1:{web.server_address[1]}"
    expected = {
        "ssh": r"is not a Dask scheduler \(it sent b.SSH-2\.0-",
        "web": r"is not a Dask scheduler \(it said nothing within 5 s",
        "silent after its size": r"is not a Dask scheduler \(it announced a message of 100 bytes and sent 0 within",
        "short": r"is not a Dask scheduler \(it sent .*, a message of 4 bytes",
    }

    def refusal(name: str) -> str:
        with pytest.raises(InputError) as refused:
            connect(addresses[name])
        return str(refused.value)

    try:
        with concurrent.futures.ThreadPoolExecutor(len(addresses)) as pool:
            said = dict(zip(addresses, pool.map(refusal, addresses), strict=True))
    finally:
        web.shutdown()
        web.server_close()
        for server in servers.values():
            server.close()
    for name, pattern in expected.items():
        assert re.search(pattern, said[name]), (name, said[name])


COMMANDS_WITH_A_PARAMETER = [
    (["frc", "instance-1", "--param", "Omega", "1.5", "1.6", "--set", "Omega=9"], "Omega is given by --param"),
    (["atlas", "instance-1", "--x", "Omega", "1", "2", "3", "--y", "Q2", "70", "71", "3", "--set", "Q2=1"],
     "Q2 is given by --y"),
    (["sweep", "bifurcation-omega", "--set", "Omega=2"], "Omega is given by --param (or the case's [sweep])"),
    (["design", "instance-1", "--vary", "d1=3,4", "--over", "Omega", "1.4", "1.6", "--objective", "x_max_m1",
      "--set", "Omega=1.5"], "Omega is given by --over"),
    (["basins", "instance-1", "--x", "x1", "-1", "1", "3", "--y", "v1", "-1", "1", "3", "--set", "v1=2"],
     "v1 is given by --y"),
    (["attractors", "instance-1", "--param", "Q2", "--from", "71", "--to", "72", "--set", "Q2=3"],
     "Q2 is given by --param"),
    # the landing engines are those --help names
    (["frc", "instance-1", "--param", "Omega", "1.5", "1.6", "--engine", "scipy"],
     "--engine must be one of dop853, cvode, got 'scipy'"),
    (["atlas", "instance-1", "--x", "Omega", "1", "2", "3", "--y", "Q2", "70", "71", "3", "--engine", "sksundae"],
     "--engine must be one of dop853, cvode"),
    (["explore", "instance-1", "--engine", "scipy"], "--engine must be one of dop853, cvode"),
]  # fmt: skip


@pytest.mark.parametrize(("args", "said"), COMMANDS_WITH_A_PARAMETER)
def test_a_value_another_option_gives_or_an_engine_the_command_does_not_run_is_refused(tmp_path, capsys, args, said):
    """``--set Omega=9`` beside ``--param Omega`` was silently ignored (continue refused it); an
    engine --help does not list was run."""
    from oscillator.cli.app import main

    out = [] if args[0] == "explore" else ["--out", str(tmp_path / "out")]
    with pytest.raises(SystemExit) as done:
        main([*args, *out])
    error = capsys.readouterr().err
    assert done.value.code == 2 and error.startswith("error: ") and said in error, error
    assert list(tmp_path.iterdir()) == []


def test_unspecified_workers_are_every_core_except_for_few_starts(monkeypatch):
    """Without ``workers`` a many-start computation takes every core, but one below
    ``SERIAL_BELOW`` starts (a pool costs more than it gains there: measured in its comment);
    given workers are kept, and checked."""
    from oscillator.analysis.execution import SERIAL_BELOW, check_workers

    monkeypatch.setattr("os.cpu_count", lambda: 4)
    assert check_workers(None) == 4 and check_workers(None, starts=SERIAL_BELOW) == 4
    assert check_workers(None, starts=SERIAL_BELOW - 1) == 1 and check_workers(3, starts=10) == 3
    with pytest.raises(oscillator.InputError, match="workers must be a whole number from 1 to 16"):
        check_workers(17, starts=10)


class _Counted(BaseException):
    """Raised by the spy below once a command has said how many landings it runs."""


_ATLAS = ["atlas", "instance-1", "--x", "Omega", "1.3", "1.85"]
_FRC = ["frc", "instance-1", "--param", "Omega"]


@pytest.mark.parametrize(
    ("module", "arguments", "landings"),
    [
        ("plane", [*_ATLAS, "12", "--y", "Q2", "68.5", "72", "8"], 96),
        ("plane", [*_ATLAS, "5", "--y", "d1", "3.3", "4", "4", "--starts", "3"], 60),
        ("frequency", [*_FRC, "1.3", "1.85"], 2 * 41 + 5),
        ("frequency", [*_FRC, "1.5", "1.7", "--sweep", "21", "--seeds", "3", "--starts", "4"], 42 + 12),
    ],
)
def test_a_command_without_workers_asks_for_the_pool_by_its_landings(
    monkeypatch, tmp_path, module, arguments, landings
):
    """The atlas (points x starts) and the frequency response (two sweeps and the seeds' starts)
    pass their landings to ``check_workers``, so that without ``--workers`` a small one runs in the
    command's own process (``benchmarks/pool.py``: the 12 x 8 atlas 3.53 s on one worker, 4.98 s on
    two)."""
    from typer.testing import CliRunner

    from oscillator.analysis.execution import check_workers
    from oscillator.cli.app import app

    asked = []

    def spy(workers, starts=None):
        asked.append((workers, starts, check_workers(workers, starts=starts)))
        raise _Counted

    monkeypatch.setattr("os.cpu_count", lambda: 4)
    monkeypatch.setattr(f"oscillator.cli.{module}.check_workers", spy)
    with pytest.raises(_Counted):  # a BaseException: the runner lets it through
        CliRunner().invoke(app, [*arguments, "--out", str(tmp_path / "out")])
    assert asked == [(None, landings, 1)]
