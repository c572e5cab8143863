"""``oscillator basins`` (basins of attraction over a slice, resumable, local or on Dask),
``oscillator attractors`` (the attractors over a parameter, their shares and where each appears
or ends) and ``oscillator lyapunov`` (the Lyapunov spectrum of a motion)."""

from __future__ import annotations

import functools
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer
from rich import box
from rich.table import Table
from rich.text import Text

from oscillator.analysis.execution import check_workers
from oscillator.cli.commands import command
from oscillator.cli.console import fail, load, message, out, progress_bar, say, warn
from oscillator.cli.inputs import case_from, check_engine, refuse_taken
from oscillator.cli.options import (
    LANDING_ENGINES,
    NO_CUTOFF,
    AxisOption,
    CaseArgument,
    CutoffOption,
    FullTransientOption,
    LandingEngineOption,
    NoPlotsOption,
    QuietOption,
    RecordOption,
    ResumableOutOption,
    SchedulerOption,
    SetOption,
    TransientOption,
    WorkersOption,
)
from oscillator.cli.resumable import (
    computing,
    locked,
    new_folder,
    outputs,
    refusing,
    say_reused,
    with_progress,
    write_claimed,
)
from oscillator.errors import InputError, OscillatorError
from oscillator.text import printable

if TYPE_CHECKING:  # pragma: no cover
    from oscillator.analysis.axes import Axis
    from oscillator.attractors.basins import Basins
    from oscillator.attractors.chain_attractors import ChainBasins
    from oscillator.attractors.mapping import AttractorSettings
    from oscillator.io.cases import Case
    from oscillator.io.files import FolderClaim
    from oscillator.model.chains import FrictionChain

__all__ = ["analysis_settings", "attractors", "basins", "finish_basins", "landing_settings", "lyapunov"]


def axis_of(values: AxisOption, flag: str) -> Axis:
    from oscillator.analysis.axes import Axis

    name, low, high, count = values
    try:
        return Axis(name, low, high, count)
    except InputError as error:
        raise InputError(f"{flag}: {error}", field=flag) from None


def landing_settings(**given: float | bool | str | None) -> AttractorSettings:
    """The settings the options give, the others :class:`AttractorSettings`' defaults."""
    from oscillator.attractors.mapping import AttractorSettings

    check_engine(given.get("engine"), LANDING_ENGINES)  # type: ignore[arg-type]  # a str or None
    try:
        chosen: dict[str, Any] = {name: value for name, value in given.items() if value is not None}
        return AttractorSettings(**chosen)
    except InputError as error:
        flag = f"--{(error.field or '').replace('_', '-')}"
        raise InputError(f"{flag}: {error}", field=flag) from None


def analysis_settings(
    transient: int | None, record: int | None, full_transient: bool, engine: str, cutoff: float | None
) -> AttractorSettings:
    """The settings of ``--transient``, ``--record``, ``--full-transient``, ``--engine`` and
    ``--cutoff`` (:func:`landing_settings`)."""
    return landing_settings(transient=transient, record=record, settle=not full_transient, engine=engine, cutoff=cutoff)


@command(100, "Basins of attraction over a slice of starting states.")
def basins(
    case: CaseArgument,
    x: Annotated[
        AxisOption,
        typer.Option(
            "--x",
            metavar="NAME LOW HIGH N",
            help="The slice's first axis: x1, v1, x2 or v2 (a system file's x:<mass>, v:<mass> or z:<slider>).",
        ),
    ],
    y: Annotated[AxisOption, typer.Option("--y", metavar="NAME LOW HIGH N", help="The slice's second axis.")],
    transient: TransientOption = None,
    record: RecordOption = None,
    full_transient: FullTransientOption = False,
    engine: LandingEngineOption = "dop853",
    cutoff: CutoffOption = None,
    max_period: Annotated[
        int | None, typer.Option("--max-period", metavar="N", help="The longest period looked for (default 16).")
    ] = None,
    workers: WorkersOption = None,
    scheduler: SchedulerOption = None,
    out_dir: ResumableOutOption = None,
    set_: SetOption = None,
    no_plots: NoPlotsOption = False,
    quiet: QuietOption = False,
) -> None:
    """Basins of attraction over a slice of starting states: every attractor the starts reach
    (a periodic orbit with its multipliers, or an aperiodic set with its largest Lyapunov
    exponent), each cell's attractor, and each attractor's share of the slice.

    The two other state components and the section t0 are the case's start; each start runs 200
    forcing periods (--transient), then 32 are recorded (--record). Writes basins.parquet,
    attractors.parquet, figures/basins.png and a report. Interrupted or killed, the same command
    with the same --out resumes where it stopped. Without --workers, fewer than 1,000 starts run
    in this process (a pool costs more than it gains there), more on every core.

    \b
    A system file (docs/systems.md) takes its own state's names as axes (x:blade, v:blade, ...,
    z:platform) and --set by its names; its starts run on CVODE.

    \b
    Examples:
      oscillator basins instance-1 --set Q2=71.165 --x x2 3 6 16 --y v2 -4 4 16 --out runs/basins
      oscillator basins instance-1 --set Omega=1.85 --x x1 2 5 4 --y v1 -3 3 4 --transient 100 --record 8
      oscillator basins docs/systems/blade-damper.toml --x x:blade -2 2 4 --y v:blade -2 2 3 --transient 100 --record 8
    """
    with refusing():
        x_axis, y_axis = axis_of(x, "--x"), axis_of(y, "--y")
        chosen = {"transient": transient, "record": record, "max_period": max_period, "engine": engine}
        settings = landing_settings(**chosen, cutoff=cutoff, settle=not full_transient)
    from oscillator.cli.system_attractors import basins_system

    if basins_system(case, (x_axis, y_axis), settings, (workers, scheduler, out_dir), set_, no_plots, quiet):
        return
    with refusing():
        resolved = case_from(case, None, set_)
        refuse_taken(set_, {x_axis.name: "--x", y_axis.name: "--y"})
        store, lock, client, count = _open_basins(resolved, x_axis, y_axis, settings, out_dir, workers, scheduler)
    with computing(store, "starts", lock, client):
        from oscillator.attractors.basins import find_basins

        run = functools.partial(find_basins, resolved, x_axis, y_axis, store, settings=settings, workers=count)
        found = with_progress(functools.partial(run, client=client), f"{resolved.name}: basins", "starts", quiet)
    finish_basins(found, store, no_plots, quiet)


def _open_basins(
    case: Case,
    x: Axis,
    y: Axis,
    settings: AttractorSettings,
    out_dir: Path | None,
    workers: int | None,
    scheduler: str | None,
) -> tuple[Any, Any, Any, int]:
    """Everything refused before work: the slice, the folder (new, or these basins to resume),
    the workers (by default every core, one below 1,000 starts), the scheduler; the folder's name
    locked."""
    count = check_workers(workers, starts=x.count * y.count)
    load("oscillator.attractors.basins", notice=True)
    from oscillator.attractors.basins import basin_store, grid_starts

    grid_starts(case, x, y)
    folder = out_dir if out_dir is not None else new_folder(case, "basins")
    store = basin_store(folder, case, x, y, settings)
    store.check()
    lock, client = locked(folder, scheduler)
    return store, lock, client, count


def finish_basins(found: Basins | ChainBasins, store: Any, no_plots: bool, quiet: bool) -> None:
    """Write a computed basins folder (a case's or a declared system's), print its attractors
    and say what could not be written or drawn (exit 1; the tables are kept)."""
    say_reused(store, store.reused["landings"], f"of the {found.x.count * found.y.count} starts", quiet)
    folder = store.folder
    from oscillator.attractors.basins import Basins
    from oscillator.attractors.finding import share_text
    from oscillator.report.attractors import attractor_table, write_basins
    from oscillator.report.chain_attractors import chain_attractor_table, write_chain_basins

    if isinstance(found, Basins):
        table, write = attractor_table(found), functools.partial(write_basins, found)
    else:
        table, write = chain_attractor_table(found), functools.partial(write_chain_basins, found)
    problems = outputs(folder, "starts", lambda: write(folder, plots=not no_plots))
    if not quiet:
        shown = Table(title="attractors", title_justify="left", header_style="bold", box=box.SIMPLE_HEAD)
        for column in ("attractor", "share of starts [95 %]", "orbit", "largest |multiplier|"):
            shown.add_column(column)
        for row in table.to_dict("records"):
            periodic = row["kind"] == "periodic"
            orbit = "" if not periodic or row["stable"] is None else ("stable" if row["stable"] else "unstable")
            largest = f"{row['largest_multiplier']:.4g}" if periodic else ""
            shown.add_row(Text(str(row["name"])), share_text(row["fraction"], row["low"], row["high"]), orbit, largest)
        out.print(shown)
    for warning in found.found.warnings:
        warn(warning)
    say(f"written to {printable(str(folder))}")
    if not found.found.attractors:
        labels = found.found.labels
        raise fail(
            f"every start failed ({printable(str(labels.message.iloc[0]))}); the starts' reasons are in "
            f"{printable(str(folder))}/basins.parquet",
            1,
        )
    if problems:
        raise fail("; ".join(problems) + f"; the tables are in {folder}", 1)


@command(120, "The Lyapunov spectrum of a motion.")
def lyapunov(
    case: CaseArgument,
    periods: Annotated[int, typer.Option("--periods", metavar="N", help="Forcing periods averaged over.")] = 500,
    transient: Annotated[
        int, typer.Option("--transient", metavar="N", help="Forcing periods run before averaging.")
    ] = 100,
    out_dir: Annotated[
        Path | None,
        typer.Option("--out", metavar="DIR", help="Also write lyapunov.parquet, lyapunov.json and the figure there."),
    ] = None,
    set_: SetOption = None,
    no_plots: NoPlotsOption = False,
) -> None:
    """The Lyapunov spectrum of the motion from the case's start: variational equations with the
    saltation matrix at every switch, re-orthonormalised every forcing period (QR).

    A system file (docs/systems.md) takes --set by its names; its spectrum has one exponent per
    coordinate of its state.

    \b
    Examples:
      oscillator lyapunov instance-1 --set Omega=1.85 --periods 200
      oscillator lyapunov instance-1 --set Omega=1.85 --periods 100 --out runs/lyapunov
      oscillator lyapunov docs/systems/blade-damper.toml --set platform.F=0.5 --periods 50
    """
    from oscillator.cli.system_attractors import spectrum_target
    from oscillator.io.files import check_new, claim_folder

    try:
        resolved, name = spectrum_target(case, set_)
        if out_dir is not None:
            check_new(out_dir, option="--out")
        from oscillator.model.parameters import check_count

        check_count(periods, "--periods", 1, 10_000_000)  # before the numerical libraries load
        check_count(transient, "--transient", 0, 10_000_000)
        load("oscillator.attractors.lyapunov", notice=True)
        from oscillator.attractors.lyapunov import lyapunov as spectrum_of

        claim = claim_folder(out_dir, option="--out") if out_dir is not None else None  # writable, before the work
    except OscillatorError as error:
        raise fail(message(error)) from None
    try:
        bar, report = progress_bar(f"{printable(name)}: Lyapunov exponents", "periods")
        with bar:
            spectrum = spectrum_of(resolved, periods=periods, transient=transient, progress=report)
    except BaseException as error:
        if claim is not None:
            claim.abandon()
        if isinstance(error, OscillatorError):  # refused before it ran (exit 2), or failed on the way (1)
            raise fail(message(error), 2 if isinstance(error, InputError) else 1) from None
        if isinstance(error, KeyboardInterrupt):
            raise fail("interrupted; nothing was written", 130) from None
        raise
    exponents = ", ".join(f"{value:.6g}" for value in spectrum.exponents)
    out.print(Text(f"{printable(name)}: Lyapunov exponents (1/s), {periods} periods: {exponents}"))
    out.print(Text(f"  largest {spectrum.largest:.6g} 1/s; Kaplan-Yorke dimension of the map {spectrum.dimension:.4g}"))
    if claim is not None:
        _write_lyapunov(spectrum, claim, no_plots)


def _write_lyapunov(spectrum: Any, claim: FolderClaim, no_plots: bool) -> None:
    from oscillator.report.attractors import write_lyapunov

    write_claimed(claim, lambda folder: write_lyapunov(spectrum, folder, plots=not no_plots), "the exponents")


@command(110, "The attractors over a parameter: shares, and where each appears or ends.")
def attractors(
    case: CaseArgument,
    param: Annotated[str, typer.Option("--param", metavar="NAME", help="The parameter varied.")],
    start: Annotated[float, typer.Option("--from", metavar="A", help="First value.")],
    stop: Annotated[float, typer.Option("--to", metavar="B", help="Last value.")],
    steps: Annotated[int, typer.Option("--steps", metavar="N", help="Number of values.")] = 11,
    x: Annotated[
        AxisOption | None,
        typer.Option("--x", metavar="NAME LOW HIGH N", help="Fresh starts on a slice: its first axis (with --y)."),
    ] = None,
    y: Annotated[
        AxisOption | None, typer.Option("--y", metavar="NAME LOW HIGH N", help="The slice's second axis.")
    ] = None,
    tol: Annotated[float, typer.Option("--tol", metavar="TOL", help="Where each attractor ends, to this.")] = 1e-5,
    transient: TransientOption = None,
    record: RecordOption = None,
    full_transient: FullTransientOption = False,
    engine: LandingEngineOption = "dop853",
    cutoff: CutoffOption = None,
    coordinate: Annotated[
        str | None,
        typer.Option(
            "--coordinate",
            metavar="NAME",
            help="The section coordinate drawn: x1, v1, x2 or v2 (x2 by default; a system file's state names, its "
            "first mass's x:<mass> by default).",
        ),
    ] = None,
    branches: Annotated[
        bool, typer.Option("--branches/--no-branches", help="Draw the periodic orbits' branches (continue_orbit).")
    ] = True,
    workers: WorkersOption = None,
    scheduler: SchedulerOption = None,
    out_dir: ResumableOutOption = None,
    set_: SetOption = None,
    no_plots: NoPlotsOption = False,
    quiet: QuietOption = False,
) -> None:
    """The attractors over a parameter: at each value every attractor the fresh starts reach (and
    the seeds from the value before), matched from value to value, each one's share of the fresh
    starts, and where each one appears or ends, bisected to --tol: the window where two coexist.

    Each start runs 200 forcing periods (--transient), then 32 are recorded (--record). Writes
    attractors.parquet, ends.parquet, figures/attractors.png and a report. Interrupted or killed,
    the same command with the same --out resumes at the value it stopped at.

    \b
    A system file (docs/systems.md) takes its own names: --param and --set its numbers
    (platform.F, wall.at, Omega), --x and --y its state's (x:<mass>, v:<mass>, z:<slider>); its
    starts run on CVODE, and the branches drawn are its period-1 orbits'.

    \b
    Examples:
      oscillator attractors instance-1 --param Q2 --from 71.10 --to 71.20 --steps 5 --x x2 3 6 3 --y v2 -4 4 3
      oscillator attractors instance-1 --param Q2 --from 71.10 --to 71.20 --steps 3 --no-branches --out runs/q2
      oscillator attractors docs/systems/impacts.toml --param Omega --from 1.6 --to 1.0 --steps 7 --tol 1e-4
    """
    with refusing():
        resolved, stem, title = subject_of(case, set_)
        refuse_taken(set_, {param: "--param"} | {axis[0]: option for axis, option in ((x, "--x"), (y, "--y")) if axis})
        given: dict[str, Any] = {"transient": transient, "record": record, "settle": not full_transient}
        given |= {"engine": engine, "cutoff": cutoff}
        name = stem if stem is not None else title  # the default folder's
        plan = _open_following(resolved, param, (start, stop, steps), (x, y), tol, given, coordinate, out_dir, name)
        values, states, settings, store, coordinate = plan
        count = check_workers(workers)
        lock, client = locked(store.folder, scheduler)
    with computing(store, "values", lock, client):
        from oscillator.attractors.following import follow_attractors, local_branches

        store.open()
        options = {"states": states, "settings": settings, "tol": tol, "store": store}
        run = functools.partial(follow_attractors, resolved, param, values, workers=count, client=client, **options)
        over = with_progress(run, f"{title}: attractors over {printable(param)}", "values", quiet)
        store.write_status("computed", values=len(values))
        drawn = local_branches(over) if branches and not no_plots else []
    _finish_following(over, store, coordinate, drawn, no_plots, quiet)


def subject_of(target: str, assignments: list[str] | None) -> tuple[Case | FrictionChain, str | None, str]:
    """A system file's chain, its stem and title (printable); or the case, None and its name."""
    from oscillator.cli.system_attractors import chain_at

    declared = chain_at(target, assignments)
    if declared is not None:
        chain, stem = declared
        return chain, stem, printable(chain.title or stem)
    article = case_from(target, None, assignments)
    return article, None, article.name


def _open_following(
    case: Case | FrictionChain,
    param: str,
    span: tuple[float, float, int],
    slice_: tuple[AxisOption | None, AxisOption | None],
    tol: float,
    given: dict[str, Any],
    coordinate: str | None,
    out_dir: Path | None,
    name: str,
) -> tuple[Any, Any, AttractorSettings, Any, str]:
    """Everything refused before work: the values, the slice, the settings, the folder (by
    default ``runs/<name>-attractors-<time>``), the coordinate drawn."""

    import numpy as np

    from oscillator.model.chains import FrictionChain

    start, stop, steps = span
    x, y = slice_
    state = case.system.state
    load("oscillator.attractors.following", notice=True)
    from oscillator.attractors.following import check_values, default_coordinate, following_store

    coordinate = default_coordinate(case) if coordinate is None else coordinate
    if coordinate not in state:
        names = ", ".join(state)
        raise InputError(
            f"--coordinate must be one of {printable(names)}, got {printable(coordinate)}", field="--coordinate"
        )
    declared = isinstance(case, FrictionChain)
    if declared and given["engine"] != "dop853":
        raise InputError("--engine applies to the article's cases: a system runs on CVODE", field="--engine")
    if declared and given["cutoff"] is not None:
        raise InputError(NO_CUTOFF, field="--cutoff")
    if isinstance(steps, bool) or not 2 <= steps <= 10_000:
        raise InputError(f"--steps must be a whole number from 2 to 10000, got {steps!r}", field="--steps")
    if (x is None) != (y is None):
        raise InputError("give both --x and --y for a slice of fresh starts, or neither", field="--x")
    settings = landing_settings(**given)
    from oscillator.attractors.basins import grid_starts
    from oscillator.attractors.chain_attractors import chain_grid

    if not (np.isfinite(start) and np.isfinite(stop)):
        raise InputError(f"--from and --to must be finite numbers, got {start!r} and {stop!r}", field="--to")
    values = np.linspace(start, stop, steps)
    check_values(case, param, values, tol)
    axes = (axis_of(x, "--x"), axis_of(y, "--y")) if x is not None and y is not None else None
    grid = chain_grid if declared else grid_starts
    states = grid(case, *axes) if axes is not None else None  # type: ignore[arg-type]
    folder = out_dir if out_dir is not None else new_folder(name, "attractors")
    store = following_store(folder, case, param, values, axes, settings)
    store.check()
    return values, states, settings, store, coordinate


def _finish_following(over: Any, store: Any, coordinate: str, branches: list[Any], no_plots: bool, quiet: bool) -> None:
    say_reused(store, store.reused["landings"], "starts (of every value's fresh starts and seeds)", quiet)
    folder = store.folder
    from oscillator.report.attractors import write_following

    write = functools.partial(
        write_following, over, folder, coordinate=coordinate, branches=branches, plots=not no_plots
    )
    problems = outputs(folder, "landings", write)
    if not quiet:
        for end in over.ends:
            verb = end.change(float(over.values[0]), float(over.values[-1]))
            out.print(
                Text(
                    f"A{end.id} ({end.name}) {verb} between {over.param} = {min(end.inside, end.outside):.10g} and "
                    f"{max(end.inside, end.outside):.10g}; "
                    f"its seed then goes to: {end.becomes}"
                )
            )
    say(f"written to {printable(str(folder))}")
    if not any(found.attractors for found in over.found):
        labels = over.found[0].labels
        raise fail(f"every start failed at every value ({labels.message.iloc[0]}); the tables are in {folder}", 1)
    if problems:
        raise fail("; ".join(problems) + f"; the tables are in {folder}", 1)
