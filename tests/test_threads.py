"""One BLAS thread (oscillator/threads.py): in the package's process whatever was imported
first, in the processes it starts, and none imposed where the user chose a number."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from oscillator.threads import CHOSEN

#: Prints the threads of every BLAS library loaded, after the imports ``argv[1]`` names.
THREADS = """
import importlib, json, sys
for name in sys.argv[1].split(","):
    importlib.import_module(name)
import scipy.linalg
from threadpoolctl import threadpool_info
print(json.dumps([pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"]))
"""

#: Prints what :data:`THREADS` prints in a process started by one that imported the package
#: (the package's workers are spawned the same way: a fresh interpreter, the parent's environment).
CHILD = """
import subprocess, sys
import oscillator
print(subprocess.run([sys.executable, "-c", sys.argv[1], "numpy"], capture_output=True, text=True, check=True).stdout)
"""


def _threads(code: str, *args: str, **chosen: str) -> list[int]:
    environment = {k: v for k, v in os.environ.items() if k not in CHOSEN} | chosen
    done = subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, env=environment,
                          check=True)  # fmt: skip
    threads: list[int] = json.loads(done.stdout)
    return threads


@pytest.mark.parametrize("imports", ["oscillator", "numpy,scipy.linalg,oscillator", "numpy,oscillator"])
def test_the_package_runs_blas_on_one_thread_whatever_was_imported_first(imports):
    threads = _threads(THREADS, imports)
    assert threads and all(n == 1 for n in threads), threads


def test_the_workers_it_starts_run_blas_on_one_thread():
    threads = _threads(CHILD, THREADS)
    assert threads and all(n == 1 for n in threads), threads


@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="BLAS runs one thread on one core anyway")
def test_a_number_the_user_chose_is_left_as_chosen():
    chosen = _threads(THREADS, "oscillator", OPENBLAS_NUM_THREADS="2")
    without = _threads(THREADS, "numpy", OPENBLAS_NUM_THREADS="2")
    assert chosen == without and all(n == 2 for n in chosen), (chosen, without)
