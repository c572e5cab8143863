"""``python -m oscillator`` and the entry point of the ``oscillator`` command.

This module imports nothing but the standard library before it can catch Ctrl-C, so that an
interrupt while the command is still starting prints one line, not a traceback.
"""

import atexit
import os
import signal
import sys


def main() -> None:
    """Run the ``oscillator`` command (see :mod:`oscillator.cli.app`)."""
    try:
        from oscillator.cli.app import main as command

        command()
    except KeyboardInterrupt:  # before the command could catch it (the command catches its own)
        sys.stderr.write("error: interrupted\n")
        interrupted_exit()
    except SystemExit:
        # The command is done and has said so: a Ctrl-C now, while the interpreter shuts down
        # (multiprocessing's exit handlers join the workers), would end the process by SIGINT
        # (exit code -2) with its work complete.
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        raise


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


if __name__ == "__main__":
    main()
