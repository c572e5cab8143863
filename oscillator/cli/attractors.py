"""``oscillator basins`` (basins of attraction over a slice, resumable, local or on Dask),
``oscillator attractors`` (the attractors over a parameter, their shares and where each appears
or ends) and ``oscillator lyapunov`` (the Lyapunov spectrum of a motion)."""

from __future__ import annotations

import contextlib
import functools
import time
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, cast

import typer
from rich import box
from rich.table import Table
from rich.text import Text

from oscillator.analysis.execution import check_workers
from oscillator.cli.console import err, fail, load, message, out, progress_bar, say, warn
from oscillator.cli.inputs import case_from
from oscillator.errors import InputError, Interrupted, OscillatorError
from oscillator.text import printable

if TYPE_CHECKING:  # pragma: no cover
    from oscillator.analysis.axes import Axis
    from oscillator.attractors.basins import Basins
    from oscillator.attractors.mapping import AttractorSettings
    from oscillator.io.cases import Case
    from oscillator.io.files import FolderClaim
    from oscillator.orbits.curves import Curve

__all__ = ["atlas", "attractors", "basins", "curve", "lyapunov"]

AxisOption = tuple[str, float, float, int]
SetOption = Annotated[list[str] | None, typer.Option("--set", metavar="NAME=VALUE", help="Override (repeatable).")]
QuietOption = Annotated[bool, typer.Option("--quiet", "-q", help="Print only the output folder.")]
NoPlotsOption = Annotated[bool, typer.Option("--no-plots", help="Skip the figure.")]
TransientOption = Annotated[int, typer.Option("--transient", metavar="N", help="Forcing periods run before recording.")]
RecordOption = Annotated[int, typer.Option("--record", metavar="N", help="Forcing periods recorded after it.")]
WorkersOption = Annotated[
    int | None, typer.Option("--workers", metavar="N", help="Local processes (default: every core).")
]
SchedulerOption = Annotated[
    str | None,
    typer.Option("--scheduler", metavar="ADDRESS", help="Run on a Dask cluster: tcp://HOST:PORT of its scheduler."),
]


def _axis(values: AxisOption, flag: str) -> Axis:
    from oscillator.analysis.axes import Axis

    name, low, high, count = values
    try:
        return Axis(name, low, high, count)
    except InputError as error:
        raise InputError(f"{flag}: {error}", field=flag) from None


def _settings(transient: int, record: int, max_period: int) -> AttractorSettings:
    from oscillator.attractors.mapping import AttractorSettings

    try:
        return AttractorSettings(transient=transient, record=record, max_period=max_period)
    except InputError as error:
        raise InputError(f"--{error.field}: {error}", field=f"--{error.field}") from None


@contextlib.contextmanager
def _computing(store: Any, what: str, lock: Any, client: Any) -> Iterator[None]:
    """The block that computes a resumable folder's ``what`` (starts, values, rows): each way it
    can stop said in one line, what it finished kept; then the folder's lock and the Dask client
    released."""
    try:
        yield
    except InputError as error:  # refused before it ran (a damaged part, a value the model refuses)
        raise fail(message(error)) from None
    except OscillatorError as error:
        raise fail(f"{message(error)}; the {what} finished so far are kept in {store.folder}", 1) from None
    except OSError as error:  # a full disk, the folder taken away: what was written stays
        raise _unwritable(error, store.folder, what) from None
    except KeyboardInterrupt:
        raise fail(f"interrupted; the {what} finished so far are kept: run the same command to resume", 130) from None
    finally:
        lock.release()
        if client is not None:
            client.close()


def _outputs(folder: Path, kept: str, write: Any) -> list[str]:
    """``write()``: a finished computation's tables, figures and report, a Ctrl-C held until they
    are written (never a folder marked computed with its tables missing); what could not be
    drawn (the tables stay)."""
    from oscillator.io.signals import interrupts_deferred

    try:
        with interrupts_deferred():
            problems: list[str] = write()
    except OSError as error:
        raise fail(f"cannot write into {printable(str(folder))} ({error}); the {kept} are kept there", 1) from None
    except KeyboardInterrupt:  # held until the outputs were written: they are
        raise fail(
            f"interrupted; the tables, figures and report are written in {printable(str(folder))}", 130
        ) from None
    return problems


def _unwritable(error: OSError, folder: Path, what: str) -> typer.Exit:
    """The one-line failure (exit 1) of a resumable computation that could not write into its
    folder: what it finished is kept there."""
    return fail(
        f"cannot write into {printable(str(folder))} ({error.strerror or error}); the {what} finished so far are "
        "kept there: free the space and run the same command to resume",
        1,
    )


def _say_reused(store: Any, reused: int, what: str, quiet: bool) -> None:
    """How much of a resumed computation was read back from its folder instead of computed:
    ``what`` names it (``"of the 900 starts"``)."""
    if reused and not quiet:
        say(f"resumed: {reused} {what} read from {printable(str(store.folder))}, the rest computed")


def _new_folder(case: Case, kind: str) -> Path:
    from oscillator.io.files import default_name

    return Path("runs") / f"{default_name(case.name)}-{kind}-{time.strftime('%Y%m%d-%H%M%S')}"


def basins(
    case: Annotated[str, typer.Argument(metavar="CASE", help="A named case or a case file (.toml).")],
    x: Annotated[
        AxisOption, typer.Option("--x", metavar="NAME LOW HIGH N", help="The slice's first axis: x1, v1, x2 or v2.")
    ],
    y: Annotated[AxisOption, typer.Option("--y", metavar="NAME LOW HIGH N", help="The slice's second axis.")],
    transient: TransientOption = 200,
    record: RecordOption = 32,
    max_period: Annotated[int, typer.Option("--max-period", metavar="N", help="The longest period looked for.")] = 16,
    workers: WorkersOption = None,
    scheduler: SchedulerOption = None,
    out_dir: Annotated[
        Path | None,
        typer.Option(
            "--out",
            metavar="DIR",
            help="Output folder (default: runs/CASE-basins-YYYYmmdd-HHMMSS); the same folder again resumes.",
        ),
    ] = None,
    set_: SetOption = None,
    no_plots: NoPlotsOption = False,
    quiet: QuietOption = False,
) -> None:
    """Basins of attraction over a slice of starting states: every attractor the starts reach
    (a periodic orbit with its multipliers, or an aperiodic set with its largest Lyapunov
    exponent), each cell's attractor, and each attractor's share of the slice.

    The two other state components and the section t0 are the case's start. Writes
    basins.parquet, attractors.parquet, figures/basins.png and a report. Interrupted or killed,
    the same command with the same --out resumes where it stopped.

    \b
    Examples:
      oscillator basins instance-1 --set Q2=71.165 --x x2 3 6 16 --y v2 -4 4 16 --out runs/basins
      oscillator basins instance-1 --set Omega=1.85 --x x1 2 5 4 --y v1 -3 3 4 --transient 100 --record 8
    """
    try:
        resolved = case_from(case, None, set_)
        x_axis, y_axis = _axis(x, "--x"), _axis(y, "--y")
        settings = _settings(transient, record, max_period)
        plan = _open_basins(resolved, x_axis, y_axis, settings, out_dir, workers, scheduler)
    except OscillatorError as error:
        raise fail(message(error)) from None
    except KeyboardInterrupt:
        raise fail("interrupted; nothing was written", 130) from None
    store, lock, client, count = plan
    with _computing(store, "starts", lock, client):
        found = _run_basins(resolved, x_axis, y_axis, store, settings, count, client, quiet)
    _finish_basins(found, store, no_plots, quiet)


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
    the workers, the scheduler; the folder's name locked."""
    count = check_workers(workers)
    load("oscillator.attractors.basins", notice=True)
    from oscillator.attractors.basins import basin_store, grid_starts

    grid_starts(case, x, y)
    folder = out_dir if out_dir is not None else _new_folder(case, "basins")
    store = basin_store(folder, case, x, y, settings)
    store.check()
    lock, client = _locked(folder, scheduler)
    return store, lock, client, count


def _locked(folder: Path, scheduler: str | None) -> tuple[Any, Any]:
    """The folder's name locked for this process, and the Dask client (or None)."""
    from oscillator.analysis.execution import connect
    from oscillator.io.files import lock_name

    busy = f"folder {printable(str(folder))} is being computed by another process now; wait for it, or give another"
    lock = lock_name(folder, busy=busy, option="--out")
    try:
        client = connect(scheduler) if scheduler else None
    except BaseException:
        lock.release()
        raise
    return lock, client


def _run_basins(
    case: Case, x: Axis, y: Axis, store: Any, settings: AttractorSettings, workers: int, client: Any, quiet: bool
) -> Basins:
    from oscillator.attractors.basins import find_basins

    if quiet or not err.is_terminal:
        return find_basins(case, x, y, store, settings=settings, workers=workers, client=client)
    bar, report = progress_bar(f"{case.name}: basins", "starts")
    with bar:
        return find_basins(case, x, y, store, settings=settings, workers=workers, client=client, progress=report)


def _finish_basins(found: Basins, store: Any, no_plots: bool, quiet: bool) -> None:
    _say_reused(store, store.reused["landings"], f"of the {found.x.count * found.y.count} starts", quiet)
    folder = store.folder
    from oscillator.attractors.finding import share_text
    from oscillator.report.attractors import attractor_table, write_basins

    problems = _outputs(folder, "starts", lambda: write_basins(found, folder, plots=not no_plots))
    if not quiet:
        table = Table(title="attractors", title_justify="left", header_style="bold", box=box.SIMPLE_HEAD)
        for column in ("attractor", "share of starts [95 %]", "orbit", "largest |multiplier|"):
            table.add_column(column)
        for row in attractor_table(found).itertuples(index=False):
            orbit = "" if row.kind != "periodic" or row.stable is None else ("stable" if row.stable else "unstable")
            largest = "" if row.kind != "periodic" else f"{row.largest_multiplier:.4g}"
            share = share_text(row.fraction, row.low, row.high)
            table.add_row(Text(str(row.name)), share, orbit, largest)
        out.print(table)
    for warning in found.found.warnings:
        warn(warning)
    say(f"written to {printable(str(folder))}")
    if not found.found.attractors:
        labels = found.found.labels
        raise fail(
            f"every start failed ({labels.message.iloc[0]}); the starts' reasons are in "
            f"{printable(str(folder))}/basins.parquet",
            1,
        )
    if problems:
        raise fail("; ".join(problems) + f"; the tables are in {folder}", 1)


def lyapunov(
    case: Annotated[str, typer.Argument(metavar="CASE", help="A named case or a case file (.toml).")],
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

    \b
    Examples:
      oscillator lyapunov instance-1 --set Omega=1.85 --periods 200
      oscillator lyapunov instance-1 --set Omega=1.85 --periods 100 --out runs/lyapunov
    """
    from oscillator.io.files import check_new, claim_folder

    try:
        resolved = case_from(case, None, set_)
        if out_dir is not None:
            check_new(out_dir, option="--out")
        load("oscillator.attractors.lyapunov", notice=True)
        from oscillator.attractors.lyapunov import lyapunov as spectrum_of
        from oscillator.orbits.shooting import check_count

        check_count(periods, "--periods", 1, 10_000_000)
        check_count(transient, "--transient", 0, 10_000_000)
        claim = claim_folder(out_dir, option="--out") if out_dir is not None else None  # writable, before the work
    except OscillatorError as error:
        raise fail(message(error)) from None
    try:
        bar, report = progress_bar(f"{resolved.name}: Lyapunov exponents", "periods")
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
    out.print(Text(f"{printable(resolved.name)}: Lyapunov exponents (1/s), {periods} periods: {exponents}"))
    out.print(Text(f"  largest {spectrum.largest:.6g} 1/s; Kaplan-Yorke dimension of the map {spectrum.dimension:.4g}"))
    if claim is not None:
        _write_lyapunov(spectrum, claim, no_plots)


def _write_lyapunov(spectrum: Any, claim: FolderClaim, no_plots: bool) -> None:
    from oscillator.report.attractors import write_lyapunov

    _write_claimed(claim, lambda folder: write_lyapunov(spectrum, folder, plots=not no_plots), "the exponents")


def attractors(
    case: Annotated[str, typer.Argument(metavar="CASE", help="A named case or a case file (.toml).")],
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
    transient: TransientOption = 200,
    record: RecordOption = 32,
    coordinate: Annotated[
        str, typer.Option("--coordinate", metavar="NAME", help="The section coordinate drawn: x1, v1, x2 or v2.")
    ] = "x2",
    branches: Annotated[
        bool, typer.Option("--branches/--no-branches", help="Draw the periodic orbits' branches (continue_orbit).")
    ] = True,
    workers: WorkersOption = None,
    scheduler: SchedulerOption = None,
    out_dir: Annotated[
        Path | None,
        typer.Option(
            "--out",
            metavar="DIR",
            help="Output folder (default: runs/CASE-attractors-YYYYmmdd-HHMMSS); the same folder again resumes.",
        ),
    ] = None,
    set_: SetOption = None,
    no_plots: NoPlotsOption = False,
    quiet: QuietOption = False,
) -> None:
    """The attractors over a parameter: at each value every attractor the fresh starts reach (and
    the seeds from the value before), matched from value to value, each one's share of the fresh
    starts, and where each one appears or ends, bisected to --tol: the window where two coexist.

    Writes attractors.parquet, ends.parquet, figures/attractors.png and a report. Interrupted or
    killed, the same command with the same --out resumes at the value it stopped at.

    \b
    Examples:
      oscillator attractors instance-1 --param Q2 --from 71.10 --to 71.20 --steps 5 --x x2 3 6 3 --y v2 -4 4 3
      oscillator attractors instance-1 --param Q2 --from 71.10 --to 71.20 --steps 3 --no-branches --out runs/q2
    """
    try:
        resolved = case_from(case, None, set_)
        plan = _open_following(resolved, param, start, stop, steps, x, y, tol, transient, record, coordinate, out_dir)
        values, states, settings, store = plan
        count = check_workers(workers)
        lock, client = _locked(store.folder, scheduler)
    except OscillatorError as error:
        raise fail(message(error)) from None
    except KeyboardInterrupt:
        raise fail("interrupted; nothing was written", 130) from None
    with _computing(store, "values", lock, client):
        over = _run_following(resolved, param, values, states, settings, tol, store, count, client, quiet)
        found = _branches_of(over) if branches and not no_plots else []
    _finish_following(over, store, coordinate, found, no_plots, quiet)


def _open_following(
    case: Case,
    param: str,
    start: float,
    stop: float,
    steps: int,
    x: AxisOption | None,
    y: AxisOption | None,
    tol: float,
    transient: int,
    record: int,
    coordinate: str,
    out_dir: Path | None,
) -> tuple[Any, Any, AttractorSettings, Any]:
    """Everything refused before work: the values, the slice, the settings, the folder."""

    import numpy as np

    from oscillator.analysis.axes import STATE

    if coordinate not in STATE:
        raise InputError(f"--coordinate must be one of {', '.join(STATE)}, got {coordinate!r}", field="--coordinate")
    if isinstance(steps, bool) or not 2 <= steps <= 10_000:
        raise InputError(f"--steps must be a whole number from 2 to 10000, got {steps!r}", field="--steps")
    if (x is None) != (y is None):
        raise InputError("give both --x and --y for a slice of fresh starts, or neither", field="--x")
    settings = _settings(transient, record, 16)
    load("oscillator.attractors.following", notice=True)
    from oscillator.attractors.basins import grid_starts
    from oscillator.attractors.following import check_values, following_store

    if not (np.isfinite(start) and np.isfinite(stop)):
        raise InputError(f"--from and --to must be finite numbers, got {start!r} and {stop!r}", field="--to")
    values = np.linspace(start, stop, steps)
    check_values(case, param, values, tol)
    axes = (_axis(x, "--x"), _axis(y, "--y")) if x is not None and y is not None else None
    states = grid_starts(case, *axes) if axes is not None else None
    folder = out_dir if out_dir is not None else _new_folder(case, "attractors")
    store = following_store(folder, case, param, values, axes, settings)
    store.check()
    return values, states, settings, store


def _run_following(
    case: Case,
    param: str,
    values: Any,
    states: Any,
    settings: AttractorSettings,
    tol: float,
    store: Any,
    workers: int,
    client: Any,
    quiet: bool,
) -> Any:
    from oscillator.attractors.following import follow_attractors

    store.open()
    options = {"states": states, "settings": settings, "tol": tol, "workers": workers, "client": client, "store": store}
    if quiet or not err.is_terminal:
        over = follow_attractors(case, param, values, **options)
    else:
        bar, report = progress_bar(f"{case.name}: attractors over {param}", "values")
        with bar:
            over = follow_attractors(case, param, values, progress=report, **options)
    store.write_status("computed", values=len(values))
    return over


def _branches_of(over: Any) -> list[Any]:
    from oscillator.attractors.following import local_branches

    return local_branches(over)


def _finish_following(over: Any, store: Any, coordinate: str, branches: list[Any], no_plots: bool, quiet: bool) -> None:
    _say_reused(store, store.reused["landings"], "starts (of every value's fresh starts and seeds)", quiet)
    folder = store.folder
    from oscillator.report.attractors import write_following

    write = functools.partial(
        write_following, over, folder, coordinate=coordinate, branches=branches, plots=not no_plots
    )
    problems = _outputs(folder, "landings", write)
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


PlaneAxis = tuple[str, float, float, int]


def atlas(
    case: Annotated[str, typer.Argument(metavar="CASE", help="A named case or a case file (.toml).")],
    x: Annotated[PlaneAxis, typer.Option("--x", metavar="NAME LOW HIGH N", help="The first parameter's axis.")],
    y: Annotated[PlaneAxis, typer.Option("--y", metavar="NAME LOW HIGH N", help="The second parameter's axis.")],
    starts: Annotated[
        int, typer.Option("--starts", metavar="N", help="Fresh starts at every point: the case's, and N-1 around it.")
    ] = 1,
    transient: TransientOption = 40,
    record: RecordOption = 10,
    workers: WorkersOption = None,
    scheduler: SchedulerOption = None,
    out_dir: Annotated[
        Path | None,
        typer.Option(
            "--out",
            metavar="DIR",
            help="Output folder (default: runs/CASE-atlas-YYYYmmdd-HHMMSS); the same folder again resumes.",
        ),
    ] = None,
    set_: SetOption = None,
    no_plots: NoPlotsOption = False,
    quiet: QuietOption = False,
) -> None:
    """The regime atlas over two parameters: at every point the attractors (from the case's start
    and seeds from the row before), each one's period, rests and contacts per period, impact
    velocity and largest Lyapunov exponent; the regime of each, and where several coexist.

    Writes atlas.parquet, figures/atlas.png (Fig. 14's lines marked) and a report. Rows are kept as
    they finish: the same command with the same --out resumes.

    \b
    Examples:
      oscillator atlas instance-1 --x Omega 1.3 1.85 12 --y Q2 68.5 72 8 --out runs/atlas
      oscillator atlas instance-1 --x Omega 1.59 1.61 3 --y Q2 71.1 71.2 3 --starts 4 --transient 60 --record 16
    """
    try:
        resolved = case_from(case, None, set_)
        from oscillator.analysis.axes import parameter_plane

        x_axis, y_axis = parameter_plane(resolved, _axis(x, "--x"), _axis(y, "--y"))
        from oscillator.attractors.atlas import AtlasSettings, atlas_store

        count = check_workers(workers)
        settings = AtlasSettings(fresh_transient=transient, record=record, starts=starts)
        folder = out_dir if out_dir is not None else _new_folder(resolved, "atlas")
        store = atlas_store(folder, resolved, x_axis, y_axis, settings)
        store.check()
        load("oscillator.attractors.atlas", notice=True)
        lock, client = _locked(folder, scheduler)
    except OscillatorError as error:
        raise fail(message(error)) from None
    except KeyboardInterrupt:
        raise fail("interrupted; nothing was written", 130) from None
    with _computing(store, "rows", lock, client):
        found = _run_atlas(resolved, x_axis, y_axis, settings, store, count, client, quiet)
    _finish_atlas(found, store, no_plots, quiet)


def _run_atlas(case: Case, x: Any, y: Any, settings: Any, store: Any, workers: int, client: Any, quiet: bool) -> Any:
    from oscillator.attractors.atlas import regime_atlas

    store.open()
    options = {"settings": settings, "store": store, "workers": workers, "client": client}
    if quiet or not err.is_terminal:
        found = regime_atlas(case, x, y, **options)
    else:
        bar, report = progress_bar(f"{case.name}: atlas", "points")
        with bar:
            found = regime_atlas(case, x, y, progress=report, **options)
    store.write_status("computed", points=x.count * y.count)
    return found


def _finish_atlas(found: Any, store: Any, no_plots: bool, quiet: bool) -> None:
    _say_reused(store, store.reused["batches"], f"of the {found.y.count} rows", quiet)
    folder = store.folder
    from oscillator.report.attractors import write_atlas

    problems = _outputs(folder, "rows", lambda: write_atlas(found, folder, plots=not no_plots))
    if not quiet:
        first = found.table[found.table.attractor <= 0]
        for regime, count in first.regime.value_counts().items():
            out.print(Text(f"  {regime}: {count} points"))
        out.print(Text(f"  several attractors coexist at {int((first.coexisting > 1).sum())} points"))
    say(f"written to {printable(str(folder))}")
    if (found.table.status == "failed").all():
        raise fail(f"every point failed ({found.table.message.iloc[0]}); the tables are in {folder}", 1)
    if problems:
        raise fail("; ".join(problems) + f"; the tables are in {folder}", 1)


RangeOption = tuple[str, float, float]


def curve(
    case: Annotated[str, typer.Argument(metavar="CASE", help="A named case or a case file (.toml).")],
    kind: Annotated[
        str, typer.Option("--kind", metavar="KIND", help="sliding, sliding_onset, sliding_vanish, grazing, fold, ...")
    ],
    at: Annotated[
        str, typer.Option("--at", metavar="X=A,Y=B", help="A point near the curve, e.g. Omega=1.6,Q2=71.15.")
    ],
    x: Annotated[RangeOption, typer.Option("--x", metavar="NAME LOW HIGH", help="The first parameter and its range.")],
    y: Annotated[RangeOption, typer.Option("--y", metavar="NAME LOW HIGH", help="The second parameter and its range.")],
    period: Annotated[int, typer.Option("--period", metavar="N", help="Forcing periods per return.")] = 1,
    step: Annotated[float, typer.Option("--step", metavar="S", help="The step, as a fraction of the window.")] = 0.05,
    over: Annotated[
        Path | None, typer.Option("--over", metavar="ATLAS_DIR", help="Draw the curve over this atlas's regimes.")
    ] = None,
    also: Annotated[
        list[Path] | None,
        typer.Option(
            "--also", metavar="CURVE_DIR", help="Draw this curve (a folder of `curve`) beside it; repeatable."
        ),
    ] = None,
    out_dir: Annotated[
        Path | None, typer.Option("--out", metavar="DIR", help="Output folder (default: runs/CASE-curve-...).")
    ] = None,
    set_: SetOption = None,
    no_plots: NoPlotsOption = False,
) -> None:
    """Trace a bifurcation curve in a plane of two parameters: from a bifurcation that `oscillator
    continue` located, each point located to 1e-8 by a continuation across the curve from its
    inside, until the curve leaves the window or ends (said how).

    \b
    Examples:
      oscillator curve instance-1 --kind sliding --at Omega=1.6,Q2=71.1577416 --x Omega 1.59 1.62 --y Q2 70.9 71.3
      oscillator curve instance-1 --kind sliding --at Omega=1.6,Q2=71.16 --x Omega 1.59 1.62 --y Q2 70.9 71.3 --out c1
      oscillator curve instance-1 --kind sliding --at Omega=1.6,Q2=71.16 --x Omega 1.59 1.62 --y Q2 70.9 71.3 --also c1
    """
    from oscillator.io.files import check_new, claim_folder

    try:
        resolved = case_from(case, None, set_)
        point = _at(at, x[0], y[0])
        folder = out_dir if out_dir is not None else _new_folder(resolved, "curve")
        check_new(folder, option="--out")
        atlas_found = _atlas_over(over, resolved, x[0], y[0]) if over is not None else None
        others = [_read_other_curve(other, x[0], y[0]) for other in also or []]
        load("oscillator.orbits.curves", notice=True)
        from oscillator.orbits.curves import check_curve, trace_curve

        window = ((x[1], x[2]), (y[1], y[2]))
        options: dict[str, Any] = dict(kind=kind, x=x[0], y=y[0], at=point, window=window, period=period, step=step)
        check_curve(resolved, **options)  # every argument refused here, before any work (exit 2)
        claim = claim_folder(folder, option="--out")  # an unwritable --out is refused before the work too
    except OscillatorError as error:
        raise fail(message(error)) from None
    except KeyboardInterrupt:
        raise fail("interrupted; nothing was written", 130) from None
    found, interrupted = _trace(trace_curve, resolved, options, claim)
    for end in found.ends:
        out.print(Text(f"  one end: {end}"))
    _write_curve(found, claim, atlas_found, others, no_plots)
    if interrupted:
        raise fail(f"interrupted; the {len(found.points)} points traced so far are written to {claim.target}", 130)


def _at(text: str, x: str, y: str) -> tuple[float, float]:
    """``--at X=A,Y=B`` as ``(A, B)`` in the order of ``--x`` and ``--y``."""
    from oscillator.io.expressions import parse_value

    values: dict[str, float] = {}
    for part in text.split(","):
        name, _, value = part.partition("=")
        number = parse_value(value.strip(), field="--at") if value else None
        if not isinstance(number, (int, float)) or isinstance(number, bool):
            raise InputError(f"--at must be {x}=A,{y}=B, got {text!r}", field="--at")
        values[name.strip()] = float(number)
    if set(values) != {x, y}:
        raise InputError(f"--at must name {x} and {y} (the --x and --y parameters), got {text!r}", field="--at")
    return values[x], values[y]


def _atlas_over(folder: Path, case: Case, x: str, y: str) -> Any:
    """The atlas to draw the curve over (``--over``): finished, and in the curve's plane."""
    from oscillator.report.attractors import read_atlas

    try:
        found = read_atlas(folder, case)
    except InputError as error:
        raise InputError(f"--over {error}", field="--over") from None
    if (found.x.name, found.y.name) != (x, y):
        raise InputError(
            f"--over {printable(str(folder))}: its atlas is over {found.x.name} and {found.y.name}, the curve in {x} "
            f"and {y}; give the atlas's axes as --x and --y, in its order",
            field="--over",
        )
    return found


def _trace(trace_curve: Any, case: Case, options: dict[str, Any], claim: FolderClaim) -> tuple[Curve, bool]:
    """The curve, and whether it was interrupted (the points traced so far); the claim abandoned
    when there is nothing to write."""
    try:
        bar, report = progress_bar(f"{case.name}: {options['kind']} curve", "points")
        with bar:
            return trace_curve(case, progress=lambda n: report(n, n), **options), False
    except OscillatorError as error:
        claim.abandon()
        raise fail(message(error), 1) from None
    except Interrupted as interrupt:  # the points traced so far are kept
        return cast("Curve", interrupt.result), True
    except KeyboardInterrupt:
        claim.abandon()
        raise fail("interrupted before the curve's first point was found; nothing was written", 130) from None
    except BaseException:
        claim.abandon()
        raise


def _read_other_curve(folder: Path, x: str, y: str) -> Curve:
    """A curve to draw beside the new one (``--also``), in the same plane."""
    from oscillator.report.attractors import read_curve

    try:
        other = read_curve(folder)
    except InputError as error:
        raise InputError(f"--also {error}", field="--also") from None
    if (other.x, other.y) != (x, y):
        raise InputError(
            f"--also {printable(str(folder))}: its curve is in {other.x} and {other.y}, this one in {x} and {y}; give "
            "a curve of the same plane",
            field="--also",
        )
    return other


def _write_curve(found: Curve, claim: FolderClaim, atlas_found: Any, others: list[Curve], no_plots: bool) -> None:
    from oscillator.report.attractors import write_curve

    def write(folder: Path) -> list[str]:
        return write_curve(found, folder, atlas=atlas_found, plots=not no_plots, also=others)

    _write_claimed(claim, write, "the curve")


def _write_claimed(claim: FolderClaim, write: Any, what: str) -> None:
    """``write(folder)`` into the claimed folder, which appears whole; a failure to write says so
    in one line (exit 1) and leaves nothing; a Ctrl-C waits until the folder is whole.  The
    problems ``write`` returns (a figure that failed: the tables are kept) exit 1 after."""
    from oscillator.io.signals import interrupts_deferred

    target = printable(str(claim.target))
    try:
        with interrupts_deferred():
            problems = write(claim.temporary)
            written = claim.commit()
    except (OSError, OscillatorError) as error:
        claim.abandon()
        reason = error.strerror if isinstance(error, OSError) and error.strerror else str(error)
        raise fail(f"cannot write {what} to {target}: {reason}; nothing was written", 1) from None
    except KeyboardInterrupt:  # held until the folder was whole: it is written
        raise fail(f"interrupted; {what} written to {target}", 130) from None
    except BaseException:
        claim.abandon()
        raise
    say(f"written to {printable(str(written))}")
    if problems:
        raise fail("; ".join(problems), 1)
