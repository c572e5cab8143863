"""The local pool's workers (oscillator/analysis/execution.py): forked from one fork server for
all the pools of a process, each with the folder and the environment its pool's caller had."""

from __future__ import annotations

import multiprocessing
import os

import pytest

from oscillator.analysis.execution import START_METHOD, Executor


def _ask(function, tasks) -> list:
    with Executor(workers=2) as executor:
        return list(executor.map(function, tasks))


@pytest.mark.skipif("forkserver" not in multiprocessing.get_all_start_methods(), reason="no fork server here")
def test_later_pools_fork_from_one_server_with_the_callers_folder_and_environment(tmp_path, monkeypatch):
    assert START_METHOD == "forkserver"
    monkeypatch.setenv("OSCILLATOR_POOL_MARK", "first")
    first = _ask(os.getppid, [()] * 8)
    assert _ask(os.getenv, [("OSCILLATOR_POOL_MARK",)] * 8) == ["first"] * 8
    monkeypatch.setenv("OSCILLATOR_POOL_MARK", "second")  # after the server started: its workers are told
    monkeypatch.chdir(tmp_path)
    second = _ask(os.getppid, [()] * 8)
    assert _ask(os.getenv, [("OSCILLATOR_POOL_MARK",)] * 8) == ["second"] * 8
    assert _ask(os.getcwd, [()] * 8) == [str(tmp_path)] * 8
    (server,) = set(first) | set(second)  # every worker of both pools: the fork server's child
    assert server != os.getpid()
