"""``oscillator design``: robust design over an operating band (resumable, local or on Dask)."""

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
from oscillator.model.parameters import check_count
from oscillator.text import printable

__all__ = ["design"]

VaryOption = Annotated[
    list[str],
    typer.Option("--vary", metavar="NAME=LOW,HIGH", help="A parameter the design chooses and its range (repeat it)."),
]
OverOption = Annotated[
    tuple[str, float, float],
    typer.Option("--over", metavar="NAME LOW HIGH", help="The operating band, e.g. Omega 1.4 1.6."),
]
ObjectiveOption = Annotated[
    list[str],
    typer.Option(
        "--objective",
        metavar="MEASURE",
        help="The response measure whose worst case is minimised; give two for their Pareto front.",
    ),
]
ConstraintOption = Annotated[
    list[str] | None,
    typer.Option("--constraint", metavar="'MEASURE <= VALUE'", help="A bound on every attractor (repeat it)."),
]


#: The options that apply to the article's cases only, at their defaults (a system file's design
#: refuses any other value, naming the option).
_DEFAULTS: dict[str, object] = {
    "--constraint": None,
    "--starts": 4,
    "--candidates": 16,
    "--front": 5,
    "--transient": None,
    "--record": None,
    "--full-transient": False,
    "--engine": "dop853",
    "--cutoff": None,
    "--workers": None,
    "--scheduler": None,
}


def _of_system(
    case: str,
    assignments: list[str] | None,
    ranges: dict[str, tuple[float, float]],
    band: tuple[tuple[str, float, float], int],
    objectives: list[str],
    out_dir: Path | None,
    given: tuple[object, ...],
    plots: bool,
    quiet: bool,
) -> bool:
    """``design FILE`` for a system file (:func:`~oscillator.cli.system_design.design_system`), the
    article's options given refused by name; whether ``case`` was one. ``--band`` is the sweep's
    values there (21 when left at 5)."""
    from oscillator.cli.system_design import design_system

    case_only = [flag for flag, value in zip(_DEFAULTS, given, strict=True) if value != _DEFAULTS[flag]]
    values = band if band[1] != 5 else (band[0], 21)
    return design_system(case, assignments, ranges, values, objectives, out_dir, case_only, plots, quiet)


def parse_ranges(texts: list[str]) -> dict[str, tuple[float, float]]:
    """``--vary NAME=LOW,HIGH`` (each) as ``{name: (low, high)}``; the names and ranges are checked
    with the problem."""
    ranges = {}
    for text in texts:
        name, _, bounds = text.partition("=")
        try:
            low, high = (float(v) for v in bounds.split(","))
        except ValueError:
            raise InputError(f"--vary {text!r}: write NAME=LOW,HIGH, e.g. d1=2.5,4.5", field="vary") from None
        ranges[name.strip()] = (low, high)
    return ranges


@command(127, "Robust design: parameters that make a measure's worst case over a band smallest.")
def design(
    case: CaseArgument,
    vary: VaryOption,
    over: OverOption,
    objective: ObjectiveOption,
    constraint: ConstraintOption = None,
    band: Annotated[int, typer.Option("--band", metavar="N", help="Band values judged.")] = 5,
    starts: Annotated[int, typer.Option("--starts", metavar="N", help="Fresh starts at each band value.")] = 4,
    candidates: Annotated[int, typer.Option("--candidates", metavar="N", help="Designs of the global search.")] = 16,
    front: Annotated[
        int, typer.Option("--front", metavar="N", help="Points of the Pareto front (two objectives).")
    ] = 5,
    transient: TransientOption = None,
    record: RecordOption = None,
    full_transient: FullTransientOption = False,
    engine: LandingEngineOption = "dop853",
    cutoff: CutoffOption = None,
    workers: WorkersOption = None,
    scheduler: SchedulerOption = None,
    out_dir: ResumableOutOption = None,
    set_: SetOption = None,
    no_plots: NoPlotsOption = False,
    quiet: QuietOption = False,
) -> None:
    """Choose the --vary parameters so that the worst --objective over --band values of the --over
    band, and over every attractor --starts fresh starts reach at each, is smallest, with every
    --constraint holding on every attractor: a global search over --candidates designs, then
    gradient refinement with the exact sensitivities, then a check from fresh starts. With two
    --objective, also their Pareto front (--front points, each a refined design).

    Writes candidates.parquet, history.parquet, attractors.parquet, best.json, figures (the
    search, the measures over the band before and after) and a report. The global search's
    surveys are kept as they finish: the same command with the same --out resumes.

    \b
    A system file (docs/systems.md) varies one number over one band (docs/damper-design.md), the
    band swept over --band values (21 unless given): history.parquet, system.toml at the best
    value, figures/design.png.

    \b
    Examples:
      oscillator design instance-1 --vary d1=2.5,4.5 --vary K6=1,40 --over Omega 1.4 1.6 --objective x_max_m1
      oscillator design docs/systems/blade-damper.toml --vary platform.F=0.05,3 --over Omega 0.6 1.6 \
        --objective x_max:blade
    """
    with refusing():
        ranges = parse_ranges(vary)
    given: tuple[object, ...] = (constraint, starts, candidates, front, transient, record, full_transient, engine)
    given += (cutoff, workers, scheduler)
    if _of_system(case, set_, ranges, (over, band), objective, out_dir, given, not no_plots, quiet):
        return
    with refusing():
        resolved = case_from(case, None, set_)
        settings = analysis_settings(transient, record, full_transient, engine, cutoff)
        load("oscillator.designing.optimise", notice=True)
        from oscillator.designing.optimise import design_store
        from oscillator.designing.problem import Problem

        name, low, high = over
        refuse_taken(set_, dict.fromkeys(ranges, "--vary") | {name: "--over"})
        problem = Problem.of(resolved, ranges, {name: (low, high)}, objective, constraint or [], band, starts)
        count = check_count(candidates, "candidates", 1, 100_000)
        check_count(front, "front", 1, 100)
        store = design_store(
            out_dir if out_dir is not None else new_folder(resolved, "design"), problem, settings, count
        )
        store.check()
        processes = check_workers(workers, starts=count * problem.band * problem.starts)
        lock, client = locked(store.folder, scheduler)
    with computing(store, "surveys", lock, client):
        from oscillator.designing.optimise import design as run_design

        store.open()
        constraints = [str(c) for c in problem.constraints]
        options: dict[str, Any] = {"band": band, "starts": starts, "candidates": count, "front": front}
        options |= {"settings": settings, "workers": processes, "client": client, "store": store}
        run = functools.partial(run_design, resolved, ranges, {name: (low, high)}, objective, constraints, **options)
        found = with_progress(run, f"{resolved.name}: design over {name}", "surveys", quiet)
        store.write_status("computed", feasible=found.best.feasible)
    _finish(found, store, settings, no_plots, quiet)


def _finish(found: Any, store: Any, settings: Any, no_plots: bool, quiet: bool) -> None:
    folder: Path = store.folder
    say_reused(store, store.reused, "surveys", quiet)
    from oscillator.report.design import write_design

    problems = outputs(folder, "surveys", lambda: write_design(found, folder, plots=not no_plots))
    if not quiet:
        values = ", ".join(f"{n} = {v:.10g}" for n, v in found.values.items())
        out.print(Text(f"  design: {values}"))
        out.print(Text(f"  worst {found.problem.objective}: {found.best.objective:.10g}"))
        out.print(Text(f"  simulations: {', '.join(f'{k} {v}' for k, v in found.runs.items())}"))
        out.print(Text(f"  {found.message}"))
        if len(found.front):
            out.print(Text(f"  Pareto front: {len(found.front)} designs (front.parquet)"))
    say(f"written to {printable(str(folder))}")
    if problems:
        raise fail("; ".join(problems) + f"; the tables are in {folder}", 1)
    if not found.best.feasible:
        raise fail(found.message, 1)
