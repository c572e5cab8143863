"""``oscillator orbit`` and ``oscillator continue``: periodic orbits, their multipliers, branches."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Annotated

import typer
from rich import box
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table
from rich.text import Text

from oscillator.cli.console import err, fail, load, message, out, say
from oscillator.cli.inputs import case_from
from oscillator.errors import InputError, OscillatorError, SimulationFailed
from oscillator.text import printable, shown

__all__ = ["continue_", "orbit"]

SetOption = Annotated[
    list[str] | None,
    typer.Option("--set", metavar="NAME=VALUE", help="Override a parameter, initial value or solver option."),
]
PeriodOption = Annotated[int, typer.Option("--period", metavar="N", help="Forcing periods per return.")]
COORDINATES = ("x1", "v1", "x2", "v2")


def orbit(
    case: Annotated[str, typer.Argument(metavar="CASE", help="A named case or a case file (.toml).")],
    set_: SetOption = None,
    period: PeriodOption = 1,
) -> None:
    """Find the periodic orbit of the stroboscopic map by Newton's method; print it, its events
    and its Floquet multipliers.

    \b
    Examples:
      oscillator orbit instance-1
      oscillator orbit instance-1 --set Q2=70.5
    """
    try:
        resolved = case_from(case, None, set_)
        load("oscillator.orbits.shooting")
        from oscillator.orbits.shooting import find_orbit

        found = find_orbit(resolved, period=period)
    except OscillatorError as error:
        raise fail(message(error), code=1 if isinstance(error, SimulationFailed) else 2) from None
    except KeyboardInterrupt:
        raise fail("interrupted", code=130) from None
    from oscillator.cli.run import _events_table

    state = ", ".join(f"{name} = {value:.10g}" for name, value in zip(COORDINATES, found.state, strict=True))
    out.print(Text(f"{printable(resolved.name)}: period-{found.period} orbit at t0 = {found.t0:g} s"))
    out.print(Text(f"  {state}"))
    out.print(Text(f"  residual {found.residual:.1e} after {found.iterations} Newton step(s); "
                   f"{'stable' if found.stable else 'unstable'}"))  # fmt: skip
    table = Table(title="Floquet multipliers", title_justify="left", header_style="bold", box=box.SIMPLE_HEAD)
    for column in ("multiplier", "modulus"):
        table.add_column(column, justify="right")
    for mu in found.multipliers:
        table.add_row(f"{mu.real:+.6e} {mu.imag:+.6e}i", f"{abs(mu):.6e}")
    out.print(table)
    out.print(_events_table(found.events))


def _progress_bar(name: str):
    columns = (TextColumn("{task.description}"), BarColumn(), TextColumn("{task.percentage:>3.0f}%"),
               TimeElapsedColumn())  # fmt: skip
    bar = Progress(*columns, console=err, transient=True)
    task = bar.add_task(printable(name), total=1.0)
    last = [0.0]

    def report(fraction: float) -> None:
        now = time.monotonic()
        if now - last[0] > 0.1:
            last[0] = now
            bar.update(task, completed=fraction)

    return bar, report


def _continue_with_progress(continue_orbit, case, settings: dict, quiet: bool):
    if quiet or not err.is_terminal:  # a progress bar only where a person watches
        return continue_orbit(case, **settings)
    bar, report = _progress_bar(case.name)
    with bar:
        return continue_orbit(case, **settings, progress=report)


def continue_(
    case: Annotated[str, typer.Argument(metavar="CASE", help="A named case or a case file (.toml).")],
    param: Annotated[str, typer.Option("--param", metavar="NAME", help="The parameter to continue in.")],
    start: Annotated[float, typer.Option("--from", metavar="VALUE", help="Start of the parameter's range.")],
    stop: Annotated[float, typer.Option("--to", metavar="VALUE", help="End of the parameter's range.")],
    set_: SetOption = None,
    period: PeriodOption = 1,
    step: Annotated[
        float | None, typer.Option("--step", metavar="S", help="Largest step, as a fraction of the range.")
    ] = None,
    coordinate: Annotated[str, typer.Option("--coordinate", help="The coordinate at t0 drawn.")] = "x2",
    over: Annotated[
        Path | None, typer.Option("--over", metavar="SWEEP_DIR", help="Draw the branch over this sweep's points.")
    ] = None,
    out_dir: Annotated[Path | None, typer.Option("--out", metavar="DIR", help="Output folder.")] = None,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="No progress bar or summary.")] = False,
) -> None:
    """Continue a periodic orbit in a parameter (pseudo-arclength, through unstable parts and
    folds); locate its sliding, grazing, fold, period-doubling and torus bifurcations.

    Writes branch.parquet, bifurcations.parquet, figures/branch.png, figures/multipliers.png
    report.md and report.html into DIR (default runs/<case>-continue-<time>).

    \b
    Examples:
      oscillator continue instance-1 --param Q2 --from 70.5 --to 71.5 --out runs/q2-branch
    """
    try:
        if coordinate not in COORDINATES:
            raise InputError(f"--coordinate must be one of {', '.join(COORDINATES)}, got {shown(coordinate)}",
                             field="--coordinate")  # fmt: skip
        resolved = case_from(case, None, set_)
        load("oscillator.orbits.continuation", "oscillator.io.runs", "oscillator.analysis.sweeps")
        from oscillator.analysis.sweeps import read_sweep
        from oscillator.io.files import check_name
        from oscillator.io.runs import claim_output
        from oscillator.orbits.continuation import continue_orbit

        sweep_points = read_sweep(over)["poincare"] if over is not None else None
        if sweep_points is not None and param not in sweep_points.columns:
            raise InputError(f"the sweep in {shown(str(over))} is not a sweep of {shown(param)}", field="--over")
        if out_dir is not None:
            check_name(out_dir, option="--out")
        claim = claim_output(out_dir, f"{resolved.name}-continue")
    except OscillatorError as error:
        raise fail(message(error), code=1 if isinstance(error, SimulationFailed) else 2) from None
    try:
        settings = {"param": param, "start": start, "stop": stop, "period": period, "step": step}
        branch = _continue_with_progress(continue_orbit, resolved, settings, quiet)
    except OscillatorError as error:
        claim.abandon()
        raise fail(message(error), code=1 if isinstance(error, SimulationFailed) else 2) from None
    except KeyboardInterrupt:
        claim.abandon()
        raise fail("interrupted; nothing was written", code=130) from None
    from oscillator.orbits.output import write_branch

    folder, problem = write_branch(branch, resolved, claim, coordinate=coordinate, sweep_points=sweep_points)
    if not quiet:
        say(f"{len(branch.points)} points, {len(branch.bifurcations)} bifurcation(s) in {folder}")
        for row in branch.bifurcations.itertuples(index=False):
            gap = "  (a gap begins)" if row.after == "" else "  (a gap ends)" if row.before == "" else ""
            out.print(Text(f"  {param} = {getattr(row, param):.10g}  {row.kind}{gap}"))
        if not branch.complete:
            out.print(Text(f"  the branch ended early: {printable(branch.message)}"))
    if problem:
        err.print(Text.assemble(("error:", "bold red"), f" {printable(problem)}; the tables are kept in {folder}"))
        raise typer.Exit(1)
