"""What the command prints: plain text on stdout, one-line errors on stderr.

Text that is not the program's own (titles, labels, paths, values) is printed as plain text,
never as markup, with control characters escaped.  The library names its own arguments in its
errors (``folder``, ``formats``, ``window``); :func:`message` names the flags instead.
"""

from __future__ import annotations

import importlib
import re

import typer
from rich.console import Console
from rich.text import Text

from oscillator.errors import OscillatorError
from oscillator.io.signals import interrupts_deferred
from oscillator.text import printable

__all__ = ["FLAGS", "err", "fail", "load", "message", "out", "say"]

#: The library's argument names and the command line's flags for them.
FLAGS = {
    "folder": "--out",
    "formats": "--format",
    "window": "--window",
    "what": "--what",
    "between": "--between",
    "tolerance": "--tolerance",
    "workers": "--workers",
    "scheduler": "--scheduler",
    "param": "--param",
    "start": "--from",
    "stop": "--to",
    "step": "--step",
    "period": "--period",
    "max_points": "--max-points",
    "guess": "--guess",
    "transient": "--transient",
    "max_iterations": "--max-iterations",
    "section": "--section",
    "over": "--over",
    "keep_events_from": "--keep-events-from",
}

#: Consoles that never read markup or emoji codes in what they print.
out = Console(highlight=False, soft_wrap=True, markup=False, emoji=False)


err = Console(stderr=True, highlight=False, soft_wrap=True, markup=False, emoji=False)


#: Whether a command has printed its own error (an interrupt that Typer turned into exit 130
#: before the command ran has not).
reported = False


def fail(message: str, code: int = 2) -> typer.Exit:
    global reported
    reported = True
    lines = str(message).split("\n")
    err.print(Text.assemble(("error:", "bold red"), " ", printable(lines[0])))
    for line in lines[1:]:
        err.print(printable(line))
    return typer.Exit(code)


def say(*parts: str | tuple[str, str]) -> None:
    """Print plain text (user text is never markup); ``(text, style)`` pairs are styled."""
    out.print(Text.assemble(*((printable(p[0]), p[1]) if isinstance(p, tuple) else printable(p) for p in parts)))


#: What a command says when numba compiles the kernels (the first run after an install).
COMPILING = "compiling the numerical kernels once (about 30 s); later runs start in about a second"
#: Seconds of loading after which the command says so even if the cache seemed full (stale): loading
#: takes about a second, a few on a busy machine; compiling about half a minute.
SLOW_LOAD = 10.0
#: Whether the notice was printed in this process.
_noticed = False


def _notice() -> None:
    global _noticed
    if not _noticed:
        _noticed = True
        err.print(Text(COMPILING + " ...", style="dim"))


def load(*modules: str, notice: bool = False) -> None:
    """Import the numerical modules a command needs, holding Ctrl-C until they are in.

    Some libraries they import catch every exception while importing (a ``KeyboardInterrupt``
    among them: SciPy's array-API layer probes NumPy's attributes), which would lose the
    interrupt and let the command run on.

    With ``notice``, a first run that compiles the kernels says so on stderr at once (numba's
    cache is empty) or after :data:`SLOW_LOAD` seconds (the cache was stale).
    """
    import threading

    timer = None
    with interrupts_deferred():
        if notice and not _noticed:
            from oscillator.compiled import kernels_cached

            if not kernels_cached():
                _notice()
            else:
                timer = threading.Timer(SLOW_LOAD, _notice)
                timer.daemon = True
                timer.start()
        try:
            for name in modules:
                importlib.import_module(name)
        finally:
            if timer is not None:
                timer.cancel()


def message(error: OscillatorError) -> str:
    """The error's message, with the library's names of arguments replaced by their flags: the
    field's name where the message begins with it, and every name the message quotes in
    backticks (```guess```)."""
    text = str(error)
    flag = FLAGS.get(error.field or "")
    if flag is not None and text.startswith(error.field or ""):
        text = flag + text[len(error.field or "") :]
    return re.sub(r"`(\w+)`", lambda m: FLAGS.get(m.group(1), m.group(1)), text)
