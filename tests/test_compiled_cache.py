"""numba's cache of the compiled kernels: an install that cannot be written, and damaged files.

Each test runs the command in a subprocess with its own cache folder, so that the shared one
is never touched.  They compile the kernels from scratch (about 15 s each): marked slow.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

pytestmark = pytest.mark.slow

RUN = ["run", "instance-1", "--no-plots", "--no-report", "-q"]

#: The command with every folder but the allowed ones read-only to it (as for a user of a shared,
#: read-only install): creating a file anywhere else fails with EACCES, as numba's and our own
#: probes of a cache folder do it (``tempfile.TemporaryFile(dir=...)``).
READ_ONLY = """
import errno, os, sys, tempfile
allowed = [os.path.realpath(p) for p in os.environ["ALLOWED"].split(os.pathsep) if p]
make = tempfile.TemporaryFile
def refused(*args, dir=None, **kwargs):
    where = os.path.realpath(dir or tempfile.gettempdir())
    if not any(where == a or where.startswith(a + os.sep) for a in allowed):
        raise PermissionError(errno.EACCES, "Permission denied", where)
    return make(*args, dir=dir, **kwargs)
tempfile.TemporaryFile = refused
from oscillator.cli.app import main
main(sys.argv[1:])
"""


def command(args, *, env, cwd, script=None):
    base = [sys.executable, "-c", script, *args] if script else [sys.executable, "-m", "oscillator", *args]
    return subprocess.run(base, cwd=cwd, env=env, capture_output=True, text=True, timeout=300)


def events(folder: Path) -> pd.DataFrame:
    return pd.read_parquet(folder / "events.parquet")


def test_a_damaged_cache_is_compiled_afresh(tmp_path):
    """Emptied, truncated and garbage cache files: the next run compiles what it cannot read,
    gives the same events, and leaves files that the run after reads."""
    cache = tmp_path / "cache"
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    first = command([*RUN, "--out", "a"], env=env, cwd=tmp_path)
    assert first.returncode == 0, first.stderr
    index, data = sorted(cache.rglob("*.nbi")), sorted(cache.rglob("*.nbc"))
    assert len(index) > 20 and len(data) > 20
    for k, path in enumerate(index):
        path.write_bytes(b"" if k % 2 else path.read_bytes()[:20])
    for path in data[::2]:
        path.write_bytes(b"not a pickle at all")
    second = command([*RUN, "--out", "b"], env=env, cwd=tmp_path)
    assert second.returncode == 0 and "Traceback" not in second.stderr, second.stderr
    pd.testing.assert_frame_equal(events(tmp_path / "a"), events(tmp_path / "b"))
    assert all(path.stat().st_size > 20 for path in index)  # rewritten whole
    assert not any(path.read_bytes() == b"not a pickle at all" for path in data[::2])
    third = command([*RUN, "--out", "c"], env=env, cwd=tmp_path)
    assert third.returncode == 0, third.stderr
    pd.testing.assert_frame_equal(events(tmp_path / "a"), events(tmp_path / "c"))


def test_a_read_only_install_caches_in_a_private_temporary_folder(tmp_path):
    """The package's folder and the home cannot be written: the cache goes to
    ``$TMPDIR/oscillator-numba-<uid>`` (private to the user), and matplotlib's folder likewise;
    nothing is printed but the result."""
    scratch, home = tmp_path / "tmp", tmp_path / "home"
    scratch.mkdir()
    env = {k: v for k, v in os.environ.items() if not k.startswith(("NUMBA_", "MPLCONFIGDIR", "XDG_"))}
    env.update(TMPDIR=str(scratch), HOME=str(home), ALLOWED=os.pathsep.join([str(scratch), str(tmp_path / "out")]))
    done = command([*RUN[:2], "-q", "--out", str(tmp_path / "out")], env=env, cwd=tmp_path, script=READ_ONLY)
    assert done.returncode == 0, done.stderr
    assert done.stderr == "" and done.stdout.strip() == str(tmp_path / "out")
    cache = scratch / f"oscillator-numba-{os.getuid()}"
    assert len(list(cache.rglob("*.nbi"))) > 20 and oct(cache.stat().st_mode & 0o777) == "0o700"
    assert (scratch / f"oscillator-matplotlib-{os.getuid()}").is_dir()  # and matplotlib did not warn (stderr)
    assert json.loads((tmp_path / "out" / "run.json").read_text())["pending"] == []
    helped = command(["--help"], env=env, cwd=tmp_path, script=READ_ONLY)
    assert helped.returncode == 0 and "Usage" in helped.stdout


def test_with_nowhere_to_write_a_cache_the_kernels_are_compiled_each_time(tmp_path):
    """Not even the temporary folder can be written: the run compiles without a cache and
    finishes, instead of numba's "cannot cache function ... no locator available"."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")}
    env.update(HOME="/nonexistent", TMPDIR=str(tmp_path / "tmp-missing"), ALLOWED=str(tmp_path / "out"))
    done = command([*RUN, "--out", str(tmp_path / "out")], env=env, cwd=tmp_path, script=READ_ONLY)
    assert done.returncode == 0, done.stderr
    assert "Traceback" not in done.stderr and "cannot cache" not in done.stderr
    assert len(events(tmp_path / "out")) == 2
