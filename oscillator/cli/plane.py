"""``oscillator atlas`` (the regime atlas over two parameters, resumable, local or on Dask) and
``oscillator curve`` (a bifurcation curve in a plane of two parameters)."""

from __future__ import annotations

import functools
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, cast

import typer
from rich.text import Text

from oscillator.analysis.execution import check_workers
from oscillator.cli.attractors import axis_of, subject_of
from oscillator.cli.commands import command
from oscillator.cli.console import fail, load, message, out, progress_bar, say
from oscillator.cli.inputs import check_engine, refuse_taken
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
from oscillator.errors import InputError, Interrupted, OscillatorError
from oscillator.text import printable

if TYPE_CHECKING:  # pragma: no cover
    from oscillator.io.cases import Case
    from oscillator.io.files import FolderClaim
    from oscillator.model.chains import FrictionChain
    from oscillator.orbits.curves import Curve

__all__ = ["atlas", "curve"]

#: ``--measures NAMES``: response measures as the atlas's columns and figures.
MeasuresOption = Annotated[
    str | None,
    typer.Option(
        "--measures",
        metavar="NAMES",
        help="Response measures as columns and figures, comma-separated: x_pp_m2,impact_max_right,...",
    ),
]
#: ``--x NAME LOW HIGH`` of a curve: a parameter and its range.
RangeOption = tuple[str, float, float]


@command(130, "The regime atlas over two parameters.")
def atlas(
    case: CaseArgument,
    x: Annotated[AxisOption, typer.Option("--x", metavar="NAME LOW HIGH N", help="The first parameter's axis.")],
    y: Annotated[AxisOption, typer.Option("--y", metavar="NAME LOW HIGH N", help="The second parameter's axis.")],
    starts: Annotated[
        int | None,
        typer.Option("--starts", metavar="N", help="Fresh starts at every point: the case's, and N-1 around it."),
    ] = None,
    measures: MeasuresOption = None,
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
    """The regime atlas over two parameters: at every point the attractors (from the case's start
    and seeds from the row before), each one's period, rests and contacts per period, impact
    velocity and largest Lyapunov exponent; the regime of each, and where several coexist; with
    --measures, the response measures named (over one return of a periodic attractor, over its
    recorded periods for an aperiodic one).

    One fresh start a point (--starts), run 40 forcing periods (--transient), then 10 recorded
    (--record). Writes atlas.parquet, figures/atlas.png (Fig. 14's lines marked) and a report.
    Rows are kept as they finish: the same command with the same --out resumes.

    \b
    A system file (docs/systems.md) takes two of its numbers as axes (Omega, wall.at,
    platform.F) and its orbits' measures in --measures (x_max:<mass>, impact_velocity:<stop>);
    its starts run on CVODE, 200 forcing periods at most (100 for a seed), and each periodic
    attractor is refined by Newton.

    \b
    Examples:
      oscillator atlas instance-1 --x Omega 1.3 1.85 12 --y Q2 68.5 72 8 --out runs/atlas
      oscillator atlas instance-1 --x Omega 1.59 1.61 3 --y Q2 71.1 71.2 3 --starts 4 --transient 60 --record 16
      oscillator atlas instance-1 --x Omega 1.3 1.85 6 --y d1 3.3 4 4 --measures impact_max_right,x_pp_m1
      oscillator atlas docs/systems/impacts.toml --x Omega 1.0 1.6 7 --y wall.at 0.3 0.9 4 --measures x_max:m
    """
    with refusing():
        resolved, stem, title = subject_of(case, set_)
        from oscillator.analysis.axes import chain_plane, parameter_plane
        from oscillator.model.chains import FrictionChain

        declared = isinstance(resolved, FrictionChain)
        plane = chain_plane if declared else parameter_plane
        x_axis, y_axis = plane(resolved, axis_of(x, "--x"), axis_of(y, "--y"))  # type: ignore[arg-type]
        refuse_taken(set_, {x_axis.name: "--x", y_axis.name: "--y"})
        from oscillator.attractors.atlas import atlas_settings, atlas_store, check_measures, measures_of

        given: dict[str, Any] = {"fresh_transient": transient, "record": record, "starts": starts, "cutoff": cutoff}
        chosen = {name: value for name, value in given.items() if value is not None}
        check_engine(engine, LANDING_ENGINES)
        if declared and engine != "dop853":
            raise InputError("--engine applies to the article's cases: a system runs on CVODE", field="--engine")
        if declared and cutoff is not None:
            raise InputError(NO_CUTOFF, field="--cutoff")
        settings = atlas_settings(resolved, **chosen, settle=not full_transient, engine=engine)
        count = check_workers(workers, starts=x_axis.count * y_axis.count * settings.starts)
        folder = out_dir if out_dir is not None else new_folder(stem if stem is not None else title, "atlas")
        names = [] if measures is None else [n.strip() for n in measures.split(",") if n.strip()]
        responses = check_measures(names, "--measures", known=measures_of(resolved))
        store = atlas_store(folder, resolved, x_axis, y_axis, settings, responses)
        store.check()
        load("oscillator.attractors.atlas", notice=True)
        lock, client = locked(folder, scheduler)
    with computing(store, "rows", lock, client):
        from oscillator.attractors.atlas import regime_atlas

        store.open()
        options: dict[str, Any] = {"settings": settings, "store": store, "measures": responses}
        run = functools.partial(regime_atlas, resolved, x_axis, y_axis, workers=count, client=client, **options)
        found = with_progress(run, f"{title}: atlas", "points", quiet)
        store.write_status("computed", points=x_axis.count * y_axis.count)
    _finish_atlas(found, store, no_plots, quiet)


def _finish_atlas(found: Any, store: Any, no_plots: bool, quiet: bool) -> None:
    say_reused(store, store.reused["batches"], f"of the {found.y.count} rows", quiet)
    folder = store.folder
    from oscillator.report.plane import write_atlas

    problems = outputs(folder, "rows", lambda: write_atlas(found, folder, plots=not no_plots))
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


@command(140, "Trace a bifurcation curve in a plane of two parameters.")
def curve(
    case: CaseArgument,
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
    A system file (docs/systems.md) takes two of its numbers (Omega, wall.at) and a kind of its
    period-1 orbits: fold, grazing (a stop or contact starts or stops closing), period_doubling
    or torus.

    \b
    Examples:
      oscillator curve instance-1 --kind sliding --at Omega=1.6,Q2=71.16 --x Omega 1.59 1.62 --y Q2 70.9 71.3 --out c1
      oscillator curve instance-1 --kind sliding --at Omega=1.6,Q2=71.16 --x Omega 1.59 1.62 --y Q2 70.9 71.3 --also c1
      oscillator curve docs/systems/impacts.toml --kind grazing --at Omega=0.6,wall.at=0.31 --x Omega 0.59 0.61 \\
        --y wall.at 0.25 0.4 --step 0.25 --set m.x=0 --out grazing
    """
    from oscillator.io.files import check_new, claim_folder

    with refusing():
        resolved, stem, title = subject_of(case, set_)
        refuse_taken(set_, {x[0]: "--x and --at", y[0]: "--y and --at"})
        point = _at(at, x[0], y[0])
        folder = out_dir if out_dir is not None else new_folder(stem if stem is not None else title, "curve")
        check_new(folder, option="--out")
        atlas_found = _atlas_over(over, resolved, x[0], y[0]) if over is not None else None
        others = [_read_other_curve(other, x[0], y[0]) for other in also or []]
        load("oscillator.orbits.curves", notice=True)
        from oscillator.orbits.curves import check_curve, trace_curve

        window = ((x[1], x[2]), (y[1], y[2]))
        options: dict[str, Any] = dict(kind=kind, x=x[0], y=y[0], at=point, window=window, period=period, step=step)
        check_curve(resolved, **options)  # every argument refused here, before any work (exit 2)
        claim = claim_folder(folder, option="--out")  # an unwritable --out is refused before the work too
    found, interrupted = _trace(trace_curve, resolved, title, options, claim)
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


def _atlas_over(folder: Path, case: Case | FrictionChain, x: str, y: str) -> Any:
    """The atlas to draw the curve over (``--over``): finished, and in the curve's plane."""
    from oscillator.report.plane import read_atlas

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


def _trace(
    trace_curve: Any, case: Case | FrictionChain, title: str, options: dict[str, Any], claim: FolderClaim
) -> tuple[Curve, bool]:
    """The curve, and whether it was interrupted (the points traced so far); the claim abandoned
    when there is nothing to write."""
    try:
        bar, report = progress_bar(f"{title}: {options['kind']} curve", "points")
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
    from oscillator.report.plane import read_curve

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
    from oscillator.report.plane import write_curve

    def write(folder: Path) -> list[str]:
        return write_curve(found, folder, atlas=atlas_found, plots=not no_plots, also=others)

    write_claimed(claim, write, "the curve")
