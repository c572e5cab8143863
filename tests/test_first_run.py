"""The first run after an install compiles the kernels: the command says so, at once."""

from __future__ import annotations

import sys
import time
import types

import pytest

from oscillator.cli import console


@pytest.fixture
def fresh(monkeypatch):
    monkeypatch.setattr(console, "_noticed", False)
    return monkeypatch


def test_an_empty_cache_is_announced_before_the_loading(fresh, capsys):
    fresh.setattr("oscillator.compiled.kernels_cached", lambda: False)
    console.load("json", notice=True)
    assert capsys.readouterr().err.startswith(console.COMPILING)
    console.load("json", notice=True)  # once per process
    assert capsys.readouterr().err == ""


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


def test_the_cache_in_use_is_found():
    """This test run's kernels are loaded, so numba's cache holds them."""
    import oscillator.model.theorems  # noqa: F401
    from oscillator.compiled import kernels_cached

    assert kernels_cached()
