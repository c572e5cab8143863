"""Atomic writes: every file and folder the package writes appears whole or not at all.

Each is written under a hidden temporary name in its own folder (so on the same file system)
and renamed into place with ``rename(2)``, which is atomic.  An interrupted or failed write
removes its temporary and leaves the previous file or folder, if any, untouched.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

__all__ = ["atomic_folder", "atomic_path", "replace_file"]


def _umask() -> int:
    umask = os.umask(0)
    os.umask(umask)
    return umask


@contextlib.contextmanager
def atomic_path(target: Path) -> Iterator[Path]:
    """A temporary file name next to ``target``; the file written there replaces ``target``.

    The file gets the usual permissions (``mkstemp`` makes it private to the user).
    """
    target = Path(target)
    handle, name = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.")
    os.close(handle)
    temporary = Path(name)
    try:
        yield temporary
        os.chmod(temporary, 0o666 & ~_umask())
        os.replace(temporary, target)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise


def replace_file(path: Path, text: str) -> None:
    """Write a text file atomically."""
    with atomic_path(path) as temporary:
        temporary.write_text(text, encoding="utf-8")


@contextlib.contextmanager
def atomic_folder(target: Path) -> Iterator[Path]:
    """A hidden temporary folder next to ``target``, renamed to ``target`` when the block ends.

    ``target`` must not exist, or be an empty folder.
    """
    target = Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    temporary = Path(tempfile.mkdtemp(dir=target.parent, prefix=f".{target.name}.partial-"))
    try:
        yield temporary
        os.chmod(temporary, 0o777 & ~_umask())
        os.replace(temporary, target)  # allowed onto an empty folder
    except BaseException:
        shutil.rmtree(temporary, ignore_errors=True)
        raise
