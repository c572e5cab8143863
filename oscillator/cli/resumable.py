"""What the resumable commands share (basins, attractors, atlas; curve and lyapunov write a
claimed folder): the folder's name locked, the computation run with each way it can stop said in
one line and what it finished kept, the outputs written with a Ctrl-C held until they are whole."""

from __future__ import annotations

import contextlib
import os
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

import typer
from rich.text import Text

from oscillator.cli.console import err, fail, message, progress_bar, say
from oscillator.errors import InputError, OscillatorError
from oscillator.text import printable

if TYPE_CHECKING:  # pragma: no cover
    from oscillator.io.cases import Case
    from oscillator.io.files import FolderClaim

__all__ = [
    "computing",
    "locked",
    "new_folder",
    "outputs",
    "progress_lines",
    "refusing",
    "say_reused",
    "unwritable",
    "with_progress",
    "write_claimed",
]

T = TypeVar("T")


@contextlib.contextmanager
def refusing() -> Iterator[None]:
    """The block that checks a command's input before any work: a refusal is one line (exit 2), a
    Ctrl-C says nothing was written (exit 130)."""
    try:
        yield
    except OscillatorError as error:
        raise fail(message(error)) from None
    except KeyboardInterrupt:
        raise fail("interrupted; nothing was written", 130) from None


#: Seconds between the lines that say the progress where stderr is not a terminal (a log, a job).
PROGRESS_EVERY = 10.0


def with_progress(run: Callable[..., T], label: str, unit: str, quiet: bool) -> T:
    """``run(progress=...)`` with a progress bar on a terminal (done of total, ``unit`` per second,
    time left), a line every :data:`PROGRESS_EVERY` s on stderr elsewhere (a log said nothing for
    minutes), nothing with ``quiet``."""
    if quiet:
        return run()
    if not err.is_terminal:
        return run(progress=progress_lines(label, unit))
    bar, report = progress_bar(label, unit)
    with bar:
        return run(progress=report)


def progress_lines(label: str, unit: str, every: float | None = None) -> Callable[[int, int], None]:
    """A ``progress(done, total)`` that prints ``label: done of total unit, elapsed, about N s left``
    on stderr at most every ``every`` s (:data:`PROGRESS_EVERY`; the time left from the rate since
    the first report)."""
    every = PROGRESS_EVERY if every is None else every
    began = time.monotonic()
    said = [began]
    first: list[int] = []

    def report(done: int, total: int) -> None:
        now = time.monotonic()
        if not first:
            first.append(done)
        if now - said[0] < every:
            return
        said[0] = now
        rate = (done - first[0]) / (now - began)
        left = f", about {max(total - done, 0) / rate:.0f} s left" if rate > 0 and total >= done else ""
        err.print(Text(f"{printable(label)}: {done} of {total} {unit}, {now - began:.0f} s{left}"), highlight=False)

    return report


@contextlib.contextmanager
def computing(store: Any, what: str, lock: Any, client: Any) -> Iterator[None]:
    """The block that computes a resumable folder's ``what`` (starts, values, rows): each way it
    can stop said in one line, what it finished kept; then the folder's lock and the Dask client
    released."""
    try:
        yield
    except InputError as error:  # refused before it ran (a damaged part, a value the model refuses)
        raise fail(message(error)) from None
    except OscillatorError as error:
        raise fail(f"{message(error)}; the {what} finished so far are kept in {store.folder}", 1) from None
    except OSError as error:  # a full disk, the folder taken away: what was written stays
        raise unwritable(error, store.folder, what) from None
    except KeyboardInterrupt:
        raise fail(f"interrupted; the {what} finished so far are kept: run the same command to resume", 130) from None
    finally:
        lock.release()
        if client is not None:
            client.close()


def outputs(folder: Path, kept: str, write: Any) -> list[str]:
    """``write()``: a finished computation's tables, figures and report, a Ctrl-C held until they
    are written (never a folder marked computed with its tables missing); what could not be
    drawn (the tables stay)."""
    from oscillator.io.signals import interrupts_deferred

    try:
        with interrupts_deferred():
            problems: list[str] = write()
    except OSError as error:
        raise fail(f"cannot write into {printable(str(folder))} ({error}); the {kept} are kept there", 1) from None
    except KeyboardInterrupt:  # held until the outputs were written: they are
        raise fail(
            f"interrupted; the tables, figures and report are written in {printable(str(folder))}", 130
        ) from None
    return problems


def unwritable(error: OSError, folder: Path, what: str) -> typer.Exit:
    """The one-line failure (exit 1) of a resumable computation that could not write into its
    folder: what it finished is kept there."""
    return fail(
        f"cannot write into {printable(str(folder))} ({error.strerror or error}); the {what} finished so far are "
        "kept there: free the space and run the same command to resume",
        1,
    )


def say_reused(store: Any, reused: int, what: str, quiet: bool) -> None:
    """How much of a resumed computation was read back from its folder instead of computed:
    ``what`` names it (``"of the 900 starts"``)."""
    if reused and not quiet:
        say(f"resumed: {reused} {what} read from {printable(str(store.folder))}, the rest computed")


def new_folder(case: Case | str, kind: str) -> Path:
    """The default output folder of a resumable command (no ``--out``): ``runs/CASE-KIND-TIME``
    (``case`` a case, or the name of a system file's stem),
    or with ``-2``, ``-3``, ... where a command of the same second has taken that name (without
    ``--out`` nothing is resumed: two commands a second apart resumed each other's folder, or
    refused it as another computation)."""
    from oscillator.io.files import default_name

    name = case if isinstance(case, str) else case.name
    base = Path("runs") / f"{default_name(name)}-{kind}-{time.strftime('%Y%m%d-%H%M%S')}"
    folder, count = base, 1
    while os.path.lexists(folder):
        count += 1
        folder = base.with_name(f"{base.name}-{count}")
    return folder


def locked(folder: Path, scheduler: str | None) -> tuple[Any, Any]:
    """The folder's name locked for this process, and the Dask client (or None)."""
    from oscillator.analysis.execution import connect
    from oscillator.io.files import lock_name

    busy = f"folder {printable(str(folder))} is being computed by another process now; wait for it, or give another"
    lock = lock_name(folder, busy=busy, option="--out")
    try:
        client = connect(scheduler) if scheduler else None
    except BaseException:
        lock.release()
        raise
    return lock, client


def write_claimed(claim: FolderClaim, write: Any, what: str) -> None:
    """``write(folder)`` into the claimed folder, which appears whole; a failure to write says so
    in one line (exit 1) and leaves nothing; a Ctrl-C waits until the folder is whole.  The
    problems ``write`` returns (a figure that failed: the tables are kept) exit 1 after."""
    from oscillator.io.signals import interrupts_deferred

    target = printable(str(claim.target))
    try:
        with interrupts_deferred():
            problems = write(claim.temporary)
            written = claim.commit()
    except (OSError, OscillatorError) as error:
        claim.abandon()
        reason = error.strerror if isinstance(error, OSError) and error.strerror else str(error)
        raise fail(f"cannot write {what} to {target}: {reason}; nothing was written", 1) from None
    except KeyboardInterrupt:  # held until the folder was whole: it is written
        raise fail(f"interrupted; {what} written to {target}", 130) from None
    except BaseException:
        claim.abandon()
        raise
    say(f"written to {printable(str(written))}")
    if problems:
        raise fail("; ".join(problems), 1)
