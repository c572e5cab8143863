"""``oscillator run`` (a case to a run folder) and ``oscillator report`` (a run folder's report)."""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer
from rich import box
from rich.console import JustifyMethod
from rich.measure import Measurement
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn
from rich.table import Table
from rich.text import Text

from oscillator.cli.commands import command
from oscillator.cli.console import err, fail, load, message, out, say
from oscillator.cli.inputs import case_from, check_engine, sample_grid
from oscillator.cli.options import CaseArgument, EngineOption, NoPlotsOption, QuietOption, SetOption
from oscillator.errors import InputError, Interrupted, OscillatorError, SimulationFailed
from oscillator.io.cases import Case
from oscillator.io.files import check_new
from oscillator.io.signals import interrupts_deferred
from oscillator.text import printable, shown

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd

    from oscillator.hybrid.result import Result
    from oscillator.io.files import FolderClaim

__all__ = ["report", "run"]

FORMATS = ("csv", "parquet", "both")


#: The event table's columns, most important first: (header, justification, cell of a row).
_EVENT_COLUMNS: tuple[tuple[str, JustifyMethod, Callable[[Any], str]], ...] = (
    ("t (s)", "right", lambda row: f"{row.t:.6f}"),
    ("mass", "right", lambda row: str(row.mass)),
    ("kind", "left", lambda row: row.kind),
    ("domain", "left", lambda row: f"{row.from_domain} → {row.to_domain}"),
    ("theorem", "left", lambda row: f"{row.theorem} {row.equation}"),
    ("boundary", "left", lambda row: row.boundary),
)


def _events_table(events: pd.DataFrame, limit: int = 40) -> Table:
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


def _simulate_with_progress(case: Case, quiet: bool, t_eval: Any = None, engine: str | None = None) -> Result:
    from oscillator.hybrid.recording import SaveAt
    from oscillator.hybrid.simulate import simulate

    if quiet or not err.is_terminal:  # a progress bar only where a person watches
        return simulate(case, save=SaveAt(ts=t_eval), engine=engine)
    span = case.t_end - case.initial.t0
    columns = (
        TextColumn("{task.description}"),
        BarColumn(),
        TextColumn("t = {task.fields[t]:.4g} s"),
        TimeElapsedColumn(),
        TimeRemainingColumn(),
    )
    with Progress(*columns, console=err, transient=True) as progress:
        task = progress.add_task(printable(case.name), total=span, t=case.initial.t0)
        last = [0.0]

        def report(t: float) -> None:
            now = time.monotonic()
            if now - last[0] > 0.1:
                last[0] = now
                progress.update(task, completed=t - case.initial.t0, t=t)

        return simulate(case, save=SaveAt(ts=t_eval), progress=report, engine=engine)


def _write_partial(error: BaseException, claim: FolderClaim, fmt: str, pending: tuple[str, ...]) -> str:
    """Write the error's partial result (``error.result``) into the claimed folder; say where."""
    from oscillator.hybrid.result import Result
    from oscillator.report.runs import write_run

    partial = error.result if isinstance(error, (SimulationFailed, Interrupted)) else None
    if not isinstance(partial, Result):
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


def _prepare_run(
    case: str,
    t_end: float | None,
    set_: list[str] | None,
    out_dir: Path | None,
    fmt: str,
    sample: float | None,
    window: tuple[float, float] | None,
    engine: str | None,
    keep: float | None,
    quiet: bool,
) -> tuple[Case, object, FolderClaim]:
    """Every check of ``run`` before anything is created, then the output folder claimed."""
    if fmt not in FORMATS:
        raise InputError(f"--format must be one of {', '.join(FORMATS)}, got {shown(fmt)}", field="--format")
    resolved = case_from(case, t_end, set_, keep)
    grid = sample_grid(resolved, sample)

    if out_dir is not None:
        check_new(out_dir, option="--out")  # before the numerical libraries load: a refusal is quick
    load("oscillator.report.runs", "oscillator.hybrid.simulate", "oscillator.report.figures", notice=not quiet)
    from oscillator.engines import build_engine
    from oscillator.hybrid.simulate import admit
    from oscillator.report.figures import figure_window
    from oscillator.report.runs import claim_output

    if window is not None:
        figure_window(resolved.initial.t0, resolved.t_end, resolved.parameters.period, window)

    with interrupts_deferred():  # the first call of the compiled formulas loads them
        admit(resolved)
        build_engine(engine, resolved.parameters, resolved.options).close()  # an engine's own refusals
    return resolved, grid, claim_output(out_dir, resolved.name)


@command(30, "Run a case; write its tables, figures and report.")
def run(
    case: CaseArgument,
    t_end: Annotated[
        float | None, typer.Option("--t-end", metavar="T", help="End time in s (default: the case's).")
    ] = None,
    set_: SetOption = None,
    out_dir: Annotated[
        Path | None,
        typer.Option("--out", metavar="DIR", help="Output folder, new (default: runs/CASE-YYYYmmdd-HHMMSS)."),
    ] = None,
    fmt: Annotated[
        str, typer.Option("--format", metavar="FORMAT", help="Event table format: csv, parquet or both.")
    ] = "both",
    no_plots: NoPlotsOption = False,
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
    engine: EngineOption = None,
    keep: Annotated[
        float | None,
        typer.Option("--keep-events-from", metavar="T", help="Keep only the events at or after T s (a long run)."),
    ] = None,
    quiet: QuietOption = False,
) -> None:
    """Run a case or a system file (docs/systems.md), print its switching events, and write tables,
    figures and a report.

    A case changed by --set in a parameter or its start is another case: the article's expected
    times are then not compared.

    \b
    Examples:
      oscillator run instance-3
      oscillator run instance-1 --t-end 30 --set Omega=1.7 --set Q2=70 --out runs/omega-1.7-q2-70
      oscillator run my-case.toml --format parquet --no-plots --quiet --out runs/mine
      oscillator run instance-1 --t-end 2000 --sample 0.05 --out runs/long
      oscillator run instance-1 --t-end 2000 --sample 0.05 --window 1000 1010 --out runs/long-window
      oscillator run instance-1 --t-end 4000 --sample 1 --keep-events-from 3990 --out runs/longer
      oscillator run docs/systems/blade-damper.toml --out runs/blade
      oscillator run docs/systems/blade-damper.toml --set platform.F=0.5 --out runs/blade-0.5
    """
    if _ran_system(case, t_end, set_, out_dir, fmt, no_plots, no_report, sample, window, engine, keep, quiet):
        return
    try:
        if window is not None and no_plots:
            raise InputError("--window chooses what the figures show; it has no use with --no-plots", field="--window")
        check_engine(engine)
        resolved, grid, claim = _prepare_run(case, t_end, set_, out_dir, fmt, sample, window, engine, keep, quiet)
    except OscillatorError as error:
        raise fail(message(error)) from None
    except KeyboardInterrupt:
        raise fail("interrupted; nothing was written", 130) from None
    pending = tuple(step for step, skipped in (("figures", no_plots), ("report", no_report)) if not skipped)
    result = _simulate_or_keep_partial(resolved, grid, claim, fmt, pending, quiet, engine)
    folder = _write_tables(result, claim, fmt, pending)
    summary = [] if quiet else _run_summary(resolved, result)
    del result  # the figures and the report read the folder: a long run's tables are not held twice
    if pending:
        _finish(folder, figures=not no_plots, report=not no_report, window=window)
    _print_summary(summary, folder, quiet)


def _ran_system(
    case: str,
    t_end: float | None,
    set_: list[str] | None,
    out_dir: Path | None,
    fmt: str,
    no_plots: bool,
    no_report: bool,
    sample: float | None,
    window: tuple[float, float] | None,
    engine: str | None,
    keep: float | None,
    quiet: bool,
) -> bool:
    """Run ``case`` if it is a system file (:mod:`oscillator.cli.system`); whether it was one."""
    from oscillator.io.chains import system_path

    system = system_path(case)
    if system is None:
        return False
    from oscillator.cli.system import run_system

    given = (("--sample", sample), ("--window", window), ("--engine", engine), ("--keep-events-from", keep))
    flags = [flag for flag, value in given if value]
    run_system(
        system,
        t_end=t_end,
        out_dir=out_dir,
        fmt=fmt,
        no_plots=no_plots,
        no_report=no_report,
        quiet=quiet,
        case_only=flags,
        assignments=set_ or [],
    )
    return True


def _simulate_or_keep_partial(
    case: Case, grid: Any, claim: FolderClaim, fmt: str, pending: tuple[str, ...], quiet: bool, engine: str | None
) -> Result:
    """The run; if it fails or is interrupted, its partial result written into the claimed folder."""
    try:
        return _simulate_with_progress(case, quiet, grid, engine)
    except OscillatorError as error:
        code = 1 if isinstance(error, SimulationFailed) and error.result is not None else 2
        raise fail(f"{error}\n{_write_partial(error, claim, fmt, pending)}", code=code) from None
    except KeyboardInterrupt as interrupt:
        raise fail(f"interrupted; {_write_partial(interrupt, claim, fmt, pending)}", 130) from None
    except BaseException:
        claim.abandon()
        raise


def _write_tables(result: Result, claim: FolderClaim, fmt: str, pending: tuple[str, ...]) -> Path:
    """The run's tables, case and run.json written whole into the claimed folder."""
    from oscillator.report.runs import write_run

    try:
        with interrupts_deferred():  # Ctrl-C waits until the tables are written whole
            folder = write_run(result, claim, formats=fmt, command=["oscillator", *sys.argv[1:]], pending=pending)
    except KeyboardInterrupt:  # it came while the tables were written: they are whole
        raise fail(f"interrupted; {_tables_kept(claim.target)}", 130) from None
    except (OSError, OscillatorError) as error:
        reason = error.strerror if isinstance(error, OSError) and error.strerror else str(error)
        raise fail(
            f"cannot write the run to {claim.target}: {reason}; nothing was written; free the space or "
            f"give another --out, and run again",
            1,
        ) from None
    return folder


def _finish(folder: Path, *, figures: bool, report: bool, window: tuple[float, float] | None) -> None:
    """The figures and the report; if they fail, the tables stay and the message says how to finish."""
    from oscillator.report.runs import finish_run

    try:
        load("oscillator.report.figures", "oscillator.report.transitions")
        finish_run(folder, figures=figures, report=report, window=window)
    except KeyboardInterrupt:
        raise fail(f"interrupted; {_tables_kept(folder)}", 130) from None
    except Exception as error:  # a later step failed: the run itself is safe
        reason = f"{type(error).__name__}: {error}"
        raise fail(f"the figures or report could not be made ({reason}); {_tables_kept(folder)}", 1) from None


def _rebuilt_chain(folder: Path, window: tuple[float, float] | None) -> bool:
    """The figures and report of a friction chain's run folder made again; whether it was one."""
    from oscillator.report.runs import is_chain_folder

    if not is_chain_folder(folder):  # an article case's folder: the chains' code is not loaded
        return False
    from oscillator.report.chain_runs import finish_chain_run, read_chain_run

    if window is not None:
        raise InputError(
            "--window redraws an article case's run; a system's figures show the whole run", field="--window"
        )
    result = read_chain_run(folder)  # a damaged folder is refused before anything is drawn
    load("oscillator.report.chain_figures")
    finish_chain_run(folder, result)
    say(f"report rebuilt: {folder / 'report.md'}, {folder / 'report.html'}")
    return True


def _tables_kept(folder: Path) -> str:
    return f"the run's tables are in {folder}; `oscillator report {folder}` makes its figures and report"


def _print_summary(summary: list[Any], folder: Path, quiet: bool) -> None:
    for k, line in enumerate(summary):  # the title wraps at the terminal's width; tables fit it themselves
        out.print(line, soft_wrap=k > 0)
    if quiet:
        out.print(printable(str(folder)))
    else:
        say("written to ", (str(folder), "bold"))


def _run_summary(case: Case, result: Result) -> list[Text | Table | str]:
    """What ``run`` prints of a finished run: its events, the energy audit, the comparison."""
    energy = result.energy
    lines: list[Text | Table | str] = [
        Text.assemble((printable(case.name), "bold"), printable(f": {case.full_title}")),
        _events_table(result.events) if len(result.events) else "no switching events",
        Text(f"energy audit residual {energy.residual:.2e} J (E0 = {energy.E0:.4f} J, E1 = {energy.E1:.4f} J)"),
    ]
    if case.expected:
        from oscillator.analysis.reproduction import compare

        comparison = compare(case, result.events)
        ok = int((comparison.within_article & comparison.within_reference).sum())
        lines.append(Text(f"expected events within tolerance: {ok}/{len(comparison)}"))
    elif case.modified:
        lines.append(
            Text(
                printable(
                    f"modified case ({', '.join(case.modified)}): the expected times of the case as "
                    "written are not compared"
                )
            )
        )
    return lines


@command(50, "Rebuild a run folder's report (and missing figures).")
def report(
    folder: Annotated[
        Path,
        typer.Argument(
            metavar="DIR", help="A folder written by oscillator run, continue, basins, atlas, curve, frc or design."
        ),
    ],
    window: Annotated[
        tuple[float, float] | None,
        typer.Option("--window", metavar="T0 T1", help="Redraw the figures for this time window."),
    ] = None,
) -> None:
    """Rebuild the report of a run or branch folder; draw its figures if they are missing.

    Finishes a run (or a continued branch) whose figures or report were interrupted. With
    --window, redraws a run's figures for that time window. A finished basins, atlas, curve, frc
    or design folder gets its tables, figures and report again, from what it keeps (nothing
    computed anew but the basins' orbits refined and the design's responses before and after).

    \b
    Examples:
      oscillator report runs/omega-1.7-q2-70
      oscillator report runs/long --window 1990 2000
      oscillator report runs/blade
    """
    try:
        load("oscillator.report.runs")
        from oscillator.report.runs import finish_run, folder_kind, read_run_folder

        if folder.is_dir() and not os.access(folder, os.W_OK):
            raise InputError(f"{folder}: cannot write in it; give a run folder you can write to", field="DIR")
        load("oscillator.report.kinds")
        from oscillator.report.kinds import rebuild

        if _rebuilt_chain(folder, window):
            return
        rebuilt = rebuild(folder)  # an analysis's folder (its marker names its kind), or None
        if rebuilt is not None:
            what, problems = rebuilt
            say(f"report rebuilt ({what}): {folder / 'report.md'}, {folder / 'report.html'}")
            if problems:
                raise fail("; ".join(problems) + f"; the tables are in {folder}", 1)
            return
        if folder_kind(folder) == "branch":
            if window is not None:
                raise InputError("--window chooses a run's time window; a branch folder has none", field="--window")
            load("oscillator.report.orbit_folders")
            from oscillator.report.orbit_folders import finish_branch

            finish_branch(folder)
        else:
            checked = read_run_folder(folder)  # a damaged folder is refused before the drawing libraries load
            load("oscillator.report.figures", "oscillator.report.transitions")
            finish_run(folder, window=window, run=checked)
    except OscillatorError as error:
        raise fail(message(error)) from None
    except KeyboardInterrupt:
        raise fail(f"interrupted; `oscillator report {folder}` finishes the report", 130) from None
    except OSError as error:
        raise fail(f"{folder}: {error.strerror or error}; the report could not be written", 1) from None
    say(f"report rebuilt: {folder / 'report.md'}, {folder / 'report.html'}")
