"""``python -m oscillator`` and the entry point of the ``oscillator`` command.

This module imports nothing but the standard library (and :mod:`oscillator.process`, which
imports nothing else) before it can catch Ctrl-C, so that an interrupt while the command is
still starting prints one line, not a traceback.
"""

import signal
import sys

from oscillator.process import interrupted_exit, interrupts_where_safe


def main() -> None:
    """Run the ``oscillator`` command (see :mod:`oscillator.cli.app`)."""
    import os

    interrupts_where_safe()
    os.environ.setdefault("OSCILLATOR_COMPILE_NOTICE", "0")  # the command says it its own way
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


if __name__ == "__main__":
    main()
