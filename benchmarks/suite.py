"""What a new user waits for, measured: the first ``oscillator run`` after an install (numba's
cache empty, the kernels compiled) against the next, and the README's test run (the default tier)
on an empty cache and a filled one; ``--slow`` times the slow end-to-end tier too, and
``--install`` the README's install of the test extra into a fresh virtual environment, by pip and
by uv (the README's), each with an empty download cache of its own (as on a fresh machine).  Each
is one run, in a fresh process, with the date, the cores and the load average before it printed
beside: the README's durations are this script's.

Usage: python benchmarks/suite.py [--install] [--slow] [--no-tests]
"""

from __future__ import annotations

import argparse
import datetime
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def timed(command: list[str], env: dict[str, str], cwd: Path) -> tuple[float, str]:
    """Wall time of ``command`` and its last line of output; a failure stops the benchmark."""
    load = os.getloadavg()[0]
    started = time.perf_counter()
    done = subprocess.run(command, env=env, cwd=cwd, capture_output=True, text=True)
    wall = time.perf_counter() - started
    if done.returncode != 0:
        sys.exit(f"{' '.join(command)} failed ({done.returncode}):\n{done.stdout[-2000:]}{done.stderr[-2000:]}")
    last = (done.stdout.strip().splitlines() or [""])[-1]
    print(f"    (load average before: {load:.2f})")
    return wall, last


#: The two ways to install the test extra into a fresh ``.venv``: pip's, and the README's (uv, its
#: modules compiled to bytecode as pip compiles them).
INSTALLS = {
    "pip": 'python3 -m venv .venv && .venv/bin/pip install -q ".[test]"',
    "uv": "python3 -m venv .venv && .venv/bin/pip install -q uv && "
    '.venv/bin/uv pip install -q --python .venv --compile-bytecode ".[test]"',
}


def installs(work: Path) -> None:
    """Each of :data:`INSTALLS` in a fresh clone of this checkout, its download cache empty."""
    for name, command in INSTALLS.items():
        clone = work / f"install-{name}"
        subprocess.run(["git", "clone", "-q", str(ROOT), str(clone)], check=True)
        caches = {"PIP_NO_CACHE_DIR": "1", "UV_CACHE_DIR": str(work / f"uv-cache-{name}")}
        wall, _ = timed(["bash", "-c", command], {**os.environ, **caches}, clone)
        print(f"install of the test extra by {name}, download cache empty: {wall:.1f} s")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--slow", action="store_true", help="time the slow end-to-end tier too")
    parser.add_argument("--no-tests", action="store_true", help="time the first run only")
    parser.add_argument("--install", action="store_true", help="time the install by pip and by uv first")
    options = parser.parse_args()
    oscillator = str(Path(sys.executable).with_name("oscillator"))
    print(f"{datetime.date.today()}, {len(os.sched_getaffinity(0))} cores, Python {sys.version.split()[0]}")
    with tempfile.TemporaryDirectory() as scratch:
        work = Path(scratch)
        if options.install:
            installs(work)
        env = {**os.environ, "NUMBA_CACHE_DIR": str(work / "cache")}
        for k, label in enumerate(("empty cache (compiles)", "cache filled")):
            wall, _ = timed([oscillator, "run", "instance-3", "--out", str(work / f"run-{k}"), "-q"], env, work)
            print(f"oscillator run instance-3, {label}: {wall:.1f} s (figures and report included)")
        if options.no_tests:
            return
        # the pytest script, as the README runs it: the installed package, not the source tree
        pytest = [str(Path(sys.executable).with_name("pytest")), "-q", "-p", "no:cacheprovider"]
        env = {**os.environ, "NUMBA_CACHE_DIR": str(work / "suite-cache")}
        for label in ("empty cache (a fresh install)", "cache filled"):
            wall, last = timed(pytest, env, ROOT)
            print(f"default tier, {label}: {wall:.1f} s wall; pytest: {re.sub(r'=+', '', last).strip()}")
        if options.slow:
            wall, last = timed([*pytest, "-m", "slow"], env, ROOT)
            print(f"slow tier: {wall:.1f} s wall; pytest: {re.sub(r'=+', '', last).strip()}")


if __name__ == "__main__":
    main()
