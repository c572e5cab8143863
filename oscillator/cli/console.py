"""What the command prints: plain text on stdout, one-line errors on stderr.

Text that is not the program's own (titles, labels, paths, values) is printed as plain text,
never as markup, with control characters escaped.  The library names its own arguments in its
errors (``folder``, ``formats``, ``window``); :func:`message` names the flags instead.
"""

from __future__ import annotations

import importlib
import os
import subprocess
import sys
import time
from collections.abc import Callable

import typer
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn
from rich.text import Text

from oscillator.errors import OscillatorError
from oscillator.io.signals import interrupts_deferred
from oscillator.text import printable

__all__ = ["FLAGS", "err", "fail", "load", "message", "out", "progress_bar", "say"]

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
    "kind": "--kind",
    "starts": "--starts",
    "record": "--record",
    "settle": "--full-transient",
    "fresh_transient": "--transient",
    "at": "--at",
    "x": "--x",
    "y": "--y",
    "span": "--param",
    "seeds": "--seeds",
    "sweep": "--sweep",
    "measure": "--measure",
    "measures": "--measures",
    "vary": "--vary",
    "objective": "--objective",
    "constraints": "--constraint",
    "band": "--band",
    "candidates": "--candidates",
    "front": "--front",
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


def warn(message: str) -> None:
    """A warning on stderr: the computation went on, but the user should know (user text is
    never markup)."""
    err.print(Text.assemble(("warning:", "bold yellow"), " ", printable(message)))


#: What a command says when numba compiles the kernels (the first run after an install).
COMPILING = "compiling the numerical kernels once (10 to 20 s); later runs start in a few seconds"
#: Seconds of loading after which the command says so even if the cache seemed full (stale): loading
#: takes about a second, a few on a busy machine; compiling about 10 s.
SLOW_LOAD = 10.0
#: The modules whose import compiles the kernels, in the order a run needs them, and what each holds.
KERNELS = (
    ("oscillator.model.fields", "the fields"),
    ("oscillator.model.theorems", "the switching theorems"),
    ("oscillator.model.switching", "the switching rules"),
    ("oscillator.engines.callbacks", "CVODE's callbacks"),
    ("oscillator.engines.stepping", "the stepping loop"),
)
#: Of :data:`KERNELS`, those a second process compiles into the cache meanwhile (on two cores or
#: more): they need none of the switching rules, which take most of the time.
BESIDE = ("oscillator.engines.callbacks", "oscillator.engines.stepping")
#: Whether the notice was printed in this process, and whether the cache was looked at.
_noticed = False
_checked = False


def _notice() -> None:
    global _noticed
    if not _noticed:
        _noticed = True
        err.print(Text(COMPILING + " ...", style="dim"))


def load(*modules: str, notice: bool | None = None) -> None:
    """Import the numerical modules a command needs, holding Ctrl-C until they are in.

    Some libraries they import catch every exception while importing (a ``KeyboardInterrupt``
    among them: SciPy's array-API layer probes NumPy's attributes), which would lose the
    interrupt and let the command run on.

    ``notice`` (True or False) says the modules need the kernels: a first run (numba's cache
    empty) compiles them first with :func:`compile_kernels`, and with ``notice`` says so on
    stderr at once and shows the progress; with a cache that turns out stale, ``notice`` says
    so after :data:`SLOW_LOAD` seconds.
    """
    import threading

    global _checked
    timer = None
    with interrupts_deferred():
        if notice is not None and not _checked:
            _checked = True
            from oscillator.compiled import CACHE, kernels_cached

            if not kernels_cached():
                if notice:
                    _notice()
                compile_kernels(beside=CACHE, show=notice)
            elif notice:
                timer = threading.Timer(SLOW_LOAD, _notice)
                timer.daemon = True
                timer.start()
        try:
            for name in modules:
                importlib.import_module(name)
        finally:
            if timer is not None:
                timer.cancel()


def compile_kernels(*, beside: bool = True, show: bool = True) -> None:
    """Import :data:`KERNELS` in turn (with ``show``, a progress bar on stderr), numba compiling
    each into its cache.  With ``beside`` (numba's cache in use) and two cores or more, a second process
    compiles :data:`BESIDE` meanwhile and this one loads them from the cache when it gets there
    (measured: 11 s -> 9 s for ``oscillator run`` on 2 cores); if that process fails or is not
    done in time, this one compiles them itself."""
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    helper = None
    if beside and len(os.sched_getaffinity(0)) > 1:
        code = "import importlib, sys\nfor name in sys.argv[1:]: importlib.import_module(name)"
        helper = subprocess.Popen(
            [sys.executable, "-c", code, *BESIDE], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
        )
    columns = (TextColumn("compiling {task.description}"), BarColumn(), TimeElapsedColumn())
    try:
        with Progress(*columns, console=err, transient=True, disable=not show) as bar:
            task = bar.add_task(KERNELS[0][1], total=len(KERNELS))
            for name, label in KERNELS:
                bar.update(task, description=label)
                if helper is not None and name in BESIDE:
                    _wait(helper)
                importlib.import_module(name)
                bar.advance(task)
    finally:
        if helper is not None and helper.poll() is None:
            helper.kill()
            helper.wait()


#: Seconds the first run waits for the second process before compiling its modules itself.
HELPER_WAIT = 30.0


def _wait(helper: subprocess.Popen[bytes]) -> None:
    try:
        helper.wait(timeout=HELPER_WAIT)
    except subprocess.TimeoutExpired:
        helper.kill()
        helper.wait()


def message(error: OscillatorError) -> str:
    """The error's message with the library's argument names said as the command line's flags
    (:meth:`~oscillator.errors.OscillatorError.said_as` with :data:`FLAGS`)."""
    return error.said_as(FLAGS)


def progress_bar(label: str, unit: str) -> tuple[Progress, Callable[[int, int], None]]:
    """A progress bar on stderr and its callback ``report(done, total)``, with the rate in ``unit``
    per second counted from the first report (a resumed computation's earlier work is not in it)."""
    columns = (
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("{task.fields[rate]}"),
        TimeElapsedColumn(),
        TimeRemainingColumn(),
    )
    bar = Progress(*columns, console=err, transient=True)
    task = bar.add_task(printable(label), total=None, rate="")
    began = time.monotonic()
    first: list[int] = []

    def report(done: int, total: int) -> None:
        if not first:
            first.append(done)
        new = done - first[0]
        rate = f"{new / (time.monotonic() - began):.2f} {unit}/s" if new else ""
        bar.update(task, completed=done, total=total, rate=rate)

    return bar, report
