"""``oscillator sweep`` (Fig. 14-style sweeps, resumable, local or on Dask) and ``oscillator locate``."""

from __future__ import annotations

import os
import time
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from oscillator.cli.attractors import subject_of
from oscillator.cli.commands import command
from oscillator.cli.console import err, fail, load, message, out, progress_bar, say
from oscillator.cli.inputs import refuse_taken, sweep_settings
from oscillator.cli.options import (
    NoPlotsOption,
    QuietOption,
    ResumableOutOption,
    SchedulerOption,
    SetOption,
    WorkersOption,
)
from oscillator.errors import InputError, OscillatorError
from oscillator.io.cases import Case, is_shipped
from oscillator.model.chains import FrictionChain
from oscillator.model.parameters import SweepSettings
from oscillator.text import printable

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd

    from oscillator.analysis.locate import Location

__all__ = ["locate", "sweep"]


#: ``--both-ways``: to the last value and back, each value from the previous one's end.
BothWaysOption = Annotated[
    bool,
    typer.Option(
        "--both-ways",
        help="Sweep to the last value and back, each value starting where the previous one ended: shows hysteresis "
        "(coexisting motions). Runs in this process.",
    ),
]


@command(60, "Sweep a parameter: Fig. 14-style switching and Poincaré points.")
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
    workers: WorkersOption = None,
    scheduler: SchedulerOption = None,
    out_dir: ResumableOutOption = None,
    set_: SetOption = None,
    both_ways: BothWaysOption = False,
    no_plots: NoPlotsOption = False,
    quiet: QuietOption = False,
) -> None:
    """Sweep a parameter: switching points, Poincaré points and a summary per value.

    Writes switches.parquet, poincare.parquet and summary.parquet (each with the swept parameter
    as a column) and Fig. 14-style diagrams. Interrupted or killed, the same command with the same
    --out resumes where it stopped. On a Dask cluster (pip install "oscillator[dask]"), give
    --scheduler tcp://HOST:PORT.

    \b
    A system file (docs/systems.md) sweeps one of its numbers (--param, --from and --to given):
    every event after the transient, the Poincaré points of its state, and per value the period,
    switches and closings per period, each friction element's fraction of time held.

    \b
    Examples:
      oscillator sweep bifurcation-omega --out runs/omega
      oscillator sweep bifurcation-q2 --steps 36 --workers 2 --out runs/q2
      oscillator sweep instance-1 --param Omega --from 1.5 --to 1.7 --steps 21 --transient 20 --record 10
      oscillator sweep bifurcation-q2 --from 71.15 --to 71.18 --steps 7 --transient 20 --record 4 --both-ways
      oscillator sweep docs/systems/impacts.toml --param Omega --from 1.0 --to 1.6 --steps 25 --record 10 --both-ways
    """
    try:
        resolved, stem, title = subject_of(case, set_)
        if isinstance(resolved, FrictionChain):
            settings = _system_settings(param, start, stop, steps, transient, record, both_ways)
        else:
            settings = sweep_settings(resolved, param, start, stop, steps, transient, record, both_ways)
        refuse_taken(set_, {settings.param: "--param (or the case's [sweep])"})
        plan = _open_sweep(resolved, settings, out_dir, workers, scheduler, stem if stem is not None else title)
    except OscillatorError as error:
        raise fail(message(error)) from None
    except KeyboardInterrupt:
        raise fail("interrupted; nothing was written", 130) from None
    folder = plan.folder
    try:
        outcome = _run_with_progress(plan, title, settings, quiet)
    except OscillatorError as error:
        raise fail(message(error), 1) from None
    except KeyboardInterrupt:
        raise fail("interrupted; the points finished so far are kept: run the same command to resume", 130) from None
    finally:
        plan.close()
    if isinstance(resolved, FrictionChain):
        _finish_system_sweep(resolved, settings, folder, outcome, (title, no_plots, quiet))
    else:
        _finish_sweep(resolved, settings, folder, outcome, no_plots, quiet)


def _system_settings(
    param: str | None,
    start: float | None,
    stop: float | None,
    steps: int | None,
    transient: int | None,
    record: int | None,
    both_ways: bool,
) -> SweepSettings:
    """A system file's sweep: ``--param``, ``--from`` and ``--to`` given (it has no [sweep] table)."""
    from oscillator.analysis.chain_sweeps import ChainSweepSettings

    for option, value in (("--param", param), ("--from", start), ("--to", stop)):
        if value is None:
            raise InputError(
                f"{option}: a system file has no [sweep] table; give --param, --from and --to", field=option
            )
    given = {"steps": steps, "transient": transient, "record": record}
    chosen = {name: value for name, value in given.items() if value is not None}
    return ChainSweepSettings(param=param, start=start, stop=stop, both_ways=both_ways, **chosen)  # type: ignore[arg-type]


def _finish_system_sweep(
    chain: FrictionChain, settings: SweepSettings, folder: Path, outcome: Any, shown: tuple[str, bool, bool]
) -> None:
    """A system's sweep drawn (its tables are safe first), its periods and hysteresis said."""
    from oscillator.analysis.sweeps import read_sweep

    title, no_plots, quiet = shown
    tables = read_sweep(folder)
    if not no_plots:

        def draw() -> None:
            from oscillator.report.chain_sweep import chain_sweep_figure
            from oscillator.report.figures import save_figure

            (folder / "figures").mkdir(exist_ok=True)
            save_figure(chain_sweep_figure(tables, chain, settings.param), folder / "figures", "sweep")

        _drawn(draw, folder)
    summary = tables["summary"]
    if _printed_quietly(summary, folder, quiet):
        return
    way = " and back" if settings.both_ways else ""
    say(
        (title, "bold"),
        f": {printable(settings.param)} from {settings.start:g} to {settings.stop:g}{way} ({settings.steps} values, "
        f"{settings.transient} + {settings.record} periods); {outcome.computed} computed, {outcome.resumed} resumed, "
        f"{outcome.failed} failed, {outcome.wall_time:.1f} s",
    )
    ok = summary[summary.status == "ok"]
    periods = ok.period.value_counts().sort_index()
    if len(periods):
        say("periods found: " + ", ".join(f"period-{n}: {c}" if n else f"none: {c}" for n, c in periods.items()))
    if settings.both_ways:
        _say_system_hysteresis(ok, settings.param)
    say("written to ", (str(folder), "bold"))
    _fail_if_every_point_failed(summary, folder)


def _say_system_hysteresis(ok: pd.DataFrame, param: str) -> None:
    """The values where the two ways end on different motions (their switches per period differ)."""
    by_way = {
        way: dict(zip(rows[param], rows.switches_per_period, strict=True)) for way, rows in ok.groupby("direction")
    }
    up, down = by_way.get("up", {}), by_way.get("down", {})
    differ = sorted(v for v in up if v in down and abs(up[v] - down[v]) > 1e-9)
    if differ:
        say(
            f"hysteresis: at {printable(param)} = {', '.join(f'{v:.6g}' for v in differ)} the two ways end on "
            "different motions (both exist there)"
        )


def _drawn(draw: Any, folder: Path) -> None:
    """Draw the figures; a failure says the tables are safe (exit 1), Ctrl-C likewise (130)."""
    try:
        load("oscillator.report.figures")
        draw()
    except KeyboardInterrupt:
        raise fail(f"interrupted while drawing; the sweep's tables are in {folder}", 130) from None
    except Exception as error:  # the sweep itself is safe
        raise fail(
            f"the diagrams could not be drawn ({type(error).__name__}: {error}); the sweep's tables are in {folder}", 1
        ) from None


def _run_with_progress(plan: Any, name: str, settings: SweepSettings, quiet: bool) -> Any:
    """Run the sweep, with a progress bar where a person watches."""
    if quiet or not err.is_terminal:
        return plan.run()
    bar, report_progress = progress_bar(f"{name}: {settings.param}", "points")
    with bar:
        return plan.run(report_progress)


def _open_sweep(
    case: Case | FrictionChain,
    settings: SweepSettings,
    out_dir: Path | None,
    workers: int | None,
    scheduler: str | None,
    title: str,
) -> Any:
    """The sweep checked and its folder locked: ``out_dir``, or a new ``runs/<case>-sweep-<timestamp>``."""
    if settings.both_ways and (scheduler is not None or (workers is not None and workers != 1)):
        option = "--scheduler" if scheduler is not None else "--workers"
        raise InputError(
            f"{option}: a --both-ways sweep runs its values one after another in this process "
            f"(each starts where the one before ended); leave out {option}",
            field=option,
        )
    from oscillator.io.files import FolderTaken, default_name

    load("oscillator.analysis.sweeps", notice=True)
    from oscillator.analysis.sweeps import open_sweep

    if out_dir is not None:
        return open_sweep(case, settings, out_dir, workers=workers, scheduler=scheduler)
    stamp, name = time.strftime("%Y%m%d-%H%M%S"), default_name(title)
    for n in range(1, 10_000):
        folder = Path("runs") / (f"{name}-sweep-{stamp}" if n == 1 else f"{name}-sweep-{stamp}-{n}")
        if os.path.lexists(folder):
            continue
        try:
            return open_sweep(case, settings, folder, workers=workers, scheduler=scheduler)
        except FolderTaken:
            continue
    raise InputError("no free folder name under runs/; give --out", field="--out")


def shown_case(case: Case) -> str:
    """The case as the command line names it: a shipped case by its name, any other by its file."""
    if case.source is None or is_shipped(case.source):
        return printable(case.name)
    return printable(str(case.source))


def _finish_sweep(case: Case, settings: SweepSettings, folder: Path, outcome: Any, no_plots: bool, quiet: bool) -> None:
    from oscillator.analysis.sweep_points import sliding_ranges
    from oscillator.analysis.sweeps import read_sweep

    tables = read_sweep(folder)
    if not no_plots:

        def draw() -> None:
            from oscillator.report.sweep_figures import write_sweep_figures

            write_sweep_figures(tables, settings.param, settings.mass, folder / "figures", title=case.name)

        _drawn(draw, folder)
    summary = tables["summary"]
    if _printed_quietly(summary, folder, quiet):
        return
    say(
        (case.name, "bold"),
        f": {settings.param} from {settings.start:g} to {settings.stop:g}{' and back' if settings.both_ways else ''} "
        f"({settings.steps} values, {settings.transient} + {settings.record} periods); {outcome.computed} computed, "
        f"{outcome.resumed} resumed, {outcome.failed} failed, {outcome.wall_time:.1f} s",
    )
    if settings.both_ways:
        _say_both_ways(summary, settings)
    else:
        ranges = sliding_ranges(summary, settings.param)
        _say_ranges(case, summary, settings, ranges)
        if not ranges and (summary.status == "ok").any():
            say(f"m{settings.mass} never slides in this range")
    periods = summary[summary.status == "ok"].period.value_counts().sort_index()
    if len(periods):
        say("periods found: " + ", ".join(f"period-{n}: {c}" if n else f"none: {c}" for n, c in periods.items()))
    say("written to ", (str(folder), "bold"))
    _fail_if_every_point_failed(summary, folder)


def _say_ranges(case: Case, summary: pd.DataFrame, settings: SweepSettings, ranges: list[tuple[float, float]]) -> None:
    """The grid values at which the mass slides, and the ``locate`` command for each end."""
    values = sorted(summary[settings.param].to_numpy(float))
    for a, b in ranges:
        say(
            f"m{settings.mass} slides (rests on its velocity boundary) at the grid values {settings.param} = "
            f"{a:.6g} to {b:.6g}"
        )
        below, above = [v for v in values if v < a], [v for v in values if v > b]
        for which, pair in (("begins", [*below[-1:], a]), ("ends", [b, *above[:1]])):
            if len(pair) == 2:
                say(
                    f"  where it {which} (between two grid values): oscillator locate {shown_case(case)} "
                    f"--param {settings.param} --between {pair[0]:.6g} {pair[1]:.6g} --what sliding"
                )


def _say_both_ways(summary: pd.DataFrame, settings: SweepSettings) -> None:
    """Where the mass slides going each way; the values where the two ways differ (hysteresis)."""
    from oscillator.analysis.sweep_points import sliding_ranges

    ways = list(dict.fromkeys(direction for direction, _ in settings.points))
    for way in ways:
        found = sliding_ranges(summary, settings.param, way)
        spans = ", ".join(f"{a:.6g} to {b:.6g}" for a, b in found)
        say(
            f"going {way}: m{settings.mass} "
            + (f"slides at the grid values {settings.param} = {spans}" if found else "never slides")
        )
    ok = summary[summary.status == "ok"]
    by_way = {way: dict(zip(rows[settings.param], rows.sliding, strict=True)) for way, rows in ok.groupby("direction")}
    differ = sorted(
        v
        for v in by_way.get(ways[0], {})
        if v in by_way.get(ways[-1], {}) and by_way[ways[0]][v] != by_way[ways[-1]][v]
    )
    if differ:
        say(
            f"hysteresis: at {settings.param} = {', '.join(f'{v:.6g}' for v in differ)} the two ways end on "
            "different motions (both exist there)"
        )


def _printed_quietly(summary: pd.DataFrame, folder: Path, quiet: bool) -> bool:
    """With ``--quiet`` only the folder is printed (and exit 1 where every point failed); whether so."""
    if quiet:
        out.print(printable(str(folder)))
        _fail_if_every_point_failed(summary, folder)
    return quiet


def _fail_if_every_point_failed(summary: pd.DataFrame, folder: Path) -> None:
    """Exit 1 when no point of the sweep could be computed, with the first point's reason."""
    failed = summary[summary.status == "failed"]
    if len(summary) and len(failed) == len(summary):
        raise fail(
            f"every point of the sweep failed; the first: {failed.message.iloc[0]} (summary.parquet in "
            f"{folder} has each point's reason)",
            1,
        )


@command(70, "Find where a sweep's summary changes, to 1e-8.")
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
    set_: SetOption = None,
) -> None:
    """Find where the sweep's summary changes between two values (bisection, to 1e-8).

    Both ends are simulated first to see that they differ; then each bisection step simulates
    the middle. Prints the bracket and, on both sides, the summary and the switching events that
    show the change.

    \b
    A system file (docs/systems.md) takes --param (one of its numbers); --what sliding is whether
    an element sticks (its stickings per period).

    \b
    Examples:
      oscillator locate bifurcation-omega --between 1.595 1.600 --what sliding
      oscillator locate docs/systems/impacts.toml --param Omega --between 0.75 0.8 --what grazing
    """
    try:
        resolved, _, _ = subject_of(case, set_)
        load("oscillator.analysis.locate", notice=True)
        lo, hi = between
        declared = isinstance(resolved, FrictionChain)
        if declared:
            settings = _system_settings(param, lo, hi, None, transient, record, False)
        else:
            settings = sweep_settings(resolved, param, lo, hi, None, transient, record)  # type: ignore[arg-type]
        refuse_taken(set_, {settings.param: "--param (or the case's [sweep])"})
        found = _locate_with_progress(resolved, settings, what, (lo, hi), tolerance)
    except OscillatorError as error:
        raise fail(message(error)) from None
    except KeyboardInterrupt:
        raise fail("interrupted", 130) from None
    say(
        (what, "bold"),
        f" changes at {printable(found.param)} = {found.value:.10f} (between {found.lower:.10f} and "
        f"{found.upper:.10f}, width {found.width:.1e}, {found.iterations} bisections)",
    )
    for side, summary, events in (
        ("below", found.below, found.evidence_below),
        ("above", found.above, found.evidence_above),
    ):
        row = summary.iloc[0]
        kinds = ", ".join(f"{printable(str(k))}: {n}" for k, n in events.kind.value_counts().items()) or "none"
        if declared:
            said = f"{row.sticks_per_period:g} sticks/period, {row.closings_per_period:g} closings/period"
        else:
            said = f"sliding {bool(row.sliding)}, rest {row.rest_time_per_period:.3g} s/period"
        say(
            f"{side} ({printable(found.param)} = {row[found.param]:.10f}): period {int(row.period)}, "
            f"{row.switches_per_period:g} switches/period, {said}; events: {kinds}"
        )


def _locate_with_progress(
    case: Case | FrictionChain, settings: SweepSettings, what: str, between: tuple[float, float], tolerance: float
) -> Location:
    """``analysis.locate`` with a progress bar (bisection step, bracket width) on a terminal."""
    from oscillator.analysis.locate import locate as locate_change

    if not err.is_terminal:
        return locate_change(case, settings, what, between, tolerance=tolerance)
    columns = (
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("{task.fields[bracket]}"),
        TimeElapsedColumn(),
    )
    with Progress(*columns, console=err, transient=True) as bar:
        task = bar.add_task(f"locating {printable(what)}", total=None, bracket="")

        def report(step: int, steps: int, a: float, b: float) -> None:
            stage = "simulating both ends" if step <= 2 else f"bracket [{a:.10g}, {b:.10g}], {b - a:.1e} wide"
            bar.update(task, completed=step - 1, total=steps, bracket=stage)

        return locate_change(case, settings, what, between, tolerance=tolerance, progress=report)
