"""The ``oscillator`` command: list, show, run, check, report, sweep and locate.

The rule for exit codes:

* **2** - the input was refused before anything ran (unknown case or parameter, bad value,
  malformed or damaged file, an output folder that is taken or cannot be written): one line
  naming the field and the fix, and nothing created.
* **1** - work started and could not finish (a solver error, a guard, a full disk, a figure
  that could not be drawn): what was computed is kept (``run`` writes its partial result marked
  ``failed``; ``sweep`` keeps its finished points); or ``check`` found a time out of tolerance.
* **130** - interrupted (Ctrl-C): the same as 1, marked ``interrupted``.

Text that is not the program's own (titles, labels, paths, values) is printed as plain text,
never as markup, with control characters escaped.  The numerical libraries are imported only
by the commands that compute, so ``--help`` and refusals are quick.
"""

from __future__ import annotations

import dataclasses
import importlib
import math
import os
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer
from rich import box
from rich.console import Console
from rich.measure import Measurement
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn
from rich.table import Table
from rich.text import Text

from oscillator import __version__
from oscillator._errors import OscillatorError
from oscillator._files import check_name
from oscillator._signals import interrupts_deferred
from oscillator._text import printable, shown
from oscillator.cases import Case, case_names, check_setting, load_case, parse_value, resolve_case
from oscillator.parameters import SolverOptions, SweepSettings

if TYPE_CHECKING:  # pragma: no cover
    from oscillator._files import FolderClaim
    from oscillator.result import Result

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
#: Consoles that never read markup or emoji codes in what they print.
out = Console(highlight=False, soft_wrap=True, markup=False, emoji=False)
err = Console(stderr=True, highlight=False, soft_wrap=True, markup=False, emoji=False)
_INTEGER_OPTIONS = {f.name for f in SolverOptions.__dataclass_fields__.values() if f.type in ("int", int)}
FORMATS = ("csv", "parquet", "both")


class Refused(Exception):
    """Input refused before anything ran: exit 2."""


#: Whether a command has printed its own error (an interrupt that Typer turned into exit 130
#: before the command ran has not).
_reported = False


def _fail(message: str, code: int = 2) -> typer.Exit:
    global _reported
    _reported = True
    lines = str(message).split("\n")
    err.print(Text.assemble(("error:", "bold red"), " ", printable(lines[0])))
    for line in lines[1:]:
        err.print(printable(line))
    return typer.Exit(code)


def _say(*parts: str | tuple[str, str]) -> None:
    """Print plain text (user text is never markup); ``(text, style)`` pairs are styled."""
    out.print(Text.assemble(*((printable(p[0]), p[1]) if isinstance(p, tuple) else printable(p) for p in parts)))


def _load(*modules: str) -> None:
    """Import the numerical modules a command needs, holding Ctrl-C until they are in.

    Some libraries they import catch every exception while importing (a ``KeyboardInterrupt``
    among them: SciPy's array-API layer probes NumPy's attributes), which would lose the
    interrupt and let the command run on.
    """
    with interrupts_deferred():
        for name in modules:
            importlib.import_module(name)


def _overrides(assignments: list[str]) -> dict:
    """``NAME=VALUE`` strings to overrides, values as numbers or expressions of pi."""
    values = {}
    for item in assignments:
        name, sep, text = item.partition("=")
        name = name.strip()
        if not sep or not name:
            raise OscillatorError(f"--set {shown(item)}: write NAME=VALUE, e.g. --set Omega=1.7", field="--set")
        check_setting(name)
        value = parse_value(text.strip(), field=f"--set {printable(name)}")
        if name in _INTEGER_OPTIONS:
            if not isinstance(value, (int, float)) or not math.isfinite(value) or not float(value).is_integer():
                raise OscillatorError(f"--set {printable(name)}={shown(text)}: {name} is a whole number", field=name)
            value = int(value)
        values[name] = value
    return values


def _case(case: str, t_end: float | None = None, assignments: list[str] | None = None) -> Case:
    return resolve_case(load_case(case), t_end=t_end, **_overrides(assignments or []))


#: The event table's columns, most important first: (header, justification, cell of a row).
_EVENT_COLUMNS = (
    ("t (s)", "right", lambda row: f"{row.t:.6f}"),
    ("mass", "right", lambda row: str(row.mass)),
    ("kind", "left", lambda row: row.kind),
    ("domain", "left", lambda row: f"{row.from_domain} → {row.to_domain}"),
    ("theorem", "left", lambda row: f"{row.theorem} {row.equation}"),
    ("boundary", "left", lambda row: row.boundary),
)


def _events_table(events, limit: int = 40) -> Table:
    """The switching events as a table as wide as the terminal allows: columns are left out, least
    important first, until it fits; a number is never cut."""
    rows = list(events.itertuples(index=False))
    shown_rows = rows if len(rows) <= limit else [*rows[: limit // 2], None, *rows[-limit // 2 :]]
    natural = out.options.update_width(10_000)
    for count in range(len(_EVENT_COLUMNS), 2, -1):
        columns = _EVENT_COLUMNS[:count]
        cells = [None if row is None else [printable(cell(row)) for _, _, cell in columns] for row in shown_rows]
        table = Table(title="switching events", title_justify="left", header_style="bold", box=box.SIMPLE_HEAD)
        for i, (header, justify, _) in enumerate(columns):
            widest = max([len(header), *(len(c[i]) for c in cells if c is not None)])
            # numbers keep their width; texts fold onto a second line if the terminal is narrower still
            table.add_column(header, justify=justify, overflow="fold", min_width=widest if i < 2 else None)
        for row in cells:
            table.add_row(*(row or ["…", "", f"{len(rows) - limit} more", *[""] * (count - 3)]))
        if Measurement.get(out, natural, table).maximum <= out.width:
            return table
    return table


def _sample_grid(case: Case, sample: float | None):
    """The grid of ``--sample DT``: every DT seconds from t0, and t_end."""
    if sample is None:
        return None
    import numpy as np

    if not (math.isfinite(sample) and sample > 0):
        raise OscillatorError(f"--sample must be a positive time step in s, got {sample!r}", field="--sample")
    rows = (case.t_end - case.initial.t0) / sample
    if rows > case.options.max_trajectory_rows:
        raise OscillatorError(
            f"--sample {sample:g} gives {rows:.3g} rows, more than max_trajectory_rows = "
            f"{case.options.max_trajectory_rows}; give a longer step",
            field="--sample",
        )
    grid = case.initial.t0 + sample * np.arange(math.floor(rows) + 1)
    return np.unique(np.append(grid[grid < case.t_end], case.t_end))


def _simulate_with_progress(case: Case, quiet: bool, t_eval=None) -> Result:
    from oscillator.simulation import simulate

    if quiet or not err.is_terminal:  # a progress bar only where a person watches
        return simulate(case, t_eval=t_eval)
    span = case.t_end - case.initial.t0
    columns = (TextColumn("{task.description}"), BarColumn(), TextColumn("t = {task.fields[t]:.4g} s"),
               TimeElapsedColumn(), TimeRemainingColumn())  # fmt: skip
    with Progress(*columns, console=err, transient=True) as progress:
        task = progress.add_task(printable(case.name), total=span, t=case.initial.t0)
        last = [0.0]

        def report(t: float) -> None:
            now = time.monotonic()
            if now - last[0] > 0.1:
                last[0] = now
                progress.update(task, completed=t - case.initial.t0, t=t)

        return simulate(case, t_eval=t_eval, progress=report)


@app.command("list", short_help="List the named cases.")
def list_cases() -> None:
    """List the named cases with their titles.

    \b
    Example:
      oscillator list
    """
    table = Table(header_style="bold")
    table.add_column("case")
    table.add_column("title")
    for name in case_names():
        table.add_row(name, load_case(name).title)
    out.print(table)


@app.command(short_help="Show a case: parameters, start, settings, expected events.")
def show(case: Annotated[str, typer.Argument(metavar="CASE", help="A named case or a case file (.toml).")]) -> None:
    """Show a case: its parameters, start, run settings and expected events.

    \b
    Example:
      oscillator show instance-2
    """
    try:
        c = load_case(case)
    except OscillatorError as error:
        raise _fail(str(error)) from None
    _say((c.name, "bold"), f": {c.title}")
    if c.description:
        _say(" ".join(c.description.split()))
    params = Table(title="parameters", title_justify="left", header_style="bold")
    for column in ("name", "value", "name ", "value "):
        params.add_column(column, justify="right" if "value" in column else "left")
    items = [(name, f"{getattr(c.parameters, name):.10g}") for name in c.parameters.names()]
    half = (len(items) + 1) // 2
    for left, right in zip(items[:half], [*items[half:], ("", "")], strict=False):
        params.add_row(*left, *right)
    out.print(params)
    initial = c.initial
    _say(
        f"start: t0 = {initial.t0} s, x1 = {initial.x1} m, v1 = {initial.v1} m/s, x2 = {initial.x2} m, "
        f"v2 = {initial.v2} m/s; end: t_end = {c.t_end} s"
    )
    _say("solver: " + ", ".join(f"{name} = {getattr(c.options, name)}" for name in c.options.names()))
    if c.expected:
        table = Table(title="expected events", title_justify="left", header_style="bold")
        for column in ("event", "mass", "kind", "domain", "article (s)", "reference (s)", "tolerance (s)"):
            table.add_column(column)
        for e in c.expected:
            table.add_row(printable(e.label), str(e.mass), str(e.kind), "" if e.to_domain is None else str(e.to_domain),
                          "—" if e.t is None else f"{e.t}", "—" if e.reference is None else f"{e.reference}",
                          f"{e.tolerance:g}")  # fmt: skip
        out.print(table)


# --------------------------------------------------------------------------- run


def _write_partial(error: BaseException, claim: FolderClaim, fmt: str, pending: tuple[str, ...]) -> str:
    """Write the error's partial result (``error.result``) into the claimed folder; say where."""
    from oscillator.output import write_run

    partial = getattr(error, "result", None)
    if partial is None:
        claim.abandon()
        return "nothing was written"
    try:
        with interrupts_deferred():
            folder = write_run(partial, claim, formats=fmt, command=["oscillator", *sys.argv[1:]], pending=pending)
    except (OSError, OscillatorError) as failure:
        return f"the partial result could not be written: {failure}"
    except KeyboardInterrupt:
        return "interrupted again while writing the partial result; nothing was written"
    return (
        f"the partial result up to t = {partial.final_state[0]:.10g} s is in {folder} "
        f'(run.json: "status": "{partial.status}"); `oscillator report {folder}` makes its report'
    )


def _prepare_run(case: str, t_end, set_, out_dir, fmt: str, sample, window) -> tuple[Case, object, FolderClaim]:
    """Every check of ``run`` before anything is created, then the output folder claimed."""
    if fmt not in FORMATS:
        raise OscillatorError(f"--format must be one of {', '.join(FORMATS)}, got {shown(fmt)}", field="--format")
    resolved = _case(case, t_end, set_)
    grid = _sample_grid(resolved, sample)

    if out_dir is not None:
        check_name(out_dir, option="--out")
    _load("oscillator.output", "oscillator.simulation", "oscillator.plotting")
    from oscillator.output import claim_output
    from oscillator.plotting import figure_window
    from oscillator.simulation import admit

    if window is not None:
        figure_window(resolved.initial.t0, resolved.t_end, resolved.parameters.period, window)

    with interrupts_deferred():  # the first call of the compiled formulas loads them
        admit(resolved)
    return resolved, grid, claim_output(out_dir, resolved.name)


@app.command(short_help="Run a case; write its tables, figures and report.")
def run(
    case: Annotated[str, typer.Argument(metavar="CASE", help="A named case (oscillator list) or a case file (.toml).")],
    t_end: Annotated[
        float | None, typer.Option("--t-end", metavar="T", help="End time in s (default: the case's).")
    ] = None,
    set_: Annotated[
        list[str] | None,
        typer.Option(
            "--set",
            metavar="NAME=VALUE",
            help="Override a parameter, initial value or solver option (repeatable). A changed parameter or start "
            "is another case: the article's expected times are then not compared.",
        ),
    ] = None,
    out_dir: Annotated[
        Path | None,
        typer.Option("--out", metavar="DIR", help="Output folder, new (default: runs/CASE-YYYYmmdd-HHMMSS)."),
    ] = None,
    fmt: Annotated[
        str, typer.Option("--format", metavar="FORMAT", help="Event table format: csv, parquet or both.")
    ] = "both",
    no_plots: Annotated[bool, typer.Option("--no-plots", help="Skip the figures.")] = False,
    no_report: Annotated[bool, typer.Option("--no-report", help="Skip the Markdown/HTML report.")] = False,
    sample: Annotated[
        float | None,
        typer.Option("--sample", metavar="DT", help="Record the trajectory every DT s, not at every solver step."),
    ] = None,
    window: Annotated[
        tuple[float, float] | None,
        typer.Option(
            "--window",
            metavar="T0 T1",
            help="Draw the figures for this time window (default: the whole run, or its last 10 forcing periods "
            "when it is longer than 20).",
        ),
    ] = None,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="Print only the output folder (for scripts).")] = False,
) -> None:
    """Run a case, print its switching events, and write tables, figures and a report.

    \b
    Examples:
      oscillator run instance-3
      oscillator run instance-1 --t-end 30 --set Omega=1.7 --set Q2=70 --out runs/omega-1.7
      oscillator run my-case.toml --format parquet --no-plots --quiet --out runs/mine
      oscillator run instance-1 --t-end 2000 --sample 0.05 --out runs/long
      oscillator run instance-1 --t-end 2000 --sample 0.05 --window 1000 1010 --out runs/long-window
    """
    try:
        if window is not None and no_plots:
            raise OscillatorError(
                "--window chooses what the figures show; it has no use with --no-plots", field="--window"
            )
        resolved, grid, claim = _prepare_run(case, t_end, set_, out_dir, fmt, sample, window)
    except OscillatorError as error:
        raise _fail(str(error)) from None
    except KeyboardInterrupt:
        raise _fail("interrupted; nothing was written", 130) from None
    from oscillator.output import finish_run, write_run

    pending = tuple(step for step, skipped in (("figures", no_plots), ("report", no_report)) if not skipped)
    try:
        result = _simulate_with_progress(resolved, quiet, grid)
    except OscillatorError as error:
        code = 1 if hasattr(error, "result") else 2
        raise _fail(f"{error}\n{_write_partial(error, claim, fmt, pending)}", code=code) from None
    except KeyboardInterrupt as interrupt:
        raise _fail(f"interrupted; {_write_partial(interrupt, claim, fmt, pending)}", 130) from None
    except BaseException:
        claim.abandon()
        raise
    try:
        with interrupts_deferred():  # Ctrl-C waits until the tables are written whole
            folder = write_run(result, claim, formats=fmt, command=["oscillator", *sys.argv[1:]], pending=pending)
    except KeyboardInterrupt:  # it came while the tables were written: they are whole
        raise _fail(f"interrupted; {_tables_kept(folder)}", 130) from None
    except (OSError, OscillatorError) as error:
        reason = error.strerror if isinstance(error, OSError) and error.strerror else str(error)
        raise _fail(f"cannot write the run to {claim.target}: {reason}; nothing was written; free the space or "
                    f"give another --out, and run again", 1) from None  # fmt: skip
    if pending:
        try:
            _load("oscillator.plotting", "oscillator.report")
            finish_run(folder, figures=not no_plots, report=not no_report, window=window)
        except KeyboardInterrupt:
            raise _fail(f"interrupted; {_tables_kept(folder)}", 130) from None
        except Exception as error:  # a later step failed: the run itself is safe
            reason = f"{type(error).__name__}: {error}"
            raise _fail(f"the figures or report could not be made ({reason}); {_tables_kept(folder)}", 1) from None
    _print_run(resolved, result, folder, quiet)


def _tables_kept(folder: Path) -> str:
    return f"the run's tables are in {folder}; `oscillator report {folder}` makes its figures and report"


def _print_run(case: Case, result: Result, folder: Path, quiet: bool) -> None:
    if quiet:
        out.print(printable(str(folder)))
        return
    _say((case.name, "bold"), f": {case.full_title}")
    out.print(_events_table(result.events) if len(result.events) else "no switching events")
    energy = result.energy
    _say(f"energy audit residual {energy['residual']:.2e} J (E0 = {energy['E0']:.4f} J, E1 = {energy['E1']:.4f} J)")
    if case.expected:
        from oscillator.reproduction import compare

        comparison = compare(case, result.events)
        ok = int((comparison.within_article & comparison.within_reference).sum())
        _say(f"expected events within tolerance: {ok}/{len(comparison)}")
    elif case.modified:
        _say(f"modified case ({', '.join(case.modified)}): the expected times of the case as written are not compared")
    _say("written to ", (str(folder), "bold"))


# --------------------------------------------------------------------------- check and report


@app.command(short_help="Compare a case's switching times with the article's.")
def check(
    case: Annotated[str, typer.Argument(metavar="CASE", help="A case with [[expected]] events.")],
    set_: Annotated[
        list[str] | None,
        typer.Option("--set", metavar="NAME=VALUE", help="A solver option (rtol, atol, ...) for this check."),
    ] = None,
) -> None:
    """Compare a case's switching times with the article's; exit 1 if one is out of tolerance.

    \b
    Examples:
      oscillator check instance-5
      oscillator check instance-3 --set rtol=1e-12 --set atol=1e-12
    """
    try:
        resolved = _case(case, None, set_)
        if resolved.modified:
            raise OscillatorError(
                f"--set changes the case ({', '.join(resolved.modified)}); its expected times are for the case as "
                f"written, so check takes solver options only (rtol, atol, ...); write a case file to check another "
                f"case",
                field="--set",
            )
        if not resolved.expected:
            raise OscillatorError(
                f"case {shown(resolved.name)} has no [[expected]] events to check against", field="case"
            )
        _load("oscillator.reproduction", "oscillator.simulation")
        from oscillator.reproduction import compare
        from oscillator.simulation import simulate

        table = compare(resolved, simulate(resolved, record_trajectory=False).events)
    except OscillatorError as error:
        raise _fail(str(error), code=1 if hasattr(error, "result") else 2) from None
    except KeyboardInterrupt:
        raise _fail("interrupted", code=130) from None
    view = Table(title=f"{printable(resolved.name)}: expected switching times", title_justify="left",
                 header_style="bold")  # fmt: skip
    for column in ("event", "article", "reference", "ours", "ours − article", "ours − reference", "ok"):
        view.add_column(column)
    for row in table.itertuples(index=False):
        ok = row.within_article and row.within_reference
        view.add_row(
            printable(row.label), _time(row.article), _time(row.reference), _time(row.ours, 6),
            _delta(row.ours_minus_article), _delta(row.ours_minus_reference), Text("✓") if ok else Text("✗", "red"),
        )  # fmt: skip
    out.print(view)
    for row in table.itertuples(index=False):
        if row.note:
            out.print(Text(f"{printable(row.label)}: {printable(row.note)}", style="dim"))
    failed = int((~(table.within_article & table.within_reference)).sum())
    if failed:
        err.print(Text(f"{failed} expected time(s) out of tolerance", style="bold red"))
        raise typer.Exit(1)
    _say(f"all {len(table)} expected times within tolerance")


def _time(value: float, digits: int = 4) -> str:
    return "—" if value != value else f"{value:.{digits}f}"


def _delta(value: float) -> str:
    return "—" if value != value else f"{value:+.1e}"


@app.command(short_help="Rebuild a run folder's report (and missing figures).")
def report(
    folder: Annotated[Path, typer.Argument(metavar="DIR", help="A folder written by oscillator run.")],
    window: Annotated[
        tuple[float, float] | None,
        typer.Option("--window", metavar="T0 T1", help="Redraw the figures for this time window."),
    ] = None,
) -> None:
    """Rebuild the report of a run folder; draw its figures if they are missing.

    Finishes a run whose figures or report were interrupted. With --window, redraws the
    figures for that time window.

    \b
    Examples:
      oscillator report runs/omega-1.7
      oscillator report runs/long --window 1990 2000
    """
    try:
        _load("oscillator.output", "oscillator.plotting", "oscillator.report")
        from oscillator.output import finish_run

        if folder.is_dir() and not os.access(folder, os.W_OK):
            raise OscillatorError(f"{folder}: cannot write in it; give a run folder you can write to", field="DIR")
        finish_run(folder, window=window)
    except OscillatorError as error:
        raise _fail(str(error)) from None
    except KeyboardInterrupt:
        raise _fail(f"interrupted; `oscillator report {folder}` finishes the report", 130) from None
    except OSError as error:
        raise _fail(f"{folder}: {error.strerror or error}; the report could not be written", 1) from None
    _say(f"report rebuilt: {folder / 'report.md'}, {folder / 'report.html'}")


# --------------------------------------------------------------------------- sweeps


def _sweep_settings(c: Case, param, start, stop, steps, transient, record) -> SweepSettings:
    """The case's ``[sweep]`` table with the command line's changes."""
    base = c.sweep
    if base is None and (param is None or start is None or stop is None):
        raise OscillatorError(
            f"case {shown(c.name)} has no [sweep] table; give --param NAME --from A --to B", field="--param"
        )
    changes = {k: v for k, v in dict(param=param, start=start, stop=stop, steps=steps, transient=transient,
                                     record=record).items() if v is not None}  # fmt: skip
    if base is None:
        return SweepSettings(**changes)
    return dataclasses.replace(base, **changes)


def _sweep_progress(name: str, settings: SweepSettings):
    """A progress bar and its callback ``report(done, total)``."""
    columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
               TextColumn("{task.fields[rate]}"), TimeElapsedColumn(), TimeRemainingColumn())  # fmt: skip
    bar = Progress(*columns, console=err, transient=True)
    task = bar.add_task(f"{printable(name)}: {settings.param}", total=settings.steps, rate="")
    began = time.monotonic()
    first: list[int] = []

    def report(done: int, total: int) -> None:
        if not first:
            first.append(done)
        new = done - first[0]
        rate = f"{new / (time.monotonic() - began):.2f} points/s" if new else ""
        bar.update(task, completed=done, total=total, rate=rate)

    return bar, report


@app.command(short_help="Sweep a parameter: Fig. 14-style switching and Poincaré points.")
def sweep(
    case: Annotated[
        str, typer.Argument(metavar="CASE", help="A scene with a [sweep] table (bifurcation-omega, ...) or any case.")
    ],
    param: Annotated[
        str | None, typer.Option("--param", metavar="NAME", help="The swept parameter (default: the case's).")
    ] = None,
    start: Annotated[float | None, typer.Option("--from", metavar="A", help="First value.")] = None,
    stop: Annotated[float | None, typer.Option("--to", metavar="B", help="Last value.")] = None,
    steps: Annotated[int | None, typer.Option("--steps", metavar="N", help="Number of values (default 111).")] = None,
    transient: Annotated[
        int | None, typer.Option("--transient", metavar="N", help="Forcing periods before recording (default 100).")
    ] = None,
    record: Annotated[
        int | None, typer.Option("--record", metavar="N", help="Forcing periods recorded (default 50).")
    ] = None,
    workers: Annotated[
        int | None, typer.Option("--workers", metavar="N", help="Local processes (default: every core).")
    ] = None,
    scheduler: Annotated[
        str | None,
        typer.Option("--scheduler", metavar="ADDRESS", help="Run on a Dask cluster: tcp://HOST:PORT of its scheduler."),
    ] = None,
    out_dir: Annotated[
        Path | None,
        typer.Option(
            "--out",
            metavar="DIR",
            help="Output folder (default: runs/CASE-sweep-YYYYmmdd-HHMMSS); the same folder again resumes the sweep.",
        ),
    ] = None,
    set_: Annotated[
        list[str] | None, typer.Option("--set", metavar="NAME=VALUE", help="Override (repeatable).")
    ] = None,
    no_plots: Annotated[bool, typer.Option("--no-plots", help="Skip the diagrams.")] = False,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="Print only the output folder.")] = False,
) -> None:
    """Sweep a parameter: switching points, Poincaré points and a summary per value.

    Writes switches.parquet, poincare.parquet and summary.parquet (each with the swept parameter
    as a column) and Fig. 14-style diagrams. Interrupted or killed, the same command with the same
    --out resumes where it stopped. On a Dask cluster (pip install "oscillator[dask]"), give
    --scheduler tcp://HOST:PORT.

    \b
    Examples:
      oscillator sweep bifurcation-omega --out runs/omega
      oscillator sweep bifurcation-q2 --steps 36 --workers 2 --out runs/q2
      oscillator sweep instance-1 --param Omega --from 1.5 --to 1.7 --steps 21 --transient 20 --record 10
    """
    try:
        resolved = _case(case, None, set_)
        settings = _sweep_settings(resolved, param, start, stop, steps, transient, record)
        plan = _open_sweep(resolved, settings, out_dir, workers, scheduler)
    except OscillatorError as error:
        raise _fail(str(error)) from None
    except KeyboardInterrupt:
        raise _fail("interrupted; nothing was written", 130) from None
    folder = plan.folder
    try:
        if quiet or not err.is_terminal:
            outcome = plan.run()
        else:
            bar, report_progress = _sweep_progress(resolved.name, settings)
            with bar:
                outcome = plan.run(report_progress)
    except OscillatorError as error:
        raise _fail(str(error), 1) from None
    except KeyboardInterrupt:
        raise _fail("interrupted; the points finished so far are kept: run the same command to resume", 130) from None
    finally:
        plan.close()
    _finish_sweep(resolved, settings, folder, outcome, no_plots, quiet)


def _open_sweep(case: Case, settings: SweepSettings, out_dir: Path | None, workers, scheduler):
    """The sweep checked and its folder locked: ``out_dir``, or a new ``runs/<case>-sweep-<timestamp>``."""
    from oscillator._files import FolderTaken

    _load("oscillator.sweep")
    from oscillator.sweep import open_sweep

    if out_dir is not None:
        return open_sweep(case, settings, out_dir, workers=workers, scheduler=scheduler)
    stamp = time.strftime("%Y%m%d-%H%M%S")
    for n in range(1, 10_000):
        folder = Path("runs") / (f"{case.name}-sweep-{stamp}" if n == 1 else f"{case.name}-sweep-{stamp}-{n}")
        if os.path.lexists(folder):
            continue
        try:
            return open_sweep(case, settings, folder, workers=workers, scheduler=scheduler)
        except FolderTaken:
            continue
    raise OscillatorError("no free folder name under runs/; give --out", field="--out")


def _finish_sweep(case: Case, settings: SweepSettings, folder: Path, outcome, no_plots: bool, quiet: bool) -> None:
    from oscillator.sweep import read_sweep, sliding_ranges

    tables = read_sweep(folder)
    if not no_plots:
        try:
            _load("oscillator.plotting")
            from oscillator.plotting import write_sweep_figures

            write_sweep_figures(tables, settings.param, settings.mass, folder / "figures", title=case.name)
        except KeyboardInterrupt:
            raise _fail(f"interrupted while drawing; the sweep's tables are in {folder}", 130) from None
        except Exception as error:  # the sweep itself is safe
            raise _fail(f"the diagrams could not be drawn ({type(error).__name__}: {error}); the sweep's tables "
                        f"are in {folder}", 1) from None  # fmt: skip
    if quiet:
        out.print(printable(str(folder)))
        return
    summary = tables["summary"]
    ranges = sliding_ranges(summary, settings.param)
    _say(
        (case.name, "bold"),
        f": {settings.param} from {settings.start:g} to {settings.stop:g} ({settings.steps} values, "
        f"{settings.transient} + {settings.record} periods); {outcome.computed} computed, {outcome.resumed} resumed, "
        f"{outcome.failed} failed, {outcome.wall_time:.1f} s",
    )
    for a, b in ranges:
        _say(f"m{settings.mass} slides (rests on its velocity boundary) for {settings.param} in [{a:.6g}, {b:.6g}]")
    if not ranges:
        _say(f"m{settings.mass} never slides in this range")
    periods = summary[summary.status == "ok"].period.value_counts().sort_index()
    _say("periods found: " + ", ".join(f"period-{n}: {c}" if n else f"none: {c}" for n, c in periods.items()))
    _say("written to ", (str(folder), "bold"))


@app.command(short_help="Find where a sweep's summary changes, to 1e-8.")
def locate(
    case: Annotated[
        str, typer.Argument(metavar="CASE", help="A scene or case (its [sweep] table gives the defaults).")
    ],
    between: Annotated[
        tuple[float, float],
        typer.Option("--between", metavar="A B", help="Two parameter values on either side of a change."),
    ],
    what: Annotated[
        str, typer.Option("--what", metavar="WHAT", help="What changes: sliding, grazing or period.")
    ] = "sliding",
    param: Annotated[
        str | None, typer.Option("--param", metavar="NAME", help="The parameter (default: the case's).")
    ] = None,
    transient: Annotated[
        int | None, typer.Option("--transient", metavar="N", help="Forcing periods before recording.")
    ] = None,
    record: Annotated[int | None, typer.Option("--record", metavar="N", help="Forcing periods recorded.")] = None,
    tolerance: Annotated[
        float, typer.Option("--tolerance", metavar="WIDTH", help="Width of the final bracket.")
    ] = 1e-8,
    set_: Annotated[
        list[str] | None, typer.Option("--set", metavar="NAME=VALUE", help="Override (repeatable).")
    ] = None,
) -> None:
    """Find where the sweep's summary changes between two values (bisection, to 1e-8).

    Both ends are simulated first to see that they differ; then each bisection step simulates
    the middle. Prints the bracket and, on both sides, the summary and the switching events that
    show the change.

    \b
    Example:
      oscillator locate bifurcation-omega --between 1.595 1.600 --what sliding
    """
    try:
        resolved = _case(case, None, set_)
        _load("oscillator.sweep")
        from oscillator.sweep import locate as locate_change

        lo, hi = between
        settings = _sweep_settings(resolved, param, lo, hi, None, transient, record)
        if not err.is_terminal:
            found = locate_change(resolved, settings, what, (lo, hi), tolerance=tolerance)
        else:
            columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
                       TextColumn("{task.fields[bracket]}"), TimeElapsedColumn())  # fmt: skip
            with Progress(*columns, console=err, transient=True) as bar:
                task = bar.add_task(f"locating {printable(what)}", total=None, bracket="")

                def report(step: int, steps: int, a: float, b: float) -> None:
                    stage = "simulating both ends" if step <= 2 else f"bracket [{a:.10g}, {b:.10g}], {b - a:.1e} wide"
                    bar.update(task, completed=step - 1, total=steps, bracket=stage)

                found = locate_change(resolved, settings, what, (lo, hi), tolerance=tolerance, progress=report)
    except OscillatorError as error:
        raise _fail(str(error)) from None
    except KeyboardInterrupt:
        raise _fail("interrupted", 130) from None
    _say(
        (what, "bold"),
        f" changes at {found.param} = {found.value:.10f} (between {found.lower:.10f} and {found.upper:.10f}, "
        f"width {found.width:.1e}, {found.iterations} bisections)",
    )
    for side, summary, events in (("below", found.below, found.evidence_below),
                                  ("above", found.above, found.evidence_above)):  # fmt: skip
        row = summary.iloc[0]
        kinds = ", ".join(f"{k}: {n}" for k, n in events.kind.value_counts().items()) or "none"
        _say(
            f"{side} ({found.param} = {row[found.param]:.10f}): sliding {bool(row.sliding)}, "
            f"period {int(row.period)}, {row.switches_per_period:g} switches/period, "
            f"rest {row.rest_time_per_period:.3g} s/period; events: {kinds}"
        )


@app.callback(invoke_without_command=True)
def _version(
    version: Annotated[bool, typer.Option("--version", help="Print the version and exit.")] = False,
) -> None:
    if version:
        out.print(f"oscillator {__version__}")
        raise typer.Exit(0)


#: Click's exception classes, as Typer uses them (recent Typer versions bring their own copy of
#: Click, older ones use Click itself): found through the class Typer exports.
_CLICK_ERROR = next(c for c in typer.BadParameter.__mro__ if c.__name__ == "ClickException")


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


def main(args: list[str] | None = None) -> None:
    """Entry point of the ``oscillator`` command: every outcome is an exit code and at most one
    line of error, never a traceback (see the module docstring for the codes)."""
    args = sys.argv[1:] if args is None else list(args)
    try:
        command = typer.main.get_command(app)
        code = command.main(args=args, prog_name="oscillator", standalone_mode=False)
        if code == 130 and not _reported:  # Typer caught Ctrl-C while it read the command line
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
        from oscillator.__main__ import interrupted_exit

        interrupted_exit()
    sys.exit(code if isinstance(code, int) else 0)
