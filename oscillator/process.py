"""How the command's process takes an interrupt: where a Ctrl-C may be raised (never inside numba's
or llvmlite's code, nor in a finalizer), and how the process ends after one it handled."""

import atexit
import os
import signal
import sys
import threading
from types import FrameType

__all__ = ["in_fragile_code", "interrupted_exit", "interrupts_where_safe"]

#: The packages whose code a ``KeyboardInterrupt`` must not cut short: llvmlite's objects own
#: LLVM memory that an exception between a C call and its bookkeeping frees twice (a crash, not
#: an error, when a later collection frees it again); numba's compiler and cache drive them.
FRAGILE_PACKAGES = ("numba", "llvmlite")

#: How long a Ctrl-C that came in fragile code waits before it is tried again (s).
RETRY = 0.01


def in_fragile_code(frame: FrameType | None) -> bool:
    """Whether the code running in ``frame`` (or any frame that called it) is a finalizer
    (``__del__``, a ``weakref.finalize`` callback) or numba's or llvmlite's: where Python would
    drop a ``KeyboardInterrupt`` (it prints a finalizer's exception as ignored and goes on) or
    where one leaves LLVM's objects half freed."""
    while frame is not None:
        module = frame.f_globals.get("__name__") or ""
        if frame.f_code.co_name == "__del__" or module.partition(".")[0] in FRAGILE_PACKAGES:
            return True
        if module == "weakref" and frame.f_code.co_name == "__call__":
            return True
        frame = frame.f_back
    return False


def interrupts_where_safe() -> None:
    """Install the command's Ctrl-C: ``KeyboardInterrupt`` at once, as Python's own handler does,
    unless it came in fragile code (:func:`in_fragile_code`); then it is sent again a moment later
    (from a timer thread: a handler cannot wait), until it lands where it can be raised.  Installed
    by the entry point only: the command's process, not a program that calls its functions."""
    if not hasattr(signal, "pthread_kill"):
        return
    main_thread = threading.main_thread().ident

    def handler(signum: int, frame: FrameType | None) -> None:
        if not in_fragile_code(frame):
            raise KeyboardInterrupt
        retry = threading.Timer(RETRY, signal.pthread_kill, (main_thread, signal.SIGINT))
        retry.daemon = True  # not kept waiting for by an interpreter that exits
        retry.start()

    signal.signal(signal.SIGINT, handler)


def interrupted_exit() -> None:
    """Exit with code 130 after an interrupt that was handled.

    Not ``sys.exit``: when Ctrl-C interrupted an import, CPython may have marked the interrupt
    as unhandled, and would then end the process by SIGINT (exit code -2) although it was
    handled.  So the exit handlers (multiprocessing's clean-up among them) run and the
    streams are flushed here, and the process ends with ``os._exit``.
    """
    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    os._exit(130)
