"""numba's cache of the compiled kernels: an install that cannot be written, and damaged files.

The end-to-end test runs the command in subprocesses with their own cache folder, so that the
shared one is never touched; it compiles the kernels from scratch once (about 20 s) and a few damaged ones again:
marked slow.  Where the cache goes when nothing can be written is checked in this process.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

RUN = ["run", "instance-1", "--no-report", "-q"]

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


def command(args, *, env, cwd):
    return subprocess.run([sys.executable, "-c", READ_ONLY, *map(str, args)], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=600)  # fmt: skip


def events(folder: Path) -> pd.DataFrame:
    return pd.read_parquet(folder / "events.parquet")


#: The package's folders whose modules hold compiled (cached) kernels.
COMPILED_FOLDERS = {"model", "engines", "orbits", "hybrid"}


def installed_package(cwd: Path) -> Path:
    """The folder of the package the command runs (the installed one: in a source checkout,
    the tests' own process may import the source tree instead)."""
    done = subprocess.run([sys.executable, "-c", "import oscillator; print(oscillator.__file__)"], cwd=cwd,
                          capture_output=True, text=True, check=True)  # fmt: skip
    return Path(done.stdout.strip()).parent


def seed_private_cache(cache: Path, package: Path) -> int:
    """Copy the kernels the installed ``package`` has compiled (its ``__pycache__`` folders) into
    the private cache folder, laid out as numba lays out a cache folder it is given (a
    subfolder per source folder: :meth:`_CacheLocator.get_suitable_cache_subpath`), so that the
    runs below load them instead of compiling all of them again (about 25 s); the damaged ones
    are compiled there.  Returns the number of index files copied."""
    import shutil

    from numba.core.caching import _CacheLocator

    copied = 0
    cache.mkdir(mode=0o700)
    for folder in package.rglob("__pycache__"):
        for path in [*folder.glob("*.nbi"), *folder.glob("*.nbc")]:
            source = folder.parent / (path.name.split(".")[0] + ".py")
            target = cache / _CacheLocator.get_suitable_cache_subpath(str(source))
            target.mkdir(mode=0o700, exist_ok=True)
            shutil.copy2(path, target / path.name)
            copied += path.suffix == ".nbi"
    return copied


@pytest.mark.slow
def test_a_read_only_install_caches_privately_and_a_damaged_cache_is_compiled_afresh(tmp_path):
    """The package's folder and the home cannot be written: the cache goes to
    ``$TMPDIR/oscillator-numba-<uid>`` (private to the user), matplotlib's folder likewise, and
    nothing is printed but the result.  Then the cache files are emptied, truncated and
    overwritten with garbage: the next run compiles what it cannot read, gives the same events
    and rewrites the files there, and the run after reads them.  (The folder starts with this
    install's compiled kernels: compiling them all from scratch would add about 25 s and show
    nothing the damaged ones do not.)"""
    scratch, out = tmp_path / "tmp", tmp_path / "out"
    scratch.mkdir()
    out.mkdir()
    env = {k: v for k, v in os.environ.items() if not k.startswith(("NUMBA_", "MPLCONFIGDIR", "XDG_"))}
    env.update(TMPDIR=str(scratch), HOME=str(tmp_path / "home"), ALLOWED=os.pathsep.join([str(scratch), str(out)]))

    cache = scratch / f"oscillator-numba-{os.getuid()}"
    seeded = seed_private_cache(cache, installed_package(tmp_path))
    first = command([*RUN, "--out", out / "a"], env=env, cwd=tmp_path)
    assert first.returncode == 0, first.stderr
    assert first.stderr == "" and first.stdout.strip() == str(out / "a")  # no warning of numba or matplotlib
    index, data = sorted(cache.rglob("*.nbi")), sorted(cache.rglob("*.nbc"))
    # one folder per package folder that holds compiled kernels (numba's layout), none elsewhere
    assert len(index) >= seeded and {path.parent.name.split("_")[0] for path in index} <= COMPILED_FOLDERS
    assert len(index) > 20 and len(data) > 20 and oct(cache.stat().st_mode & 0o777) == "0o700"
    assert (scratch / f"oscillator-matplotlib-{os.getuid()}").is_dir()
    assert json.loads((out / "a" / "run.json").read_text())["pending"] == []
    assert (out / "a" / "figures" / "fig-a-displacement.png").stat().st_size > 0  # drawn, matplotlib quiet

    # Kernels with a signature (loaded at import), each with one kind of damage (compiled again).
    def named(files, *prefixes):
        return [path for path in files if path.name.startswith(prefixes)]

    emptied, truncated = named(index, "theorems.is_zero-"), named(index, "theorems.passable-")
    garbage = named(data, "theorems.grazing-")
    assert len(emptied) == len(truncated) == len(garbage) == 1
    for path in emptied:
        path.write_bytes(b"")
    for path in truncated:
        path.write_bytes(path.read_bytes()[:20])
    for path in garbage:
        path.write_bytes(b"not a pickle at all")
    second = command([*RUN, "--no-plots", "--out", out / "b"], env=env, cwd=tmp_path)
    assert second.returncode == 0 and "Traceback" not in second.stderr, second.stderr
    pd.testing.assert_frame_equal(events(out / "a"), events(out / "b"))
    assert all(path.stat().st_size > 20 for path in emptied + truncated)  # rewritten whole
    assert not any(path.read_bytes() == b"not a pickle at all" for path in garbage)

    third = command([*RUN, "--no-plots", "--out", out / "c"], env=env, cwd=tmp_path)
    assert third.returncode == 0, third.stderr
    pd.testing.assert_frame_equal(events(out / "a"), events(out / "c"))


def test_with_nowhere_to_write_the_kernels_compile_without_a_cache(monkeypatch):
    """Not even the temporary folder can be written: no cache location, and ``cache=True`` is
    dropped from the kernels' decorators (numba would refuse it: "cannot cache function ... no
    locator available")."""
    import numba

    from oscillator import compiled

    monkeypatch.setattr(numba.config, "CACHE_DIR", "", raising=False)
    monkeypatch.setattr(compiled, "writable", lambda folder: False)
    monkeypatch.setattr(compiled, "private_scratch", lambda name: None)
    assert compiled._cache_location() is None
    seen = {}
    monkeypatch.setattr(compiled, "CACHE", False)
    compiled._cached(lambda *args, **options: seen.update(options))(cache=True, nogil=True)
    assert seen == {"nogil": True}


def test_a_private_scratch_folder_refuses_one_others_can_write(tmp_path, monkeypatch):
    """A cache folder in a shared temporary folder that another user made, or left writable to
    all, is not used (its pickles would run their code)."""
    from oscillator.folders import private_scratch

    monkeypatch.setenv("TMPDIR", str(tmp_path))
    import tempfile

    monkeypatch.setattr(tempfile, "tempdir", None)
    folder = private_scratch("probe")
    assert folder == tmp_path / f"probe-{os.getuid()}" and oct(folder.stat().st_mode & 0o777) == "0o700"
    folder.chmod(0o777)
    assert private_scratch("probe") is None


def test_a_slice_assigned_from_another_shape_raises_numbas_plain_message():
    """A kernel's slice assignment between shapes that differ is still a ValueError, with numba's
    plain message: the one naming both shapes is not compiled (oscillator.compiled)."""
    import numpy as np

    from oscillator.compiled import njit

    @njit
    def assign(into, values):
        into[:2] = values

    with pytest.raises(ValueError, match=r"^cannot assign slice from input of different size$"):
        assign(np.zeros(4), np.zeros(3))
    into = np.zeros(4)
    assign(into, np.array([1.0, 2.0]))
    assert into.tolist() == [1.0, 2.0, 0.0, 0.0]
