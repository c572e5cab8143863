"""Folders for the caches the libraries keep (numba's compiled code, matplotlib's fonts), chosen so
that a read-only install run by a user without a writable home works quietly.

Standard library only: imported before numba or matplotlib, to tell them where to write.
"""

from __future__ import annotations

import os
import stat
import tempfile
from pathlib import Path

__all__ = ["private_scratch", "writable"]


def writable(folder: Path) -> bool:
    """Whether files can be created in ``folder`` (made, with its parents, if missing)."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=folder):
            return True
    except OSError:
        return False


def private_scratch(name: str) -> Path | None:
    """``<temporary folder>/<name>-<uid>``, made if missing, owned by this user and written by no
    one else; None if that cannot be had.

    A cache in a shared temporary folder that another user could fill would run their code
    (numba's cache files and matplotlib's are pickles or trusted data), hence the checks.
    """
    uid = os.getuid() if hasattr(os, "getuid") else 0
    folder = Path(tempfile.gettempdir()) / f"{name}-{uid}"
    try:
        folder.mkdir(mode=0o700, exist_ok=True)
        info = folder.lstat()
    except OSError:
        return None
    mine = not hasattr(os, "getuid") or info.st_uid == uid
    if not (stat.S_ISDIR(info.st_mode) and mine and not info.st_mode & 0o022 and writable(folder)):
        return None
    return folder
