"""The ``oscillator`` command: list, show, run, check and report cases.

Every refusal (unknown case or parameter, bad value, malformed file, unwritable folder) is one
line naming the field and the fix, with exit code 2 and nothing written.  A run that starts and
then fails (solver error, guard) exits 1, and ``run`` writes its partial result marked
``failed``; ``check`` exits 1 when a time is outside its tolerance.  Ctrl-C exits 130.
"""

from __future__ import annotations

import dataclasses
import math
import sys
import time
from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.console import Console
from rich.markup import escape
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)
from rich.table import Table

from oscillator import OscillatorError, __version__, case_names, load_case
from oscillator._files import replace_file
from oscillator.cases import Case, parse_value
from oscillator.output import FORMATS, check_output_folder, default_output_folder, read_run, write_run
from oscillator.parameters import SolverOptions, SweepSettings
from oscillator.plotting import write_figures, write_sweep_figures
from oscillator.report import render_html, render_markdown
from oscillator.reproduction import compare
from oscillator.simulation import resolve_case, simulate
from oscillator.sweep import locate as locate_change
from oscillator.sweep import read_sweep, run_sweep, sliding_ranges

__all__ = ["app", "main"]

app = typer.Typer(
    name="oscillator",
    help="Simulate the 2-DOF frictional oscillator with elastic stops of the article, "
    "and explain every switch by its theorem.",
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    rich_markup_mode="markdown",
)
out = Console(highlight=False, soft_wrap=True)
err = Console(stderr=True, highlight=False)
_INTEGER_OPTIONS = {f.name for f in SolverOptions.__dataclass_fields__.values() if f.type in ("int", int)}


class BadInput(Exception):
    """Raised inside commands for refusals that are not the library's own."""


def _fail(message: str, code: int = 2) -> typer.Exit:
    err.print(f"[bold red]error:[/] {escape(message)}", soft_wrap=True)
    return typer.Exit(code)


def _overrides(assignments: list[str]) -> dict:
    """``NAME=VALUE`` strings to overrides, values as numbers or expressions of pi."""
    values = {}
    for item in assignments:
        name, sep, text = item.partition("=")
        name = name.strip()
        if not sep or not name:
            raise OscillatorError(f"--set {item!r}: write NAME=VALUE, e.g. --set Omega=1.7", field="--set")
        value = parse_value(text.strip(), field=f"--set {name}")
        if name in _INTEGER_OPTIONS:
            if not float(value).is_integer():
                raise OscillatorError(f"--set {name}={text}: {name} is a whole number", field=name)
            value = int(value)
        values[name] = value
    return values


def _case(case: str, t_end: float | None = None, assignments: list[str] | None = None) -> Case:
    return resolve_case(load_case(case), t_end=t_end, **_overrides(assignments or []))


def _events_table(events, limit: int = 40) -> Table:
    table = Table(title="switching events", title_justify="left", header_style="bold")
    for column in ("t (s)", "mass", "kind", "boundary", "domain", "theorem", "eq."):
        table.add_column(column, justify="right" if column in ("t (s)", "mass") else "left", no_wrap=column == "kind")
    rows = list(events.itertuples(index=False))
    shown = rows if len(rows) <= limit else [*rows[: limit // 2], None, *rows[-limit // 2 :]]
    for row in shown:
        if row is None:
            table.add_row("…", "", f"{len(rows) - limit} more", "", "", "", "")
            continue
        table.add_row(
            f"{row.t:.6f}", str(row.mass), row.kind, row.boundary, f"{row.from_domain} → {row.to_domain}",
            row.theorem, row.equation,
        )  # fmt: skip
    return table


def _sample_grid(case: Case, sample: float | None):
    """The grid of ``--sample DT``: every DT seconds from t0, and t_end."""
    if sample is None:
        return None
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


def _simulate_with_progress(case: Case, quiet: bool, t_eval=None):
    if quiet:
        return simulate(case, t_eval=t_eval)
    span = case.t_end - case.initial.t0
    columns = (TextColumn("[bold]{task.description}"), BarColumn(), TextColumn("t = {task.fields[t]:.4g} s"),
               TimeElapsedColumn(), TimeRemainingColumn())  # fmt: skip
    with Progress(*columns, console=err, transient=True) as progress:
        task = progress.add_task(case.name, total=span, t=case.initial.t0)
        last = [0.0]

        def report(t: float) -> None:
            now = time.monotonic()
            if now - last[0] > 0.1:
                last[0] = now
                progress.update(task, completed=t - case.initial.t0, t=t)

        return simulate(case, t_eval=t_eval, progress=report)


@app.command("list")
def list_cases() -> None:
    """List the named cases with their titles."""
    table = Table(header_style="bold")
    table.add_column("case")
    table.add_column("title")
    for name in case_names():
        table.add_row(name, load_case(name).title)
    out.print(table)


@app.command()
def show(case: Annotated[str, typer.Argument(help="A named case or the path of a case file.")]) -> None:
    """Show a case: its parameters, start, run settings and expected events.

    Example: `oscillator show instance-2`
    """
    try:
        c = load_case(case)
    except OscillatorError as error:
        raise _fail(str(error)) from None
    out.print(f"[bold]{c.name}[/]: {c.title}")
    if c.description:
        out.print(" ".join(c.description.split()))
    params = Table(title="parameters", title_justify="left", header_style="bold")
    for column in ("name", "value", "name ", "value "):
        params.add_column(column, justify="right" if "value" in column else "left")
    items = [(name, f"{getattr(c.parameters, name):.10g}") for name in c.parameters.names()]
    half = (len(items) + 1) // 2
    for left, right in zip(items[:half], [*items[half:], ("", "")], strict=False):
        params.add_row(*left, *right)
    out.print(params)
    initial = c.initial
    out.print(
        f"start: t0 = {initial.t0} s, x1 = {initial.x1} m, v1 = {initial.v1} m/s, x2 = {initial.x2} m, "
        f"v2 = {initial.v2} m/s; end: t_end = {c.t_end} s"
    )
    options = ", ".join(f"{name} = {getattr(c.options, name)}" for name in c.options.names())
    out.print(f"solver: {options}")
    if c.expected:
        table = Table(title="expected events", title_justify="left", header_style="bold")
        for column in ("event", "mass", "kind", "domain", "article (s)", "reference (s)", "tolerance (s)"):
            table.add_column(column)
        for e in c.expected:
            table.add_row(e.label, str(e.mass), str(e.kind), "" if e.to_domain is None else str(e.to_domain),
                          "—" if e.t is None else f"{e.t}", "—" if e.reference is None else f"{e.reference}",
                          f"{e.tolerance:g}")  # fmt: skip
        out.print(table)


def _keep_partial(error: BaseException, folder: Path | None, fmt: str) -> str:
    """Write the error's partial result (``error.result``), if any; say where it went, or why not.

    The partial result is written like a complete run (tables, case.toml, and run.json with its
    status and reason) without figures or report: ``oscillator report`` makes those.
    """
    partial = getattr(error, "result", None)
    if partial is None or folder is None:
        return "nothing was written"
    try:
        write_run(partial, folder, formats=fmt, command=["oscillator", *sys.argv[1:]])
    except (OscillatorError, OSError, KeyboardInterrupt) as failure:
        return f"the partial result could not be written: {failure}"
    return (
        f"the partial result up to t = {partial.final_state[0]:.10g} s is in {folder} "
        f'(run.json: "status": "{partial.status}"); `oscillator report {folder}` makes its report'
    )


@app.command()
def run(
    case: Annotated[str, typer.Argument(help="A named case (see `oscillator list`) or a case file (.toml).")],
    t_end: Annotated[float | None, typer.Option("--t-end", help="End time in s (default: the case's).")] = None,
    set_: Annotated[
        list[str] | None,
        typer.Option("--set", help="Override a parameter, initial value or solver option: NAME=VALUE (repeatable)."),
    ] = None,
    out_dir: Annotated[
        Path | None, typer.Option("--out", help="Output folder (default: runs/<case>-<timestamp>/); must not exist.")
    ] = None,
    fmt: Annotated[str, typer.Option("--format", help="Event table format: csv, parquet or both.")] = "both",
    no_plots: Annotated[bool, typer.Option("--no-plots", help="Skip the figures.")] = False,
    no_report: Annotated[bool, typer.Option("--no-report", help="Skip the Markdown/HTML report.")] = False,
    sample: Annotated[
        float | None,
        typer.Option("--sample", help="Record the trajectory every DT s, not at every solver step (long runs)."),
    ] = None,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="Print only the output folder (for scripts).")] = False,
) -> None:
    """Run a case, print its switching events and write tables, figures and a report.

    Examples:

    * `oscillator run instance-3`
    * `oscillator run instance-1 --t-end 30 --set Omega=1.7 --set Q2=70 --out runs/omega-1.7`
    * `oscillator run my-case.toml --format parquet --no-plots --quiet`
    * `oscillator run instance-1 --t-end 20000 --sample 0.05` (a long run, trajectory every 0.05 s)
    """
    folder: Path | None = None
    try:
        if fmt not in FORMATS:
            raise OscillatorError(f"--format must be one of {', '.join(FORMATS)}, got {fmt!r}", field="--format")
        resolved = _case(case, t_end, set_)
        folder = out_dir if out_dir is not None else default_output_folder(resolved.name)
        check_output_folder(folder)
        result = _simulate_with_progress(resolved, quiet, _sample_grid(resolved, sample))
        comparison = compare(resolved, result) if resolved.expected else None

        def extras(tmp: Path, info: dict) -> None:
            if not no_plots:
                start = (resolved.initial.t0, *resolved.initial.y)
                write_figures(result.trajectory, result.events, resolved.parameters, start, tmp / "figures",
                              title=resolved.name)  # fmt: skip
            if comparison is not None:
                info["check"] = {
                    "expected": len(comparison),
                    "within_tolerance": int((comparison.within_article & comparison.within_reference).sum()),
                }
            if not no_report:
                text = render_markdown(resolved, result.events, info, comparison=comparison, figures=not no_plots)
                (tmp / "report.md").write_text(text, encoding="utf-8")
                (tmp / "report.html").write_text(render_html(text, tmp), encoding="utf-8")

        write_run(result, folder, formats=fmt, extras=extras, command=["oscillator", *sys.argv[1:]])
    except OscillatorError as error:
        if not hasattr(error, "result"):  # refused before running: exit 2
            raise _fail(str(error)) from None
        raise _fail(f"{error}\n{_keep_partial(error, folder, fmt)}", code=1) from None
    except KeyboardInterrupt as interrupt:
        raise _fail(f"interrupted; {_keep_partial(interrupt, folder, fmt)}", code=130) from None
    if quiet:
        out.print(str(folder))
        return
    out.print(f"[bold]{resolved.name}[/]: {resolved.title}")
    out.print(_events_table(result.events) if len(result.events) else "no switching events")
    energy = result.energy
    out.print(
        f"energy audit residual {energy['residual']:.2e} J (E0 = {energy['E0']:.4f} J, E1 = {energy['E1']:.4f} J)"
    )
    if comparison is not None:
        ok = int((comparison.within_article & comparison.within_reference).sum())
        out.print(f"expected events within tolerance: {ok}/{len(comparison)}")
    out.print(f"written to [bold]{folder}[/]")


@app.command()
def check(
    case: Annotated[str, typer.Argument(help="A case with [[expected]] events.")],
    set_: Annotated[list[str] | None, typer.Option("--set", help="Override: NAME=VALUE (repeatable).")] = None,
) -> None:
    """Compare a case's switching times with the article's; exit 1 if one is out of tolerance.

    Example: `oscillator check instance-5`
    """
    try:
        resolved = _case(case, None, set_)
        if not resolved.expected:
            raise OscillatorError(f"case {resolved.name!r} has no [[expected]] events to check against", field="case")
        table = compare(resolved, simulate(resolved, record_trajectory=False))
    except OscillatorError as error:
        raise _fail(str(error), code=1 if hasattr(error, "result") else 2) from None
    except KeyboardInterrupt:
        raise _fail("interrupted", code=130) from None
    view = Table(title=f"{resolved.name}: expected switching times", title_justify="left", header_style="bold")
    for column in ("event", "article", "reference", "ours", "ours − article", "ours − reference", "ok"):
        view.add_column(column)
    for row in table.itertuples(index=False):
        ok = row.within_article and row.within_reference
        view.add_row(
            row.label, _time(row.article), _time(row.reference), _time(row.ours, 6),
            _delta(row.ours_minus_article), _delta(row.ours_minus_reference), "✓" if ok else "[red]✗[/]",
        )  # fmt: skip
    out.print(view)
    for row in table.itertuples(index=False):
        if row.note:
            out.print(f"[dim]{row.label}: {row.note}[/]")
    failed = int((~(table.within_article & table.within_reference)).sum())
    if failed:
        err.print(f"[bold red]{failed} expected time(s) out of tolerance[/]")
        raise typer.Exit(1)
    out.print(f"all {len(table)} expected times within tolerance")


def _time(value: float, digits: int = 4) -> str:
    return "—" if value != value else f"{value:.{digits}f}"


def _delta(value: float) -> str:
    return "—" if value != value else f"{value:+.1e}"


@app.command()
def report(folder: Annotated[Path, typer.Argument(help="A folder written by `oscillator run`.")]) -> None:
    """Rebuild the report (and any missing figures) of a run folder.

    Example: `oscillator report runs/instance-3-20261121-101500`
    """
    try:
        run_folder = read_run(folder)
        case = run_folder.case
        figures = folder / "figures"
        if not figures.is_dir() and not run_folder.trajectory.empty:
            start = (case.initial.t0, *case.initial.y)
            write_figures(run_folder.trajectory, run_folder.events, case.parameters, start, figures, title=case.name)
        comparison = None
        if case.expected:
            from oscillator.result import Result

            result = Result(case, run_folder.events, run_folder.trajectory, run_folder.run.get("energy", {}), {}, ())
            comparison = compare(case, result)
        text = render_markdown(case, run_folder.events, run_folder.run, comparison=comparison,
                               figures=figures.is_dir())  # fmt: skip
        replace_file(folder / "report.md", text)
        replace_file(folder / "report.html", render_html(text, folder))
    except OscillatorError as error:
        raise _fail(str(error)) from None
    except OSError as error:
        raise _fail(f"{folder}: {error.strerror}; give a run folder you can write to") from None
    out.print(f"report rebuilt: {folder / 'report.md'}, {folder / 'report.html'}")


def _sweep_settings(c: Case, param, start, stop, steps, transient, record) -> SweepSettings:
    """The case's ``[sweep]`` table with the command line's changes."""
    base = c.sweep
    if base is None and (param is None or start is None or stop is None):
        raise OscillatorError(
            f"case {c.name!r} has no [sweep] table; give --param NAME --from A --to B", field="--param"
        )
    changes = {k: v for k, v in dict(param=param, start=start, stop=stop, steps=steps, transient=transient,
                                     record=record).items() if v is not None}  # fmt: skip
    if base is None:
        return SweepSettings(**changes)
    return dataclasses.replace(base, **changes)


@app.command()
def sweep(
    case: Annotated[str, typer.Argument(help="A scene with a [sweep] table (bifurcation-omega, ...) or any case.")],
    param: Annotated[str | None, typer.Option("--param", help="The swept parameter (default: the case's).")] = None,
    start: Annotated[float | None, typer.Option("--from", help="First value.")] = None,
    stop: Annotated[float | None, typer.Option("--to", help="Last value.")] = None,
    steps: Annotated[int | None, typer.Option("--steps", help="Number of values (default 111).")] = None,
    transient: Annotated[
        int | None, typer.Option("--transient", help="Forcing periods before recording (100).")
    ] = None,
    record: Annotated[int | None, typer.Option("--record", help="Forcing periods recorded (50).")] = None,
    workers: Annotated[int | None, typer.Option("--workers", help="Local processes (default: every core).")] = None,
    scheduler: Annotated[
        str | None, typer.Option("--scheduler", help="Run on a Dask cluster: tcp://HOST:PORT of its scheduler.")
    ] = None,
    out_dir: Annotated[
        Path | None, typer.Option("--out", help="Output folder; the same folder again resumes the sweep.")
    ] = None,
    set_: Annotated[list[str] | None, typer.Option("--set", help="Override: NAME=VALUE (repeatable).")] = None,
    no_plots: Annotated[bool, typer.Option("--no-plots", help="Skip the diagrams.")] = False,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="Print only the output folder.")] = False,
) -> None:
    """Sweep a parameter and tabulate switching points, Poincaré points and a summary per value.

    Writes `switches.parquet`, `poincare.parquet`, `summary.parquet` (each with the swept parameter
    as a column) and Fig. 14-style diagrams. Interrupted or killed, the same command with the same
    `--out` resumes where it stopped.

    Examples:

    * `oscillator sweep bifurcation-omega --out runs/omega`
    * `oscillator sweep bifurcation-q2 --steps 36 --workers 2 --out runs/q2`
    * `oscillator sweep instance-1 --param Omega --from 1.5 --to 1.7 --steps 21 --transient 20 --record 10`
    * `oscillator sweep bifurcation-omega --scheduler tcp://10.0.0.5:8786 --out runs/omega`
    """
    try:
        resolved = _case(case, None, set_)
        settings = _sweep_settings(resolved, param, start, stop, steps, transient, record)
        if workers is not None and workers < 1:
            raise OscillatorError(f"--workers must be >= 1, got {workers}", field="--workers")
        folder = out_dir if out_dir is not None else default_output_folder(f"{resolved.name}-sweep")
        if quiet:
            outcome = run_sweep(resolved, settings, folder, workers=workers, scheduler=scheduler)
        else:
            columns = (TextColumn("[bold]{task.description}"), BarColumn(), MofNCompleteColumn(),
                       TextColumn("{task.fields[rate]}"), TimeElapsedColumn(), TimeRemainingColumn())  # fmt: skip
            with Progress(*columns, console=err, transient=True) as bar:
                task = bar.add_task(f"{resolved.name}: {settings.param}", total=settings.steps, rate="")
                began = time.monotonic()
                first: list[int] = []

                def report(done: int, total: int) -> None:
                    first.append(done) if not first else None
                    new = done - first[0]
                    rate = f"{new / (time.monotonic() - began):.2f} points/s" if new else ""
                    bar.update(task, completed=done, total=total, rate=rate)

                outcome = run_sweep(resolved, settings, folder, workers=workers, scheduler=scheduler, progress=report)
        tables = read_sweep(folder)
        if not no_plots:
            write_sweep_figures(tables, settings.param, settings.mass, folder / "figures", title=resolved.name)
    except OscillatorError as error:
        raise _fail(str(error)) from None
    except KeyboardInterrupt:
        raise _fail("interrupted; the points finished so far are kept: run the same command to resume", 130) from None
    if quiet:
        out.print(str(folder))
        return
    summary = tables["summary"]
    ranges = sliding_ranges(summary, settings.param)
    out.print(
        f"[bold]{resolved.name}[/]: {settings.param} from {settings.start:g} to {settings.stop:g} "
        f"({settings.steps} values, {settings.transient} + {settings.record} periods); "
        f"{outcome.computed} computed, {outcome.resumed} resumed, {outcome.failed} failed, {outcome.wall_time:.1f} s"
    )
    if ranges:
        for a, b in ranges:
            out.print(
                f"m{settings.mass} slides (rests on its velocity boundary) for {settings.param} in [{a:.6g}, {b:.6g}]"
            )
    else:
        out.print(f"m{settings.mass} never slides in this range")
    periods = summary[summary.status == "ok"].period.value_counts().sort_index()
    out.print("periods found: " + ", ".join(f"period-{n}: {c}" if n else f"none: {c}" for n, c in periods.items()))
    out.print(f"written to [bold]{folder}[/]")


@app.command()
def locate(
    case: Annotated[str, typer.Argument(help="A scene or case (its [sweep] table gives the defaults).")],
    between: Annotated[
        tuple[float, float], typer.Option("--between", help="Two parameter values on either side of a change.")
    ],
    what: Annotated[str, typer.Option("--what", help="What changes: sliding, grazing or period.")] = "sliding",
    param: Annotated[str | None, typer.Option("--param", help="The parameter (default: the case's).")] = None,
    transient: Annotated[int | None, typer.Option("--transient", help="Forcing periods before recording.")] = None,
    record: Annotated[int | None, typer.Option("--record", help="Forcing periods recorded.")] = None,
    tolerance: Annotated[float, typer.Option("--tolerance", help="Width of the final bracket.")] = 1e-8,
    set_: Annotated[list[str] | None, typer.Option("--set", help="Override: NAME=VALUE (repeatable).")] = None,
) -> None:
    """Find where the sweep's summary changes between two values, to 1e-8 in the parameter.

    Bisection; prints the bracket and, on both sides, the summary and the switching events that
    show the change.

    Example: `oscillator locate bifurcation-omega --between 1.53 1.535 --what sliding`
    """
    try:
        resolved = _case(case, None, set_)
        lo, hi = between
        settings = _sweep_settings(resolved, param, lo, hi, None, transient, record)
        found = locate_change(resolved, settings, what, (lo, hi), tolerance=tolerance)
    except OscillatorError as error:
        raise _fail(str(error)) from None
    out.print(
        f"[bold]{what}[/] changes at {found.param} = {found.value:.10f} "
        f"(between {found.lower:.10f} and {found.upper:.10f}, width {found.width:.1e}, {found.iterations} bisections)"
    )
    for side, summary, events in (("below", found.below, found.evidence_below),
                                  ("above", found.above, found.evidence_above)):  # fmt: skip
        row = summary.iloc[0]
        kinds = ", ".join(f"{k}: {n}" for k, n in events.kind.value_counts().items()) or "none"
        out.print(
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


def main() -> None:
    """Entry point of the ``oscillator`` command."""
    app()
