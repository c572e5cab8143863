"""How the command's process takes an interrupt: one that lands in a finalizer, and how it ends after
one it handled (the command and its entry point)."""

import atexit
import os
import signal
import sys
import threading

__all__ = ["interrupted_exit", "interrupts_from_finalizers"]


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


def interrupts_from_finalizers() -> None:
    """Deliver a Ctrl-C that lands while a finalizer runs to the command.

    Python does not raise an exception from a finalizer: it prints it as ignored, with its
    traceback, and goes on, and numba frees its LLVM objects at any time.  The process's hook for
    such exceptions sends SIGINT to the main thread again instead, from a timer thread (from the
    hook itself the interrupt would be raised in the hook), where the command's own handling of
    Ctrl-C takes it.  Installed by the entry point only: the command's process, not a program
    that calls the command's functions."""
    default = sys.unraisablehook

    def hook(unraisable: "sys.UnraisableHookArgs") -> None:
        main_thread = threading.main_thread().ident
        if isinstance(unraisable.exc_value, KeyboardInterrupt) and main_thread is not None:
            threading.Timer(0.01, signal.pthread_kill, (main_thread, signal.SIGINT)).start()
            return
        default(unraisable)

    if hasattr(signal, "pthread_kill"):
        sys.unraisablehook = hook
