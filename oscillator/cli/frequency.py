"""``oscillator frc``: the frequency response over a parameter's span (resumable, local or on Dask)."""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.text import Text

from oscillator.analysis.execution import check_workers
from oscillator.cli.attractors import analysis_settings
from oscillator.cli.commands import command
from oscillator.cli.console import fail, load, out, say
from oscillator.cli.inputs import case_from, refuse_taken
from oscillator.cli.options import (
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
from oscillator.cli.resumable import computing, locked, new_folder, outputs, refusing, say_reused, with_progress
from oscillator.errors import InputError
from oscillator.text import printable

__all__ = ["frc"]

#: ``--param NAME LOW HIGH``: the parameter and its span.
SpanOption = tuple[str, float, float]
#: ``--seeds N``: where attractors are sought (5 by default; a system file's branches only with it).
SeedsOption = Annotated[
    int | None,
    typer.Option("--seeds", metavar="N", help="Values where attractors are sought (5; a system file: none)."),
]


#: The options of ``frc`` for the article's cases, at their defaults, in the order ``frc`` reads them
#: (a system file takes none of them).
_DEFAULTS: dict[str, object] = {
    "--max-points": 3000,
    "--record": None,
    "--full-transient": False,
    "--engine": "dop853",
    "--cutoff": None,
    "--workers": None,
    "--scheduler": None,
    "--period": 1,
    "--measure": "x_pp",
}


@command(125, "The frequency response: every branch of periodic orbits, and slow sweeps up and down.")
def frc(
    case: CaseArgument,
    param: Annotated[
        SpanOption, typer.Option("--param", metavar="NAME LOW HIGH", help="The parameter and its span, e.g. Omega.")
    ],
    period: Annotated[int, typer.Option("--period", metavar="N", help="Forcing periods per return.")] = 1,
    seeds: SeedsOption = None,
    sweep: Annotated[int, typer.Option("--sweep", metavar="N", help="Values of each slow sweep.")] = 41,
    measure: Annotated[
        str, typer.Option("--measure", metavar="NAME", help="The measure drawn: x_pp, x_max, v_peak, impact_max, ...")
    ] = "x_pp",
    starts: Annotated[
        int, typer.Option("--starts", metavar="N", help="Starts at each seed: the case's, and N-1 around it.")
    ] = 1,
    max_points: Annotated[int, typer.Option("--max-points", metavar="N", help="The most points a branch.")] = 3000,
    transient: TransientOption = None,
    record: RecordOption = None,
    full_transient: FullTransientOption = False,
    engine: LandingEngineOption = "dop853",
    cutoff: CutoffOption = None,
    workers: WorkersOption = None,
    scheduler: SchedulerOption = None,
    out_dir: ResumableOutOption = None,
    set_: SetOption = None,
    noise: Annotated[
        bool,
        typer.Option(
            "--noise",
            help="Also measure every branch point's noise and spectra: noise.parquet, spectra.parquet, a figure.",
        ),
    ] = False,
    no_plots: NoPlotsOption = False,
    quiet: QuietOption = False,
) -> None:
    """The frequency response over a parameter's span: the periodic attractors at --seeds values
    (from the case's start, or --starts around it), each orbit continued both ways through folds
    and unstable stretches, every branch point measured (amplitudes, peak velocity, RMS
    acceleration, rests, impact velocities, contact forces, energies), and slow sweeps up and
    down with their jumps.

    Writes points.parquet, bifurcations.parquet, sweeps.parquet, figures/frequency-*.png (the
    --measure of each mass, and the impact velocities where there are contacts) and a report;
    with --noise, each point's noise measures and spectra too (noise.parquet, spectra.parquet,
    figures/frequency-spectra.png; docs/noise.md).  Parts are kept as they finish: the same
    command with the same --out resumes.  A system file
    (docs/systems.md) is swept up and down over --sweep values, its orbit followed from value to
    value (sweeps.parquet, figures/frequency.png); with --seeds N (and --starts) every period-1
    branch its attractors at N values and its sweeps reach, through folds (branches.parquet);
    with --noise every orbit's levels and spectra (noise.parquet, spectra.parquet).

    \b
    Examples:
      oscillator frc instance-1 --param Omega 1.3 1.85 --out runs/frc
      oscillator frc instance-1 --param Omega 1.5 1.7 --seeds 3 --sweep 21 --measure v_peak
      oscillator frc instance-1 --set Q2=71.165 --param Omega 1.5999 1.6001 --starts 16 --out runs/frc-window
      oscillator frc instance-1 --set d=1 --set d1=3.5 --param Omega 1.45 1.6 --seeds 2 --noise --out runs/frc-noise
      oscillator frc docs/systems/blade-damper.toml --param Omega 0.6 1.6 --sweep 21 --out runs/blade-frc
      oscillator frc docs/systems/impacts.toml --param Omega 1.0 1.6 --seeds 3 --sweep 21 --out runs/impacts-frc
      oscillator frc docs/systems/impacts.toml --param Omega 1.0 1.6 --sweep 21 --noise --out runs/impacts-noise
    """
    from oscillator.cli.system import frc_system

    given = (max_points, record, full_transient, engine, cutoff, workers, scheduler, period, measure)
    case_only = [flag for flag, value in zip(_DEFAULTS, given, strict=True) if value != _DEFAULTS[flag]]
    if frc_system(case, set_, param, (sweep, seeds, starts), transient, out_dir, case_only, not no_plots, quiet, noise):
        return
    with refusing():
        resolved = case_from(case, None, set_)
        name, low, high = param
        refuse_taken(set_, {name: "--param"})
        seeded = 5 if seeds is None else seeds
        options: dict[str, Any] = {"period": period, "seeds": seeded, "sweep": sweep, "max_points": max_points}
        _checked(resolved, (name, low, high), measure, starts, options)
        settings = analysis_settings(transient, record, full_transient, engine, cutoff)
        store = _opened(resolved, (name, low, high), starts, settings, options, out_dir)
        count = check_workers(workers, starts=2 * sweep + seeded * starts)  # the landings of sweeps and seeds
        lock, client = locked(store.folder, scheduler)
    with computing(store, "parts", lock, client):
        from oscillator.attractors.frequency import frequency_response

        store.open()
        pool = {"settings": settings, "workers": count, "client": client, "store": store}
        run = functools.partial(frequency_response, resolved, name, (low, high), **pool, **options)
        found = with_progress(run, f"{resolved.name}: frequency response over {name}", "tasks", quiet)
        store.write_status("computed", branches=len(found.branches))
    _finish(found, store, (measure, noise), no_plots, quiet)


def _checked(case: Any, param: SpanOption, measure: str, starts: int, options: dict[str, Any]) -> None:
    """Everything refused before work: the span and the counts (before the numerical libraries
    load), then the measure."""
    from oscillator.model.parameters import check_count
    from oscillator.orbits.settings import check_frequency

    name, low, high = param
    check_frequency(case, name, (low, high), **options)
    check_count(starts, "--starts", 1, 1000)
    from oscillator.report.frequency import MEASURES

    if measure not in MEASURES:
        raise InputError(f"--measure must be one of {', '.join(MEASURES)}, got {measure!r}", field="--measure")


def _opened(
    case: Any, param: SpanOption, starts: int, settings: Any, options: dict[str, Any], out_dir: Path | None
) -> Any:
    """The frequency response's store (its folder refused if it holds another computation), and
    ``options`` completed with the starts."""
    load("oscillator.attractors.frequency", notice=True)
    from oscillator.attractors.atlas import fresh_starts
    from oscillator.attractors.frequency import frequency_store

    name, low, high = param
    options["states"] = fresh_starts(case, starts)
    folder = out_dir if out_dir is not None else new_folder(case, "frc")
    store = frequency_store(folder, case, name, (low, high), settings=settings, **options)
    store.check()
    return store


def _finish(found: Any, store: Any, asked: tuple[str, bool], no_plots: bool, quiet: bool) -> None:
    """The folder written (with the noise tables where ``asked``: the measure drawn, whether to
    measure the noise), what was found said."""
    folder: Path = store.folder
    measure, noise = asked
    say_reused(store, store.reused, "parts", quiet)
    from oscillator.report.frequency import write_frequency

    tables, interrupted = None, False
    if noise and found.branches:
        try:
            tables = with_progress(
                found.noise_tables, f"{found.case.name}: noise of the branch points", "points", quiet
            )
        except KeyboardInterrupt:  # the frequency response is written all the same, without its noise
            interrupted = True
    problems = outputs(
        folder, "parts", lambda: write_frequency(found, folder, measure, plots=not no_plots, noise=tables)
    )
    if interrupted:
        raise fail(f"interrupted while measuring the noise; the frequency response is in {printable(str(folder))}", 130)
    if not quiet and found.branches:
        points = found.points
        out.print(Text(f"  {len(found.branches)} branches, {len(points)} points, {points.stable.mean():.0%} stable"))
    if not quiet:
        for direction in ("up", "down"):
            jumps = ", ".join(f"{value:g}" for value in found.jumps(direction)) or "none"
            out.print(Text(f"  sweep {direction}: jumps at {jumps}"))
        for _, row in found.bifurcations.iterrows():
            out.print(Text(f"  branch {int(row.branch)}: {str(row.kind).replace('_', ' ')} at {row[found.param]:.8g}"))
    say(f"written to {printable(str(folder))}")
    if not found.branches:
        problems.insert(0, found.nothing_found())
    if problems:
        raise fail("; ".join(problems) + f"; the tables are in {printable(str(folder))}", 1)
