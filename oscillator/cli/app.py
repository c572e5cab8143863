"""The ``oscillator`` command: list, show, run, check, report, sweep, locate, orbit, continue, basins
and lyapunov.

The rule for exit codes:

* **2** - the input was refused before anything ran (unknown case or parameter, bad value,
  malformed or damaged file, an output folder that is taken or cannot be written): one line
  naming the field and the fix, and nothing created.
* **1** - work started and could not finish (a solver error, a guard, a full disk, a figure
  that could not be drawn): what was computed is kept (``run`` writes its partial result marked
  ``failed``; ``sweep`` keeps its finished points); or ``check`` found a time out of tolerance.
* **130** - interrupted (Ctrl-C): the same as 1, marked ``interrupted``.

The numerical libraries are imported only by the commands that compute, so ``--help`` and
refusals are quick.
"""

from __future__ import annotations

import importlib
import os
import pkgutil
import sys
from typing import Annotated

import typer
from rich.text import Text

import oscillator.cli as cli
from oscillator.cli import console
from oscillator.cli.commands import COMMANDS
from oscillator.cli.console import err, out
from oscillator.text import printable
from oscillator.version import __version__

__all__ = ["app", "main"]

app = typer.Typer(
    name="oscillator",
    help="Simulate the 2-DOF frictional oscillator with elastic stops of the article, "
    "and explain every switch by its theorem.",
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,
)


def _version(
    version: Annotated[bool, typer.Option("--version", help="Print the version and exit.")] = False,
) -> None:
    if version:
        out.print(f"oscillator {__version__}")
        raise typer.Exit(0)


#: Click's exception classes, as Typer uses them (recent Typer versions bring their own copy of
#: Click, older ones use Click itself): found through the class Typer exports.
_CLICK_ERROR: type[Exception] = next(c for c in typer.BadParameter.__mro__ if c.__name__ == "ClickException")


def _usage_error(error: Exception, args: list[str]) -> int:
    """A usage error (unknown option, value of the wrong type) in one line, naming the option."""
    context = getattr(error, "ctx", None)
    if not args and context is not None:  # `oscillator` alone: the help, as with --help
        out.print(context.get_help(), markup=False)
        return 2
    message = printable(" ".join(str(error.format_message()).split()))  # type: ignore[attr-defined]
    hint = f" (see '{context.command_path} --help')" if context is not None else ""
    err.print(Text.assemble(("error:", "bold red"), f" {message}{printable(hint)}"))
    return int(getattr(error, "exit_code", 2))


def _tolerant_streams() -> None:
    """A terminal or pipe that cannot encode every character (``PYTHONIOENCODING=ascii``, the
    POSIX locale) gets ``\\u2192``-style escapes for the characters it lacks (→, Ω, μ in the
    tables), never a UnicodeEncodeError that loses a finished result."""
    for stream in (sys.stdout, sys.stderr):
        reconfigure = getattr(stream, "reconfigure", None)
        if reconfigure is not None and (stream.encoding or "").lower().replace("-", "") not in ("utf8", "utf16"):
            try:
                reconfigure(errors="backslashreplace")
            except (ValueError, OSError):  # a closed or detached stream: nothing to print to anyway
                pass


def main(args: list[str] | None = None) -> None:
    """Entry point of the ``oscillator`` command: every outcome is an exit code and at most one
    line of error, never a traceback (see the module docstring for the codes)."""
    args = sys.argv[1:] if args is None else list(args)
    _tolerant_streams()
    try:
        command = typer.main.get_command(app)
        code = command.main(args=args, prog_name="oscillator", standalone_mode=False)
        if code == 130 and not console.reported:  # Typer caught Ctrl-C while it read the command line
            raise KeyboardInterrupt
    except _CLICK_ERROR as error:
        code = _usage_error(error, args)
    except (typer.Abort, KeyboardInterrupt):
        err.print(Text.assemble(("error:", "bold red"), " interrupted"))
        code = 130
    except BrokenPipeError:  # the reader of our output went away (`oscillator list | head -1`)
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # nothing more to flush at exit
        code = 1
    if code == 130:
        from oscillator.process import interrupted_exit

        interrupted_exit()
    sys.exit(code if isinstance(code, int) else 0)


def _register() -> None:
    """Every command the package's modules declare (:mod:`oscillator.cli.commands`), in rank order."""
    for module in pkgutil.iter_modules(cli.__path__):
        if module.name != "app":
            importlib.import_module(f"oscillator.cli.{module.name}")
    for declared in sorted(COMMANDS, key=lambda c: c.rank):
        app.command(declared.name, short_help=declared.short_help)(declared.function)


_register()
app.callback(invoke_without_command=True)(_version)
