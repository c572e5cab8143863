"""Files in and out: untrusted files read safely, and every output written atomically.

Reading.  Case files and run folders come from other people: :func:`read_untrusted` opens a
file without blocking (a FIFO or a device is refused, never read), refuses anything that is not
a regular file or is larger than a limit, and decodes it as strict UTF-8, naming the byte that
is not.

Writing.  Every file and folder appears whole or not at all.  Each is written under a hidden
temporary name in its own folder (so on the same file system) and renamed into place with
``rename(2)``, which is atomic.  An interrupted or failed write removes its temporary and leaves
the previous file or folder, if any, untouched.

Claiming.  A run's output folder is claimed before the run starts (:func:`claim_folder`): the
name is checked, the parents are created, a lock is taken on the name (so that two processes
never write the same folder) and the hidden temporary folder is made.  Every problem with the
folder (permissions, a name too long, a full disk, a concurrent run) thus shows before any
computing, and a refusal leaves nothing behind.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import itertools
import os
import shutil
import stat
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

from oscillator.errors import InputError, OscillatorError
from oscillator.text import printable, unsafe_characters
from oscillator.text import shown as shown_value

__all__ = [
    "FolderClaim",
    "FolderTaken",
    "atomic_folder",
    "atomic_path",
    "claim_folder",
    "default_name",
    "inner_folder",
    "lock_name",
    "read_untrusted",
    "refuse_link",
    "replace_file",
]

#: The longest name a file may have on the usual file systems (bytes).
_NAME_MAX = 255
#: What the temporary and lock names add to a folder's name: ``.NAME.partial-XXXXXXXX``.
_TEMPORARY_EXTRA = len("..partial-") + 8


def _umask() -> int:
    umask = os.umask(0)
    os.umask(umask)
    return umask


# --------------------------------------------------------------------------- reading


def read_untrusted(path: Path, *, what: str, field: str, limit: int) -> str:
    """The text of a file someone else wrote: a regular file of at most ``limit`` bytes, in UTF-8.

    Raises
    ------
    OscillatorError
        The file cannot be opened, is not a regular file (a folder, FIFO or device: never read),
        is larger than ``limit``, or is not UTF-8 (with the line and column of the first bad
        byte).
    """
    shown = printable(str(path))
    try:
        descriptor = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except OSError as exc:
        raise InputError(f"cannot read {what} {shown}: {exc.strerror}", field=field) from exc
    try:
        info = os.fstat(descriptor)
        if not stat.S_ISREG(info.st_mode):
            kind = "a folder" if stat.S_ISDIR(info.st_mode) else "not a regular file"
            raise InputError(f"{what} {shown} is {kind}; give the path of a file", field=field)
        chunks, size = [], 0
        while size <= limit and (chunk := os.read(descriptor, min(1 << 20, limit + 1 - size))):
            chunks.append(chunk)
            size += len(chunk)
        data = b"".join(chunks)
    except OSError as exc:
        raise InputError(f"cannot read {what} {shown}: {exc.strerror}", field=field) from exc
    finally:
        os.close(descriptor)
    if len(data) > limit:
        raise InputError(f"{what} {shown} is larger than {limit:,} bytes; a {what} is a small text file", field=field)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        column = exc.start - (data.rfind(b"\n", 0, exc.start) + 1) + 1
        raise InputError(
            f"{what} {shown} is not UTF-8 text: byte 0x{data[exc.start]:02x} at line {line}, column {column}; "
            f"save the file as UTF-8",
            field=field,
        ) from exc


# --------------------------------------------------------------------------- atomic writes


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


def inner_folder(folder: Path) -> Path:
    """``folder``, a folder inside an output folder (``figures/``), made if it is missing; refused
    if it is a link or not a folder: nothing is written through a link inside an output folder
    (a link there would send the files wherever it points)."""
    folder = Path(folder)
    with contextlib.suppress(FileExistsError):
        folder.mkdir(exist_ok=True)
    if folder.is_symlink() or not folder.is_dir():
        kind = "a link" if folder.is_symlink() else "not a folder"
        raise InputError(
            f"{printable(str(folder))} is {kind}; an output folder holds plain folders only, and nothing is written "
            "through a link: remove it and run the command again",
            field="folder",
        )
    return folder


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


# --------------------------------------------------------------------------- locks and claims


class Busy(OscillatorError):
    """Another process holds the lock on a name."""


class FolderTaken(OscillatorError):
    """The output folder exists already, or another run is writing it now."""


def _lock(path: Path) -> int:
    """An exclusive lock on the file ``path`` (created if need be); its descriptor.

    The lock is the kernel's (``flock``): it goes with the process, so a killed process never
    leaves a stale lock behind.  A lock file that another process unlinked while we waited for
    it is not the one at ``path`` any more; then the lock is taken again on the new file.
    """
    for _ in range(16):
        descriptor = os.open(path, os.O_RDWR | os.O_CREAT | getattr(os, "O_CLOEXEC", 0), 0o600)
        try:
            fcntl.flock(descriptor, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(descriptor)
            raise Busy(f"{printable(str(path))} is locked by another process", field="lock") from None
        try:
            same = os.stat(path).st_ino == os.fstat(descriptor).st_ino
        except FileNotFoundError:
            same = False
        if same:
            return descriptor
        os.close(descriptor)
    raise Busy(f"{printable(str(path))} keeps changing hands", field="lock")


def _unlock(path: Path, descriptor: int) -> None:
    with contextlib.suppress(OSError):
        path.unlink()
    os.close(descriptor)


@dataclass
class NameLock:
    """The lock on a folder's name (the file ``.NAME.lock`` next to it), held until :meth:`release`."""

    path: Path
    _descriptor: int
    _created: list[Path] = field(default_factory=list)
    _held: bool = True

    def release(self) -> None:
        """Let go of the lock, and remove the parents it created if they are empty."""
        if self._held:
            self._held = False
            _unlock(self.path, self._descriptor)
            _undo(self._created)


def lock_name(folder: Path, *, busy: str, option: str = "folder") -> NameLock:
    """Lock the name ``folder`` (creating its missing parents); refuse with ``busy`` if taken.

    Raises
    ------
    FolderTaken
        Another process holds the lock.
    OscillatorError
        The parent cannot be written.
    """
    created: list[Path] = []
    path = folder.parent / f".{folder.name}.lock"
    try:
        created = _make_parents(folder)
        return NameLock(path, _lock(path), created)
    except Busy:
        _undo(created)
        raise FolderTaken(busy, field=option) from None
    except OSError as exc:
        _undo(created)
        raise InputError(
            f"{option} {printable(str(folder))}: cannot write in {printable(str(folder.parent))} "
            f"({exc.strerror or exc}); choose a writable folder",
            field=option,
        ) from exc


#: The longest case name a default folder name keeps (bytes), before its time stamp.
_DEFAULT_NAME_MAX = 100


def default_name(text: str) -> str:
    """A folder name made from ``text`` (a case's name, which comes from a file name and may
    hold anything): control characters, path separators and a leading dot replaced by ``_``,
    and cut to :data:`_DEFAULT_NAME_MAX` bytes of UTF-8, so that the default folder of a run
    can always be written."""
    name = "".join("_" if unsafe_characters(c) or c in "/\\" else c for c in text)
    name = name.encode("utf-8", "replace").decode("utf-8", "replace")
    if name.startswith("."):
        name = "_" + name[1:]
    cut = name.encode("utf-8")[:_DEFAULT_NAME_MAX].decode("utf-8", "ignore")
    return cut or "case"


def as_folder(value: object, *, option: str = "folder") -> Path:
    """``value`` as a :class:`~pathlib.Path` if it names a folder (text or a path), else refused
    naming ``option``."""
    if isinstance(value, str) or (isinstance(value, os.PathLike) and isinstance(os.fspath(value), str)):
        return Path(value)
    raise InputError(f"{option} must be a folder's name (text or a Path), got {shown_value(value)}", field=option)


def check_name(folder: Path, *, option: str) -> None:
    """Refuse a folder name that cannot be written as given: not UTF-8 text, control characters,
    an empty name, or a name too long once the temporary's suffix is added."""
    text = str(folder)
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:
        raise InputError(
            f"{option} {printable(text)}: the name is not UTF-8 text; give a name in UTF-8", field=option
        ) from None
    if unsafe_characters(text):
        raise InputError(
            f"{option} {printable(text)}: the name holds control characters; give a plain name", field=option
        )
    name = folder.name
    if not name or name in (".", ".."):
        raise InputError(f"{option} {text!r}: give the name of a new folder", field=option)
    longest = _NAME_MAX - _TEMPORARY_EXTRA
    if len(name.encode("utf-8")) > longest:
        raise InputError(
            f"{option}: the folder name is {len(name.encode('utf-8'))} bytes long; at most {longest} bytes fit "
            f"with the temporary name it is written under; give a shorter name",
            field=option,
        )


@dataclass
class FolderClaim:
    """An output folder reserved for this process until :meth:`commit` or :meth:`abandon`.

    Attributes
    ----------
    target : Path
        The folder that :meth:`commit` creates.
    temporary : Path
        The hidden folder next to it that the output is written into.
    """

    target: Path
    temporary: Path
    _lock_path: Path
    _descriptor: int
    _created: list[Path] = field(default_factory=list)
    _open: bool = True

    def commit(self) -> Path:
        """Rename the temporary folder to the target and release the claim; the folder's path.

        The lock keeps every other run of this package off the name.  Should something else
        have put a file or folder there meanwhile, the output goes to the first free name
        ``TARGET-2``, ``TARGET-3``, ... instead of being lost; the path returned says where.
        """
        os.chmod(self.temporary, 0o777 & ~_umask())
        name = self.target.name
        others = (self.target.with_name(f"{name}-{n}") for n in range(2, 10_000))
        for folder in itertools.chain([self.target], (p for p in others if not os.path.lexists(p))):
            try:
                os.rename(self.temporary, folder)
            except OSError as exc:
                if exc.errno not in (errno.EEXIST, errno.ENOTEMPTY, errno.ENOTDIR, errno.EISDIR):
                    raise
            else:
                self._release()
                return folder
        raise OSError(errno.EEXIST, f"no free name next to {self.target}")

    def abandon(self) -> None:
        """Remove the temporary folder and the parents the claim created; release the claim."""
        if not self._open:
            return
        shutil.rmtree(self.temporary, ignore_errors=True)
        self._release()
        for parent in self._created:  # deepest first
            with contextlib.suppress(OSError):
                parent.rmdir()

    def _release(self) -> None:
        if self._open:
            self._open = False
            _unlock(self._lock_path, self._descriptor)


def _make_parents(folder: Path) -> list[Path]:
    """Create the missing parents of ``folder``; the ones created, deepest first."""
    missing = []
    parent = folder.parent
    while not parent.exists():
        missing.append(parent)
        if parent.parent == parent:
            break
        parent = parent.parent
    for path in reversed(missing):
        path.mkdir()
    return missing


def refuse_link(target: Path, *, option: str = "folder") -> None:
    """Refuse an output folder's name that is a link (to a folder or anything else): an output is
    written in a folder of its own, never through a link."""
    if Path(target).is_symlink():
        raise InputError(
            f"{option} {printable(str(target))} is a link; give the name of a folder of its own (outputs are never "
            "written through a link)",
            field=option,
        )


def check_new(target: Path, *, option: str = "folder") -> None:
    """Refuse a folder name that cannot be written (:func:`check_name`) or that exists already:
    the check a command makes before it loads anything, and :func:`claim_folder` again."""
    check_name(target, option=option)
    refuse_link(target, option=option)
    if os.path.lexists(target):
        raise FolderTaken(
            f"{option} {printable(str(target))} exists already; give a new folder (runs are never overwritten)",
            field=option,
        )


def claim_folder(target: Path, *, option: str = "folder") -> FolderClaim:
    """Reserve ``target`` as a new output folder; see the module docstring.

    Raises
    ------
    FolderTaken
        The folder exists already, or another run is writing it now.
    OscillatorError
        The name cannot be written (see :func:`check_name`), or its parent cannot be written.
        Nothing is left behind.
    """
    target = Path(target)
    check_new(target, option=option)
    shown = printable(str(target))
    exists = f"{option} {shown} exists already; give a new folder (runs are never overwritten)"
    created: list[Path] = []
    descriptor = None
    lock_path = target.parent / f".{target.name}.lock"
    try:
        created = _make_parents(target)
        descriptor = _lock(lock_path)
        if os.path.lexists(target):  # finished by another run while we looked
            raise FolderTaken(exists, field=option)
        temporary = Path(tempfile.mkdtemp(dir=target.parent, prefix=f".{target.name}.partial-"))
    except Busy:
        _undo(created)
        raise FolderTaken(
            f"{option} {shown} is being written by another run now; give another folder", field=option
        ) from None
    except OscillatorError:
        if descriptor is not None:
            _unlock(lock_path, descriptor)
        _undo(created)
        raise
    except OSError as exc:
        if descriptor is not None:
            _unlock(lock_path, descriptor)
        _undo(created)
        failed = Path(exc.filename) if exc.filename else target.parent
        where = printable(str(failed.parent if failed.name.startswith(f".{target.name}.") else failed))
        reason = exc.strerror or str(exc)
        if exc.errno == errno.ENAMETOOLONG:
            reason += " (give a shorter name)"
        raise InputError(
            f"{option} {shown}: cannot write in {where} ({reason}); choose a writable folder", field=option
        ) from exc
    return FolderClaim(target, temporary, lock_path, descriptor, created)


def _undo(created: list[Path]) -> None:
    for parent in created:
        with contextlib.suppress(OSError):
            parent.rmdir()
