"""How the process ends after an interrupt it handled (the command and its entry point)."""

import atexit
import os
import sys

__all__ = ["interrupted_exit"]


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
