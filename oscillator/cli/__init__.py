"""The ``oscillator`` command (Typer): one module per group of commands; :mod:`oscillator.cli.app` holds
the application and the entry point."""
