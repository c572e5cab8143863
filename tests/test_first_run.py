"""The first run after an install compiles the kernels: the command says so at once, shows which
kernels it compiles, and has a second process compile the engine's meanwhile."""

from __future__ import annotations

import os
import subprocess
import sys
import time
import types
from pathlib import Path
from typing import ClassVar

import pytest

from oscillator.cli import console


class FakeHelper:
    """Stands for the second process: records what it was asked to import."""

    started: ClassVar[list[list[str]]] = []

    def __init__(self, command, **_):
        FakeHelper.started.append(command)
        self.waited = False

    def poll(self):
        return 0

    def wait(self, timeout=None):
        self.waited = True
        return 0


@pytest.fixture
def fresh(monkeypatch):
    monkeypatch.setattr(console, "_noticed", False)
    monkeypatch.setattr(console, "_checked", False)
    FakeHelper.started = []
    monkeypatch.setattr(console.subprocess, "Popen", FakeHelper)
    return monkeypatch


def test_an_empty_cache_is_announced_before_the_loading(fresh, capsys):
    fresh.setattr("oscillator.compiled.kernels_cached", lambda: False)
    console.load("json", notice=True)
    assert capsys.readouterr().err.startswith(console.COMPILING)
    console.load("json", notice=True)  # once per process
    assert capsys.readouterr().err == ""


def test_the_kernels_are_compiled_in_order_with_the_engine_s_beside(fresh):
    imported = []
    real = console.importlib.import_module
    fresh.setattr(console.importlib, "import_module", lambda name: imported.append(name) or real(name))
    fresh.setattr(console.os, "sched_getaffinity", lambda _: {0, 1})
    console.compile_kernels(beside=True)
    assert imported == [name for name, _ in console.KERNELS]
    (command,) = FakeHelper.started
    assert command[0] == sys.executable and command[-len(console.BESIDE) :] == list(console.BESIDE)
    assert set(console.BESIDE) < {name for name, _ in console.KERNELS}


def test_one_core_or_no_cache_compiles_without_a_second_process(fresh):
    fresh.setattr(console.os, "sched_getaffinity", lambda _: {0})
    console.compile_kernels(beside=True)
    fresh.setattr(console.os, "sched_getaffinity", lambda _: {0, 1})
    console.compile_kernels(beside=False)
    assert FakeHelper.started == []


def test_a_second_process_that_hangs_is_killed_and_the_kernels_compiled_here(fresh):
    killed = []

    class Hanging(FakeHelper):
        def poll(self):
            return None

        def wait(self, timeout=None):
            if timeout is not None and not killed:
                raise subprocess.TimeoutExpired("helper", timeout)
            return -9

        def kill(self):
            killed.append(True)

    fresh.setattr(console.subprocess, "Popen", Hanging)
    fresh.setattr(console.os, "sched_getaffinity", lambda _: {0, 1})
    console.compile_kernels(beside=True)
    assert killed


def test_a_slow_load_is_announced_even_with_a_cache(fresh, capsys):
    fresh.setattr("oscillator.compiled.kernels_cached", lambda: True)
    fresh.setattr(console, "SLOW_LOAD", 0.05)
    slow = types.ModuleType("slow_to_load")
    fresh.setitem(sys.modules, "slow_to_load", slow)

    def loading(name):  # a load that lasts until the notice came, however busy the machine
        deadline = time.monotonic() + 60
        while not console._noticed and time.monotonic() < deadline:
            time.sleep(0.01)
        return slow

    fresh.setattr(console.importlib, "import_module", loading)
    console.load("slow_to_load", notice=True)
    assert capsys.readouterr().err.startswith(console.COMPILING)


def test_a_quick_load_with_a_cache_and_a_quiet_command_say_nothing(fresh, capsys):
    fresh.setattr("oscillator.compiled.kernels_cached", lambda: True)
    console.load("json", notice=True)
    fresh.setattr("oscillator.compiled.kernels_cached", lambda: False)
    console.load("json", notice=False)
    assert capsys.readouterr().err == ""


def test_a_quiet_first_run_compiles_the_same_way_and_says_nothing(fresh, capsys):
    calls = []
    fresh.setattr("oscillator.compiled.kernels_cached", lambda: False)
    fresh.setattr(console, "compile_kernels", lambda **kw: calls.append(kw))
    console.load("json")  # modules that need no kernels: nothing compiled
    assert calls == []
    console.load("json", notice=False)
    console.load("json", notice=False)  # the cache is looked at once per process
    assert calls == [{"beside": console_cache(), "show": False}]
    assert capsys.readouterr().err == ""


def console_cache() -> bool:
    from oscillator.compiled import CACHE

    return CACHE


def test_the_cache_in_use_is_found():
    """This test run's kernels are loaded, so numba's cache holds them."""
    import oscillator.model.theorems  # noqa: F401
    from oscillator.compiled import kernels_cached

    assert kernels_cached()


@pytest.mark.slow
def test_the_first_run_after_an_install_compiles_says_so_and_the_next_does_not(tmp_path):
    """numba's cache empty (a fresh install): the README's first command compiles, says so, and
    gives the same run as with the cache filled."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    command = [sys.executable, "-m", "oscillator", "run", "instance-3", "--no-plots", "--no-report"]
    first = subprocess.run([*command, "--out", str(tmp_path / "a")], env=env, capture_output=True, text=True)
    assert first.returncode == 0, first.stderr
    assert first.stderr.startswith(console.COMPILING)
    assert "expected events within tolerance: 6/6" in first.stdout
    assert any(Path(tmp_path / "cache").rglob("callbacks.*.nbi"))
    second = subprocess.run([*command, "--out", str(tmp_path / "b")], env=env, capture_output=True, text=True)
    assert second.returncode == 0 and console.COMPILING not in second.stderr
    a, b = (Path(tmp_path / x / "events.csv").read_text() for x in "ab")
    assert a == b


@pytest.mark.slow
def test_a_python_programs_first_simulation_says_that_it_compiles(tmp_path):
    """The first simulate of a program on a fresh install compiled for 17 s in silence: it says so
    once on stderr (not the command, which says it its own way), and the next program says nothing."""
    from oscillator.compiled import COMPILING

    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    env.pop("OSCILLATOR_COMPILE_NOTICE", None)
    code = "import oscillator; print(len(oscillator.simulate('instance-3').events))"
    first = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, cwd=tmp_path)
    assert first.returncode == 0 and first.stderr.count(COMPILING) == 1, first.stderr
    second = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, cwd=tmp_path)
    assert second.returncode == 0 and second.stderr == "" and second.stdout == first.stdout


def test_the_tests_silence_the_packages_own_compile_notice_by_its_name():
    """tests/conftest.py writes the notice's variable out (importing oscillator.compiled says the
    notice): the two names are one."""
    from conftest import NOTICE
    from oscillator.compiled import NOTICE_VARIABLE

    assert NOTICE == NOTICE_VARIABLE
