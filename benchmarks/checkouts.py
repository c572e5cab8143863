"""The benchmarks' comparison with an earlier checkout: the same calls in a fresh process on this code
and on the code of ``--against DIR`` (a checkout of an earlier commit, ``git worktree add DIR REV``),
alternating so that a busy spell slows both, the minimum of the repeats each (:func:`alternating`).

A call script prints, as its last line, a JSON object ``{name: [seconds, answer]}``; it runs with
the checkout first on ``sys.path`` and asserts that it imported the package from there.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]

__all__ = ["ROOT", "alternating", "fastest", "script", "timed"]

_TIMING = """
import json as _json, time as _time
_timed = {}
for _name in _NAMES:
    _call = globals()[_name]
    _call()  # numba's cache loaded, the code warm
    _started = _time.perf_counter()
    _answer = _call()
    _timed[_name] = (_time.perf_counter() - _started, _answer)
print(_json.dumps(_timed))
"""


def script(body: str, names: tuple[str, ...]) -> str:
    """A call script: ``body`` (which defines the functions ``names``), then each called twice, the
    second time timed, and the times and answers printed as its last line."""
    return f"{body}\n_NAMES = {names!r}\n{_TIMING}"


def timed(code: Path, calls: str, *args: str) -> dict[str, tuple[float, Any]]:
    """The calls' times and answers in a fresh process on the package at ``code``."""
    env = {**os.environ, "PYTHONPATH": str(code)}
    done = subprocess.run(  # run in ``code``: ``-c`` puts the working folder first on the path
        [sys.executable, "-c", calls, str(code), *args], cwd=code, env=env, capture_output=True, text=True
    )
    if done.returncode != 0:
        raise SystemExit(f"the calls failed on {code}:\n{done.stderr[-3000:]}")
    found: dict[str, tuple[float, Any]] = json.loads(done.stdout.splitlines()[-1])
    return found


def alternating(against: Path, calls: str, *args: str, repeats: int) -> dict[str, list[dict[str, tuple[float, Any]]]]:
    """``{"before": [...], "now": [...]}``: :func:`timed` on ``against`` and on this code in turn,
    ``repeats`` times each."""
    runs: dict[str, list[dict[str, tuple[float, Any]]]] = {"before": [], "now": []}
    for _ in range(repeats):
        runs["before"].append(timed(against.resolve(), calls, *args))
        runs["now"].append(timed(ROOT, calls, *args))
    return runs


def fastest(runs: list[dict[str, tuple[float, Any]]], name: str) -> float:
    """The least time of the call ``name`` over ``runs``."""
    return min(run[name][0] for run in runs)
