"""``python -m oscillator`` is the ``oscillator`` command (see :mod:`oscillator.cli`)."""

from oscillator.cli import main

if __name__ == "__main__":
    main()
