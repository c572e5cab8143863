"""Ctrl-C and the death of a parent: what a finished result and a pool of workers need.

* :func:`interrupts_deferred` holds Ctrl-C while files are being written, so that a finished
  computation reaches the disk whole; the interrupt is raised when the block ends.
* :func:`interrupts_heard` raises Ctrl-C at once, as Python does, unless it came in fragile code
  (a finalizer, which a garbage collection runs anywhere, or numba's or llvmlite's code:
  :func:`oscillator.process.in_fragile_code`), and remembers it: the caller raises it where it
  next asks.
* :func:`interrupts_ignored` ignores SIGINT while worker processes are spawned: they are born
  ignoring it, so a Ctrl-C that reaches a worker before it is ready (its imports take seconds)
  cannot print a traceback.
* :func:`prepare_worker` runs first in each worker: it ignores SIGINT (the parent alone decides
  what an interrupt does, and stops the workers) and exits when the parent dies, so that a
  killed sweep leaves no orphan processes behind (nor the fork server, which lives as long as
  its workers).
* :func:`quiet_resource_tracker` starts multiprocessing's resource tracker so that, when a
  killed sweep leaves the pool's semaphores to it, it removes them without a warning on the
  user's terminal.
"""

from __future__ import annotations

import contextlib
import os
import select
import signal
import threading
import time
from collections.abc import Callable, Iterator
from types import FrameType

from oscillator.process import in_fragile_code

__all__ = ["interrupts_deferred", "interrupts_heard", "interrupts_ignored", "prepare_worker", "quiet_resource_tracker"]

#: How often a worker checks that its parent is alive (s).
_WATCH_INTERVAL = 0.25


def _main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


@contextlib.contextmanager
def interrupts_deferred() -> Iterator[None]:
    """Hold SIGINT for the block; raise ``KeyboardInterrupt`` after it if one came."""
    if not _main_thread():
        yield
        return
    received: list[int] = []
    previous = signal.signal(signal.SIGINT, lambda signum, frame: received.append(signum))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
    if received:
        raise KeyboardInterrupt


@contextlib.contextmanager
def interrupts_heard() -> Iterator[Callable[[], bool]]:
    """Raise ``KeyboardInterrupt`` at SIGINT, as Python's own handler does, and yield a function
    that says whether one came during the block.  One that comes in fragile code (a finalizer,
    where Python would drop it, or numba's or llvmlite's code, which it would leave with LLVM's
    objects half freed) is only remembered: the caller, which asks where it can stop, raises it.
    Where SIGINT is not Python's own (a worker ignoring it, a block deferring it, the command's
    handler: :func:`oscillator.process.interrupts_where_safe`), it is left as it is."""
    if not _main_thread() or signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        yield lambda: False
        return
    heard: list[int] = []

    def handler(signum: int, frame: FrameType | None) -> None:
        heard.append(signum)
        if not in_fragile_code(frame):
            raise KeyboardInterrupt

    previous = signal.signal(signal.SIGINT, handler)
    try:
        yield lambda: bool(heard)
    finally:
        signal.signal(signal.SIGINT, previous)


@contextlib.contextmanager
def interrupts_ignored() -> Iterator[None]:
    """Ignore SIGINT for the block: processes started in it are born ignoring it.

    A process keeps an ignored signal ignored across ``exec``, and Python then installs no
    ``KeyboardInterrupt`` handler of its own; so a Ctrl-C that reaches a worker while it starts
    (its imports take seconds) cannot print a traceback.  (A blocked mask would not do:
    ``multiprocessing`` starts processes with an empty one.)  A Ctrl-C that reaches this
    process during the block, a few milliseconds while the workers are spawned, is lost.
    """
    if not _main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def _watch_parent(parent: int) -> None:
    """Exit as soon as process ``parent`` has: a worker forked by the fork server is that server's
    child, and the server lives as long as its workers do, so the worker watches the pool's parent
    itself (a process descriptor, readable once the process has exited; where there is none, its
    pid looked up every :data:`_WATCH_INTERVAL`)."""
    try:
        handle = os.pidfd_open(parent)
    except ProcessLookupError:
        os._exit(1)
    except (AttributeError, OSError):  # not Linux, or a kernel before 5.3
        handle = None
    if handle is not None:
        watch = select.poll()  # not select(): a descriptor numbered past 1024 would not fit
        watch.register(handle, select.POLLIN)
        watch.poll()
        os._exit(1)
    while True:
        try:
            os.kill(parent, 0)
        except (ProcessLookupError, PermissionError):  # gone, or its pid reused by another user's process
            os._exit(1)
        time.sleep(_WATCH_INTERVAL)


def prepare_worker(parent: int, environment: dict[str, str]) -> None:
    """A worker's initializer: ignore SIGINT, exit as soon as process ``parent`` (the pool's) is
    gone, and take ``environment`` (the parent's when the pool started: a worker forked by the fork
    server has the server's, from the first pool)."""
    if os.environ != environment:
        os.environ.clear()
        os.environ.update(environment)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    threading.Thread(target=_watch_parent, args=(parent,), name="parent-watch", daemon=True).start()


#: The warning multiprocessing's resource tracker prints for the semaphores of a killed parent.
_LEAK_WARNING = "ignore:resource_tracker:UserWarning"


def quiet_resource_tracker() -> None:
    """Start multiprocessing's resource tracker (if it is not running) with its leak warning off.

    When the parent of a process pool is killed (SIGKILL), the tracker removes the pool's
    semaphores, as it should, but also prints "There appear to be N leaked semaphore objects"
    to the user's terminal.  The tracker is a process of its own, started with the
    interpreter's ``-W`` options: the filter given here is its only change.
    """
    import sys
    from multiprocessing import resource_tracker

    if _LEAK_WARNING in sys.warnoptions:
        resource_tracker.ensure_running()
        return
    sys.warnoptions.append(_LEAK_WARNING)
    try:
        resource_tracker.ensure_running()
    finally:
        sys.warnoptions.remove(_LEAK_WARNING)
