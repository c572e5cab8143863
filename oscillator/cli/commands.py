"""The commands, each declared beside its function: ``@command(rank, "short help")``.

:mod:`oscillator.cli.app` imports every module of this package and registers the commands they
declare in the order of their ranks (the order ``oscillator --help`` lists them), so that a new
command is one module here.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, TypeVar

__all__ = ["COMMANDS", "Command", "command"]

F = TypeVar("F", bound=Callable[..., Any])


@dataclass(frozen=True)
class Command:
    """A command: its function, its place in the list, its one-line help and its name (the
    function's, with ``_`` as ``-``, unless given)."""

    rank: int
    function: Callable[..., Any]
    short_help: str
    name: str | None = None


#: Every command declared so far.
COMMANDS: list[Command] = []


def command(rank: int, short_help: str, *, name: str | None = None) -> Callable[[F], F]:
    """Declare the decorated function a command (registered by :mod:`oscillator.cli.app`)."""

    def declare(function: F) -> F:
        COMMANDS.append(Command(rank, function, short_help, name))
        return function

    return declare
